#!/usr/bin/env bash
# The README's test command: installs what is missing, builds and runs every test.
#  1. the full build (bake + runtime + tools) and its tests;
#  2. formats + runtime alone with -DDRAPE_BUILD_BAKE=OFF: the libraries and tools build and their
#     link lines name no assimp, CGAL or OSMesa (their tests run in 1 with the same flags, and
#     in 4 in a -DDRAPE_BUILD_BAKE=OFF build under sanitizers);
#  3. cmake --install of that build, and a tiny consumer that find_package(drape)s it;
#  4. formats + runtime tests again (what an engine links and feeds untrusted .drape files),
#     under AddressSanitizer + UndefinedBehaviorSanitizer, built with clang (stage 1 builds with
#     the system's gcc, so both compilers build the runtime with warnings as errors, and clang's
#     UBSan also checks float-to-integer casts) and without OpenMP
#     (-DDRAPE_OPENMP=OFF: an engine that links no libgomp; the loops run on the calling thread)
#     and checked to link no libgomp; the bad-model corpus through drape-bake runs in stage 1
#     (the model reader runs in a child process there);
#  5. each libFuzzer target over its seed corpus, reproducibly: a fixed seed and 100 000 inputs
#     (DRAPE_FUZZ_RUNS; scripts/fuzz.sh alone runs a million, or explores with a random seed).
set -uo pipefail
cd "$(dirname "$0")/.."
root=$(pwd)
jobs=${DRAPE_JOBS:-2}
scripts/setup.sh || exit 1

total_passed=0 total_failed=0
run_ctest() {  # build dir; adds to the totals
  local log
  log=$(mktemp)
  (cd "$1" && ctest --output-on-failure -j "$jobs" --timeout 900) | tee "$log"
  local line
  line=$(grep -E "tests passed, [0-9]+ tests failed out of" "$log" | tail -1)
  local failed total
  failed=$(echo "$line" | sed -E 's/.* ([0-9]+) tests failed out of ([0-9]+).*/\1/')
  total=$(echo "$line" | sed -E 's/.* out of ([0-9]+).*/\1/')
  if [ -z "$line" ]; then failed=1 total=1; fi
  total_passed=$((total_passed + total - failed))
  total_failed=$((total_failed + failed))
  rm -f "$log"
}
check() {  # name, command...: one pass/fail step of this script
  local name=$1
  shift
  if "$@"; then
    echo "check passed: $name"
    total_passed=$((total_passed + 1))
  else
    echo "check FAILED: $name"
    total_failed=$((total_failed + 1))
  fi
}

# Each stage's wall time, printed when the next one starts: where the command's minutes go.
stage_start=$SECONDS
stage() {
  echo "(previous stage: $((SECONDS - stage_start)) s)"
  stage_start=$SECONDS
  echo "== $1"
}

echo "== 1. full build"
cmake --preset test >/dev/null && cmake --build build -j "$jobs" || { echo "tests: 0 passed, 1 failed"; exit 1; }
run_ctest build

stage "2. runtime alone (-DDRAPE_BUILD_BAKE=OFF)"
cmake --preset runtime-only >/dev/null &&
  cmake --build build-runtime -j "$jobs" --target drape_formats drape_runtime drape-inspect \
    drape-query ||
  { echo "tests: $total_passed passed, $((total_failed + 1)) failed"; exit 1; }
no_bake_in_link_lines() {
  local hits
  hits=$(grep -rliE "assimp|CGAL|OSMesa|libgmp|libmpfr" build-runtime/formats build-runtime/runtime \
    --include=link.txt 2>/dev/null)
  if [ -n "$hits" ]; then echo "bake libraries on runtime link lines: $hits"; return 1; fi
  if grep -qiE "^(assimp|CGAL|Eigen3)_DIR:PATH=/" build-runtime/CMakeCache.txt; then
    echo "the runtime-only configure looked for bake packages"; return 1
  fi
  ! ldd build-runtime/bin/drape-inspect | grep -qiE "assimp|CGAL|OSMesa|gmp|mpfr"
}
check "runtime link lines name no assimp, CGAL or OSMesa" no_bake_in_link_lines

stage "3. install and find_package(drape) from a consumer"
install_consumer() {
  local prefix consumer
  prefix=$(mktemp -d) consumer=$(mktemp -d)
  cmake --install build-runtime --prefix "$prefix" >/dev/null &&
    cmake -S tests/install_consumer -B "$consumer" -DCMAKE_PREFIX_PATH="$prefix" >/dev/null &&
    cmake --build "$consumer" -j "$jobs" >/dev/null &&
    "$consumer/consumer" "$root/tests/golden/mannequin_v1.drape" &&
    "$consumer/consumer_c" "$root/tests/golden/mannequin_v1.drape"
  local rc=$?
  rm -rf "$prefix" "$consumer"
  return $rc
}
check "installed drape::runtime links into a C++ and a C consumer" install_consumer

stage "4. formats + runtime tests under ASan + UBSan, built with clang, without OpenMP"
if cmake --preset sanitize >/dev/null && cmake --build build-sanitize -j "$jobs"; then
  ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 \
    UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1:suppressions=$root/tests/tools/ubsan_suppressions.txt \
    LSAN_OPTIONS=suppressions=$root/tests/tools/lsan_suppressions.txt run_ctest build-sanitize
  check "the runtime built without OpenMP links no libgomp" \
    bash -c '! ldd build-sanitize/bin/drape-inspect | grep -q libgomp'
else
  check "sanitizer build" false
fi

stage "5. fuzzing"
fuzz_runs=${DRAPE_FUZZ_RUNS:-100000}
check "fuzz targets run clean (fixed seed, $fuzz_runs inputs each)" \
  env DRAPE_FUZZ_RUNS="$fuzz_runs" scripts/fuzz.sh "${DRAPE_FUZZ_SECONDS:-60}"

echo "(previous stage: $((SECONDS - stage_start)) s; all stages: $SECONDS s)"
echo "tests: $total_passed passed, $total_failed failed"
[ "$total_failed" -eq 0 ]
