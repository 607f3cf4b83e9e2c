#!/usr/bin/env bash
# The bench command: what each microsecond buys.
#   scripts/bench.sh              speed against error on the built-in mannequin and every shared
#                                 character present: out/bench/speed_vs_error.{csv,md,png}
#   scripts/bench.sh --quick      the reduced sweep, fewer motions (about a minute)
#   scripts/bench.sh --gbench     also every Google Benchmark program (bench_*), output in
#                                 out/bench/gbench/*.json
#   scripts/bench.sh --gbench-only NAME...   re-runs those Google Benchmark programs alone
#                                 (bench_NAME) into an earlier full run's out/bench, each JSON
#                                 recording its own commit and date, and rewrites the document
# Then it writes out/bench/PERFORMANCE.md (scripts/performance_doc.py: docs/PERFORMANCE.md's
# shape, this run's figures, machine, command and commit) with its charts in out/bench/images/.
# Installs what is missing, builds the bench preset (Release + benchmarks), runs on two cores.
# Figures depend on the machine and its load: run it on an idle machine.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${DRAPE_JOBS:-2}
load_start=$(cut -d ' ' -f 1-3 /proc/loadavg)  # before this command's own build and runs
quick=()
gbench=0
only=()
for arg in "$@"; do
  case "$arg" in
    --quick) quick=(--quick --queries 1000) ;;
    --gbench) gbench=1 ;;
    --gbench-only) gbench=only ;;
    -*) echo "bench.sh: unknown option $arg (--quick, --gbench, --gbench-only NAME...)" >&2
        exit 2 ;;
    *) [ "$gbench" = only ] || { echo "bench.sh: $arg: a name needs --gbench-only" >&2; exit 2; }
       only+=("bench_${arg#bench_}") ;;
  esac
done
scripts/setup.sh
cmake --preset bench >/dev/null
if [ "$gbench" = only ]; then
  # One program at a time into the last full run's output; its JSON carries its commit and date.
  [ ${#only[@]} -gt 0 ] || { echo "bench.sh: --gbench-only needs program names" >&2; exit 2; }
  [ -f out/bench/run_info.txt ] || { echo "bench.sh: no earlier run in out/bench" >&2; exit 2; }
  cmake --build build-bench -j "$jobs" --target "${only[@]}"
  mkdir -p out/bench/gbench
  commit=$(git rev-parse --short HEAD)
  [ -z "$(git status --porcelain --untracked-files=no)" ] || commit="$commit with local changes"
  for b in "${only[@]}"; do
    echo "== $b"
    "build-bench/bin/$b" --benchmark_repetitions=3 --benchmark_report_aggregates_only=true \
      --benchmark_context=drape_commit="$commit" --benchmark_context=drape_date="$(date -u +%F)" \
      --benchmark_out="out/bench/gbench/$b.json" --benchmark_out_format=json
  done
  python3 scripts/performance_doc.py --out out/bench
  exit 0
fi
targets=(drape-speed-vs-error)
if [ "$gbench" = 1 ]; then
  for source in bench/gbench/*_bench.cpp; do
    name=$(basename "$source" .cpp)
    targets+=("bench_${name%_bench}")
  done
fi
cmake --build build-bench -j "$jobs" --target "${targets[@]}"

out=out/bench
mkdir -p "$out"
# What the generated document states about this run (read by scripts/performance_doc.py).
compiler=$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' build-bench/CMakeCache.txt)
{
  echo "command=scripts/bench.sh${*:+ $*}"
  echo "commit=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
  if [ -n "$(git status --porcelain --untracked-files=no 2>/dev/null)" ]; then
    echo "worktree=modified"
  else
    echo "worktree=clean"
  fi
  echo "date=$(date -u +%Y-%m-%d)"
  echo "cpu=$(sed -n 's/^model name[[:space:]]*: //p' /proc/cpuinfo | head -n 1)"
  echo "cores=$(nproc)"
  echo "compiler=$("${compiler:-c++}" --version | head -n 1)"
  echo "preset=bench (Release, -DDRAPE_BUILD_BENCH=ON)"
  echo "quick=$([ ${#quick[@]} -gt 0 ] && echo 1 || echo 0)"
  echo "gbench=$gbench"
  echo "omp=OMP_PROC_BIND=${OMP_PROC_BIND:-close} OMP_WAIT_POLICY=${OMP_WAIT_POLICY:-(default)}"
  echo "load_start=$load_start"
} >"$out/run_info.txt"

# --check holds every setting to its accuracy claims (the body-map targets of the people, the
# hulls' own surfaces, the exact peer, the moving sets' start clearance); a failure is reported
# at the end, after the figures are written.
checks=0
OMP_PROC_BIND=${OMP_PROC_BIND:-close} build-bench/bin/drape-speed-vs-error --out "$out" \
  --character all --check "${quick[@]}" || checks=$?
if [ "$gbench" = 1 ]; then
  mkdir -p "$out/gbench"
  rm -f "$out"/gbench/*.json
  for b in "${targets[@]:1}"; do
    echo "== $b"
    "build-bench/bin/$b" --benchmark_repetitions=3 --benchmark_report_aggregates_only=true \
      --benchmark_out="$out/gbench/$b.json" --benchmark_out_format=json
  done
fi
echo "load_end=$(cut -d ' ' -f 1-3 /proc/loadavg)" >>"$out/run_info.txt"

python3 scripts/performance_doc.py --out "$out"
echo
echo "bench: $out/speed_vs_error.csv (every row), $out/speed_vs_error.md (tables, targets),"
echo "       $out/speed_vs_error.png (chart of the first character; one per character beside it),"
echo "       $out/PERFORMANCE.md (the current state, with its charts in $out/images/)."
echo "To adopt this run's figures (an idle machine, the full sweep with --gbench):"
echo "  cp $out/PERFORMANCE.md docs/ && cp $out/images/*.png docs/images/"
if [ "$checks" != 0 ]; then
  echo "bench: drape-speed-vs-error --check FAILED (exit $checks): see its output above" >&2
  exit "$checks"
fi
