#!/usr/bin/env bash
# drape-bake --batch: every item baked in its own process, a failing item named with its reason
# while the others are kept, the exit code saying whether any failed, one summary report; a bad
# manifest bakes nothing and names the manifest, the item and the reason.
set -u
BAKE=$1 SOURCE=$2
. "$(dirname "$0")/cli_test_lib.sh"
MANNEQUIN="$SOURCE/samples/mannequin/mannequin.gltf"
echo '{"maps": {"resolution": 128}}' >"$WORK/bake.json"
echo "garbage" >"$WORK/broken.fbx"
cat >"$WORK/manifest.json" <<JSON
{"items": [
  {"input": "$MANNEQUIN", "output": "out/a.drape", "config": "bake.json", "report": "out/a.json"},
  {"input": "broken.fbx", "output": "out/broken.drape"},
  {"input": "$MANNEQUIN", "output": "out/b.drape", "config": "bake.json", "depfile": "out/b.d"}
]}
JSON
"$BAKE" --batch "$WORK/manifest.json" -j 2 --report "$WORK/summary.json" >"$WORK/stdout" 2>"$WORK/stderr"
check [ $? -eq 1 ]
check [ -s "$WORK/out/a.drape" ]
check [ -s "$WORK/out/b.drape" ]
check [ -s "$WORK/out/a.json" ]
check [ -s "$WORK/out/b.d" ]
check [ ! -e "$WORK/out/broken.drape" ]
check cmp -s "$WORK/out/a.drape" "$WORK/out/b.drape"  # the same inputs, two processes
check grep -q "broken.fbx: FAILED: .*broken.fbx.*unsupported or corrupt" "$WORK/stdout"
check grep -q "batch: 2 baked, 1 failed" "$WORK/stdout"
check python3 - "$WORK/summary.json" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
assert s["baked"] == 2 and s["failed"] == 1, s
bad = [i for i in s["items"] if i["status"] == "failed"]
assert len(bad) == 1 and bad[0]["input"].endswith("broken.fbx") and "broken.fbx" in bad[0]["error"], bad
PY

# All good: exit 0.
cat >"$WORK/good.json" <<JSON
{"items": [{"input": "$MANNEQUIN", "output": "good/a.drape", "config": "bake.json"}]}
JSON
"$BAKE" --batch "$WORK/good.json" >/dev/null 2>&1
check [ $? -eq 0 ]

# A bad manifest: one line naming it, the item and the reason; nothing baked.
cat >"$WORK/typo.json" <<JSON
{"items": [{"input": "$MANNEQUIN", "output": "typo/a.drape"}, {"input": "x.glb", "ouptut": "y"}]}
JSON
"$BAKE" --batch "$WORK/typo.json" >/dev/null 2>"$WORK/typo.err"
check [ $? -eq 1 ]
check grep -q "typo.json: /items/1/ouptut: unknown key" "$WORK/typo.err"
check [ ! -e "$WORK/typo/a.drape" ]
echo '{"items": [{"input": "a.glb", "output": "same.drape"}, {"input": "b.glb", "output": "same.drape"}]}' >"$WORK/twice.json"
"$BAKE" --batch "$WORK/twice.json" >/dev/null 2>"$WORK/twice.err"
check grep -q "also the output of /items/0" "$WORK/twice.err"
"$BAKE" --batch "$WORK/good.json" "$MANNEQUIN" >/dev/null 2>"$WORK/mixed.err"
check grep -q "takes its inputs" "$WORK/mixed.err"

finish batch_cli_test
