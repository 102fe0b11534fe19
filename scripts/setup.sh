#!/usr/bin/env bash
# Installs what the project needs on a fresh Debian machine:
#   - Debian packages: pkg-config, FFmpeg (video decoding), Chromium (report test), DejaVu fonts
#   - ONNX Runtime's shared library and the pose models (`cargo xtask setup`)
#   - public test footage that Debian ships: OpenCV's pedestrian scene `vtest.avi` (package
#     opencv-doc, Apache-2.0 / BSD-3-Clause), into .cache/footage/ (never committed)
# Idempotent: what is already there is skipped.
#
#   bash scripts/setup.sh        # builds the set-up tool in cargo's release profile, as `mp` is built
#   bash scripts/setup.sh dev    # in the dev profile, whose compiled crates `cargo test` reuses
#   bash scripts/setup.sh gpu    # also ONNX Runtime's GPU build with CUDA (several GB); then
#                                # `source .cache/onnxruntime-gpu.env` runs the pose models on the GPU
set -euo pipefail
PROFILE="${1:-release}"
GPU=()
case "$PROFILE" in
  release|dev) ;;
  gpu) PROFILE=release; GPU=(--gpu) ;;
  *) echo "setup: unknown profile '$PROFILE' (release, dev or gpu)" >&2; exit 2 ;;
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

# Test footage: one file taken out of the downloaded package (not installed).
fetch_footage() {
  local dir=.cache/footage name=vtest.avi
  [ -s "$dir/$name" ] && return 0
  local tmp
  tmp="$(mktemp -d)"
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  # (Package lists may be missing on a fresh machine whose packages were all there.)
  if (cd "$tmp" && apt-get download -qq opencv-doc >/dev/null 2>&1) \
    || { $sudo apt-get update -qq && (cd "$tmp" && apt-get download -qq opencv-doc >/dev/null 2>&1); }; then
    mkdir -p "$dir"
    dpkg-deb --fsys-tarfile "$tmp"/opencv-doc_*.deb \
      | tar -x -O ./usr/share/doc/opencv-doc/examples/data/$name >"$dir/$name.part"
    dpkg-deb --fsys-tarfile "$tmp"/opencv-doc_*.deb \
      | tar -x -O ./usr/share/doc/opencv-doc/copyright >"$dir/$name.copyright"
    mv "$dir/$name.part" "$dir/$name"
    echo "setup: test footage $dir/$name (from Debian's opencv-doc)"
  else
    echo "setup: could not download opencv-doc; the street-scene tests will skip" >&2
  fi
  rm -rf "$tmp"
}
fetch_footage

# ONNX Runtime (from PyPI's onnxruntime wheel) and the pose models, into .cache/
if [ "$PROFILE" = dev ]; then
  cargo run --quiet --package xtask -- setup
else
  cargo xtask setup "${GPU[@]}"
fi
