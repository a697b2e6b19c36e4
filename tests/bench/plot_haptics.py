#!/usr/bin/env python3
"""Force and torque per axis over time from haptic loop logs (HapticLoop::writeLog CSV), as a PNG.

    /usr/bin/python3 tests/bench/plot_haptics.py LOG.csv OUT.png "title"

Six panels sharing the time axis, one per axis: fx fy fz (N) and tx ty tz (N m) of the wrench
written to the device, with the Figure 6.7 sequence's phase boundaries every 20 s. matplotlib
(Debian's python3-matplotlib) with the Agg backend: no display needed.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402  (after choosing the backend)

PHASE_SECONDS = 20  # Figure 6.7: rotate x, translate x, translate z, rotate z, rotate y, translate y


def main():
    if len(sys.argv) != 4:
        sys.exit(__doc__)
    log, out, title = sys.argv[1:]
    with open(log) as f:
        rows = list(csv.DictReader(f))
    if not rows:
        sys.exit(f"{log}: no rows")
    t0 = float(rows[0]["time"])
    t = [float(r["time"]) - t0 for r in rows]
    axes_spec = [("fx", "fx (N)"), ("fy", "fy (N)"), ("fz", "fz (N)"),
                 ("tx", "tx (N m)"), ("ty", "ty (N m)"), ("tz", "tz (N m)")]
    colours = ["tab:red", "tab:green", "tab:blue"] * 2
    fig, axes = plt.subplots(6, 1, sharex=True, figsize=(9, 8.5))
    fig.suptitle(title)
    for ax, (key, label), colour in zip(axes, axes_spec, colours):
        ax.plot(t, [float(r[key]) for r in rows], color=colour, linewidth=0.8)
        ax.axhline(0, color="0.6", linewidth=0.6)
        for phase in range(0, int(t[-1]) + 1, PHASE_SECONDS):
            ax.axvline(phase, color="0.8", linestyle=":", linewidth=0.8)
        ax.set_ylabel(label)
    axes[-1].set_xlabel("time (s)")
    axes[-1].set_xlim(0, max(t[-1], 1e-9))
    fig.tight_layout()
    fig.savefig(out, dpi=100)


if __name__ == "__main__":
    main()
