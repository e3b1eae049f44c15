#!/usr/bin/env bash
# Qiao 2021 fig. 7: ten BAS-PSO identifications of each of Qiao's three pose-error models on
# one data set (trial 0 of scenarios/qiao2021-tx60.toml), differing only in the search's seed.
# Prints, per model, the validation position error after compensation (mean over the 30
# validation poses, mm: Qiao's APE) of each run and its spread, and writes them to
# OUT/fig7.csv. Every run spends the same budget, 60 000 fitness evaluations.
#
# usage: examples/qiao-fig7/run.sh [OUT (default /tmp/qiao-fig7)] [RUNS (default 10)]
set -euo pipefail
cd "$(dirname "$0")/../.."
out=${1:-/tmp/qiao-fig7}
runs=${2:-10}
bin=${CALBENCH:-target/release/calbench}
[ -x "$bin" ] || cargo build --release --quiet
rm -rf "$out"
mkdir -p "$out"
"$bin" simulate scenarios/qiao2021-tx60.toml --trial 0 --out "$out/data" >/dev/null
echo "model,seed,ape_mm,evaluations" >"$out/fig7.csv"
for model in differential coordinate_transfer direct_fk; do
    set_model=()
    # Model 3 is the search on the forward kinematics, bas-pso's own fitness.
    [ "$model" = direct_fk ] || set_model=(--set "error_model=\"$model\"")
    for seed in $(seq 1 "$runs"); do
        dir="$out/$model-$seed"
        "$bin" identify --robot tx60 --data "$out/data/measurements.csv" \
            --validate "$out/data/validation.csv" --method bas-pso \
            --set max_evaluations=60000 "${set_model[@]}" --seed "$seed" --out "$dir" >/dev/null
        python3 - "$dir/identified.json" "$model" "$seed" >>"$out/fig7.csv" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
print(f"{sys.argv[2]},{sys.argv[3]},{d['validation_after_mm']['mean']:.6f},{d['evaluations']}")
PY
    done
done
python3 - "$out/fig7.csv" <<'PY'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print("| model | runs | APE mean mm | min | max | std |")
print("|---|--:|--:|--:|--:|--:|")
for m in ("differential", "coordinate_transfer", "direct_fk"):
    v = [float(r["ape_mm"]) for r in rows if r["model"] == m]
    sd = statistics.pstdev(v) if len(v) > 1 else 0.0
    print(f"| {m} | {len(v)} | {statistics.mean(v):.4f} | {min(v):.4f} | {max(v):.4f} | {sd:.5f} |")
PY
