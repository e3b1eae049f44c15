#!/usr/bin/env bash
# Identification speed against scipy, in one sitting: runs the 1000-trial study
# benches/h2h.toml with `calbench run --threads 1`, then benches/scipy_ref.py (scipy's
# least_squares, Levenberg-Marquardt, analytic Jacobian, the same problem shape), and prints
# the time per identification of each and the ratios. The machine's speed drifts: only the
# ratio of one sitting means something.
#
# usage: benches/scipy_ratio.sh [PYTHON]
#   PYTHON   a Python with numpy and scipy (default: $PYTHON, else python3);
#            e.g. python3 -m venv /tmp/sp && /tmp/sp/bin/pip install numpy scipy
#   CALBENCH=path  use that calbench binary instead of building target/release/calbench
#   SCIPY_TRIALS=n scipy fits to time (default 100)
# Exits 2, before any work, when the Python, numpy or scipy is missing. Nothing else in the
# project needs Python.
set -euo pipefail
cd "$(dirname "$0")/.."
py=${1:-${PYTHON:-python3}}
command -v "$py" >/dev/null 2>&1 || { echo "scipy_ratio.sh: Python not found: $py (give a Python with numpy and scipy as the argument or in \$PYTHON)" >&2; exit 2; }
"$py" -c "import numpy, scipy" >/dev/null 2>&1 || { echo "scipy_ratio.sh: $py lacks numpy/scipy (python3 -m venv DIR && DIR/bin/pip install numpy scipy)" >&2; exit 2; }
if [ -n "${CALBENCH:-}" ]; then
    bin=$CALBENCH
else
    cargo build --release --quiet
    bin=target/release/calbench
fi
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
"$bin" run benches/h2h.toml --threads 1 --out "$out/h2h" >/dev/null
"$py" benches/scipy_ref.py "${SCIPY_TRIALS:-100}" >"$out/scipy.txt"
"$py" - "$out/h2h/timing.json" "$out/scipy.txt" <<'PY'
import json, sys
t = {r["method"]: r["seconds_per_identification"] for r in json.load(open(sys.argv[1]))["results"]}
ref = dict(l.split(maxsplit=1) for l in open(sys.argv[2]) if l.strip())
scipy = float(ref["scipy_lm_s_per_identification"])
print(f"scipy least_squares lm: {scipy * 1e3:.3f} ms per identification "
      f"({ref['params'].split()[0]} parameters, validation RMS {float(ref['scipy_val_rms_after_mm']):.4f} mm)")
for m, s in t.items():
    print(f"calbench {m}: {s * 1e3:.4f} ms ({scipy / s:.1f}x faster than scipy)")
print(f"igg3 / ls time: {t['igg3'] / t['ls']:.2f}")
PY
