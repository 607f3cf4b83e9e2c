#!/usr/bin/env bash
# drape-bake / drape-inspect contract: every bad input -> exit != 0, one stderr line that names
# the input and the reason, no output file. Good input -> a file drape-inspect loads.
set -u
BAKE=$1 INSPECT=$2 SOURCE=$3 SHARED=$4 QUERY=$5 ENGINE_SAMPLE=${6:-}
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
echo '{"maps": {"clip": "wlak"}}' >"$WORK/bad_clip.json"
NAMED="$WORK/bad_clip.json" expect_error bad_maps_clip "$MANNEQUIN" \
  "bad_clip.json: /maps/clip: no clip named 'wlak' in '.*mannequin.gltf' \(clips: walk" --config "$WORK/bad_clip.json"
# --strict: a bake with warnings fails like any error (a 1 mm hulls.max_bloat makes every hull a
# warning), naming the count and the first warning; without warnings it bakes.
echo '{"maps": {"enabled": false}, "hulls": {"max_bloat": 0.001, "max_pieces": 1}}' >"$WORK/tight.json"
expect_error strict "$MANNEQUIN" "--strict: [0-9]+ warnings?(, the first)?: [a-z0-9]" --strict \
  --config "$WORK/tight.json"
echo '{"maps": {"enabled": false}, "hulls": {"max_bloat": 1}}' >"$WORK/loose.json"
if "$BAKE" "$MANNEQUIN" -o "$WORK/strict.drape" --config "$WORK/loose.json" --strict 2>"$WORK/strict.err" &&
  [ -s "$WORK/strict.drape" ] && [ ! -s "$WORK/strict.err" ]; then
  passed=$((passed + 1))
else
  fail "--strict on a bake without warnings (a glTF states its unit and up axis): $(cat "$WORK/strict.err")"
fi
# What assimp drops without a word is counted: an OBJ with a two-corner face and empty f lines
# bakes, and says so on stderr and in the report.
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 3 4\nf 1 2\nf\nf 2 4 3\nf 1 4 2\nf  \n' >"$WORK/sloppy.obj"
if "$BAKE" "$WORK/sloppy.obj" -o "$WORK/sloppy.drape" --report "$WORK/sloppy.json" 2>"$WORK/sloppy.stderr" &&
  grep -q "warning: $WORK/sloppy.obj: 2 'f' lines without a corner skipped" "$WORK/sloppy.stderr" &&
  grep -q "1 faces with one or two corners (points and lines) dropped" "$WORK/sloppy.json"; then
  passed=$((passed + 1))
else
  fail "OBJ faces dropped without a warning: $(cat "$WORK/sloppy.stderr")"
fi

# --- Good input: bake, inspect, the report has the contract fields.
if "$BAKE" "$MANNEQUIN" -o "$WORK/mannequin.drape" --report "$WORK/mannequin.json" 2>"$WORK/good.stderr"; then
  if "$INSPECT" "$WORK/mannequin.drape" >"$WORK/inspect.txt" && grep -q "17 joints" "$WORK/inspect.txt"; then
    passed=$((passed + 1))
  else
    fail "inspect of the baked mannequin: $(cat "$WORK/inspect.txt")"
  fi
  # What placing a garment needs: the body's box and height, each joint's position (the
  # mannequin stands 1.75 m tall with its hips at 0.95 m).
  if grep -q "body at rest: .*(height 1.750 m)" "$WORK/inspect.txt" &&
    grep -qE "^ +0 hips +parent - +\( *-?0\.000 +0\.950 +-?0\.000\) / \( *-?0\.000 +0\.950" "$WORK/inspect.txt" &&
    "$INSPECT" "$WORK/mannequin.drape" --json | grep -q '"rest_height": 1.75'; then
    passed=$((passed + 1))
  else
    fail "inspect lacks the body's box or the joints' positions: $(head -8 "$WORK/inspect.txt")"
  fi
  # The engine sample on an asset without a clip says why it stops.
  if [ -n "$ENGINE_SAMPLE" ]; then
    cat >"$WORK/post.obj" <<'OBJ'
