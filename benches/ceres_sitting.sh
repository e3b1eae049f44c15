#!/usr/bin/env bash
# Identification speed against Ceres Solver and scipy, in one sitting. The Ceres program is not
# part of this repository: PEER_DIR is a folder holding it as ceres/sitting.sh (which builds the
# Ceres program, writes its 200 data sets, then runs three alternating rounds of the Ceres
# program, PEER_DIR/scipy_ref.py 100 and `calbench run PEER_DIR/h2h.toml --threads 1`, with
# CALBENCH, PY and WORK from the environment) and ceres/summarize.py (which turns the sitting's
# log into a table of milliseconds per identification and their ratios to calbench).
#
# usage: benches/ceres_sitting.sh PEER_DIR [PYTHON]
#   PEER_DIR  required: the folder with ceres/sitting.sh, ceres/summarize.py, h2h.toml and
#             scipy_ref.py
#   PYTHON    a Python with numpy and scipy (default: $PYTHON, else python3)
#   CALBENCH=path  use that calbench binary instead of building target/release/calbench
# Needs Ceres (Debian: apt-get install -y libceres-dev g++ pkg-config). Exits 2, before any
# work, naming what is missing. Nothing else in the project needs Ceres.
set -euo pipefail
cd "$(dirname "$0")/.."
if [ $# -lt 1 ] || [ -z "$1" ]; then
    echo "ceres_sitting.sh: missing PEER_DIR, the folder with the Ceres program (ceres/sitting.sh, ceres/summarize.py, h2h.toml, scipy_ref.py); usage: benches/ceres_sitting.sh PEER_DIR [PYTHON]" >&2
    exit 2
fi
peer=$1
py=${2:-${PYTHON:-python3}}
[ -d "$peer" ] || { echo "ceres_sitting.sh: PEER_DIR $peer is not a folder" >&2; exit 2; }
missing=()
for f in ceres/sitting.sh ceres/summarize.py h2h.toml scipy_ref.py; do
    [ -f "$peer/$f" ] || missing+=("$f")
done
[ ${#missing[@]} -eq 0 ] || { echo "ceres_sitting.sh: $peer lacks ${missing[*]}" >&2; exit 2; }
[ -x "$peer/ceres/sitting.sh" ] || { echo "ceres_sitting.sh: $peer/ceres/sitting.sh is not executable" >&2; exit 2; }
peer=$(cd "$peer" && pwd)
command -v "$py" >/dev/null 2>&1 || { echo "ceres_sitting.sh: Python not found: $py (give a Python with numpy and scipy as the argument or in \$PYTHON)" >&2; exit 2; }
"$py" -c "import numpy, scipy" >/dev/null 2>&1 || { echo "ceres_sitting.sh: $py lacks numpy/scipy (python3 -m venv DIR && DIR/bin/pip install numpy scipy)" >&2; exit 2; }
command -v pkg-config >/dev/null 2>&1 && pkg-config --exists eigen3 && [ -f /usr/include/ceres/ceres.h ] || { echo "ceres_sitting.sh: Ceres is not installed (apt-get install -y libceres-dev g++ pkg-config)" >&2; exit 2; }
if [ -n "${CALBENCH:-}" ]; then
    bin=$(cd "$(dirname "$CALBENCH")" && pwd)/$(basename "$CALBENCH")
else
    cargo build --release --quiet
    bin=$PWD/target/release/calbench
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
PYTHONPATH="$peer${PYTHONPATH:+:$PYTHONPATH}" PY="$py" CALBENCH="$bin" \
    WORK="$work" "$peer/ceres/sitting.sh" >"$work/sitting.log"
"$py" "$peer/ceres/summarize.py" "$work/sitting.log"
