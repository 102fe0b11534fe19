#!/usr/bin/env bash
# Runs the whole test suite on a fresh machine: set-up first, then every test of the workspace.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cargo test --workspace --no-fail-fast 2>&1
