#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, bakes the built-in mannequin and
# shows what the asset holds. Output goes to out/sample/.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${DRAPE_JOBS:-2}
scripts/setup.sh
cmake --preset default >/dev/null
cmake --build build -j "$jobs" --target drape-bake drape-inspect
out=out/sample
mkdir -p "$out"
build/bin/drape-bake samples/mannequin/mannequin.gltf -o "$out/mannequin.drape" \
  --report "$out/mannequin.report.json" --preview "$out/preview"
build/bin/drape-inspect "$out/mannequin.drape"
echo
echo "sample: wrote $out/mannequin.drape, its bake report $out/mannequin.report.json and previews in $out/preview/"
