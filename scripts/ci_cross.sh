#!/usr/bin/env bash
# CI, cross-compilation part (issue 4), run by .ci/run after the host presets:
#  1. Cortex-M4F image (hal/mps2) in build/host/cross-m4f, the tree the host
#     ctest (cross_m4f_*) already built: full build including the rule check
#     (no heap, no exceptions, no soft-double in the estimator hot path), then
#     the footprint report docs/footprint.md (qemu-system-arm -icount), which
#     fails the step when a target of issue 4 (flash, RAM, cost, float-only) is missed.
#  2. aarch64 preset: the ECU binary and the test areas of the code an ECU runs
#     (the aarch64 build preset's targets) cross-compiled; their GoogleTest unit
#     tests run under qemu-aarch64 (CMAKE_CROSSCOMPILING_EMULATOR) with the
#     aarch64 test preset's filter. The host-tool areas (simulator, evaluation,
#     calibration, streaming replay) and the script tests stay in the host presets.
# Every step runs; the script fails at the end if any step failed.
# UWBNAV_HOST_BUILD / UWBNAV_AARCH64_BUILD override the build trees.
set -uo pipefail
cd "$(dirname "$0")/.."
start=$(date +%s)
failed=()
step() {
  local name="$1"
  shift
  echo "ci_cross: == $name"
  local t0
  t0=$(date +%s)
  if "$@"; then
    echo "ci_cross: $name ok ($(( $(date +%s) - t0 )) s)"
  else
    echo "ci_cross: $name FAILED ($(( $(date +%s) - t0 )) s)"
    failed+=("$name")
  fi
}

bash scripts/bootstrap.sh cortex-m4f aarch64 || exit 1  # cross toolchains, qemu, arm64 libraries
host="${UWBNAV_HOST_BUILD:-build/host}"          # host tree of the preceding host run
a64="${UWBNAV_AARCH64_BUILD:-build/aarch64}"     # binaryDir of the aarch64 preset
if [[ ! -x "$host/bin/uwbnav" ]]; then
  cmake --preset host -B "$host" >/dev/null && cmake --build "$host" --target uwbnav || exit 1
fi
m4f="$host/cross-m4f"
step "cortex-m4f image" cmake -DSOURCE="$PWD" -DBINARY="$PWD/$m4f" -DUWBNAV="$PWD/$host/bin/uwbnav" \
  -P hal/mps2/build_image.cmake
step "cortex-m4f rule check" cmake --build "$m4f" --target uwbnav_mps2_check
step "footprint report (targets of issue 4)" bash scripts/footprint.sh --check "$m4f" docs/footprint.md
step "aarch64 configure" cmake --preset aarch64 -B "$a64"
# The build preset's targets and the test preset's exclusion filter, applied to
# whichever tree was configured.
exclude=""
a64_targets=()
{
  read -r exclude
  read -r -a a64_targets
} < <(/usr/bin/python3 -c 'import json; p = json.load(open("CMakePresets.json"))
print(next(t["filter"]["exclude"]["name"] for t in p["testPresets"] if t["name"] == "aarch64"))
print(" ".join(next(b["targets"] for b in p["buildPresets"] if b["name"] == "aarch64")))')
if [[ -z "${exclude:-}" || ${#a64_targets[@]} -eq 0 ]]; then
  echo "ci_cross: CMakePresets.json has no aarch64 build targets or test filter"
  exit 1
fi
step "aarch64 build" cmake --build "$a64" --target "${a64_targets[@]}"
step "aarch64 tests (qemu-aarch64)" ctest --test-dir "$a64" -j2 --output-on-failure -E "$exclude"

echo "ci_cross: done in $(( $(date +%s) - start )) s"
if [[ ${#failed[@]} -gt 0 ]]; then
  echo "ci_cross: failed: ${failed[*]}"
  exit 1
fi
