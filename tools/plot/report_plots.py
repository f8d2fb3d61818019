#!/usr/bin/python3
"""Draws the evaluation figures of one recording from the CSV series that
`uwbnav eval report` wrote (the numbers come from the C++ code; this only draws).

usage: /usr/bin/python3 tools/plot/report_plots.py REPORT_DIR
Writes REPORT_DIR/{trajectories,cdf_east_north,error_time,sigma_band}.png
(seed 000 Fig. 10, Figs. 6-7, Figs. 8-9, and the filter's claimed 2-sigma band).
"""
import csv
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

# Methods drawn, in legend order (others stay in the tables only).
METHODS = [
    ("imu_only", "IMU only", ":"),
    ("ls_uwb", "LS-UWB", "-."),
    ("ekf_none", "EKF, no gating", "--"),
    ("default", "uwbnav default", "-"),
]


def read_csv(path):
    if not os.path.exists(path):
        return None
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        return None
    return {k: np.array([float(r[k]) if r[k] != "" else np.nan for r in rows]) for k in rows[0]}


def shade_periods(ax, periods):
    if periods is None:
        return
    done = set()
    for kind, t0, t1 in periods:
        color = "tab:red" if kind == "nlos" else "tab:gray"
        label = None if kind in done else ("labelled NLOS" if kind == "nlos" else "UWB outage")
        done.add(kind)
        ax.axvspan(t0, t1, color=color, alpha=0.12, lw=0, label=label)


def error_axis_limit(series):
    """Half-height of the error-over-time axes [m]: the filter's (uwbnav default)
    largest east/north error plus 15 %, at least 0.05 m, so that baselines with
    far larger errors (LS-UWB spikes of tens of metres) do not flatten it."""
    s = series.get("default")
    if s is None:
        return None
    e = np.concatenate([np.abs(s["ex_m"]), np.abs(s["ey_m"])])
    e = e[np.isfinite(e)]
    if len(e) == 0:
        return None
    return max(0.05, 1.15 * float(np.max(e)))


def draw_error_time(d, name, series, periods):
    """Error over time with NLOS periods and outages shaded (Figs. 8-9), scaled
    to the filter's error; other methods beyond the axis are clipped at its edge
    (x markers) and the count of clipped epochs is given in the legend.
    Returns the y limit used (None: autoscaled)."""
    lim = error_axis_limit(series)
    fig, axes = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    for ax, col, title in ((axes[0], "ex_m", "east"), (axes[1], "ey_m", "north")):
        shade_periods(ax, periods)
        for key, label, ls in METHODS:
            s = series[key]
            if s is None or key == "imu_only":
                continue
            v = s[col]
            if lim is None:
                ax.plot(s["t_s"], v, ls, lw=0.8, label=label)
                continue
            out = np.abs(v) > lim
            n_out = int(np.sum(out))
            if n_out:
                label = f"{label} ({n_out} of {len(v)} beyond ±{lim:.2f} m, clipped)"
            line = ax.plot(s["t_s"], np.clip(v, -lim, lim), ls, lw=0.8, label=label)[0]
            if n_out:
                ax.plot(s["t_s"][out], np.sign(v[out]) * lim, "x", ms=4, color=line.get_color())
        if lim is not None:
            ax.set_ylim(-1.05 * lim, 1.05 * lim)
        ax.set_ylabel(f"{title} error [m]")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc="upper right")
    axes[1].set_xlabel("t [s]")
    scale = "" if lim is None else f" (axis scaled to uwbnav default, ±{lim:.2f} m)"
    fig.suptitle(f"{name}: position error over time{scale}")
    fig.tight_layout()
    fig.savefig(os.path.join(d, "error_time.png"), dpi=110)
    plt.close(fig)
    return lim


def main(d):
    name = os.path.basename(os.path.normpath(d))
    series = {k: read_csv(os.path.join(d, f"series_{k}.csv")) for k, _, _ in METHODS}
    tracks = {k: read_csv(os.path.join(d, f"track_{k}.csv")) for k, _, _ in METHODS}
    truth = read_csv(os.path.join(d, "track_truth.csv"))
    anchors = read_csv(os.path.join(d, "anchors.csv"))
    periods = []
    pth = os.path.join(d, "periods.csv")
    if os.path.exists(pth):
        with open(pth, newline="") as f:
            periods = [(r["kind"], float(r["t0_s"]), float(r["t1_s"])) for r in csv.DictReader(f)]

    # Trajectories over the anchor map (Fig. 10).
    fig, ax = plt.subplots(figsize=(8, 6))
    if truth is not None:
        ax.plot(truth["x_m"], truth["y_m"], color="k", lw=0.8, label="truth")
    for key, label, ls in METHODS:
        t = tracks[key]
        if t is not None and key != "imu_only":
            ax.plot(t["x_m"], t["y_m"], ls, lw=1.0, label=label)
    if anchors is not None:
        ax.plot(anchors["x_m"], anchors["y_m"], "^", color="tab:red", ms=9, label="anchors")
    ax.set_xlabel("x (east) [m]")
    ax.set_ylabel("y (north) [m]")
    ax.set_title(f"{name}: trajectories")
    ax.axis("equal")
    ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(d, "trajectories.png"), dpi=110)
    plt.close(fig)

    # East / north |error| CDFs (Figs. 6-7).
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    for ax, col, title in ((axes[0], "ex_m", "east"), (axes[1], "ey_m", "north")):
        for key, label, ls in METHODS:
            s = series[key]
            if s is None or len(s[col]) == 0:
                continue
            v = np.sort(np.abs(s[col]))
            ax.plot(v, np.linspace(0, 1, len(v)), ls, label=label)
        ax.set_xscale("log")
        ax.set_xlabel(f"|{title} error| [m]")
        ax.set_ylabel("cumulative fraction")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle(f"{name}: error CDFs")
    fig.tight_layout()
    fig.savefig(os.path.join(d, "cdf_east_north.png"), dpi=110)
    plt.close(fig)

    draw_error_time(d, name, series, periods)

    # Claimed 2-sigma band over the actual error (default policy).
    s = series["default"]
    if s is not None:
        fig, axes = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
        for ax, e, sg, title in ((axes[0], "ex_m", "sx_m", "x"), (axes[1], "ey_m", "sy_m", "y")):
            shade_periods(ax, periods)
            ax.fill_between(s["t_s"], -2 * s[sg], 2 * s[sg], color="tab:blue", alpha=0.2, label="claimed ±2σ")
            ax.plot(s["t_s"], s[e], color="k", lw=0.7, label="actual error")
            inside = np.mean(np.abs(s[e]) <= 2 * s[sg]) * 100
            ax.set_ylabel(f"{title} error [m]")
            ax.set_title(f"{title}: {inside:.1f} % inside 2σ", fontsize=9)
            ax.grid(True, alpha=0.3)
        axes[0].legend(fontsize=8, loc="upper right")
        axes[1].set_xlabel("t [s]")
        fig.suptitle(f"{name}: uwbnav default, claimed 2σ vs actual error")
        fig.tight_layout()
        fig.savefig(os.path.join(d, "sigma_band.png"), dpi=110)
        plt.close(fig)


if __name__ == "__main__":
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    main(sys.argv[1])