v -0.15 0 -0.15
v 0.15 0 -0.15
v 0.15 0 0.15
v -0.15 0 0.15
v -0.15 1.7 -0.15
v 0.15 1.7 -0.15
v 0.15 1.7 0.15
v -0.15 1.7 0.15
f 1 3 2
f 1 4 3
f 5 6 7
f 5 7 8
f 1 2 6
f 1 6 5
f 2 3 7
f 2 7 6
f 3 4 8
f 3 8 7
f 4 1 5
f 4 5 8
OBJ
    "$BAKE" "$WORK/post.obj" -o "$WORK/no_clip.drape" 2>"$WORK/post.err" || fail "baking a post: $(cat "$WORK/post.err")"
    if "$ENGINE_SAMPLE" "$WORK/no_clip.drape" >/dev/null 2>"$WORK/engine.err"; then
      fail "engine_sample ran on an asset without a clip"
    elif grep -q "no_clip.drape: no clip to animate" "$WORK/engine.err"; then
      passed=$((passed + 1))
    else
      fail "engine_sample on an asset without a clip: '$(cat "$WORK/engine.err")'"
    fi
  fi
  for field in source_to_asset unit_scale up_axis joint_count clips warnings timings tool_version format_version fit bloat_max_mm; do
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
# --- drape-query: the runtime's answers from the command line.
if [ -e "$WORK/mannequin.drape" ]; then
  # Inside the chest, far in front of the body, inside the left thigh; one segment through the
  # left shin from front to back (thinner than the step: must be caught by maps and hulls).
  printf '0 1.32 0.02\n0 1.0 0.8\n0.095 0.7 0.0\n' >"$WORK/points.txt"
  printf '0.095 0.3 0.3 0.095 0.3 -0.3\n' >"$WORK/segments.txt"
  "$QUERY" "$WORK/mannequin.drape" --points "$WORK/points.txt" >"$WORK/points.csv" 2>"$WORK/query.stderr"
  rows=$(grep -c '^[0-9]' "$WORK/points.csv")
  if [ "$rows" -eq 12 ]; then passed=$((passed + 1)); else fail "query: expected 12 rows (3 points x 4 methods), got $rows: $(cat "$WORK/query.stderr")"; fi
  # inside flags: column 3. Chest: maps and hulls say inside; the far point: nobody.
  check_flag() {  # row method expected
    local got
    got=$(awk -F, -v r="$1" -v m="$2" '$1 == r && $2 == m {print $3}' "$3")
    if [ "$got" = "$4" ]; then passed=$((passed + 1)); else fail "query row $1 $2: inside=$got, expected $4"; fi
  }
  check_flag 0 maps "$WORK/points.csv" 1
  check_flag 0 hulls "$WORK/points.csv" 1
  check_flag 1 maps "$WORK/points.csv" 0
  check_flag 1 hulls "$WORK/points.csv" 0
  check_flag 1 spheres "$WORK/points.csv" 0
  check_flag 0 capsules "$WORK/points.csv" 1
  check_flag 1 capsules "$WORK/points.csv" 0
  check_flag 2 maps "$WORK/points.csv" 1
  "$QUERY" "$WORK/mannequin.drape" --segments "$WORK/segments.txt" --method all >"$WORK/segments.csv"
  for method in maps hulls capsules; do
    contact=$(awk -F, -v m=$method '$1 == 0 && $2 == m {print $4}' "$WORK/segments.csv")
    if [ "$contact" = 1 ]; then passed=$((passed + 1)); else fail "query: $method missed a segment through the shin"; fi
  done
  "$QUERY" "$WORK/mannequin.drape" --clip walk --time 0.5 --mesh "$WORK/posed.obj"
  if [ "$(grep -c '^f ' "$WORK/posed.obj")" -eq 7584 ]; then passed=$((passed + 1)); else fail "query --mesh: wrong face count"; fi
  if "$QUERY" "$WORK/mannequin.drape" --clip nope --points "$WORK/points.txt" 2>"$WORK/q.err" >/dev/null; then
    fail "query accepted a missing clip"
  elif grep -q "no clip named 'nope'" "$WORK/q.err"; then passed=$((passed + 1)); else fail "query message: $(cat "$WORK/q.err")"; fi
  # Coordinates that are not finite or beyond +-1e6 m are read and answered as invalid input
  # (flags 128, the last column), with no contact and the position unchanged; a word is refused.
  printf '1e30 0 0\nnan 0 0\n0 -inf 0\n0 0 -1e7\n0 1.32 0.02\n' >"$WORK/huge.txt"
  printf '0 1.32 0.02 1e30 1.32 0.02\n' >"$WORK/huge_segments.txt"
  if "$QUERY" "$WORK/mannequin.drape" --points "$WORK/huge.txt" >"$WORK/huge.csv" 2>"$WORK/q.err" &&
    "$QUERY" "$WORK/mannequin.drape" --segments "$WORK/huge_segments.txt" >>"$WORK/huge.csv" 2>>"$WORK/q.err"; then
    invalid=$(awk -F, '$1 ~ /^[0-9]+$/ && $4 == 0 && $16 == 128' "$WORK/huge.csv" | wc -l)
    chest=$(awk -F, '$1 == 4 && $2 == "hulls" {print $3 "," $16}' "$WORK/huge.csv")
    if [ "$invalid" -eq 20 ] && [ "$chest" = "1,2" ]; then passed=$((passed + 1)); else fail "query on huge and non-finite rows: $invalid invalid rows of 20, chest '$chest': $(cat "$WORK/huge.csv")"; fi
  else
    fail "query refused huge or non-finite rows: $(cat "$WORK/q.err")"
  fi
  # Any pose: a clip time between the baked poses and the same pose as joint world matrices give
  # the same answers for every method (maps rendered from the skinned mesh for both); the body
  # moved 1 m along x by the matrices is found there, and not where it was.
  "$QUERY" "$WORK/mannequin.drape" --clip walk --time 0.37 --write-joint-matrices "$WORK/walk.txt"
  "$QUERY" "$WORK/mannequin.drape" --clip walk --time 0.37 --points "$WORK/points.txt" >"$WORK/clip.csv" 2>"$WORK/clip.err"
  "$QUERY" "$WORK/mannequin.drape" --joint-matrices "$WORK/walk.txt" --points "$WORK/points.txt" >"$WORK/matrices.csv" 2>/dev/null
  if cmp -s "$WORK/clip.csv" "$WORK/matrices.csv" && [ "$(grep -c '^[0-9]*,maps,' "$WORK/clip.csv")" -eq 3 ] &&
    grep -q "rendered for this pose" "$WORK/clip.err"; then
    passed=$((passed + 1))
  else
    fail "query: a clip time and its joint matrices answer differently: $(cat "$WORK/clip.err") $(diff "$WORK/clip.csv" "$WORK/matrices.csv")"
  fi
  grep -v '^#' "$WORK/walk.txt" | awk '{$4 = $4 + 1; print}' >"$WORK/moved.txt"
  printf '1 1.32 0.02\n0 1.32 0.02\n' >"$WORK/moved_points.txt"
  "$QUERY" "$WORK/mannequin.drape" --joint-matrices "$WORK/moved.txt" --points "$WORK/moved_points.txt" >"$WORK/moved.csv" 2>/dev/null
  check_flag 0 maps "$WORK/moved.csv" 1
  check_flag 0 hulls "$WORK/moved.csv" 1
  check_flag 1 maps "$WORK/moved.csv" 0
  check_flag 1 hulls "$WORK/moved.csv" 0
  head -n 4 "$WORK/walk.txt" >"$WORK/short.txt"
  if "$QUERY" "$WORK/mannequin.drape" --joint-matrices "$WORK/short.txt" --points "$WORK/points.txt" >/dev/null 2>"$WORK/q.err"; then
    fail "query accepted too few joint matrices"
  elif grep -qE "short.txt: 3 matrices, the skeleton has [0-9]+ joints" "$WORK/q.err"; then passed=$((passed + 1)); else fail "query message: $(cat "$WORK/q.err")"; fi
  printf '1 0 0 0 0 1 0 0 0 0 1 0 0 0 1 1\n' >"$WORK/projective.txt"
  if "$QUERY" "$WORK/mannequin.drape" --joint-matrices "$WORK/projective.txt" --points "$WORK/points.txt" >/dev/null 2>"$WORK/q.err"; then
    fail "query accepted a projective matrix"
  elif grep -q "projective.txt:1: the last row is not 0 0 0 1" "$WORK/q.err"; then passed=$((passed + 1)); else fail "query message: $(cat "$WORK/q.err")"; fi
  # Per-bone local maps: baked on request, answered by --method bone_maps (and all) for a clip
  # time; an asset without them says so.
  printf '{"bone_maps": {"enabled": true}}' >"$WORK/bone_maps.json"
  if "$BAKE" "$MANNEQUIN" -o "$WORK/bone_maps.drape" --config "$WORK/bone_maps.json" 2>/dev/null &&
    "$QUERY" "$WORK/bone_maps.drape" --clip walk --time 0.37 --points "$WORK/points.txt" --method all >"$WORK/bones.csv" 2>/dev/null; then
    check_flag 0 bone_maps "$WORK/bones.csv" 1
    check_flag 1 bone_maps "$WORK/bones.csv" 0
  else
    fail "query: bone maps of the mannequin"
  fi
  if "$QUERY" "$WORK/mannequin.drape" --method bone_maps --points "$WORK/points.txt" >/dev/null 2>"$WORK/q.err"; then
    fail "query answered bone_maps for an asset without them"
  elif grep -q "mannequin.drape: no bone maps baked" "$WORK/q.err"; then passed=$((passed + 1)); else fail "query message: $(cat "$WORK/q.err")"; fi
  printf '0 1 zero\n' >"$WORK/word.txt"
  if "$QUERY" "$WORK/mannequin.drape" --points "$WORK/word.txt" >/dev/null 2>"$WORK/q.err"; then
    fail "query accepted a word as a coordinate"
  elif grep -q "word.txt:1: 'zero' is not a number" "$WORK/q.err"; then passed=$((passed + 1)); else fail "query message: $(cat "$WORK/q.err")"; fi
fi
# --- configs: a number beyond a double and a key given twice are errors naming the JSON path
# (exit 1, no output), never an abort.
printf '{"maps": {"resolution": 1e400}}' >"$WORK/overflow.json"
printf '{"maps": {"resolution": 64, "resolution": 128}}' >"$WORK/twice.json"
for config in overflow twice; do
  "$BAKE" "$SOURCE/samples/mannequin/mannequin.gltf" -o "$WORK/$config.drape" --config "$WORK/$config.json" 2>"$WORK/$config.err"
  code=$?
  if [ $code -eq 1 ] && [ ! -e "$WORK/$config.drape" ] && grep -q "$config.json: /maps/resolution: " "$WORK/$config.err"; then
    passed=$((passed + 1))
  else
    fail "config $config: exit $code, $(cat "$WORK/$config.err")"
  fi
done
if "$BAKE" --dump-config | grep -q '"unit_scale"'; then passed=$((passed + 1)); else fail "--dump-config"; fi

echo "$passed passed, $failures failed"
[ $failures -eq 0 ]
