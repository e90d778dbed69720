#!/usr/bin/env bash
# Installs the Debian 12 packages `tbdrsim import` needs to capture and export a frame
# (docs/capture-import.md): RenderDoc with its Python replay module, Mesa's software Vulkan driver
# (lavapipe), Xvfb for a display, vkcube (vulkan-tools) as the example application. Not needed to
# build or test tbdrsim: the tests import the committed intermediate (tests/data/capture) without them.
# Idempotent: when every package is already installed it does nothing (no apt-get update).
set -euo pipefail
packages=(renderdoc python3-renderdoc mesa-vulkan-drivers vulkan-tools xvfb xauth)
missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_capture_deps: all ${#packages[@]} packages present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install_capture_deps: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
