#!/usr/bin/env bash
# Installs the Debian 12 packages drape builds with, only those missing. Idempotent.
#   scripts/setup.sh            everything (bake + runtime + tests + benchmarks)
#   scripts/setup.sh runtime    what formats + runtime + their tests need
# Beyond Debian's packages: the Khronos glTF validator (npm, pinned) that the glTF exports' tests
# run, in ${DRAPE_NODE_DIR:-~/.cache/drape-node}.
set -euo pipefail
profile=${1:-all}
runtime_packages=(g++ cmake make pkg-config libcereal-dev libgtest-dev libgmock-dev)
bake_packages=(libassimp-dev libcgal-dev libgmp-dev libmpfr-dev libeigen3-dev libosmesa6-dev
  nlohmann-json3-dev libcli11-dev libstb-dev libbenchmark-dev ccache clang libclang-rt-14-dev
  libfcl-dev libbullet-dev gnuplot-nox python3 ninja-build libtinygltf-dev libmeshoptimizer-dev)
# node and npm from Debian unless some node is installed already (e.g. NodeSource's, which
# bundles npm and conflicts with Debian's npm package).
command -v npm >/dev/null || bake_packages+=(nodejs npm)
packages=("${runtime_packages[@]}")
[ "$profile" = runtime ] || packages+=("${bake_packages[@]}")

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO=sudo
  export DEBIAN_FRONTEND=noninteractive
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi
node_dir=${DRAPE_NODE_DIR:-${XDG_CACHE_HOME:-$HOME/.cache}/drape-node}
if [ "$profile" != runtime ] && [ ! -f "$node_dir/node_modules/gltf-validator/package.json" ]; then
  echo "setup: installing gltf-validator (npm) into $node_dir"
  npm install --silent --no-audit --no-fund --prefix "$node_dir" gltf-validator@2.0.0-dev.3.10 \
    >/dev/null
fi
