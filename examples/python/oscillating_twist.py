#!/usr/bin/env python3
"""Twist a cylinder back and forth with a hand driven by a function of time; record the wrench.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/oscillating_twist.py --out /tmp/osc

The 2430-tet cylinder (E = 1 MPa, nu = 0.3, rho = 1000 kg/m^3), its base held, a hand on its top
whose goal frame is turned to theta(t) = theta_max sin(2 pi f t) before every step. First a slow
twist to theta_max and a hold measure the static stiffness k = torque / angle; then the world goes
back to its start (save_state / restore_state) and oscillates for a few periods. Written into
--out: oscillating_twist.csv (time, commanded and reached angle, hand and base torque, per step)
and oscillating_twist.png (torque and angle against time, and torque against angle).

Far below the first torsional mode (about 1.2 Hz here), the torque follows the angle in phase with
amplitude k theta_max, corrected by the cylinder's inertia: a uniform shaft held at one end and
turned at the other feels T = k theta (beta L) cot(beta L) at the turned end and
k theta (beta L) / sin(beta L) at the held one, beta L = omega sqrt(I / k) with I its polar moment
of inertia (the wave equation of torsion). The stiffness damping leads the torque by about
atan(beta_K omega).
"""

import argparse
import math
import pathlib

import numpy as np

import torsion

MESH = pathlib.Path(__file__).resolve().parents[2] / "assets" / "meshes" / "cylinder_2430.node"
MATERIAL = torsion.Material(E=1e6, nu=0.3, rho=1000, mass_damping=0, stiffness_damping=0.01)


def build():
    world = torsion.World(gravity=(0, 0, 0), dt=0.01, threads=1)
    body = world.add_body("cylinder", str(MESH), material=MATERIAL)
    world.add_node_set("base", body, plane=((0, 0, 0), (0, 0, 1)))
    pivot = (0, 0, body.rest_positions[:, 2].max() - 0.1)
    hand = world.add_hand("hand", body)
    hand.grab(torsion.Frame(position=pivot))
    return world, pivot


def drive(world, pivot, angle_at, steps):
    """Steps the world with the hand's goal at angle_at(t) (t: the end of the step); rows of
    (t, commanded angle, reached angle, hand torque, base torque)."""
    hand, base = world.hand("hand"), world.node_set("base")
    rows = []
    for _ in range(steps):
        t = world.time + world.dt
        hand.move_to(torsion.Frame.from_axis_angle(pivot, (0, 0, 1), angle_at(t)))
        world.step()
        q = hand.frame.quaternion  # (x, y, z, w), a rotation about z
        rows.append((world.time, angle_at(t), 2 * math.atan2(q[2], q[3]), -hand.wrench[5],
                     base.wrench[5]))
    return np.array(rows)


def fit_sine(t, y, omega):
    """y ~ a sin(omega t) + b cos(omega t) + c: amplitude and phase (rad, > 0: y leads sin)."""
    design = np.column_stack([np.sin(omega * t), np.cos(omega * t), np.ones_like(t)])
    (a, b, _), *_ = np.linalg.lstsq(design, y, rcond=None)
    return math.hypot(a, b), math.atan2(b, a)


def measure(theta_max=0.1, frequency=0.1, periods=2, ramp_s=4.0, hold_s=2.0):
    """The slow twist's stiffness and the oscillation's rows and fitted torque (last period)."""
    world, pivot = build()
    start = world.save_state()
    slow = drive(world, pivot, lambda t: theta_max * min(t / ramp_s, 1.0),
                 round((ramp_s + hold_s) / world.dt))
    stiffness = slow[-1, 3] / slow[-1, 2]  # N m / rad, hand torque over reached angle

    world.restore_state(start)
    omega = 2 * math.pi * frequency
    steps = round(periods / frequency / world.dt)
    rows = drive(world, pivot, lambda t: theta_max * math.sin(omega * t), steps)
    last = rows[:, 0] > rows[-1, 0] - 1 / frequency + 1e-9  # the last full period
    hand_amplitude, hand_phase = fit_sine(rows[last, 0], rows[last, 3], omega)
    base_amplitude, base_phase = fit_sine(rows[last, 0], rows[last, 4], omega)

    body = world.body("cylinder")
    x = body.rest_positions
    inertia = float(np.sum(body.masses * (x[:, 0] ** 2 + x[:, 1] ** 2)))  # kg m^2 about z
    beta_l = omega * math.sqrt(inertia / stiffness)
    return {
        "theta_max": theta_max, "frequency": frequency, "omega": omega, "stiffness": stiffness,
        "inertia": inertia, "beta_l": beta_l, "rows": rows,
        "hand_amplitude": hand_amplitude, "hand_phase": hand_phase,
        "base_amplitude": base_amplitude, "base_phase": base_phase,
        "hand_predicted": stiffness * theta_max * beta_l / math.tan(beta_l),
        "base_predicted": stiffness * theta_max * beta_l / math.sin(beta_l),
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--theta-max", type=float, default=0.1, help="rad")
    parser.add_argument("--frequency", type=float, default=0.1, help="Hz")
    parser.add_argument("--periods", type=int, default=2)
    parser.add_argument("--out", default=".", help="output directory")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    m = measure(args.theta_max, args.frequency, args.periods)
    rows = m["rows"]
    np.savetxt(out / "oscillating_twist.csv", rows, delimiter=",",
               header="time_s,commanded_angle_rad,angle_rad,hand_torque_Nm,base_torque_Nm",
               comments="")
    print(f"slow twist: k = {m['stiffness']:.1f} N m/rad; I = {m['inertia']:.0f} kg m^2; "
          f"beta L = {m['beta_l']:.3f} at {m['frequency']:g} Hz")
    for end in ("hand", "base"):
        print(f"{end}: torque amplitude {m[end + '_amplitude']:.2f} N m "
              f"(k theta_max {m['stiffness'] * m['theta_max']:.2f}, "
              f"wave equation {m[end + '_predicted']:.2f}), "
              f"leads the angle by {math.degrees(m[end + '_phase']):.2f} deg")

    import matplotlib
    matplotlib.use("Agg")  # headless: write a file, open no window
    import matplotlib.pyplot as plt
    fig, (left, right) = plt.subplots(1, 2, figsize=(10, 4))
    left.plot(rows[:, 0], rows[:, 3], label="hand torque (N m)")
    left.plot(rows[:, 0], rows[:, 4], label="base torque (N m)")
    left.plot(rows[:, 0], m["stiffness"] * rows[:, 2], "k--", label="k θ(t) (slow twist's k)")
    left.set_xlabel("time (s)")
    left.legend()
    right.plot(rows[:, 2], rows[:, 3])
    right.set_xlabel("twist angle θ (rad)")
    right.set_ylabel("hand torque (N m)")
    right.set_title(f"θ = {m['theta_max']:g} sin(2π {m['frequency']:g} t)")
    fig.tight_layout()
    fig.savefig(out / "oscillating_twist.png", dpi=100)
    print(f"wrote {out / 'oscillating_twist.csv'} and {out / 'oscillating_twist.png'}")


if __name__ == "__main__":
    main()
