#!/usr/bin/env bash
# drape-sim contract: a scene bakes once and is cached (the cache is keyed by the character's bytes
# and the effective bake configuration), simulates without NaN and with contacts, writes frames,
# an animation or contact sheet, OBJ files and stats.json, gives bit-identical cloth at 1 and 2
# threads, and a bad scene fails with one stderr line naming the file and the JSON path.
# Usage: sim_cli_test.sh DRAPE_SIM SOURCE_DIR
set -u
SIM=$1 SOURCE=$2
WORK=$(mktemp -d)
trap 'rm -rf "$WORK"' EXIT
failures=0 passed=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }
pass() { passed=$((passed + 1)); }

MANNEQUIN="$SOURCE/samples/mannequin/mannequin.gltf"
# The demo scene, small: 96 px pictures of every 3rd frame, OBJ output.
write_scene() {  # write_scene FILE HULL_DELTA GARMENT_TYPE JOINT [TOP_RADIUS]
  cat >"$1" <<JSON
{
  "character": "$MANNEQUIN",
  "bake": {"hulls": {"delta": $2}},
  "animation": {"clip": "walk", "start": 0.0, "duration": 3.0, "settle": 0.5},
  "garments": [{
    "name": "skirt", "type": "$3", "anchor": "hips",
    "shape": {"top_center": [0, 0.03, 0], "top_radius": ${5:-0.185}, "bottom_radius": 0.34,
              "length": 0.42, "segments": 64, "rings": 24},
    "attach": {"joint": "$4", "ring": "waist"}
  }],
  "collision": {"methods": ["hulls", "spheres"], "passes": 4},
  "solver": {"dt": 0.0166667, "substeps": 4, "iterations": 5, "friction": 0.3, "separation": 0.002},
  "output": {"every": 3, "width": 96, "height": 96, "obj": true}
}
JSON
}

# json_number FILE KEY: the first "KEY": <number> in a JSON file.
json_number() { grep -o "\"$2\": *[-0-9.e+]*" "$1" | head -1 | sed 's/.*: *//'; }
mtime() { stat -c %y "$1"; }

# --- 1. First run: bakes, simulates 12 frames, writes everything.
write_scene "$WORK/scene.json" 0.005 skirt hips
OUT="$WORK/out"
if "$SIM" "$WORK/scene.json" -o "$OUT" --frames 12 --threads 1 >"$WORK/run1.out" 2>"$WORK/run1.err"; then
  pass
else
  fail "first run exited non-zero: $(cat "$WORK/run1.err")"
fi
grep -q "drape-sim: baked" "$WORK/run1.out" && pass || fail "first run did not report a bake: $(cat "$WORK/run1.out")"
# Pictures are named by the simulation frame they show: 0, 3, 6, 9.
for k in 0 3 6 9; do
  f=$(printf "%s/frames/frame_%04d.png" "$OUT" "$k")
  [ -s "$f" ] && pass || fail "missing picture $f"
done
[ "$(ls "$OUT/frames" | wc -l)" -eq 4 ] && pass || fail "12 frames every 3rd should give 4 pictures: $(ls "$OUT/frames")"
head -c 8 "$OUT/frames/frame_0000.png" | od -An -c | grep -q "P   N   G" && pass || fail "frame_0000.png is not a PNG"
{ [ -s "$OUT/contact_sheet.png" ] || [ -s "$OUT/animation.mp4" ]; } && pass || fail "no animation or contact sheet"
[ -s "$OUT/obj/skirt_0009.obj" ] && [ ! -e "$OUT/obj/skirt_0001.obj" ] && pass ||
  fail "OBJ output not named by simulation frame: $(ls "$OUT/obj")"
