#!/usr/bin/env bash
# Head-to-head speed against scipy, in one sitting: runs the 1000-trial study PEER/h2h.toml
# with `calbench run --threads 1`, then PEER/scipy_ref.py (scipy least_squares, LM, analytic
# Jacobian, same problem shape), and prints the seconds per identification of each and their
# ratio. Needs a Python with numpy and scipy (PYTHON, default the venv the acceptance checks
# create); nothing else in the project, and no test, needs Python.
#
# usage: benches/scipy_ratio.sh [PEER_DIR (default ../shared/peer)] [PYTHON]
set -euo pipefail
cd "$(dirname "$0")/.."
peer=${1:-../shared/peer}
py=${2:-/tmp/calbench-peer-venv/bin/python}
[ -f "$peer/h2h.toml" ] && [ -f "$peer/scipy_ref.py" ] || { echo "no h2h.toml / scipy_ref.py in $peer" >&2; exit 2; }
"$py" -c "import numpy, scipy" 2>/dev/null || { echo "$py lacks numpy/scipy (python3 -m venv DIR && DIR/bin/pip install numpy scipy)" >&2; exit 2; }
cargo build --release --quiet
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
target/release/calbench run "$peer/h2h.toml" --threads 1 --out "$out/h2h" >/dev/null
OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$py" "$peer/scipy_ref.py" 100 >"$out/scipy.txt"
python3 - "$out/h2h/timing.json" "$out/scipy.txt" <<'PY'
import json, sys
t = {r["method"]: r["seconds_per_identification"] for r in json.load(open(sys.argv[1]))["results"]}
scipy = next(float(l.split()[1]) for l in open(sys.argv[2]) if l.startswith("scipy_lm_s_per_identification"))
print(f"scipy least_squares lm: {scipy * 1e3:.3f} ms per identification")
for m, s in t.items():
    print(f"calbench {m}: {s * 1e3:.4f} ms ({scipy / s:.1f}x faster than scipy)")
print(f"igg3 / ls time: {t['igg3'] / t['ls']:.2f}")
PY
