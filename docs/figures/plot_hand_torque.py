#!/usr/bin/python3
"""The torque a turning hand needs against its turn angle, from a run's wrench.csv.

    /usr/bin/python3 docs/figures/plot_hand_torque.py RESULTS_DIR SCENE.json OUT.png [LABEL RESULTS_DIR ...]

The angle is the hand's scripted one, |angular_velocity| t while t < duration (the scene's first
hand); the torque is the hand's wrench about its pivot, along the turn axis (hand.tx..tz in
wrench.csv, docs/outputs.md). Further (LABEL, RESULTS_DIR) pairs of runs of the same scene are
drawn on the same axes.
"""
import csv
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def curve(results_dir, hand, axis, speed, duration):
    angles, torques = [], []
    with open(f"{results_dir}/wrench.csv") as f:
        for row in csv.DictReader(f):
            t = float(row["time"])
            torque = sum(axis[k] * float(row[f"{hand}.t{c}"]) for k, c in enumerate("xyz"))
            angles.append(speed * min(t, duration) / (2 * math.pi))
            torques.append(-torque * 1e3)  # what the hand applies (the body's wrench on it: -)
    return angles, torques


def main(argv):
    if len(argv) < 4 or len(argv) % 2:
        sys.exit(__doc__)
    results, scene_file, out = argv[1:4]
    scene = json.load(open(scene_file))
    hand = scene["hands"][0]
    omega = hand["motion"]["angular_velocity"]
    speed = math.sqrt(sum(w * w for w in omega))
    axis = [w / speed for w in omega]
    duration = hand["motion"].get("duration", math.inf)
    runs = [(scene["name"], results)] + list(zip(argv[4::2], argv[5::2]))
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    for label, directory in runs:
        ax.plot(*curve(directory, hand["name"], axis, speed, duration), label=label, lw=1)
    ax.set_xlabel("turns of the hand")
    ax.set_ylabel("torque about the turn axis (mN m)")
    ax.grid(alpha=0.3)
    if len(runs) > 1:
        ax.legend()
    fig.tight_layout()
    fig.savefig(out, dpi=120)


if __name__ == "__main__":
    main(sys.argv)
