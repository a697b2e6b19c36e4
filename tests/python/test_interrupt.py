"""Ctrl-C stops a long World.step at a step boundary and raises KeyboardInterrupt."""

import os
import signal
import threading
import time

import numpy as np
import pytest

import torsion
from conftest import cube_mesh

# The clock sums dt once per step: in a float-Bullet build it drifts by more than double's round-off.
CLOCK_RTOL = 1e-9 if torsion.bullet_precision == "double" else 1e-4


@pytest.mark.skipif(threading.current_thread() is not threading.main_thread(),
                    reason="signals reach Python's main thread only")
def test_sigint_interrupts_a_long_step_and_leaves_whole_steps():
    world = torsion.World(gravity=(0, 0, -9.81), dt=0.01, threads=1)
    nodes, tets = cube_mesh(2)
    body = world.add_body("cube", nodes=nodes, tets=tets)
    world.add_node_set("base", body, plane=((0, 0, 0), (0, 0, 1)))
    timer = threading.Timer(0.5, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            world.step(10 ** 9)
    finally:
        timer.cancel()
    assert time.monotonic() - start < 30
    steps = world.step_count
    assert 0 < steps < 10 ** 9
    assert world.time == pytest.approx(steps * world.dt, rel=CLOCK_RTOL)
    assert np.isfinite(body.positions).all()
    # The world goes on from there, as after world.step(steps).
    world.step(2)
    assert world.step_count == steps + 2
    assert world.time == pytest.approx((steps + 2) * world.dt, rel=CLOCK_RTOL)
    # and the interrupted run is the same as an uninterrupted one of as many steps
    again = torsion.World(gravity=(0, 0, -9.81), dt=0.01, threads=1)
    other = again.add_body("cube", nodes=nodes, tets=tets)
    again.add_node_set("base", other, plane=((0, 0, 0), (0, 0, 1)))
    again.step(steps + 2)
    assert np.array_equal(other.positions, body.positions)
