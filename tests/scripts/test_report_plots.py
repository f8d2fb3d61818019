#!/usr/bin/python3
"""error_time.png is scaled to the filter's error (issue 18): with LS-UWB
spikes of +-30 m and a filter error of a few decimetres, the axes span the
filter's error and the LS spikes are clipped and counted.
usage: /usr/bin/python3 tests/scripts/test_report_plots.py SOURCE_DIR WORK_DIR"""
import os
import sys

import numpy as np

sys.path.insert(0, os.path.join(sys.argv[1], "tools", "plot"))
import report_plots  # noqa: E402


def series(err_m, t):
    return {"t_s": t, "ex_m": err_m, "ey_m": -0.5 * err_m}


def main():
    work = sys.argv[2]
    os.makedirs(work, exist_ok=True)
    t = np.arange(0.0, 60.0, 0.1)
    filt = 0.2 * np.sin(t)
    ls = 0.3 * np.cos(t)
    ls[::50] = 30.0  # LS spikes
    ls[25::50] = -30.0
    s = {"imu_only": None, "ls_uwb": series(ls, t), "ekf_none": series(0.5 * filt, t), "default": series(filt, t)}
    lim = report_plots.draw_error_time(work, "synthetic", s, [("nlos", 10.0, 12.0)])
    assert lim is not None and 0.2 <= lim <= 0.25, f"axis half-height {lim} m, expected the filter's 0.2 m + 15 %"
    assert os.path.getsize(os.path.join(work, "error_time.png")) > 0
    # Without the filter's series the axes fall back to autoscaling.
    fallback = os.path.join(work, "no_filter")
    os.makedirs(fallback, exist_ok=True)
    assert report_plots.draw_error_time(fallback, "synthetic", dict(s, default=None), []) is None
    print("error_time axis +-%.3f m (filter max 0.200 m, LS spikes 30 m clipped)" % lim)


if __name__ == "__main__":
    main()
