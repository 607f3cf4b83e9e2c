#!/usr/bin/env bash
# The README's main command: installs what is missing, builds, then
#  1. bakes the built-in mannequin with previews and shows what the asset holds (out/sample/);
#  2. runs the built-in demo scene: the mannequin walking in a skirt against its colliders,
#     with PNG frames, an animation or contact sheet, and stats.json (out/demo/).
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${DRAPE_JOBS:-2}
scripts/setup.sh
cmake --preset default >/dev/null
cmake --build build -j "$jobs" --target drape-bake drape-inspect drape-sim
out=out/sample
mkdir -p "$out"
build/bin/drape-bake samples/mannequin/mannequin.gltf -o "$out/mannequin.drape" \
  --report "$out/mannequin.report.json" --preview "$out/preview"
build/bin/drape-inspect "$out/mannequin.drape"
echo
build/bin/drape-sim samples/scenes/demo.json -o out/demo
echo
echo "sample: the baked asset is $out/mannequin.drape (report $out/mannequin.report.json);"
echo "        previews of the body maps and colliders are in $out/preview/;"
echo "        the demo's frames are in out/demo/frames/, its animation or contact sheet and"
echo "        stats.json in out/demo/."
