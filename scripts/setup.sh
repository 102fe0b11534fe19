#!/usr/bin/env bash
# Installs what the project needs on a fresh Debian machine:
#   - Debian packages: pkg-config, FFmpeg (video decoding), Chromium (report test), DejaVu fonts
#   - ONNX Runtime's shared library and the pose models (`cargo xtask setup`)
# Idempotent: what is already there is skipped.
#
#   bash scripts/setup.sh        # builds the set-up tool in cargo's release profile, as `mp` is built
#   bash scripts/setup.sh dev    # in the dev profile, whose compiled crates `cargo test` reuses
set -euo pipefail
PROFILE="${1:-release}"
case "$PROFILE" in
  release|dev) ;;
  *) echo "setup: unknown profile '$PROFILE' (release or dev)" >&2; exit 2 ;;
esac
cd "$(dirname "$0")/.."

PKGS=(pkg-config ffmpeg chromium fonts-dejavu-core)
missing=()
for p in "${PKGS[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
  echo "setup: installing Debian packages: ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
fi

# ONNX Runtime (from PyPI's onnxruntime wheel) and the pose models, into .cache/
if [ "$PROFILE" = dev ]; then
  cargo run --quiet --package xtask -- setup
else
  cargo xtask setup
fi
