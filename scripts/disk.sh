#!/usr/bin/env bash
# Disk use of the test suite.
#   bash scripts/disk.sh check    # free space where the build goes, and a warning if it is short
#   bash scripts/disk.sh report   # what the build, the Python environment and the caches take
# A full run of scripts/test.sh on a fresh clone needs about NEED_GB (docs/results/robustness.md, "Disk").
set -euo pipefail
cd "$(dirname "$0")/.."
NEED_GB="${MP_TEST_DISK_GB:-6}"
free_kb() { df -Pk "${CARGO_TARGET_DIR:-.}" 2>/dev/null | awk 'NR==2 {print $4}'; }
case "${1:-check}" in
  check)
    kb=$(free_kb)
    gb=$((kb / 1024 / 1024))
    echo "disk: ${gb} GB free for the build (a fresh run needs about ${NEED_GB} GB)"
    if [ "$gb" -lt "$NEED_GB" ]; then
      echo "disk: WARNING: only ${gb} GB free; the build, the Python environment (Ray) and the" \
        "converted models may not fit. Free space, or point CARGO_TARGET_DIR at a larger disk." >&2
    fi
    ;;
  report)
    for d in "${CARGO_TARGET_DIR:-target}" .venv .cache "${CARGO_HOME:-$HOME/.cargo}/registry"; do
      [ -e "$d" ] && du -sh "$d" 2>/dev/null | sed 's/^/disk: /'
    done
    kb=$(free_kb)
    echo "disk: $((kb / 1024 / 1024)) GB free after the run"
    ;;
  *)
    echo "usage: scripts/disk.sh check|report" >&2
    exit 2
    ;;
esac
