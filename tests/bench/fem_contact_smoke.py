#!/usr/bin/env python3
"""Smoke test of bench_fem_contact on bullet_collide_soft's first 20 steps (two soft cubes at 15 m/s
each, touching from step 8): Torsion keeps them apart and keeps their momentum; without FEM contact
they pass through each other and the interpenetration check says so (so it can fail); Bullet's
run completes with its detection time read from its profile zones.

    fem_contact_smoke.py BENCH_BINARY SCENE.json
"""
import json
import subprocess
import sys


def main() -> int:
    bench, scene = sys.argv[1], sys.argv[2]
    out = subprocess.run([bench, scene, "--steps", "20"], check=True, capture_output=True,
                         text=True).stdout
    rows = {row["engine"]: row for row in map(json.loads, out.splitlines())}
    failures = []

    def expect(condition: bool, what: str) -> None:
        if not condition:
            failures.append(what)

    torsion = rows.get("torsion", {})
    expect(torsion.get("steps") == 20 and not torsion.get("exploded", True),
           "torsion ran 20 steps without exploding")
    expect(torsion.get("passed_through") is False, "torsion keeps the cubes apart")
    expect(torsion.get("momentum") == "kept", "torsion keeps the momentum")
    expect(torsion.get("energy_gained") is False, "torsion gains no kinetic energy")
    off = rows.get("torsion_no_fem_contact", {})
    expect(off.get("steps") == 20, "the run without FEM contact completes (a warning, no error)")
    expect(off.get("passed_through") is True, "without FEM contact the check sees them pass through")
    bullet = rows.get("bullet", {})
    expect(bullet.get("steps") == 20 and not bullet.get("exploded", True),
           "bullet ran 20 steps without exploding")
    expect(bullet.get("detect_cpu_ms_per_step", 0) > 0 and bullet.get("solve_cpu_ms_per_step", 0) > 0,
           "bullet's detection and solve times come from its profile zones")
    for what in failures:
        print("FAILED:", what)
    if failures:
        print(out)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
