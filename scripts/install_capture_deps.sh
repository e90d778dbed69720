#!/usr/bin/env bash
# Installs the Debian 12 packages `tbdrsim import` needs to capture and export a frame
# (docs/capture-import.md): RenderDoc with its Python replay module, Mesa's software Vulkan driver
# (lavapipe), Xvfb for a display, vkcube (vulkan-tools) as the example application. Not needed to
# build or test tbdrsim: the tests import the committed intermediate (tests/data/capture) without them.
# Idempotent: when every package is already installed it does nothing (no apt-get update).
set -euo pipefail
packages=(renderdoc python3-renderdoc mesa-vulkan-drivers vulkan-tools xvfb xauth)
. "$(dirname "$0")/apt_install.sh"
apt_install install_capture_deps "${packages[@]}"
