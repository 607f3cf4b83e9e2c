#!/usr/bin/env bash
# drape-diff: assets compared by meaning. The same asset agrees (exit 0); a changed body-map
# offset moves texel depths and a changed hull budget changes the hulls (exit 1, lines naming
# them); a tolerance file loosens the limits; --json is JSON; a missing file or a bad tolerance
# key is one line naming it and exit 2.
set -u
BAKE=$1 DIFF=$2 SOURCE=$3
. "$(dirname "$0")/cli_test_lib.sh"
GOLDEN="$SOURCE/tests/golden/mannequin_colliders_v2.drape"
MANNEQUIN="$SOURCE/samples/mannequin/mannequin.gltf"
echo '{"maps": {"resolution": 256, "epsilon": 0.006}}' >"$WORK/offset.json"
echo '{"maps": {"resolution": 256}, "hulls": {"max_pieces": 1}}' >"$WORK/pieces.json"
"$BAKE" "$MANNEQUIN" -o "$WORK/offset.drape" --config "$WORK/offset.json" 2>/dev/null || fail "bake"
"$BAKE" "$MANNEQUIN" -o "$WORK/pieces.drape" --config "$WORK/pieces.json" 2>/dev/null || fail "bake"

"$DIFF" "$GOLDEN" "$GOLDEN" >"$WORK/same.txt"
check [ $? -eq 0 ]
check grep -q "agree within tolerance" "$WORK/same.txt"

"$DIFF" "$GOLDEN" "$WORK/offset.drape" >"$WORK/offset.txt"
check [ $? -eq 1 ]
check grep -q "body map pose 0 (rest).*texel depths moved" "$WORK/offset.txt"
check grep -q "differences beyond tolerance" "$WORK/offset.txt"
if grep -q "^hull" "$WORK/offset.txt"; then fail "a map offset moved a hull: $(cat "$WORK/offset.txt")"; else pass; fi

"$DIFF" "$GOLDEN" "$WORK/pieces.drape" >"$WORK/pieces.txt"
check [ $? -eq 1 ]
check grep -qE "^hulls: [0-9]+ vs [0-9]+" "$WORK/pieces.txt"

echo '{"map_depth_p99_mm": 50, "map_depth_max_mm": 1000, "map_coverage_pct": 5}' >"$WORK/loose.json"
"$DIFF" "$GOLDEN" "$WORK/offset.drape" --tolerance "$WORK/loose.json" >"$WORK/loose.txt"
check [ $? -eq 0 ]
"$DIFF" "$GOLDEN" "$WORK/offset.drape" --json >"$WORK/offset.json.out"
check python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert d['within_tolerance'] is False and d['findings']" "$WORK/offset.json.out"

"$DIFF" "$GOLDEN" "$WORK/missing.drape" >/dev/null 2>"$WORK/missing.err"
check [ $? -eq 2 ]
check grep -q "missing.drape" "$WORK/missing.err"
echo '{"plane_mn": 1}' >"$WORK/typo.json"
"$DIFF" "$GOLDEN" "$GOLDEN" --tolerance "$WORK/typo.json" >/dev/null 2>"$WORK/typo.err"
check [ $? -eq 2 ]
check grep -q "plane_mn" "$WORK/typo.err"

finish diff_cli_test
