#!/usr/bin/env bash
# The main job on the embedded default: set up what is missing (system packages, ONNX Runtime, the
# pose models, and the Python package in .venv), then run `mp` on a procedurally generated performer
# and say where the results are.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
bash scripts/python.sh
OUT="${1:-mp-out}"
cargo run --quiet --release -p mp-cli -- demo --out "$OUT"
