#!/usr/bin/python3
"""Runs the MPS2 firmware image under qemu-system-arm and the host `uwbnav replay`
on the same recording, and compares the image's digest with the host outputs.

Float results on the Cortex-M4F (single-precision FPU, picolibc libm, no SIMD)
and on the host (SSE, glibc libm, Eigen vectorisation) are not bit-identical,
so positions are compared within a tolerance and decision counts within a small
margin; cycles, ranges received and the final status must match exactly.

usage: check_replay.py --qemu QEMU --image ELF --uwbnav UWBNAV --recording DIR --out DIR
                       [--machine mps2-an386] [--tolerance-m 0.05]
"""
import argparse
import csv
import math
import os
import subprocess
import sys

QEMU_TIMEOUT_S = 600


def qemu_command(qemu, machine, image):
    # Semihosting output goes to qemu's stderr; -icount shift=0 makes one
    # instruction advance virtual time by 1 ns (the digest's instruction counts).
    return [qemu, "-M", machine, "-nographic", "-monitor", "none", "-serial", "none",
            "-semihosting-config", "enable=on,target=native", "-icount", "shift=0", "-kernel", image]


def parse_digest(text):
    """Digest lines 'key a=b c=d ...' -> {key: {a: b, ...}}; traj lines -> list."""
    digest, traj = {}, []
    for line in text.splitlines():
        parts = line.split()
        if not parts:
            continue
        if "=" in parts[0]:
            key, fields = "", parts
        else:
            key, fields = parts[0], parts[1:]
        kv = dict(f.split("=", 1) for f in fields if "=" in f)
        if key == "traj":
            traj.append((int(kv["t_us"]), int(kv["status"]), [float(x) for x in kv["pos_m"].split(",")]))
        else:
            digest.setdefault(key, {}).update(kv)
    return digest, traj


def read_csv(path):
    with open(path) as f:
        rows = [r for r in csv.reader(line for line in f if line.strip() and not line.startswith("#"))]
    return rows[0], rows[1:]


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--qemu", required=True)
    p.add_argument("--machine", default="mps2-an386")
    p.add_argument("--image", required=True)
    p.add_argument("--uwbnav", required=True)
    p.add_argument("--recording", required=True)
    p.add_argument("--out", required=True)
    p.add_argument("--tolerance-m", type=float, default=0.05)
    args = p.parse_args()
    os.makedirs(args.out, exist_ok=True)

    cmd = qemu_command(args.qemu, args.machine, args.image)
    print("$ " + " ".join(cmd))
    try:
        q = subprocess.run(cmd, capture_output=True, text=True, timeout=QEMU_TIMEOUT_S)
    except subprocess.TimeoutExpired:
        print(f"FAIL: qemu did not finish within {QEMU_TIMEOUT_S} s")
        return 1
    text = q.stderr + q.stdout
    with open(os.path.join(args.out, "digest.txt"), "w") as f:
        f.write(text)
    if q.returncode != 0 or "end ok" not in text:
        print(text)
        print(f"FAIL: the image exited with code {q.returncode} (0 expected, digest ending in 'end ok')")
        return 1

    host_out = os.path.join(args.out, "host")
    cmd = [args.uwbnav, "replay", args.recording, "--out", host_out]
    print("$ " + " ".join(cmd))
    h = subprocess.run(cmd, capture_output=True, text=True)
    if h.returncode != 0:
        print(h.stdout + h.stderr)
        print(f"FAIL: uwbnav replay exited with code {h.returncode}")
        return 1

    digest, traj = parse_digest(text)
    head, est = read_csv(os.path.join(host_out, "estimates.csv"))
    col = {n: i for i, n in enumerate(head)}
    by_t = {round(float(r[col["t_s"]]) * 1e6): r for r in est}
    rhead, ranges = read_csv(os.path.join(host_out, "ranges.csv"))
    rcol = {n: i for i, n in enumerate(rhead)}

    failures = []
    rows = []

    def compare(what, target, host, tolerance):
        diff = abs(target - host)
        good = diff <= tolerance
        rows.append((what, target, host, diff, tolerance, "ok" if good else "MISMATCH"))
        if not good:
            failures.append(what)

    cycles = int(digest["loop"]["cycles"])
    compare("cycles (outputs)", cycles, len(est), 0)
    compare("ranges reported", int(digest["ranges"]["reported"]), len(ranges), 0)
    n_ranges = max(len(ranges), 1)
    margin = max(3, math.ceil(0.01 * n_ranges))
    compare("ranges used", int(digest["ranges"]["used"]), sum(r[rcol["used"]] == "1" for r in ranges), margin)
    compare("ranges nlos", int(digest["ranges"]["nlos"]), sum(r[rcol["nlos"]] == "1" for r in ranges), margin)
    status_margin = max(3, math.ceil(0.01 * cycles))
    for code, name in enumerate(("initialising", "valid", "degraded", "invalid")):
        host_n = sum(int(r[col["status"]]) == code for r in est)
        compare(f"cycles {name}", int(digest["status_cycles"][name]), host_n, status_margin)

    final = digest["final"]
    last = est[-1]
    compare("final t_us", int(final["t_us"]), round(float(last[col["t_s"]]) * 1e6), 0)
    compare("final status", int(final["status"]), int(last[col["status"]]), 0)
    target_pos = [float(x) for x in final["pos_m"].split(",")]
    host_pos = [float(last[col[c]]) for c in ("x_m", "y_m", "z_m")]
    compare("final position |dp| [m]", 0.0, math.dist(target_pos, host_pos), args.tolerance_m)

    worst, worst_t = 0.0, None
    for t_us, _, pos in traj:
        r = by_t.get(t_us)
        if r is None:
            failures.append(f"trajectory t_us={t_us} missing on the host")
            continue
        d = math.dist(pos, [float(r[col[c]]) for c in ("x_m", "y_m", "z_m")])
        if d > worst:
            worst, worst_t = d, t_us
    compare(f"trajectory 1 Hz, max |dp| [m] (t_us={worst_t})", 0.0, worst, args.tolerance_m)

    print(f"{'quantity':44s} {'target':>14s} {'host':>14s} {'|diff|':>10s} {'allowed':>8s}")
    for what, a, b, d, tol, verdict in rows:
        print(f"{what:44s} {a:14.6g} {b:14.6g} {d:10.4g} {tol:8.4g}  {verdict}")
    for line in text.splitlines():
        if line.startswith(("cost ", "stack ", "memory ")):
            print("target " + line)
    if failures:
        print("FAIL: the Cortex-M4F image and the host replay disagree: " + "; ".join(failures))
        return 1
    print("PASS: the Cortex-M4F image reproduces the host replay")
    return 0


if __name__ == "__main__":
    sys.exit(main())
