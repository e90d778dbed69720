#!/usr/bin/env bash
# Installs the Debian 12 packages tbdrsim needs to build, test (with fuzzers and sanitizers) and plot.
# Idempotent: when every package is already installed it does nothing (no apt-get update).
set -euo pipefail
packages=(
  cmake g++ make pkg-config
  libboost-program-options-dev libglm-dev libtinygltf-dev libsqlite3-dev
  libgtest-dev libstb-dev libdeflate-dev nlohmann-json3-dev sqlite3
  python3 python3-pandas python3-matplotlib
  clang-14 libclang-rt-14-dev  # scripts/fuzz.sh and scripts/sanitize.sh (CI runs both): clang, libFuzzer, ASan, UBSan
)
. "$(dirname "$0")/apt_install.sh"
apt_install install_deps "${packages[@]}"
