#!/usr/bin/env bash
# Quick start 1 — the main job: bootstrap if needed, build (preset host), run the
# firmware loop in lockstep on the built-in default scenario (simulated parking
# lot with NLOS), print the result table, write outputs to out/run (or $1).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/bootstrap.sh host
cmake --preset host >/dev/null
cmake --build --preset host --target uwbnav
out="${1:-out/run}"
exec ./build/host/bin/uwbnav run --out "$out"
