#!/usr/bin/env bash
# The bake in an asset build: drape's package installed, drape_add_bake under Ninja.
#  - a project baking two characters builds, then has no work to do;
#  - touching the external buffer of one (a file only its dependency file names) plans exactly
#    that character's bake;
#  - samples/pipeline (the sample a studio copies) configures, builds, exports glTF views the
#    Khronos validator passes, and passes its golden test (drape-diff) against the install.
# Usage: pipeline_sample_test.sh CMAKE BUILD_DIR SOURCE_DIR SHARED_DIR NODE_DIR
set -u
CMAKE=$1 BUILD=$2 SOURCE=$3 SHARED=$4 NODE_DIR=$5
. "$(dirname "$0")/cli_test_lib.sh"
command -v ninja >/dev/null || { echo "FAIL: ninja is not installed (scripts/setup.sh installs ninja-build)"; exit 1; }

"$CMAKE" --install "$BUILD" --prefix "$WORK/prefix" >/dev/null || { echo "FAIL: install"; exit 1; }

# Two characters: the mannequin with its buffer in an external .bin, and the built-in one.
mkdir -p "$WORK/assets/external"
external_buffer_mannequin "$SOURCE" "$WORK/assets/external"
cat >"$WORK/assets/CMakeLists.txt" <<CM
cmake_minimum_required(VERSION 3.22)
project(asset_build NONE)
find_package(drape 0.1 REQUIRED)
drape_add_bake(TARGET external INPUT external/mannequin.gltf OUTPUT external.drape)
drape_add_bake(TARGET builtin INPUT "$SOURCE/samples/mannequin/mannequin.gltf" OUTPUT builtin.drape
               REPORT builtin.json)
CM
plan() { ninja -C "$WORK/build" -n 2>&1 | grep "drape-bake " || true; }
if "$CMAKE" -S "$WORK/assets" -B "$WORK/build" -G Ninja -DCMAKE_PREFIX_PATH="$WORK/prefix" >/dev/null &&
  ninja -C "$WORK/build" >"$WORK/build.log" 2>&1; then
  pass
else
  fail "the asset build failed: $(tail -5 "$WORK/build.log" 2>/dev/null)"
fi
[ -s "$WORK/build/external.drape" ] && [ -s "$WORK/build/builtin.drape" ] && [ -s "$WORK/build/builtin.json" ] &&
  pass || fail "the assets or the report are missing"
[ -z "$(plan)" ] && pass || fail "a fresh build still plans: $(plan)"
touch "$WORK/assets/external/mannequin.bin"
planned=$(plan)
if [ "$(echo "$planned" | grep -c 'drape-bake')" -eq 1 ] && echo "$planned" | grep -q "drape-bake external"; then
  pass
else
  fail "touching external/mannequin.bin should plan the external bake alone; the plan: $planned"
fi
ninja -C "$WORK/build" >/dev/null 2>&1 && [ -z "$(plan)" ] && pass || fail "the re-bake did not settle"

# The sample project, with the smallest shared character when the shared folder is there.
if "$CMAKE" -S "$SOURCE/samples/pipeline" -B "$WORK/sample" -G Ninja -DCMAKE_PREFIX_PATH="$WORK/prefix" \
  -DDRAPE_SHARED_DIR="$SHARED" -DDRAPE_PIPELINE_CHARACTERS=RiggedSimple >/dev/null &&
  ninja -C "$WORK/sample" >"$WORK/sample.log" 2>&1 && [ -s "$WORK/sample/assets/mannequin.drape" ]; then
  pass
else
  fail "samples/pipeline did not build: $(tail -5 "$WORK/sample.log" 2>/dev/null)"
fi
# Its glTF views pass the Khronos validator (when scripts/setup.sh installed it).
if [ -f "$NODE_DIR/node_modules/gltf-validator/package.json" ]; then
  NODE_PATH="$NODE_DIR/node_modules" node "$SOURCE/tests/tools/validate_gltf.js" "$WORK"/sample/views/*.glb \
    >"$WORK/views.txt" 2>&1 && pass || fail "the sample's glTF views: $(cat "$WORK/views.txt")"
else
  fail "the glTF validator is not installed in $NODE_DIR (scripts/setup.sh installs it)"
fi
# Its golden test, through the installed drape-diff.
if (cd "$WORK/sample" && ctest --output-on-failure >"$WORK/golden.log" 2>&1); then pass; else
  fail "samples/pipeline's golden test failed: $(tail -8 "$WORK/golden.log")"
fi

finish pipeline_sample_test
