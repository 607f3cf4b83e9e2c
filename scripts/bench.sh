#!/usr/bin/env bash
# The bench command: what each microsecond buys.
#   scripts/bench.sh              speed against error on the built-in mannequin and every shared
#                                 character present: out/bench/speed_vs_error.{csv,md,png}
#   scripts/bench.sh --quick      the reduced sweep, fewer motions (about a minute)
#   scripts/bench.sh --gbench     also every Google Benchmark program (bench_*), output in
#                                 out/bench/gbench/*.json
# Installs what is missing, builds the bench preset (Release + benchmarks), runs on two cores.
# Figures depend on the machine and its load: run it on an idle machine.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${DRAPE_JOBS:-2}
quick=()
gbench=0
for arg in "$@"; do
  case "$arg" in
    --quick) quick=(--quick --queries 1000) ;;
    --gbench) gbench=1 ;;
    *) echo "bench.sh: unknown option $arg (--quick, --gbench)" >&2; exit 2 ;;
  esac
done
scripts/setup.sh
cmake --preset bench >/dev/null
cmake --build build-bench -j "$jobs" --target drape-speed-vs-error
out=out/bench
mkdir -p "$out"
OMP_PROC_BIND=${OMP_PROC_BIND:-close} build-bench/bin/drape-speed-vs-error --out "$out" \
  --character all "${quick[@]}"
if [ "$gbench" = 1 ]; then
  cmake --build build-bench -j "$jobs"
  mkdir -p "$out/gbench"
  for b in build-bench/bin/bench_*; do
    name=$(basename "$b")
    echo "== $name"
    "$b" --benchmark_repetitions=3 --benchmark_report_aggregates_only=true \
      --benchmark_out="$out/gbench/$name.json" --benchmark_out_format=json
  done
fi
echo
echo "bench: $out/speed_vs_error.csv (every row), $out/speed_vs_error.md (tables, targets),"
echo "       $out/speed_vs_error.png (chart of the first character; one per character beside it)."
