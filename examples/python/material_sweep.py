#!/usr/bin/env python3
"""Sweep Young's modulus and Poisson's ratio of a cylinder built in code; tabulate its torsional
stiffness.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/material_sweep.py

Each case: the 2430-tet cylinder, its base held, a hand on its top turned slowly to 0.05 rad and
held until the waves settle; the table (printed and written to sweep.csv in --out) gives the
torque on the base and the ratio to St Venant's G J theta / L.
"""

import argparse
import math
import pathlib

import numpy as np

import torsion

# Light and damped, so that the shear waves cross the 10 m cylinder many times and die out within
# the hold: the torque read is then the static one.
RHO = 100.0  # kg/m^3
MESH = pathlib.Path(__file__).resolve().parents[2] / "assets" / "meshes" / "cylinder_2430.node"


def torsional_torque(E, nu, angle, ramp_steps, hold_steps):
    world = torsion.World(gravity=(0, 0, 0), dt=0.01, threads=1)
    body = world.add_body("cylinder", str(MESH),
                          material=torsion.Material(E=E, nu=nu, rho=RHO, mass_damping=2.0))
    base = world.add_node_set("base", body, plane=((0, 0, 0), (0, 0, 1)))
    top = body.rest_positions[:, 2].max()
    hand = world.add_hand("hand", body)
    hand.grab(torsion.Frame(position=(0, 0, top - 0.1)))
    for k in range(1, ramp_steps + hold_steps + 1):
        turned = angle * min(k, ramp_steps) / ramp_steps
        hand.move_to(torsion.Frame.from_axis_angle((0, 0, top - 0.1), (0, 0, 1), turned))
        world.step()
    x = body.rest_positions
    length = x[:, 2].max() - x[:, 2].min()
    radius = math.sqrt(body.masses.sum() / RHO / (math.pi * length))
    st_venant = body.material.shear_modulus * math.pi * radius ** 4 / 2 * angle / length
    return base.wrench[5], st_venant


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=".")
    parser.add_argument("--quick", action="store_true", help="two values each, short holds")
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    Es = [5e4, 2e5] if args.quick else [5e4, 1e5, 2e5]
    nus = [0.2, 0.4] if args.quick else [0.2, 0.3, 0.4]
    ramp, hold = (100, 150) if args.quick else (100, 300)
    rows = []
    print(f"{'E (Pa)':>10} {'nu':>5} {'base torque (N m)':>18} {'St Venant (N m)':>16} {'ratio':>6}")
    for E in Es:
        for nu in nus:
            torque, st_venant = torsional_torque(E, nu, 0.05, ramp, hold)
            rows.append((E, nu, torque, st_venant, torque / st_venant))
            print(f"{E:10.3g} {nu:5.2f} {torque:18.2f} {st_venant:16.2f} {torque / st_venant:6.3f}")
    np.savetxt(out / "sweep.csv", np.array(rows), delimiter=",",
               header="E_Pa,nu,base_torque_Nm,st_venant_Nm,ratio", comments="")
    print(f"wrote {out / 'sweep.csv'}")


if __name__ == "__main__":
    main()
