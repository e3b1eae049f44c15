#!/usr/bin/env bash
# The one test command: everything CI checks, in order, from the repository root whatever the
# caller's working directory. Stops at the first failure.
#
# usage: scripts/test.sh
set -euo pipefail
cd "$(dirname "$0")/.."
cargo fmt --check
cargo clippy --all-targets -- -D warnings
RUSTDOCFLAGS=-Dwarnings cargo doc --no-deps
cargo test