STATS="$OUT/stats.json"
if [ -s "$STATS" ]; then
  [ "$(json_number "$STATS" nan_frames)" = "0" ] && pass || fail "stats.json reports NaN frames"
  ! grep -q '"nan": true' "$STATS" && pass || fail "a frame has NaN"
  [ "$(sed -n '/"totals"/,/}/p' "$STATS" | grep -o '"frames": *[0-9]*' | sed 's/.*: *//')" = "12" ] &&
    pass || fail "stats.json totals do not count 12 frames"
  contacts=$(json_number "$STATS" contacts_max)
  [ "${contacts:-0}" -gt 0 ] && pass || fail "no contacts in 12 frames (contacts_max=${contacts:-none})"
  [ "$(grep -c '"step_ms"' "$STATS")" = "12" ] && pass || fail "stats.json should list 12 frames"
  [ "$(grep -c '"held_inside_particles"' "$STATS")" = "12" ] && pass ||
    fail "stats.json should count the held particles inside apart, every frame"
else
  fail "stats.json missing"
fi
[ -s "$OUT/reach.json" ] && grep -q '"reachable": false' "$OUT/reach.json" && pass ||
  fail "reach.json missing or leaves nothing out (the feet are out of a skirt's reach)"

# --- 1b. A waistband drawn inside the hips: its held particles stay there (no collider moves a
# held particle); they are counted apart and named in the summary line, and the penetration
# figure is the simulated particles' alone.
write_scene "$WORK/inside.json" 0.005 skirt hips 0.09
if "$SIM" "$WORK/inside.json" -o "$WORK/inside" --frames 3 --threads 1 >"$WORK/inside.out" 2>&1; then
  held=$(json_number "$WORK/inside/stats.json" held_inside_particles_max)
  [ "${held:-0}" -gt 0 ] && pass || fail "a waistband inside the hips: held_inside_particles_max=${held:-none}"
  grep -q "held particles: up to $held inside" "$WORK/inside.out" && pass ||
    fail "the summary line does not name the held particles inside: $(cat "$WORK/inside.out")"
  inside=$(json_number "$WORK/inside/stats.json" inside_particles_max)
  [ "${inside:-64}" -lt 64 ] && pass || fail "the held ring counted as simulated particles inside (${inside:-none})"
else
  fail "waistband-inside run exited non-zero: $(cat "$WORK/inside.out")"
fi

# --- 2. Second run: the cached asset is reused (log line and unchanged file).
before=$(mtime "$OUT/character.drape")
"$SIM" "$WORK/scene.json" -o "$OUT" --frames 12 --threads 1 >"$WORK/run2.out" 2>"$WORK/run2.err" ||
  fail "second run exited non-zero: $(cat "$WORK/run2.err")"
grep -q "using the cached asset" "$WORK/run2.out" && pass || fail "second run did not reuse the cache: $(cat "$WORK/run2.out")"
[ "$(mtime "$OUT/character.drape")" = "$before" ] && pass || fail "the cached asset was rewritten"

# --- 3. Same cloth at 2 threads (bit-identical OBJ files).
"$SIM" "$WORK/scene.json" -o "$WORK/out2" --frames 12 --threads 2 >/dev/null 2>"$WORK/run3.err" ||
  fail "2-thread run exited non-zero: $(cat "$WORK/run3.err")"
cmp -s "$OUT/obj/skirt_0003.obj" "$WORK/out2/obj/skirt_0003.obj" && pass ||
  fail "cloth differs between 1 and 2 threads"

# --- 4. A changed bake parameter rebakes.
write_scene "$WORK/scene.json" 0.006 skirt hips
"$SIM" "$WORK/scene.json" -o "$OUT" --frames 3 --threads 1 >"$WORK/run4.out" 2>"$WORK/run4.err" ||
  fail "rebake run exited non-zero: $(cat "$WORK/run4.err")"
grep -q "baked.*bake configuration changed" "$WORK/run4.out" && pass ||
  fail "a changed /bake override did not rebake: $(cat "$WORK/run4.out")"

