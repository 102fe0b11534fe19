#!/usr/bin/env bash
# Builds the Python package `motion_programs` (crates/mp-py, PyO3 + maturin) and installs it into the
# project's virtual environment `.venv`, with numpy, pytest, matplotlib, Ray (Ray Data, pyarrow), pandas,
# pose-format and c3d (the tests read and write Parquet, `.pose` and C3D files with them).
#   bash scripts/python.sh            # optimised wheel (cargo's release profile)
#   bash scripts/python.sh dev        # the dev profile (what the test suite builds; shares its artifacts)
# Idempotent: packages already installed are kept; the wheel is rebuilt incrementally.
set -euo pipefail
cd "$(dirname "$0")/.."
PROFILE="${1:-release}"
PY="${PYTHON:-python3}"
if [ ! -x .venv/bin/python ]; then
  echo "python: creating .venv"
  "$PY" -m venv .venv
fi
VPY=.venv/bin/python
if ! "$VPY" -c "import maturin, numpy, pytest, ray, pyarrow, pandas, matplotlib, pose_format, c3d" 2>/dev/null; then
  echo "python: installing maturin, numpy, pytest, matplotlib, Ray, pandas, pose-format, c3d into .venv"
  "$VPY" -m pip install -q --no-cache-dir --upgrade pip
  "$VPY" -m pip install -q --no-cache-dir "maturin>=1.9,<2" "numpy>=1.21" pytest matplotlib "ray[data]>=2.40" pyarrow pandas pose-format c3d
fi
WHEELS="target/wheels/$PROFILE"
rm -rf "$WHEELS"
.venv/bin/maturin build --quiet -m crates/mp-py/Cargo.toml --profile "$PROFILE" --out "$WHEELS"
"$VPY" -m pip install -q --force-reinstall --no-deps "$WHEELS"/motion_programs-*.whl
"$VPY" -c "import motion_programs as m; print('python: motion_programs', m.__version__, 'installed in .venv')"
