#!/usr/bin/env bash
# Qiao 2021 fig. 7: ten BAS-PSO identifications of each of Qiao's three pose-error models on
# one data set (trial 0 of scenarios/qiao2021-tx60.toml), differing only in the search's seed.
# Prints, per model, the validation position error after compensation (mean over the 30
# validation poses, mm: Qiao's APE) of each run and its spread, and the mean attitude error
# (Qiao's AAE, deg), and writes them to OUT/fig7.csv. Every run spends the same budget,
# 60 000 fitness evaluations.
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
# The scenario's registration is `known` (Qiao measures in the base frame built beforehand):
# the tracker's readings are brought into the base frame with the trial's tracker pose
# (truth.json; x, y, z mm and fixed X-Y-Z angles in degrees), and identified as they are.
python3 - "$out/data" <<'PY'
import csv, json, math, sys
d = sys.argv[1]
x, y, z, rx, ry, rz = json.load(open(f"{d}/truth.json"))["tracker_pose"]
def axis(a, i):
    h = math.radians(a) / 2
    q = [math.cos(h), 0.0, 0.0, 0.0]
    q[1 + i] = math.sin(h)
    return q
def mul(a, b):
    return [a[0]*b[0] - a[1]*b[1] - a[2]*b[2] - a[3]*b[3],
            a[0]*b[1] + a[1]*b[0] + a[2]*b[3] - a[3]*b[2],
            a[0]*b[2] - a[1]*b[3] + a[2]*b[0] + a[3]*b[1],
            a[0]*b[3] + a[1]*b[2] - a[2]*b[1] + a[3]*b[0]]
def rotate(q, v):
    w = mul(mul(q, [0.0] + v), [q[0], -q[1], -q[2], -q[3]])
    return w[1:]
t = mul(axis(rz, 2), mul(axis(ry, 1), axis(rx, 0)))  # R = Rz Ry Rx
for name in ("measurements.csv", "validation.csv"):
    rows = list(csv.DictReader(open(f"{d}/{name}")))
    with open(f"{d}/base-{name}", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            p = rotate(t, [float(r[k]) for k in "xyz"])
            r.update({k: f"{v + o:.9f}" for k, v, o in zip("xyz", p, (x, y, z))})
            if "qw" in r:
                q = mul(t, [float(r[k]) for k in ("qw", "qx", "qy", "qz")])
                r.update({k: f"{v:.12f}" for k, v in zip(("qw", "qx", "qy", "qz"), q)})
            w.writerow(r)
PY
echo "model,seed,ape_mm,aae_deg,evaluations" >"$out/fig7.csv"
# Qiao's 24 parameters (§3.2), the scenario's [errors] params.
qiao24=$(sed -n 's/^params = \[\(.*\)\]$/\1/p' scenarios/qiao2021-tx60.toml | head -1 | tr -d '" ')
for model in differential coordinate_transfer direct_fk; do
    set_model=()
    # Model 3 is the search on the forward kinematics, bas-pso's own fitness.
    [ "$model" = direct_fk ] || set_model=(--set "error_model=\"$model\"")
    for seed in $(seq 1 "$runs"); do
        dir="$out/$model-$seed"
        "$bin" identify --robot tx60-floor --data "$out/data/base-measurements.csv" \
            --validate "$out/data/base-validation.csv" --registration known \
            --params "$qiao24" --method bas-pso \
            --set max_evaluations=60000 "${set_model[@]}" --seed "$seed" --out "$dir" >/dev/null
        python3 - "$dir/identified.json" "$model" "$seed" >>"$out/fig7.csv" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
print(f"{sys.argv[2]},{sys.argv[3]},{d['validation_after_mm']['mean']:.6f},"
      f"{d['validation_after_attitude_deg']['mean']:.6f},{d['evaluations']}")
PY
    done
done
python3 - "$out/fig7.csv" <<'PY'
import csv, statistics, sys
rows = list(csv.DictReader(open(sys.argv[1])))
print("| model | runs | APE mean mm | min | max | std | AAE mean deg |")
print("|---|--:|--:|--:|--:|--:|--:|")
for m in ("differential", "coordinate_transfer", "direct_fk"):
    v = [float(r["ape_mm"]) for r in rows if r["model"] == m]
    a = [float(r["aae_deg"]) for r in rows if r["model"] == m]
    sd = statistics.pstdev(v) if len(v) > 1 else 0.0
    print(f"| {m} | {len(v)} | {statistics.mean(v):.4f} | {min(v):.4f} | {max(v):.4f} | {sd:.5f} "
          f"| {statistics.mean(a):.4f} |")
PY
