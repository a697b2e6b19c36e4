"""Checkpoints continue bit for bit; long loops do not leak; a step lets other threads run."""

import pickle
import resource
import threading
import time

import numpy as np
import pytest

import torsion


def snapshot(world):
    return [np.array(b.positions) for b in world.bodies] + [np.array(b.velocities) for b in world.bodies] + \
           [h.wrench for h in world.hands] + [s.wrench for s in world.node_sets] + \
           [np.concatenate([r.position, r.quaternion, r.linear_velocity, r.angular_velocity])
            for r in world.rigid_bodies]


# Scenes with hands, node sets and FEM-rigid contact. Not rigid-rigid contact: Bullet's persistent
# manifolds (its contact warm starts) are not part of a checkpoint (docs/python.md).
@pytest.mark.parametrize("scene", ["twist_cylinder_2430", "drop", "two_hands"])
def test_restoring_a_saved_state_repeats_the_continuation_bit_for_bit(scene):
    world = torsion.World.from_scene(scene, threads=1)
    world.step(30)
    state = world.save_state()
    assert state.time == world.time
    world.step(25)
    first = snapshot(world)
    world.restore_state(state)
    assert world.step_count == 30
    world.step(25)
    second = snapshot(world)
    assert all(np.array_equal(a, b) for a, b in zip(first, second))
    assert any(not np.array_equal(a, b) for a, b in zip(first, snapshot_at_start(scene)))


def snapshot_at_start(scene):
    return snapshot(torsion.World.from_scene(scene, threads=1))


def test_a_state_from_before_a_hand_was_added_is_refused():
    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    state = world.save_state()
    world.add_hand("another", "cylinder")
    with pytest.raises(ValueError, match="added since"):
        world.restore_state(state)


def test_a_state_says_why_it_cannot_be_pickled():
    state = torsion.World.from_scene("drop", threads=1).save_state()
    with pytest.raises(TypeError, match="cannot be pickled"):
        pickle.dumps(state)


def rss_kib():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * resource.getpagesize() // 1024


def test_ten_thousand_steps_reading_every_array_do_not_grow_memory():
    world = torsion.World.from_scene("drop", threads=1)  # 125 nodes on the ground
    body = world.body("ball")

    def loop(steps):
        for _ in range(steps):
            world.step()
            total = body.positions.sum() + body.velocities.sum() + body.rest_positions.sum()
            total += body.tets.sum() + body.surface_triangles.sum() + body.external_forces.sum()
            total += body.masses.sum() + body.von_mises_stress().sum() + world.time
            assert np.isfinite(total)

    loop(1000)  # allocator and caches warm
    before = rss_kib()
    loop(9000)
    grown = rss_kib() - before
    # a leak of one small array per step would be > 9000 * 1 KiB
    assert grown < 2048, f"resident memory grew by {grown} KiB over 9000 steps"


def test_a_python_thread_runs_while_the_world_steps():
    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    counter = [0]
    stop = threading.Event()

    def count():
        while not stop.is_set():
            counter[0] += 1

    thread = threading.Thread(target=count)
    thread.start()
    time.sleep(0.05)
    before = counter[0]
    start = time.perf_counter()
    world.step(150)
    elapsed = time.perf_counter() - start
    during = counter[0] - before
    stop.set()
    thread.join()
    # Holding the GIL through step() would leave the counter at most a switch interval's worth
    # of increments; released, it counts all along.
    assert elapsed > 0.1
    assert during > 100_000 * elapsed * 0.2, (during, elapsed)


def test_calls_during_a_step_in_another_thread_are_refused_not_raced():
    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    errors = []
    thread = threading.Thread(target=lambda: world.step(1000))
    thread.start()
    while thread.is_alive() and not errors:  # until the step has begun (a loaded machine is slow)
        try:
            world.save_state()
        except RuntimeError as e:
            errors.append(str(e))
        time.sleep(0.001)
    thread.join()
    assert errors and "stepping in another thread" in errors[0]
    assert world.step_count == 1000  # the step itself went through
