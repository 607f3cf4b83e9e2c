#!/usr/bin/env bash
# drape-bake --gltf: the asset as glTF 2.0 (.gltf and .glb) that the Khronos validator passes with
# no error, holding the skeleton, the skinned body, a node per hull and joint sphere on its joint
# and the clips; an export that cannot be written fails the bake and leaves nothing.
# With drape-sim (SIM): a short run of the demo scene as an animated glTF passes too.
# Usage: gltf_export_test.sh BAKE SOURCE SHARED NODE_DIR [SIM]
set -u
BAKE=$1 SOURCE=$2 SHARED=$3 NODE_DIR=$4 SIM=${5:-}
. "$(dirname "$0")/cli_test_lib.sh"
if [ ! -f "$NODE_DIR/node_modules/gltf-validator/package.json" ]; then
  echo "FAIL: the glTF validator is not installed in $NODE_DIR (scripts/setup.sh installs it)"
  exit 1
fi
echo '{"maps": {"resolution": 128}}' >"$WORK/bake.json"
"$BAKE" "$SOURCE/samples/mannequin/mannequin.gltf" -o "$WORK/m.drape" --config "$WORK/bake.json" \
  --gltf "$WORK/m.gltf" 2>/dev/null
check [ $? -eq 0 ]
files=("$WORK/m.gltf")
if [ -f "$SHARED/assets/characters/Fox/Fox.glb" ]; then
  "$BAKE" "$SHARED/assets/characters/Fox/Fox.glb" -o "$WORK/fox.drape" --config "$WORK/bake.json" \
    --gltf "$WORK/fox.glb" 2>/dev/null
  check [ $? -eq 0 ]
  files+=("$WORK/fox.glb")
else
  echo "note: $SHARED/assets/characters absent: the .glb export is checked on the mannequin only"
  "$BAKE" "$SOURCE/samples/mannequin/mannequin.gltf" -o "$WORK/m2.drape" --config "$WORK/bake.json" \
    --gltf "$WORK/m2.glb" 2>/dev/null
  files+=("$WORK/m2.glb")
fi
if [ -n "$SIM" ]; then
  "$SIM" "$SOURCE/samples/scenes/demo.json" -o "$WORK/sim" --frames 24 --threads 1 \
    --gltf "$WORK/sim/demo.glb" >/dev/null 2>&1
  check [ $? -eq 0 ]
  files+=("$WORK/sim/demo.glb")
fi
NODE_PATH="$NODE_DIR/node_modules" node "$(dirname "$0")/validate_gltf.js" "${files[@]}" >"$WORK/validator.txt" 2>&1
check [ $? -eq 0 ]
cat "$WORK/validator.txt"
# What the .gltf holds, against the .drape (drape-inspect's counts through the bake report).
check python3 - "$WORK/m.gltf" <<'PY'
import json, sys
g = json.load(open(sys.argv[1]))
names = [n.get("name", "") for n in g["nodes"]]
joints = len(g["skins"][0]["joints"])
hulls = sum(1 for n in names if n.startswith("hull "))
spheres = sum(1 for n in names if n.startswith("joint sphere "))
assert joints == 17, joints                      # the mannequin's skeleton
assert "body" in names and g["nodes"][names.index("body")]["skin"] == 0
assert hulls >= 17 and spheres >= 10, (hulls, spheres)
for k, n in enumerate(g["nodes"]):              # every collider hangs from a joint
    if n.get("name", "").startswith(("hull ", "joint sphere ")):
        assert any(k in p.get("children", []) for p in g["nodes"][:joints]), n["name"]
assert [a["name"] for a in g["animations"]] == ["walk"], g["animations"]
PY
# A path that cannot be written: the bake fails, names it, and leaves no asset.
"$BAKE" "$SOURCE/samples/mannequin/mannequin.gltf" -o "$WORK/x.drape" --config "$WORK/bake.json" \
  --gltf "$WORK/no/such/dir/x.gltf" 2>"$WORK/x.err"
check [ $? -ne 0 ]
check grep -q "no/such/dir/x.gltf" "$WORK/x.err"
check [ ! -e "$WORK/x.drape" ]
finish gltf_export_test
