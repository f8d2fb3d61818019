#!/usr/bin/env bash
# Footprint and cost report of the Cortex-M4F firmware image: builds the MPS2
# image (preset cortex-m4f, or the build tree given), runs it under
# qemu-system-arm -icount shift=0, analyses the ELF and writes docs/footprint.md.
# Usage: scripts/footprint.sh [--check] [BUILD_DIR [OUT.md]]
#   --check    exit 1 when a target of issue 4 is missed (flash, RAM, cost, float-only)
set -euo pipefail
cd "$(dirname "$0")/.."
check=()
if [[ "${1:-}" == "--check" ]]; then
  check=(--check)
  shift
fi
build="${1:-build/cortex-m4f}"
out="${2:-docs/footprint.md}"
py=/usr/bin/python3

if [[ ! -f "$build/CMakeCache.txt" ]]; then
  if [[ "$build" != "build/cortex-m4f" ]]; then
    echo "footprint: $build is not a configured build tree" >&2
    exit 2
  fi
  if [[ ! -x build/host/bin/uwbnav ]]; then
    cmake --preset host >/dev/null
    cmake --build --preset host --target uwbnav
  fi
  cmake --preset cortex-m4f >/dev/null
fi
# The ELFs alone: the rule check (target uwbnav_mps2_check) may fail; this report lists its findings.
cmake --build "$build" --target uwbnav_mps2 uwbnav_mps2_profile

elf="$build/hal/mps2/uwbnav_mps2.elf"
map="$build/hal/mps2/uwbnav_mps2.map"
work="$build/footprint"
mkdir -p "$work"
profile_elf="$build/hal/mps2/uwbnav_mps2_profile.elf"
qemu=(qemu-system-arm -M mps2-an386 -nographic -monitor none -serial none
      -semihosting-config enable=on,target=native -icount shift=0)
echo "footprint: ${qemu[*]} -kernel $elf"
if ! timeout 600 "${qemu[@]}" -kernel "$elf" 2>"$work/digest.txt" >/dev/null || ! grep -q '^end ok' "$work/digest.txt"; then
  cat "$work/digest.txt" >&2
  echo "footprint: the image did not complete its run" >&2
  exit 1
fi
# Same run of the profile build (SysTick PC sampling) for where the instructions go.
if ! timeout 600 "${qemu[@]}" -kernel "$profile_elf" 2>"$work/profile.txt" >/dev/null; then
  echo "footprint: the profile image did not complete its run" >&2
  exit 1
fi
"$py" hal/mps2/image_analysis.py footprint --elf "$elf" --map "$map" \
  --estimator-lib "$build/estimator/libuwbnav_estimator.a" --callgraph-dir "$build" > "$work/analysis.json"
"$py" hal/mps2/image_analysis.py footprint --elf "$profile_elf" --map "$build/hal/mps2/uwbnav_mps2_profile.map" \
  --estimator-lib "$build/estimator/libuwbnav_estimator.a" --callgraph-dir "$build" \
  --profile "$work/profile.txt" > "$work/profile.json"
"$py" hal/mps2/footprint_report.py "${check[@]}" --analysis "$work/analysis.json" --digest "$work/digest.txt" \
  --profile "$work/profile.json" \
  --cache "$build/CMakeCache.txt" --out "$out" --git "$(git rev-parse --short=12 HEAD 2>/dev/null || echo unknown)" \
  --qemu-command "qemu-system-arm -M mps2-an386 -nographic -monitor none -serial none -semihosting-config enable=on,target=native -icount shift=0 -kernel uwbnav_mps2.elf"
echo "footprint: wrote $out"
