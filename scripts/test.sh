#!/usr/bin/env bash
# Runs the whole test suite on a fresh machine: set-up first, then the lints (rustfmt, clippy with
# warnings as errors), every Rust test of the workspace, and the Python package's tests (pytest)
# against the same build.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo fmt --all --check
cargo clippy --workspace --all-targets --quiet -- -D warnings
cargo test --workspace --no-fail-fast 2>&1
# The Python package in the dev profile, which shares its compiled crates with the tests above.
bash scripts/python.sh dev
MP_BIN="$PWD/target/debug/mp" .venv/bin/python -m pytest -q crates/mp-py/tests 2>&1
