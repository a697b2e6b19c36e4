#!/usr/bin/env python3
"""A parameter sweep fanned out over Dask: a torque-angle curve per (E, nu, twist rate).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/dask_sweep.py --out /tmp/sweep
    PYTHONPATH=build/python /usr/bin/python3 examples/python/dask_sweep.py --scheduler tcp://host:8786

Each case: the 2430-tet cylinder (10 m long, radius 1 m) with its base held, twisted by a hand on
its top at a constant rate; its curve is the torque the hand feels (N m) at every step's angle
(rad). The cases run as Dask tasks: on a LocalCluster of --workers processes by default, or on the
cluster whose scheduler is at --scheduler. Every worker steps with World(threads=1): one solver
thread per task, so that a machine's worker processes (one per core) do not oversubscribe it.

A task receives a torsion.Material (pickled) and a rate, builds its world on the worker (the mesh
from the worker's own torsion.data_path()), and returns numpy arrays. The results, written to
sweep.npz and sweep.csv in --out, are the same bit for bit as a serial run's
(tests/python/test_dask_sweep.py checks it).
"""

import argparse
import itertools
import logging
import pathlib
import time

import numpy as np

import torsion

DT = 0.01     # s
RHO = 100.0   # kg/m^3: light and damped, so that the torque follows the twist closely
MASS_DAMPING = 2.0  # 1/s


def mesh_path():
    """The cylinder as installed with torsion on this machine (each worker resolves its own)."""
    return torsion.data_path() / "assets" / "meshes" / "cylinder_2430.node"


def torque_angle_curve(material, rate, steps, threads=1):
    """The hand's angle (rad) and its torque about the axis (N m) after each of `steps` steps of a
    twist at `rate` rad/s, on `threads` solver threads."""
    world = torsion.World(gravity=(0, 0, 0), dt=DT, threads=threads)
    body = world.add_body("cylinder", str(mesh_path()), material=material)
    world.add_node_set("base", body, plane=((0, 0, 0), (0, 0, 1)))
    top = body.rest_positions[:, 2].max() - 0.1
    hand = world.add_hand("hand", body)
    hand.grab(torsion.Frame(position=(0, 0, top)))
    angles = np.empty(steps)
    torques = np.empty(steps)
    for k in range(steps):
        angles[k] = rate * DT * (k + 1)
        hand.move_to(torsion.Frame.from_axis_angle((0, 0, top), (0, 0, 1), angles[k]))
        world.step()
        torques[k] = -hand.wrench[5]
    return angles, torques


def cases(quick):
    """(Material, rate rad/s) for every combination of E, nu and rate."""
    Es = [5e4, 2e5] if quick else [5e4, 1e5, 2e5]
    nus = [0.2, 0.4] if quick else [0.2, 0.3, 0.4]
    rates = [0.1] if quick else [0.02, 0.05, 0.1]
    return [(torsion.Material(E=E, nu=nu, rho=RHO, mass_damping=MASS_DAMPING), rate)
            for E, nu, rate in itertools.product(Es, nus, rates)]


def run_case(case, steps, threads=1):
    material, rate = case
    return torque_angle_curve(material, rate, steps, threads)


def sweep_serial(all_cases, steps):
    return [run_case(case, steps) for case in all_cases]


def sweep_on_dask(client, all_cases, steps, threads=1):
    """One task per case; the results in the order of the cases."""
    futures = client.map(run_case, all_cases, steps=steps, threads=threads, pure=False)
    return client.gather(futures)


def local_cluster(workers):
    """`workers` worker processes of one thread each, no dashboard."""
    from distributed import LocalCluster
    return LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                        dashboard_address=None, silence_logs=logging.ERROR)


def write(out, all_cases, results):
    out.mkdir(parents=True, exist_ok=True)
    table = np.array([(m.E, m.nu, rate) for m, rate in all_cases])
    np.savez(out / "sweep.npz", cases=table, angles=np.array([a for a, _ in results]),
             torques=np.array([t for _, t in results]))
    rows = [(m.E, m.nu, rate, a[-1], t[-1]) for (m, rate), (a, t) in zip(all_cases, results)]
    np.savetxt(out / "sweep.csv", np.array(rows), delimiter=",", fmt="%.17g",
               header="E_Pa,nu,rate_rad_per_s,final_angle_rad,final_torque_Nm", comments="")


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scheduler", help="a Dask scheduler's address (tcp://host:8786); "
                                            "default: a LocalCluster on this machine")
    parser.add_argument("--workers", type=int, default=2,
                        help="worker processes of the LocalCluster (one thread each)")
    parser.add_argument("--steps", type=int, default=500, help="steps per case (of 0.01 s)")
    parser.add_argument("--threads", type=int, default=1,
                        help="solver threads per world (0: all cores; oversubscribes, see "
                             "docs/python.md)")
    parser.add_argument("--quick", action="store_true", help="4 cases instead of 27")
    parser.add_argument("--out", default=".")
    args = parser.parse_args()
    from distributed import Client

    all_cases = cases(args.quick)
    start = time.perf_counter()
    if args.scheduler:
        with Client(args.scheduler) as client:
            results = sweep_on_dask(client, all_cases, args.steps, args.threads)
    else:
        with local_cluster(args.workers) as cluster, Client(cluster) as client:
            results = sweep_on_dask(client, all_cases, args.steps, args.threads)
    seconds = time.perf_counter() - start
    print(f"{len(all_cases)} cases of {args.steps} steps on Dask: {seconds:.1f} s")
    print(f"{'E (Pa)':>10} {'nu':>5} {'rate (rad/s)':>12} {'angle (rad)':>11} {'torque (N m)':>13}")
    for (material, rate), (angles, torques) in zip(all_cases, results):
        print(f"{material.E:10.3g} {material.nu:5.2f} {rate:12.3g} {angles[-1]:11.3f} "
              f"{torques[-1]:13.2f}")
    out = pathlib.Path(args.out)
    write(out, all_cases, results)
    print(f"wrote {out / 'sweep.npz'} and {out / 'sweep.csv'}")


if __name__ == "__main__":
    main()
