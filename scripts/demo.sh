#!/usr/bin/env bash
# The main job on the embedded default: set up what is missing, then run `mp` on a procedurally
# generated performer and say where the results are.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
OUT="${1:-mp-out}"
cargo run --quiet --release -p mp-cli -- demo --out "$OUT"
