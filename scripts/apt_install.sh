#!/usr/bin/env bash
# Sourced by scripts/install_deps.sh and scripts/install_capture_deps.sh: installs the Debian 12
# packages it is given that are not installed yet. Idempotent: when every package is already
# installed it does nothing (no apt-get update).
# Usage: apt_install NAME PACKAGE...   (NAME prefixes its messages)
apt_install() {
  local name=$1
  shift
  local missing=() p
  for p in "$@"; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
      missing+=("$p")
    fi
  done
  if [ ${#missing[@]} -eq 0 ]; then
    echo "$name: all $# packages present"
    return 0
  fi
  local sudo=""
  if [ "$(id -u)" -ne 0 ]; then sudo="sudo"; fi
  echo "$name: installing ${missing[*]}"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}
