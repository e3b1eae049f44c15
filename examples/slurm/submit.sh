#!/bin/bash
# Submits a sharded calbench study and its merge: examples/slurm/submit.sh SCENARIO N
# (from the project root, after `cargo build --release`). CPUS (default 8) is the CPUs per
# array task: a task asking for more CPUs than a node has stays pending for ever (reason
# PartitionConfig), so on small nodes say e.g. CPUS=2 examples/slurm/submit.sh SCENARIO N.
set -euo pipefail
SCENARIO=${1:?usage: [CPUS=C] submit.sh SCENARIO N}
N=${2:?usage: [CPUS=C] submit.sh SCENARIO N}
CPUS=${CPUS:-8}
export SCENARIO N
ARRAY=$(sbatch --parsable --array=0-$((N - 1)) --cpus-per-task="$CPUS" --export=ALL \
    examples/slurm/run-shards.sbatch)
sbatch --dependency=afterok:"$ARRAY" --export=ALL examples/slurm/merge.sbatch
