#!/bin/bash
# Submits a sharded calbench study and its merge: examples/slurm/submit.sh SCENARIO N
# (from the project root, after `cargo build --release`).
set -euo pipefail
SCENARIO=${1:?usage: submit.sh SCENARIO N}
N=${2:?usage: submit.sh SCENARIO N}
export SCENARIO N
ARRAY=$(sbatch --parsable --array=0-$((N - 1)) --export=ALL examples/slurm/run-shards.sbatch)
sbatch --dependency=afterok:"$ARRAY" --export=ALL examples/slurm/merge.sbatch
