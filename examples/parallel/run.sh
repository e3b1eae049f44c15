#!/bin/bash
# A sharded calbench study on one big machine with GNU parallel, then its merge:
#   examples/parallel/run.sh SCENARIO N [JOBS]
# N shards, JOBS at a time (default: one per core), each shard with --threads 1 so that the
# shards, not the threads, share the cores; the merge writes results/NAME/, the same bytes
# as one unsharded run. The one-liner, for scenarios/ci-guard.toml in 8 shards:
#   parallel calbench run scenarios/ci-guard.toml --shard {}/8 --threads 1 --out shards/ci-guard/{} ::: $(seq 0 7) && calbench merge shards/ci-guard/{0..7} --out results/ci-guard
set -euo pipefail
SCENARIO=${1:?usage: run.sh SCENARIO N [JOBS]}
N=${2:?usage: run.sh SCENARIO N [JOBS]}
JOBS=${3:-0}
CALBENCH=${CALBENCH:-calbench}
NAME=$(basename "$SCENARIO" .toml)
parallel --halt now,fail=1 --jobs "$JOBS" \
    "$CALBENCH" run "$SCENARIO" --shard {}/"$N" --threads 1 --out "shards/$NAME/{}" \
    ::: $(seq 0 $((N - 1)))
SHARDS=()
for ((i = 0; i < N; i++)); do SHARDS+=("shards/$NAME/$i"); done
"$CALBENCH" merge "${SHARDS[@]}" --out "results/$NAME"
