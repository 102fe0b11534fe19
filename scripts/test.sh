#!/usr/bin/env bash
# Runs the whole test suite on a fresh machine: set-up first, then the lints (rustfmt, clippy with
# warnings as errors), every Rust test of the workspace, and the Python package's tests (pytest)
# against the same build.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo fmt --all --check
cargo clippy --workspace --all-targets --quiet -- -D warnings
# Tests that need the shared data sets (../shared/data or MP_DATA_DIR) skip without them and
# list themselves here.
export MP_SKIP_LOG="$PWD/target/skipped-data-tests.txt"
mkdir -p target
rm -f "$MP_SKIP_LOG"
cargo test --workspace --no-fail-fast 2>&1
if [ -s "$MP_SKIP_LOG" ]; then
    echo "data-set tests skipped: $(cut -f1 "$MP_SKIP_LOG" | sort -u | wc -l) (no ../shared/data or MP_DATA_DIR): see target/skipped-data-tests.txt"
    cut -f1 "$MP_SKIP_LOG" | sort -u | sed 's/^/  /'
else
    echo "data-set tests skipped: 0"
fi
# The Python package in the dev profile, which shares its compiled crates with the tests above.
bash scripts/python.sh dev
MP_BIN="$PWD/target/debug/mp" .venv/bin/python -m pytest -q crates/mp-py/tests 2>&1
