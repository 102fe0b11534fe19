#!/usr/bin/env bash
# Installs what the project needs on a fresh Debian machine:
#   - Debian packages: pkg-config, FFmpeg (video decoding), Chromium (report test), DejaVu fonts
#   - ONNX Runtime's shared library and the pose models (`cargo xtask setup`)
# Idempotent: what is already there is skipped.
set -euo pipefail
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
cargo xtask setup
