#!/usr/bin/env bash
# Real-time stress of the Linux firmware loop (issue 18, docs/realtime.md): runs
# `uwbnav firmware` at 100 Hz for DURATION_S seconds (default 600) with the stdio
# console busy (a `pos` stream at 10 Hz and `stats` every 2 s, read through a
# pipe), CAN publishing and the CAN log on, while a disk writer
# (dd ... conv=fsync in a loop) and one CPU hog run; then prints the firmware's
# cycle-latency histogram, overruns and CAN log counters.
# usage: scripts/rt_stress.sh [DURATION_S] [BUILD_DIR]     (not run in CI: it takes DURATION_S)
# environment: RT_STRESS_LOAD="dd hog" (default; any of dd, hog, or empty for an idle machine),
#              RT_STRESS_ARGS="..." extra firmware options (e.g. --no-rt to compare, --cpu N
#              for the loop thread alone on CPU N), RT_STRESS_WRAP="..." a command in front
#              of the firmware (e.g. taskset -c 0: every thread on CPU 0)
set -euo pipefail
cd "$(dirname "$0")/.."
duration="${1:-600}"
build="${2:-build/host}"
uwbnav="$build/bin/uwbnav"
[[ -x "$uwbnav" ]] || { echo "rt_stress: $uwbnav not built (cmake --build --preset host)" >&2; exit 2; }
work=$(mktemp -d /tmp/uwbnav-rt-stress.XXXXXX)
pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -- "-$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
  rm -rf "$work"
}
trap cleanup EXIT

# A drive longer than the run, so that the recording does not end first.
printf 'base = parking_nlos\n[scenario]\nname = rt_stress\nduration_s = %s\n' "$((duration + 10))" > "$work/long.scn"
"$uwbnav" sim "$work/long.scn" --seed 5 --out "$work/rec" > /dev/null

# Load: a disk writer that syncs every 500 MB, and one CPU hog (each in its own process group).
load="${RT_STRESS_LOAD-dd hog}"
for l in $load; do
  case "$l" in
    dd) setsid bash -c "while :; do dd if=/dev/zero of='$work/dd.bin' bs=1M count=500 conv=fsync status=none; done" & ;;
    hog) setsid bash -c 'while :; do :; done' & ;;
    *) echo "rt_stress: unknown load '$l' (dd, hog)" >&2; exit 2 ;;
  esac
  pids+=($!)
done
echo "rt_stress: ${duration} s at 100 Hz; console, CAN and CAN log on; load: ${load:-none} ${RT_STRESS_ARGS:-}"

feed() {
  sleep 1
  echo "stream pos 10"
  while :; do sleep 2; echo "stats"; done
}
feed | ${RT_STRESS_WRAP:-} "$uwbnav" firmware --recording "$work/rec" --console stdio --duration "$duration" \
  --can-log "$work/can.log" ${RT_STRESS_ARGS:-} | cat > "$work/console.log" || true

grep -a -E '^firmware: (real time|note|loop thread)' "$work/console.log" || true
grep -a -o -E '(firmware: stopped.*|^  (loop|latency|rt|cpu|CAN log|CAN tx) .*)' "$work/console.log" || {
  echo "rt_stress: no summary from the firmware; console log tail:" >&2
  tail -20 "$work/console.log" >&2
  exit 1
}
echo "console lines received: $(grep -a -c 'pos t_us' "$work/console.log") \$pos, $(grep -a -c 'stats loop' "$work/console.log") stats replies; CAN log $(wc -l < "$work/can.log") lines"
