#!/usr/bin/python3
"""Regenerates the evaluation tables of a small recording and compares them
with the committed docs/results/<name>/tables.csv. Accuracy figures must agree
within noise (1 mm or 1 %); timing columns are machine-dependent and ignored.
Exit 0 pass, 1 mismatch, 77 skipped (nothing committed to compare with)."""
import argparse
import csv
import math
import os
import subprocess
import sys

SPECS = [("sim:parking_nlos:202", "parking_nlos_seed202"), ("hanyang/hanyang_los_trajA_case1", "hanyang_los_trajA_case1")]
IGNORED = {"us_per_cycle", "recording", "method"}


def load(path):
    with open(path, newline="") as f:
        return {r["method"]: r for r in csv.DictReader(f)}


def close(a, b):
    if a == b:
        return True
    try:
        x, y = float(a), float(b)
    except ValueError:
        return False
    if math.isnan(x) and math.isnan(y):
        return True
    return abs(x - y) <= max(1e-3, 0.01 * max(abs(x), abs(y)))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--uwbnav", required=True)
    ap.add_argument("--docs", required=True)
    ap.add_argument("--data", required=True, help="data/ folder of the repository (real recordings)")
    ap.add_argument("--work", required=True)
    a = ap.parse_args()
    checked = 0
    failures = []
    for spec, name in SPECS:
        committed = os.path.join(a.docs, name, "tables.csv")
        if not spec.startswith("sim:"):
            src = os.path.join(a.data, spec)
            if not os.path.isdir(src):
                failures.append(f"{name}: {src} absent (the real recordings ship in data/)")
                continue
            spec = src
        if not os.path.exists(committed):
            failures.append(f"{name}: no committed {committed} (run scripts/make_results.sh)")
            continue
        out = os.path.join(a.work, name)
        subprocess.run([a.uwbnav, "eval", "report", spec, "--out", out, "--no-figures", "--jobs", "1"], check=True,
                       stdout=subprocess.DEVNULL)
        fresh = load(os.path.join(out, name, "tables.csv"))
        old = load(committed)
        if set(fresh) != set(old):
            failures.append(f"{name}: methods differ: {sorted(set(fresh) ^ set(old))}")
            continue
        for method, row in fresh.items():
            for col, val in row.items():
                if col in IGNORED:
                    continue
                if not close(val, old[method].get(col, "")):
                    failures.append(f"{name}/{method}/{col}: committed {old[method].get(col)} but the code gives {val}")
        checked += 1
        print(f"checked {name}: {len(fresh)} methods")
    for f in failures:
        print("MISMATCH", f)
    if failures:
        print("docs/results disagree with the code: regenerate with scripts/make_results.sh")
        return 1
    if checked == 0:
        print("skip: nothing to compare")
        return 77
    return 0


if __name__ == "__main__":
    sys.exit(main())
