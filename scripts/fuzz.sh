#!/usr/bin/env bash
# Builds the libFuzzer targets with clang and runs each over its committed seed corpus
# (tests/fuzz/corpus/<name>/). New inputs go to a scratch copy, not the repository.
#   scripts/fuzz.sh [SECONDS_PER_TARGET]   (default 60)
# By default the run is reproducible: a fixed seed (DRAPE_FUZZ_SEED, default 1) and a fixed
# number of inputs (DRAPE_FUZZ_RUNS, default 1e6, one to two minutes per target here), capped at
# twice SECONDS_PER_TARGET. A slower machine then tests a prefix of the same inputs, so the test
# command cannot turn red by luck; every crash found is added to the corpus as a regression.
# DRAPE_FUZZ_SEED=0 DRAPE_FUZZ_RUNS=-1 explores with a random seed for SECONDS_PER_TARGET.
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-60}
seed=${DRAPE_FUZZ_SEED:-1}
runs=${DRAPE_FUZZ_RUNS:-1000000}
limit=$((seconds * 2))
[ "$runs" = "-1" ] && limit=$seconds
cmake -S tests/fuzz -B build-fuzz -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=RelWithDebInfo >/dev/null
cmake --build build-fuzz -j "${DRAPE_JOBS:-2}" >/dev/null
status=0
for pair in asset_decode:asset bake_config:config scene_parse:scene; do
  name=${pair%%:*} seeds=tests/fuzz/corpus/${pair##*:}
  corpus=$(mktemp -d)
  cp "$seeds"/* "$corpus"/
  echo "fuzz: $name, seed $seed, $runs inputs at most, ${limit}s at most"
  if ! build-fuzz/fuzz_$name -seed="$seed" -runs="$runs" -max_total_time="$limit" -rss_limit_mb=2048 -timeout=10 \
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
