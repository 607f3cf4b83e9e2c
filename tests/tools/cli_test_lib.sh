# Sourced by the command-line tests: a scratch directory removed on exit, and pass/fail counting.
#   check COMMAND...   passes when COMMAND succeeds
#   fail MESSAGE       records a failure
#   finish NAME        prints the counts and returns non-zero after any failure
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
failures=0 passed=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
pass() { passed=$((passed + 1)); }
check() { if "$@"; then pass; else fail "$*"; fi; }
finish() {
  echo "$1: $passed passed, $failures failed"
  [ "$failures" -eq 0 ]
}
# The built-in mannequin with its buffer moved to an external mannequin.bin, written to DIR.
external_buffer_mannequin() {  # SOURCE DIR
  python3 - "$1/samples/mannequin/mannequin.gltf" "$2" <<'PY'
import base64, json, sys
gltf = json.load(open(sys.argv[1]))
uri = gltf["buffers"][0]["uri"]
open(sys.argv[2] + "/mannequin.bin", "wb").write(base64.b64decode(uri.split(",", 1)[1]))
gltf["buffers"][0]["uri"] = "mannequin.bin"
json.dump(gltf, open(sys.argv[2] + "/mannequin.gltf", "w"))
PY
}
