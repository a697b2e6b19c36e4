#!/usr/bin/python3
"""Hand torque and elastic energy of the 2430-tet cylinder twisted past its kink, from the
`--print` lines of tests/bench/bench_kink_self_contact (docs/validation-twist.md, "Twisting past the
kink"). Usage: plot_kink_torque.py OUT.png LABEL=LOG [LABEL=LOG ...]
"""
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

LINE = re.compile(r"step (\d+): twist ([\d.]+) pi, hand torque ([\d.e+-]+) N m, elastic ([\d.e+-]+) J")


def read(path):
    steps, torque, elastic = [], [], []
    with open(path) as f:
        for line in f:
            m = LINE.match(line)
            if m:
                steps.append(int(m.group(1)) * 0.01)
                torque.append(float(m.group(3)) / 1e3)
                elastic.append(float(m.group(4)) / 1e3)
    return steps, torque, elastic


def main():
    out = sys.argv[1]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 6.5), sharex=True)
    for arg in sys.argv[2:]:
        label, path = arg.split("=", 1)
        t, torque, elastic = read(path)
        top.plot(t, torque, label=label, linewidth=1.2)
        bottom.plot(t, elastic, label=label, linewidth=1.2)
    top.set_ylabel("hand torque (kN m)")
    bottom.set_ylabel("elastic energy (kJ)")
    bottom.set_xlabel("time (s); twist 0.5 rad/s up to 4 pi at 25.1 s (5 pi at 31.4 s), then held")
    top.legend(fontsize=8)
    top.grid(alpha=0.3)
    bottom.grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out, dpi=110)


if __name__ == "__main__":
    main()
