#!/usr/bin/env bash
# Runs the tests that execute ONNX models on an emulated x86-64 CPU with AVX2
# and without AVX-512 or VNNI (QEMU user mode, `-cpu EPYC-Rome`), whatever
# CPU this machine has. ONNX Runtime picks its kernels (the int8 ones above
# all) from the CPU's instruction sets and has no option to restrict them, so
# emulation is how the suite is shown to hold on such CPUs.
#
#   bash scripts/test-avx2.sh [crate:test ...]
#
# By default, the test targets that run the ONNX models: the pose models'
# contracts and their accuracy on real frames, the forecaster, the refinement
# networks and the network wrapper.
# Emulation is 20–50 times slower than the host; expect tens of minutes.
set -euo pipefail
cd "$(dirname "$0")/.."

CPU=${MP_EMULATED_CPU:-EPYC-Rome}
TARGETS=("$@")
if [ ${#TARGETS[@]} -eq 0 ]; then
  TARGETS=(mp-pose:contracts mp-pose:pipeline mp-pose:errors mp-onnx:network
    mp-forecast:onnx_model mp-refine:nets mp-refine:refine_default)
fi

if ! command -v qemu-x86_64 >/dev/null; then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  echo "test-avx2: installing qemu-user"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends qemu-user >/dev/null
fi
bash scripts/setup.sh dev >/dev/null

# The test executables, as cargo builds them.
mapfile -t bins < <(for t in "${TARGETS[@]}"; do
  cargo test -p "${t%%:*}" --test "${t#*:}" --no-run --message-format=json 2>/dev/null
done |
  python3 -c '
import json, sys
for line in sys.stdin:
    try:
        m = json.loads(line)
    except ValueError:
        continue
    if m.get("reason") == "compiler-artifact" and m.get("executable") and m["profile"]["test"]:
        print(m["manifest_path"].rsplit("/", 1)[0] + "\t" + m["executable"])
')

echo "test-avx2: emulated CPU $CPU: $(qemu-x86_64 -cpu "$CPU" /bin/true 2>/dev/null && echo ok)"
failed=0
for entry in "${bins[@]}"; do
  dir=${entry%%$'\t'*}
  exe=${entry#*$'\t'}
  echo "== $(basename "$exe") ($dir)"
  # Each test binary runs in its crate's folder, as `cargo test` runs it.
  if ! (cd "$dir" && qemu-x86_64 -cpu "$CPU" "$exe" --test-threads 2 2>&1 |
    grep -v "TCG doesn't support requested feature"); then
    failed=1
  fi
done
if [ $failed -ne 0 ]; then
  echo "test-avx2: FAILED on the emulated $CPU"
  exit 1
fi
echo "test-avx2: all passed on the emulated $CPU"
