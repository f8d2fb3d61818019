#!/usr/bin/env bash
# Coverage-guided fuzzing (libFuzzer + ASan + UBSan) of every input parser the
# firmware and tools take from outside: builds the `fuzz` preset, runs each
# target on its committed seeds (tests/fuzz/corpus/<target>) plus a working
# corpus in build/fuzz/corpus/<target>, prints executions and crashes per
# target (docs/hardening.md) and fails when any target crashed.
# Usage: scripts/fuzz.sh [--ci | --seconds N | --runs N] [--jobs J] [TARGET...]
#   --ci         25 s per target (CI budget: ~2 min for the five targets)
#   --seconds N  N seconds per target (long runs on demand; default 300)
#   --runs N     N executions per target, however long that takes (the issue's
#                10 M offline runs); the "s" column then shows the wall time
#   --jobs J     J fuzzer processes per target on the same working corpus
#                (--runs N: N/J executions each; --seconds: J times the
#                executions); the row sums their executions, shows the largest
#                coverage and counts a crash in any of them
# Crash inputs land in build/fuzz/artifacts/<target>-crash-*; replay one with
#   build/fuzz/fuzz/<target> FILE
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=300
runs=0
jobs=1
targets=()
while [[ $# -gt 0 ]]; do
  case "$1" in
    --ci) seconds=25 ;;
    --seconds) seconds="$2"; shift ;;
    --runs) runs="$2"; seconds=0; shift ;;
    --jobs) jobs="$2"; shift ;;
    -h | --help) sed -n 2,17p "$0"; exit 0 ;;
    *) targets+=("$1") ;;
  esac
  shift
done
all=(fuzz_recording fuzz_can_decoder fuzz_console fuzz_param_blob fuzz_sequence)
[[ ${#targets[@]} -gt 0 ]] || targets=("${all[@]}")

bash scripts/bootstrap.sh fuzz
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz
bin=build/fuzz/fuzz
seeds=tests/fuzz/corpus
mkdir -p build/fuzz/artifacts build/fuzz/tmp
# fuzz_recording writes a recording per input: on a RAM file system (tmpfs
# /dev/shm where there is one) it runs about 6x faster than on the disk.
export TMPDIR="$PWD/build/fuzz/tmp"
if [[ -d /dev/shm && -w /dev/shm ]] && shm_dir=$(mktemp -d /dev/shm/uwbnav_fuzz.XXXXXX 2>/dev/null); then
  export TMPDIR="$shm_dir"
  trap 'rm -rf "$shm_dir"' EXIT
fi

max_len() {
  case "$1" in
    fuzz_sequence) echo 32768 ;;
    fuzz_recording) echo 8192 ;;
    fuzz_can_decoder) echo 4096 ;;
    fuzz_console) echo 2048 ;;
    *) echo 1024 ;;
  esac
}

failed=()
rows=()
for t in "${targets[@]}"; do
  work="build/fuzz/corpus/$t"
  mkdir -p "$work"
  log="build/fuzz/$t.log"
  if [[ $runs -gt 0 ]]; then
    budget=(-runs="$(((runs + jobs - 1) / jobs))")
    echo "fuzz: $t for $runs executions ($jobs process(es))"
  else
    budget=(-max_total_time="$seconds")
    echo "fuzz: $t for ${seconds} s ($jobs process(es))"
  fi
  rm -f "build/fuzz/$t".[0-9]*.log
  start=$SECONDS
  # One process per job; a crash, leak, sanitizer report or 10 s slow input stops it.
  pids=()
  for ((j = 0; j < jobs; ++j)); do
    jlog="$log"
    [[ $jobs -gt 1 ]] && jlog="build/fuzz/$t.$j.log"
    "$bin/$t" "${budget[@]}" -timeout=10 -rss_limit_mb=2048 -max_len="$(max_len "$t")" \
      -print_final_stats=1 -artifact_prefix="build/fuzz/artifacts/$t-" "$work" "$seeds/$t" >"$jlog" 2>&1 &
    pids+=($!)
  done
  rc=0
  for p in "${pids[@]}"; do wait "$p" || rc=$?; done
  took=$((SECONDS - start))
  if [[ $jobs -gt 1 ]]; then cat "build/fuzz/$t".[0-9]*.log >"$log"; fi
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | awk '{s += $1} END {if (NR) print s}')
  rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log" | awk '{s += $1} END {if (NR) print s}')
  cov=$(grep -o 'cov: [0-9]*' "$log" | cut -d' ' -f2 | sort -n | tail -1)
  crashes=0
  if [[ $rc -ne 0 ]]; then
    crashes=1
    failed+=("$t")
    grep -m3 -E "ERROR|runtime error|fuzz_sequence:|deadly signal|Test unit written" "$log" || true
  fi
  rows+=("$(printf '| %-17s | %5s | %11s | %7s | %6s | %7s |' "$t" "$took" "${execs:-?}" "${rate:-?}" "${cov:-?}" "$crashes")")
done

echo
echo "| target            | s     | executions  | exec/s  | cov    | crashes |"
echo "|-------------------|-------|-------------|---------|--------|---------|"
printf '%s\n' "${rows[@]}"
if [[ ${#failed[@]} -gt 0 ]]; then
  echo "fuzz: crashed: ${failed[*]} (inputs in build/fuzz/artifacts/, logs build/fuzz/<target>.log)"
  exit 1
fi
