#!/usr/bin/env python3
"""Stepping overhead from Python against `torsion run`, on the 2430-tet twist.

    PYTHONPATH=build/python /usr/bin/python3 tests/bench/bench_python_step.py \
        --torsion build/demos/torsion --steps 500 --repeats 5

Both step the same scene the same way (scene::stepScene); what differs is around the step: the
CLI writes its CSV rows per step, Python crosses the binding, releases the GIL and keeps a
checkpoint of the last good step. Measured per step, alternating the two so that a machine shared
with other work loads both alike:
  cli      the median ms/step `torsion run` reports in summary.json (timer around each step)
  py.step  the median of timing each world.step() call from Python
  cli.loop `torsion run` wall time for N steps less that for 1 step, divided by N - 1 (with its
           per-step CSV rows, as a user runs it)
  py.loop  world.step(N) in one call, divided by N (wall time, like cli.loop)
Prints one table; docs/performance.md keeps the numbers.

With --instructions (valgrind installed), it also counts instructions, which a loaded machine does
not disturb: callgrind over N world.step() calls from Python and over `torsion run --steps N`,
each less the same program with 1 step, per step, in all and inside scene::stepScene alone.
"""

import argparse
import json
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import torsion


def cli_ms_per_step(exe, scene, steps, threads):
    with tempfile.TemporaryDirectory() as out:
        subprocess.run([exe, "run", scene, "--steps", str(steps), "--threads", str(threads),
                        "--out", out], check=True, capture_output=True)
        return json.loads((pathlib.Path(out) / "summary.json").read_text())["ms_per_step"]["median"]


def cli_loop_ms_per_step(exe, scene, steps, threads):
    def wall(n):
        with tempfile.TemporaryDirectory() as out:
            start = time.perf_counter()
            subprocess.run([exe, "run", scene, "--steps", str(n), "--threads", str(threads),
                            "--out", out], check=True, capture_output=True)
            return (time.perf_counter() - start) * 1e3
    return (wall(steps) - wall(1)) / (steps - 1)


def python_ms_per_step(scene, steps, threads):
    world = torsion.World.from_scene(scene, threads=threads)
    times = []
    for _ in range(steps):
        start = time.perf_counter()
        world.step()
        times.append((time.perf_counter() - start) * 1e3)
    return statistics.median(times)


def python_loop_ms_per_step(scene, steps, threads):
    world = torsion.World.from_scene(scene, threads=threads)
    start = time.perf_counter()
    world.step(steps)
    return (time.perf_counter() - start) * 1e3 / steps


STEP_SCENE = "torsion::scene::stepScene(*"
PYTHON_LOOP = """import sys, torsion
world = torsion.World.from_scene(sys.argv[1], threads=int(sys.argv[3]))
for _ in range(int(sys.argv[2])):
    world.step()
"""


def callgrind(command):
    """(all instructions, those inside scene::stepScene) of `command` under callgrind."""
    counts = []
    with tempfile.TemporaryDirectory() as out:
        for toggle in ([], [f"--toggle-collect={STEP_SCENE}"]):
            log = pathlib.Path(out) / "callgrind.out"
            subprocess.run(["valgrind", "--tool=callgrind", f"--callgrind-out-file={log}", *toggle,
                            *command], check=True, capture_output=True)
            totals = [line for line in log.read_text().splitlines()
                      if line.startswith("totals:")]
            counts.append(int(totals[0].split()[1]))
    return counts


def instructions_per_step(exe, scene, steps, threads):
    with tempfile.TemporaryDirectory() as out:
        script = pathlib.Path(out) / "loop.py"
        script.write_text(PYTHON_LOOP)
        python = lambda n: [sys.executable, str(script), scene, str(n), str(threads)]
        cli = lambda n: [exe, "run", scene, "--steps", str(n), "--threads", str(threads), "--out",
                         str(pathlib.Path(out) / f"cli{n}")]
        rows = {}
        for name, command in (("py.step", python), ("cli", cli)):
            many, one = callgrind(command(steps)), callgrind(command(1))
            rows[name] = [(m - o) / (steps - 1) for m, o in zip(many, one)]
        return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--torsion", required=True, help="the torsion executable")
    parser.add_argument("--scene", default="twist_cylinder_2430")
    parser.add_argument("--steps", type=int, default=500)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--instructions", type=int, metavar="N", default=0,
                        help="also count instructions over N steps with callgrind (e.g. 101)")
    args = parser.parse_args()

    runs = {"cli": [], "py.step": [], "cli.loop": [], "py.loop": []}
    for _ in range(args.repeats):
        runs["cli"].append(cli_ms_per_step(args.torsion, args.scene, args.steps, args.threads))
        runs["py.step"].append(python_ms_per_step(args.scene, args.steps, args.threads))
        runs["cli.loop"].append(cli_loop_ms_per_step(args.torsion, args.scene, args.steps,
                                                     args.threads))
        runs["py.loop"].append(python_loop_ms_per_step(args.scene, args.steps, args.threads))
    reference = {"cli": "cli", "py.step": "cli", "cli.loop": "cli.loop", "py.loop": "cli.loop"}
    print(f"{args.scene}, {args.steps} steps x {args.repeats}, threads {args.threads}")
    print(f"{'':8} {'median ms/step':>15} {'min':>8} {'max':>8} {'vs':>9}")
    for name, values in runs.items():
        median = statistics.median(values)
        base = statistics.median(runs[reference[name]])
        print(f"{name:8} {median:15.3f} {min(values):8.3f} {max(values):8.3f} "
              f"{(median / base - 1) * 100:+7.1f}% ({reference[name]})")
    if args.instructions:
        rows = instructions_per_step(args.torsion, args.scene, args.instructions, args.threads)
        print(f"instructions per step (callgrind, {args.instructions} steps less 1 step):")
        print(f"{'':8} {'whole program':>15} {'stepScene':>12}")
        for name, (whole, inner) in rows.items():
            print(f"{name:8} {whole:15.0f} {inner:12.0f}")
        whole, inner = (rows["py.step"][k] / rows["cli"][k] - 1 for k in range(2))
        print(f"py.step vs cli: {whole * 100:+.2f}% whole program, {inner * 100:+.2f}% stepScene")


if __name__ == "__main__":
    main()
