#!/usr/bin/env bash
# Quick start 2 — the test suite: bootstrap what the preset needs, build (preset given as
# $1, default host), run every test with ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
preset="${1:-host}"
bash scripts/bootstrap.sh "$preset"
cmake --preset "$preset"
cmake --build --preset "$preset"
ctest --preset "$preset" -j2
