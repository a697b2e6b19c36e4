#!/usr/bin/env python3
"""Save a world's state, try something, and go back: the continuation repeats bit for bit.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/checkpoint_restore.py

Twists the cylinder of twist_cylinder_2430 for a while, saves, then branches: the scripted twist
goes on twice from the same state (identical to the bit), and once with a sideways push on every
node (different).
"""

import argparse

import numpy as np

import torsion


def main():
    argparse.ArgumentParser(description=__doc__.splitlines()[0]).parse_known_args()  # --out: unused
    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    body = world.body("cylinder")
    world.step(100)
    saved = world.save_state()  # in memory; restore_state goes back to it any number of times
    print(f"saved at t = {saved.time:.2f} s")

    world.step(50)
    first = body.positions.copy()  # positions is a live view: copy to keep this moment

    world.restore_state(saved)
    world.step(50)
    print("same 50 steps again, identical to the bit:", np.array_equal(first, body.positions))

    world.restore_state(saved)
    push = np.zeros((body.node_count, 3))
    push[:, 0] = 0.5  # N on every node, along x
    body.set_external_forces(push)
    world.step(50)
    drift = np.abs(body.positions - first).max()
    print(f"with a 0.5 N push per node instead: largest difference {drift:.4f} m")
    world.restore_state(saved)  # forces are part of the state: the push is gone again
    print("push undone by restore:", not body.external_forces.any())


if __name__ == "__main__":
    main()
