#!/usr/bin/env bash
# Installs the Debian 12 packages the given build presets need, and nothing
# else. Idempotent: packages already present are skipped; apt runs only when
# something is missing; uses sudo when not root.
# Usage: scripts/bootstrap.sh [PRESET...]   (default: host)
#   host, host-debug, host-asan, host-double   compilers, cmake, ninja, GoogleTest/Benchmark,
#                                              Eigen, libsvm, zlib, python3 modules, can-utils
#   cortex-m4f, cortex-m7                      host + arm-none-eabi gcc, picolibc, qemu-system-arm
#   aarch64                                    host + aarch64 cross g++, arm64 libsvm/zlib, qemu-user
#   fuzz                                       host + clang with the libFuzzer/sanitizer runtimes
#   all                                        every group above
#   --list                                     prints the packages of the presets, installs nothing
# (--host-only is accepted as a synonym of host.)
set -euo pipefail

host_pkgs=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libgtest-dev libgmock-dev libbenchmark-dev
  libsvm-dev libsvm-tools zlib1g-dev
  python3 python3-numpy python3-matplotlib python3-can python3-canmatrix
  can-utils
)
# The cross presets configure the host tools too (the image build runs host uwbnav).
m4f_pkgs=(gcc-arm-none-eabi libstdc++-arm-none-eabi-picolibc picolibc-arm-none-eabi qemu-system-arm)
aarch64_pkgs=(g++-aarch64-linux-gnu libc6-dev-arm64-cross qemu-user googletest libsvm-dev:arm64 zlib1g-dev:arm64)
fuzz_pkgs=(clang libclang-rt-14-dev)

list=0
presets=()
for a in "$@"; do
  case "$a" in
    --list) list=1 ;;
    --host-only) presets+=(host) ;;
    *) presets+=("$a") ;;
  esac
done
[[ ${#presets[@]} -gt 0 ]] || presets=(host)

pkgs=("${host_pkgs[@]}")
arm64=0
for p in "${presets[@]}"; do
  case "$p" in
    host | host-debug | host-asan | host-double) ;;
    cortex-m4f | cortex-m7) pkgs+=("${m4f_pkgs[@]}") ;;
    aarch64) pkgs+=("${aarch64_pkgs[@]}"); arm64=1 ;;
    fuzz) pkgs+=("${fuzz_pkgs[@]}") ;;
    all) pkgs+=("${m4f_pkgs[@]}" "${aarch64_pkgs[@]}" "${fuzz_pkgs[@]}"); arm64=1 ;;
    *) echo "bootstrap: unknown preset '$p' (host, host-debug, host-asan, host-double, cortex-m4f, cortex-m7, aarch64, fuzz, all)" >&2
       exit 2 ;;
  esac
done
# De-duplicate, keep order.
declare -A seen=()
uniq=()
for p in "${pkgs[@]}"; do [[ -n "${seen[$p]:-}" ]] || { seen[$p]=1; uniq+=("$p"); }; done
pkgs=("${uniq[@]}")

if [[ $list -eq 1 ]]; then
  printf '%s\n' "${pkgs[@]}"
  exit 0
fi

missing=()
for p in "${pkgs[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [[ ${#missing[@]} -eq 0 ]]; then
  echo "bootstrap (${presets[*]}): all ${#pkgs[@]} packages present"
  exit 0
fi

echo "bootstrap (${presets[*]}): installing ${#missing[@]} package(s): ${missing[*]}"
SUDO=""
if [[ $(id -u) -ne 0 ]]; then SUDO="sudo"; fi
export DEBIAN_FRONTEND=noninteractive
# The aarch64 build links libsvm and zlib from Debian's arm64 packages (multiarch).
if [[ $arm64 -eq 1 ]] && ! dpkg --print-foreign-architectures | grep -qx arm64; then
  $SUDO dpkg --add-architecture arm64
fi
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
echo "bootstrap: done"
