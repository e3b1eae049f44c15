#!/usr/bin/env bash
# The one test command: everything CI checks, in order, from the repository root whatever the
# caller's working directory. Stops at the first failure.
#
# Rust (the library, the CLI and the Python module's crate python/): cargo fmt --check, clippy
# with warnings denied, rustdoc with warnings denied, cargo test (with CI=true also the slow
# coverage test of the intervals, ignored by default). Then the Python module: built
# into the virtual environment .venv/ (maturin, pytest, numpy, pandas, matplotlib, and scipy,
# which the paired comparisons are tested against) and its pytest suite python/tests/ run
# against the CLI; a fresh clone's .venv/ is made here first
# (python3 -m venv, pip install from PyPI). When it cannot be made the Python part is skipped
# with a message, except under CI=true, where it fails.
#
# usage: scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."
# CI as the Rust tests read it: `true` or `1`.
ci() { [ "${CI:-}" = "true" ] || [ "${CI:-}" = "1" ]; }
# One pass builds everything once, so incremental caches gain nothing and cost disk: they were
# 5.8 GB of a 9.3 GB target/debug, and a CI machine ran out of space linking the Python module.
export CARGO_INCREMENTAL=0
cargo fmt --all --check
cargo clippy --workspace --all-targets -- -D warnings
RUSTDOCFLAGS=-Dwarnings cargo doc --no-deps --workspace
cargo test
# The coverage of the 95 % intervals (40 runs of 50 trials against a 4000-trial run, seconds
# on an idle machine, minutes on a loaded one) and identify's peak memory on 2 000 000 rows
# (GNU time) and a study's peak memory flat in its trials are ignored by default; CI runs them.
if ci; then
    cargo test --test study -- --ignored intervals_cover_the_long_run_figure
    cargo test --test cli -- --ignored identify_peak_memory_on_two_million_rows
    cargo test --test cli -- --ignored a_study_peak_memory_is_flat_in_its_trials
fi

py=.venv/bin/python
has_tools() { [ -x "$py" ] && "$py" -c "import maturin, pytest, numpy, pandas, matplotlib, scipy" 2>/dev/null; }
if ! has_tools; then
    # A fresh clone: make the environment (PyPI), as the README's set-up promises.
    echo "making .venv/ with maturin, pytest, numpy, pandas, matplotlib and scipy from PyPI" >&2
    { [ -x "$py" ] || python3 -m venv .venv; } &&
        "$py" -m pip install --quiet --upgrade maturin pytest numpy pandas matplotlib scipy >&2 || true
fi
if ! has_tools; then
    msg="the Python module's tests need .venv/ with maturin, pytest, numpy, pandas, matplotlib and scipy, which could not be made (python3 -m venv, pip install from PyPI)"
    if ci; then
        echo "error: $msg" >&2
        exit 1
    fi
    echo "skipped: $msg" >&2
    exit 0
fi
# The dev profile: its dependencies are those cargo test just built (optimised, as
# Cargo.toml sets for every dependency), calbench's own code at the test profile's level.
VIRTUAL_ENV="$PWD/.venv" "$py" -m maturin develop --quiet
CALBENCH_BIN="${CARGO_TARGET_DIR:-$PWD/target}/debug/calbench" "$py" -m pytest -q python/tests