# --- 5. Bad scenes: one stderr line naming the file and the JSON path, non-zero exit.
expect_error() {  # expect_error NAME SCENE EXPECTED_TEXT
  local out="$WORK/bad_$1"
  "$SIM" "$2" -o "$out" --frames 2 --threads 1 >/dev/null 2>"$WORK/$1.err"
  local rc=$?
  if [ $rc -eq 0 ]; then fail "$1: exit 0 on a bad scene"; return; fi
  if [ "$(wc -l <"$WORK/$1.err")" -ne 1 ]; then fail "$1: expected one stderr line: $(cat "$WORK/$1.err")"; return; fi
  if ! grep -qF -- "$3" "$WORK/$1.err"; then fail "$1: message lacks '$3': $(cat "$WORK/$1.err")"; return; fi
  if [ -e "$out/stats.json" ]; then fail "$1: stats.json written for a bad scene"; return; fi
  pass
}
write_scene "$WORK/bad_type.json" 0.005 dress hips
expect_error bad_type "$WORK/bad_type.json" "$WORK/bad_type.json: /garments/0/type: 'dress' is not one of"
expect_error missing "$WORK/nowhere.json" "$WORK/nowhere.json: cannot open the scene file"
echo '{"character": ' >"$WORK/broken.json"
expect_error broken "$WORK/broken.json" "$WORK/broken.json: not valid JSON"
# An unknown joint is found once the character is loaded (from the cache of run 1's directory).
write_scene "$WORK/bad_joint.json" 0.006 skirt hipz
cp -r "$OUT" "$WORK/bad_joint_cache"
"$SIM" "$WORK/bad_joint.json" -o "$WORK/bad_joint_cache" --frames 2 --threads 1 >/dev/null 2>"$WORK/joint.err"
if [ $? -ne 0 ] && grep -qF "$WORK/bad_joint.json: /garments/0/attach/joint: no joint named 'hipz'" "$WORK/joint.err" &&
  [ "$(wc -l <"$WORK/joint.err")" -eq 1 ]; then
  pass
else
  fail "unknown joint: $(cat "$WORK/joint.err")"
fi

# A clip the character lacks: one message naming /animation/clip and the clips, whether the
# scene's maps are baked over the clip (refused by the bake) or only hulls pose it (refused once
# the cached asset is loaded).
for methods in '"hulls", "spheres"' '"maps", "hulls"'; do
  write_scene "$WORK/bad_clip.json" 0.006 skirt hips
  sed -i "s/\"clip\": \"walk\"/\"clip\": \"wlak\"/; s/\"methods\": \[[^]]*\]/\"methods\": [$methods]/" \
    "$WORK/bad_clip.json"
  rm -rf "$WORK/bad_clip_cache" && cp -r "$OUT" "$WORK/bad_clip_cache"
  "$SIM" "$WORK/bad_clip.json" -o "$WORK/bad_clip_cache" --frames 2 --threads 1 >/dev/null 2>"$WORK/clip.err"
  if [ $? -ne 0 ] && [ "$(wc -l <"$WORK/clip.err")" -eq 1 ] &&
    grep -qF "$WORK/bad_clip.json: /animation/clip: no clip named 'wlak' in '$MANNEQUIN' (clips: walk" "$WORK/clip.err"; then
    pass
  else
    fail "unknown clip with methods [$methods]: $(cat "$WORK/clip.err")"
  fi
done

# --- 6. Bad command lines: a readable range, not the range of a double.
"$SIM" "$WORK/scene.json" -o "$WORK/zero" --frames 0 >/dev/null 2>"$WORK/zero.err"
rc=$?
if [ $rc -ne 0 ] && grep -q "not in range 1 to 10000000" "$WORK/zero.err" && ! grep -q 1797 "$WORK/zero.err"; then
  pass
else
  fail "--frames 0: exit $rc, $(cat "$WORK/zero.err")"
fi

echo "sim_cli_test: $passed passed, $failures failed"
[ $failures -eq 0 ]
