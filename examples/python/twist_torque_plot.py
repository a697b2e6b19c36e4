#!/usr/bin/env python3
"""Twist the 2430-tet cylinder of demos/scenes and plot torque against twist angle.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/twist_torque_plot.py --steps 1000

Writes torque_vs_angle.png (and .csv) into --out: the torque the hand and the held base feel,
against St Venant's G J theta / L for a circular shaft.
"""

import argparse
import math
import pathlib

import matplotlib

matplotlib.use("Agg")  # headless: write a file, open no window
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import torsion  # noqa: E402


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=1000, help="steps of 0.01 s (0.1 rad/s)")
    parser.add_argument("--out", default=".", help="output directory")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    hand, base = world.hand("hand"), world.node_set("base")
    body = world.body("cylinder")
    rows = []
    for _ in range(args.steps):
        world.step()
        q = hand.frame.quaternion  # (x, y, z, w): a rotation about z
        angle = 2 * math.atan2(q[2], q[3])
        rows.append((world.time, angle, -hand.wrench[5], base.wrench[5]))
    rows = np.array(rows)
    np.savetxt(out / "torque_vs_angle.csv", rows, delimiter=",",
               header="time_s,angle_rad,hand_torque_Nm,base_torque_Nm", comments="")

    x = body.rest_positions
    length = x[:, 2].max() - x[:, 2].min()
    radius = np.sqrt(np.sum(body.masses) / body.material.rho / (math.pi * length))
    stiffness = body.material.shear_modulus * math.pi * radius ** 4 / 2 / length  # N m / rad

    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(rows[:, 1], rows[:, 2], label="hand (body on the hand)")
    ax.plot(rows[:, 1], rows[:, 3], label="base (body on the base)")
    ax.plot(rows[:, 1], stiffness * rows[:, 1], "k--", label="St Venant G J θ / L")
    ax.set_xlabel("twist angle θ (rad)")
    ax.set_ylabel("torque about z (N m)")
    ax.set_title(f"twist_cylinder_2430, E = {body.material.E:g} Pa, ν = {body.material.nu:g}")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out / "torque_vs_angle.png", dpi=100)
    print(f"{args.steps} steps to {rows[-1, 1]:.3f} rad: hand {rows[-1, 2]:.1f} N m, "
          f"base {rows[-1, 3]:.1f} N m, St Venant {stiffness * rows[-1, 1]:.1f} N m")
    print(f"wrote {out / 'torque_vs_angle.png'}")


if __name__ == "__main__":
    main()
