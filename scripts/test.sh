#!/usr/bin/env bash
# Runs the whole test suite on a fresh machine: set-up first, then the lints (rustfmt, clippy with
# warnings as errors), every Rust test of the workspace, and the Python package's tests (pytest)
# against the same build.
set -euo pipefail
cd "$(dirname "$0")/.."
# A full run builds every crate once: incremental caches would only take disk.
export CARGO_INCREMENTAL=0
bash scripts/disk.sh check
# The packages built on their own and each crate's own tests resolve the workspace tests'
# dependency features (shared builds).
bash scripts/features.sh
# (The set-up tool in the dev profile: the tests below reuse its compiled crates.)
bash scripts/setup.sh dev
cargo fmt --all --check
cargo clippy --workspace --all-targets --quiet -- -D warnings
# Tests that need the shared data sets (../shared/data or MP_DATA_DIR) or a model the set-up
# could not provide skip without them and list themselves (test, what it needs) here.
export MP_SKIP_LOG="$PWD/target/skipped-tests.txt"
mkdir -p target
rm -f "$MP_SKIP_LOG"
cargo test --workspace --no-fail-fast 2>&1
# The Python package in the dev profile, which shares its compiled crates with the tests above.
bash scripts/python.sh dev
MP_BIN="$PWD/target/debug/mp" .venv/bin/python -m pytest -q crates/mp-py/tests 2>&1
# Rust and Python tests that skipped, with what they need.
if [ -s "$MP_SKIP_LOG" ]; then
    n_models=$(grep -P '\tmodels/' "$MP_SKIP_LOG" | cut -f1 | sort -u | wc -l || true)
    n_data=$(grep -vP '\tmodels/' "$MP_SKIP_LOG" | cut -f1 | sort -u | wc -l || true)
    echo "tests skipped: $(cut -f1 "$MP_SKIP_LOG" | sort -u | wc -l) ($n_data need the shared data sets: no ../shared/data or MP_DATA_DIR; $n_models need a model the set-up could not convert): see target/skipped-tests.txt"
    sort -u "$MP_SKIP_LOG" | sed 's/^/  /; s/\t/  needs  /'
else
    echo "tests skipped: 0 (the shared data sets and every model were present)"
fi
bash scripts/disk.sh report
