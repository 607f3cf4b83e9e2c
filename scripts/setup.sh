#!/usr/bin/env bash
# Installs the Debian 12 packages drape builds with, only those missing. Idempotent.
#   scripts/setup.sh            everything (bake + runtime + tests + benchmarks)
#   scripts/setup.sh runtime    what formats + runtime + their tests need
set -euo pipefail
profile=${1:-all}
runtime_packages=(g++ cmake make pkg-config libcereal-dev libgtest-dev libgmock-dev)
bake_packages=(libassimp-dev libcgal-dev libgmp-dev libmpfr-dev libeigen3-dev libosmesa6-dev
  nlohmann-json3-dev libcli11-dev libstb-dev libbenchmark-dev ccache clang libclang-rt-14-dev
  libfcl-dev libbullet-dev gnuplot-nox python3 ninja-build)
packages=("${runtime_packages[@]}")
[ "$profile" = runtime ] || packages+=("${bake_packages[@]}")

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "setup: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO=sudo
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
