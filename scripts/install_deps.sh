#!/usr/bin/env bash
# Installs the Debian 12 packages tbdrsim needs to build, test (with fuzzers and sanitizers) and plot.
# Idempotent: when every package is already installed it does nothing (no apt-get update).
set -euo pipefail
packages=(
  cmake g++ make pkg-config
  libboost-program-options-dev libglm-dev libtinygltf-dev libsqlite3-dev
  libgtest-dev libstb-dev zlib1g-dev nlohmann-json3-dev sqlite3
  python3 python3-pandas python3-matplotlib
  clang-14 libclang-rt-14-dev  # scripts/fuzz.sh and scripts/sanitize.sh (CI runs both): clang, libFuzzer, ASan, UBSan
)
missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "install_deps: all ${#packages[@]} packages present"
  exit 0
fi
SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "install_deps: installing ${missing[*]}"
$SUDO apt-get update -qq
DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
