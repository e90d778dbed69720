#!/usr/bin/env bash
# Installs the Debian 12 packages `tbdrsim import` needs to capture and export a frame
# (docs/capture-import.md): RenderDoc with its Python replay module, Mesa's software Vulkan driver
# (lavapipe), Xvfb for a display, vkcube (vulkan-tools) as the example application. Not needed to
# build or test tbdrsim: the tests import the committed intermediate (tests/data/capture) without them.
# The OpenGL route (scripts/capture/capture_gl.sh: GL through Mesa's zink on lavapipe, captured as
# Vulkan) also needs zink (libgl1-mesa-dri), Mesa's GLX (libglx-mesa0) and glxinfo (mesa-utils),
# which capture_frame.py --gl uses to check that the renderer is zink; they are in the list below.
# Usage: install_capture_deps.sh [--examples]
#   --examples  also installs the example OpenGL applications (not needed by the route itself):
#               glmark2-x11, glmark2-es2-x11 (glmark2 2023.01) and supertuxkart (1.4, about 660 MB
#               to download, 820 MB installed).
# Idempotent: when every package is already installed it does nothing (no apt-get update).
set -euo pipefail
packages=(renderdoc python3-renderdoc mesa-vulkan-drivers vulkan-tools xvfb xauth
  libgl1-mesa-dri libglx-mesa0 mesa-utils)
examples=(glmark2-x11 glmark2-es2-x11 supertuxkart)
case "${1:-}" in
  "") ;;
  --examples) packages+=("${examples[@]}") ;;
  *) echo "usage: $0 [--examples]" >&2; exit 2 ;;
esac
. "$(dirname "$0")/apt_install.sh"
apt_install install_capture_deps "${packages[@]}"
