#!/usr/bin/env bash
# Builds the libFuzzer targets with clang and runs each for a bounded time over its committed
# seed corpus (tests/fuzz/corpus/<name>/). New inputs go to a scratch copy, not the repository.
#   scripts/fuzz.sh [SECONDS_PER_TARGET]   (default 60)
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
cmake -S tests/fuzz -B build-fuzz -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build-fuzz -j "${DRAPE_JOBS:-2}" >/dev/null
status=0
for pair in asset_decode:asset bake_config:config scene_parse:scene; do
  name=${pair%%:*} seeds=tests/fuzz/corpus/${pair##*:}
  corpus=$(mktemp -d)
  cp "$seeds"/* "$corpus"/
  echo "fuzz: $name for ${seconds}s"
  if ! build-fuzz/fuzz_$name -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 \
      -artifact_prefix="build-fuzz/crash-$name-" "$corpus" 2>build-fuzz/$name.log; then
    echo "fuzz: $name FAILED; see build-fuzz/$name.log and build-fuzz/crash-$name-*"
    tail -30 build-fuzz/$name.log
    status=1
  else
    grep -E "^Done|stat::number_of_executed_units" build-fuzz/$name.log | tail -1 || true
  fi
  rm -rf "$corpus"
done
exit $status
