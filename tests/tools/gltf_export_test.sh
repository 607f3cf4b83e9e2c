#!/usr/bin/env bash
# drape-bake --gltf: the asset as glTF 2.0 (.gltf and .glb) that the Khronos validator passes with
# no error, holding the skeleton, the skinned body, a node per hull and joint sphere on its joint
# and the clips; an export that cannot be written fails the bake and leaves nothing.
# With drape-sim (SIM): a short run of the demo scene as an animated glTF passes too, and so does
# its skirt exported bound to the skeleton (--export-garments), which reads back as a glTF garment.
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
    --gltf "$WORK/sim/demo.glb" --export-garments "$WORK/garments" >/dev/null 2>&1
  check [ $? -eq 0 ]
  files+=("$WORK/sim/demo.glb" "$WORK/garments/skirt.glb")
  # The exported skirt read back as a scene's glTF garment (its waist held by max distance 0),
  # and the sample that reads a painted one.
  check python3 - "$SOURCE/samples/scenes/demo.json" "$WORK/garments/skirt.glb" "$WORK/back.json" <<'PY'
import json, sys
scene = json.load(open(sys.argv[1]))
scene["character"] = sys.argv[1].rsplit("/", 2)[0] + "/mannequin/mannequin.gltf"
scene["garments"] = [{"name": "skirt", "type": "gltf",
                      "shape": {"file": sys.argv[2], "mesh": "skirt"},
                      "skin": {"paint": "attribute"}}]
json.dump(scene, open(sys.argv[3], "w"))
PY
  "$SIM" "$WORK/back.json" -o "$WORK/back" --frames 4 --threads 1 >"$WORK/back.txt" 2>&1
  check [ $? -eq 0 ]
  check grep -q "0 NaN frames" "$WORK/back.txt"
  "$SIM" "$SOURCE/samples/scenes/mannequin_gltf_dress.json" -o "$WORK/dress" --frames 4 \
    --threads 1 >/dev/null 2>&1
  check [ $? -eq 0 ]
  sed 's|"file": "[^"]*"|"file": "no_such_garment.glb"|' "$WORK/back.json" >"$WORK/missing.json"
  "$SIM" "$WORK/missing.json" -o "$WORK/missing" --frames 1 >/dev/null 2>"$WORK/missing.err"
  check [ $? -ne 0 ]
  check grep -q "/garments/0/shape/file.*no_such_garment.glb" "$WORK/missing.err"
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
capsules = sum(1 for n in names if n.startswith("capsule "))
assert hulls >= 17 and spheres >= 10 and capsules == 17, (hulls, spheres, capsules)
for k, n in enumerate(g["nodes"]):              # every collider hangs from a joint
    if n.get("name", "").startswith(("hull ", "joint sphere ", "capsule ")):
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
