#!/usr/bin/env bash
# Head-to-head against Ceres Solver and scipy, in one sitting: runs PEER/ceres/sitting.sh
# (builds the peer's Ceres program, writes its 200 datasets, then three alternating rounds of
# the Ceres program, PEER/scipy_ref.py 100 and `calbench run PEER/h2h.toml --threads 1`) and
# prints PEER/ceres/summarize.py's table: milliseconds per identification and their ratios to
# calbench's adaptive `lm` and `ls`. Needs Debian's Ceres (apt-get install -y libceres-dev
# g++ pkg-config) and a Python with numpy and scipy (PYTHON, default the venv the acceptance
# checks create); nothing else in the project, and no test, needs them.
#
# usage: benches/ceres_sitting.sh [PEER_DIR (default ../shared/peer)] [PYTHON]
set -euo pipefail
cd "$(dirname "$0")/.."
peer=${1:-../shared/peer}
py=${2:-/tmp/calbench-peer-venv/bin/python}
[ -f "$peer/h2h.toml" ] && [ -x "$peer/ceres/sitting.sh" ] || { echo "no h2h.toml / ceres/sitting.sh in $peer" >&2; exit 2; }
peer=$(cd "$peer" && pwd)
"$py" -c "import numpy, scipy" 2>/dev/null || { echo "$py lacks numpy/scipy (python3 -m venv DIR && DIR/bin/pip install numpy scipy)" >&2; exit 2; }
pkg-config --exists eigen3 && [ -f /usr/include/ceres/ceres.h ] || { echo "Ceres is not installed (apt-get install -y libceres-dev g++ pkg-config)" >&2; exit 2; }
cargo build --release --quiet
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
PYTHONPATH="$peer${PYTHONPATH:+:$PYTHONPATH}" PY="$py" CALBENCH="$PWD/target/release/calbench" \
    WORK="$work" "$peer/ceres/sitting.sh" >"$work/sitting.log"
"$py" "$peer/ceres/summarize.py" "$work/sitting.log"
