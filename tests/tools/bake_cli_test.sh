#!/usr/bin/env bash
# drape-bake / drape-inspect contract: every bad input -> exit != 0, one stderr line that names
# the input and the reason, no output file. Good input -> a file drape-inspect loads.
set -u
BAKE=$1 INSPECT=$2 SOURCE=$3 SHARED=$4
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
failures=0 passed=0

fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

# expect_error NAME INPUT_FILE EXPECTED_REASON_REGEX [extra args]
# The message must name the bad file: NAMED (default INPUT_FILE).
expect_error() {
  local name=$1 input=$2 reason=$3
  shift 3
  local named=${NAMED:-$input}
  local out="$WORK/$name.drape"
  "$BAKE" "$input" -o "$out" --report "$WORK/$name.json" "$@" >"$WORK/$name.stdout" 2>"$WORK/$name.stderr"
  local rc=$?
  local lines
  lines=$(wc -l <"$WORK/$name.stderr")
  if [ $rc -eq 0 ]; then fail "$name: exit 0 on bad input"; return; fi
  if [ "$lines" -ne 1 ]; then fail "$name: expected one stderr line, got $lines: $(cat "$WORK/$name.stderr")"; return; fi
  if ! grep -qF -- "$named" "$WORK/$name.stderr"; then fail "$name: message does not name the input: $(cat "$WORK/$name.stderr")"; return; fi
  if ! grep -qiE -- "$reason" "$WORK/$name.stderr"; then fail "$name: message lacks reason /$reason/: $(cat "$WORK/$name.stderr")"; return; fi
  if ls "$WORK" | grep -q "^$name\.drape"; then fail "$name: an output file was left behind"; return; fi
  if [ -e "$WORK/$name.json" ]; then fail "$name: a report was left behind"; return; fi
  passed=$((passed + 1))
}

MANNEQUIN="$SOURCE/samples/mannequin/mannequin.gltf"

# --- Bad inputs.
expect_error missing "$WORK/does-not-exist.glb" "not found"
: >"$WORK/empty.glb"
expect_error empty "$WORK/empty.glb" "empty"
echo "this is not a model" >"$WORK/garbage.fbx"
expect_error garbage "$WORK/garbage.fbx" "unsupported or corrupt"
printf 'glTF\x02\x00\x00\x00\xff\xff\x00\x00' >"$WORK/truncated.glb"
expect_error truncated_glb "$WORK/truncated.glb" "unsupported or corrupt"
head -c 20000 "$MANNEQUIN" >"$WORK/truncated.gltf"
expect_error truncated_gltf "$WORK/truncated.gltf" "unsupported or corrupt"
cat >"$WORK/nomesh.gltf" <<'JSON'
{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"name": "lonely"}]}
JSON
expect_error no_mesh "$WORK/nomesh.gltf" "no meshes|corrupt"
cat >"$WORK/points.obj" <<'OBJ'
v 0 0 0
v 1 0 0
v 0 1 0
p 1 2 3
OBJ
expect_error no_triangles "$WORK/points.obj" "no triangles|no meshes|corrupt"
cat >"$WORK/nan.obj" <<'OBJ'
v 0 0 0
v nan 0 0
v 0 1 0
f 1 2 3
OBJ
expect_error nan_vertex "$WORK/nan.obj" "not finite|corrupt"
cat >"$WORK/inf.obj" <<'OBJ'
v 0 0 0
v 1e39 0 0
v 0 1 0
f 1 2 3
OBJ
expect_error inf_vertex "$WORK/inf.obj" "not finite|corrupt"
# Duplicate joint names: the mannequin with two joints renamed alike.
sed 's/"name": "knee_r"/"name": "knee_l"/' "$MANNEQUIN" >"$WORK/duplicate.gltf"
expect_error duplicate_joints "$WORK/duplicate.gltf" "duplicate joint name 'knee_l'|\"knee_l\" has the same name"
# A cyclic hierarchy: node 0's child is node 0.
cat >"$WORK/cycle.gltf" <<'JSON'
{"asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"name": "a", "children": [0]}]}
JSON
expect_error cyclic "$WORK/cycle.gltf" "cyclic|corrupt|no meshes"
echo '{"import": {"unit_scale": -1}}' >"$WORK/bad_config.json"
NAMED="$WORK/bad_config.json" expect_error bad_config_value "$MANNEQUIN" "unit_scale.*must be in" --config "$WORK/bad_config.json"
echo '{"import": {"no_such_key": 1}}' >"$WORK/unknown_key.json"
NAMED="$WORK/unknown_key.json" expect_error bad_config_key "$MANNEQUIN" "no_such_key is not a parameter" --config "$WORK/unknown_key.json"

# --- Good input: bake, inspect, the report has the contract fields.
if "$BAKE" "$MANNEQUIN" -o "$WORK/mannequin.drape" --report "$WORK/mannequin.json" 2>"$WORK/good.stderr"; then
  if "$INSPECT" "$WORK/mannequin.drape" >"$WORK/inspect.txt" && grep -q "17 joints" "$WORK/inspect.txt"; then
    passed=$((passed + 1))
  else
    fail "inspect of the baked mannequin: $(cat "$WORK/inspect.txt")"
  fi
  for field in source_to_asset unit_scale up_axis joint_count clips warnings timings tool_version format_version; do
    if grep -q "\"$field\"" "$WORK/mannequin.json"; then passed=$((passed + 1)); else fail "report lacks $field"; fi
  done
  # A corrupt .drape is refused by drape-inspect with the file named.
  head -c 100 "$WORK/mannequin.drape" >"$WORK/cut.drape"
  if "$INSPECT" "$WORK/cut.drape" 2>"$WORK/cut.stderr"; then fail "inspect accepted a truncated file";
  elif grep -q "cut.drape: truncated" "$WORK/cut.stderr"; then passed=$((passed + 1));
  else fail "inspect message for a truncated file: $(cat "$WORK/cut.stderr")"; fi
else
  fail "baking the mannequin: $(cat "$WORK/good.stderr")"
fi
if "$BAKE" --dump-config | grep -q '"unit_scale"'; then passed=$((passed + 1)); else fail "--dump-config"; fi

echo "$passed passed, $failures failed"
[ $failures -eq 0 ]
