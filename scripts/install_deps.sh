#!/usr/bin/env bash
# Installs the Debian 12 packages semlio needs, only those missing.
# Usage: scripts/install_deps.sh [extra-package ...]   (run as root, or with sudo available)
set -euo pipefail

# pkg-config and the four -dev packages: the optional bag readers (cmake/SemlioBags.cmake).
# libopencv-dnn-dev: the optional ONNX segmenter (cmake/SemlioOnnx.cmake).
packages=(build-essential cmake libeigen3-dev libnanoflann-dev catch2 libbenchmark-dev libcli11-dev libyaml-cpp-dev
          pkg-config libbz2-dev liblz4-dev libzstd-dev libsqlite3-dev libopencv-dnn-dev "$@")
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  exit 0
fi
echo "installing: ${missing[*]}"
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
