#!/usr/bin/env bash
# Installs every Debian 12 package uwbnav needs to build, test, cross-compile and
# report. Idempotent: packages already present are skipped; apt runs only when
# something is missing. Usage: scripts/bootstrap.sh [--host-only]
set -euo pipefail

host_pkgs=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libgtest-dev libgmock-dev libbenchmark-dev
  libsvm-dev libsvm-tools zlib1g-dev
  python3 python3-numpy python3-matplotlib python3-can python3-canmatrix
  can-utils
)
cross_pkgs=(
  gcc-arm-none-eabi libstdc++-arm-none-eabi-picolibc picolibc-arm-none-eabi
  qemu-system-arm qemu-user
  g++-aarch64-linux-gnu libc6-dev-arm64-cross
  googletest libsvm-dev:arm64 zlib1g-dev:arm64
)

pkgs=("${host_pkgs[@]}")
cross=0
if [[ "${1:-}" != "--host-only" ]]; then
  pkgs+=("${cross_pkgs[@]}")
  cross=1
fi

missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "bootstrap: all ${#pkgs[@]} packages present"
  exit 0
fi

echo "bootstrap: installing ${#missing[@]} package(s): ${missing[*]}"
SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
# The aarch64 build links libsvm from Debian's arm64 package (multiarch).
if [[ $cross -eq 1 ]] && ! dpkg --print-foreign-architectures | grep -qx arm64; then
  $SUDO dpkg --add-architecture arm64
fi
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "bootstrap: done"
