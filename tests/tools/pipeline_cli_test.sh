#!/usr/bin/env bash
# drape-bake as a build action: --depfile names the output and every file the bake read (a
# glTF's external buffer, the config), in Makefile syntax; the output bytes depend on the
# declared inputs only (not the working directory, absolute paths, time zone, locale or user);
# a failed bake leaves no depfile behind.
set -u
BAKE=$1 SOURCE=$2
. "$(dirname "$0")/cli_test_lib.sh"

# The mannequin with its buffer in an external .bin, in a directory whose name has a space.
mkdir -p "$WORK/first dir" "$WORK/second" "$WORK/elsewhere"
external_buffer_mannequin "$SOURCE" "$WORK/first dir"
echo '{"maps": {"resolution": 128}}' >"$WORK/first dir/bake.json"

# --- The dependency file, from a relative invocation.
(cd "$WORK" && "$BAKE" "first dir/mannequin.gltf" -o out.drape --config "first dir/bake.json" \
  --depfile out.d 2>/dev/null) || fail "bake with --depfile failed"
expected=$(printf 'out.drape: \\\n  first\\ dir/mannequin.gltf \\\n  first\\ dir/mannequin.bin \\\n  first\\ dir/bake.json')
if [ "$(cat "$WORK/out.d" 2>/dev/null)" = "$expected" ]; then pass; else
  fail "depfile differs: got [$(cat "$WORK/out.d" 2>/dev/null)] expected [$expected]"
fi

# --- Hermetic: the same inputs copied elsewhere, absolute paths, another working directory,
# time zone, locale and user name give the same bytes.
cp "$WORK/first dir/"* "$WORK/second/"
(cd "$WORK/elsewhere" && TZ=Pacific/Chatham LANG=de_DE.UTF-8 LC_ALL=de_DE.UTF-8 USER=someone \
  HOME=/nonexistent "$BAKE" "$WORK/second/mannequin.gltf" -o "$WORK/elsewhere/copy.drape" \
  --config "$WORK/second/bake.json" 2>/dev/null) || fail "bake of the copy failed"
if cmp -s "$WORK/out.drape" "$WORK/elsewhere/copy.drape"; then pass; else
  fail "the copied inputs baked from elsewhere gave different bytes"
fi

# --- OpenMP's threads wait passively unless the caller chose (the bake report says how).
(cd "$WORK" && env -u OMP_WAIT_POLICY "$BAKE" "first dir/mannequin.gltf" -o w.drape \
  --config "first dir/bake.json" --report w.json 2>/dev/null)
check python3 -c "import json,sys; assert json.load(open(sys.argv[1]))['openmp_wait_policy'] == 'passive'" "$WORK/w.json"
(cd "$WORK" && OMP_WAIT_POLICY=active "$BAKE" "first dir/mannequin.gltf" -o w.drape \
  --config "first dir/bake.json" --report w.json 2>/dev/null)
check python3 -c "import json,sys; assert json.load(open(sys.argv[1]))['openmp_wait_policy'] == 'active'" "$WORK/w.json"

# --- A failing bake writes no depfile.
echo 'not json' >"$WORK/bad.json"
if (cd "$WORK" && "$BAKE" "first dir/mannequin.gltf" -o bad.drape --config bad.json \
  --depfile bad.d 2>/dev/null); then fail "a bad config baked"; fi
if [ -e "$WORK/bad.d" ] || [ -e "$WORK/bad.drape" ]; then fail "a failed bake left a depfile or asset"; else pass; fi

finish pipeline_cli_test
