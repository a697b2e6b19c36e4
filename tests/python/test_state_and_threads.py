"""Checkpoints continue bit for bit; long loops do not leak; a step lets other threads run."""

import pickle
import resource
import threading
import time

import numpy as np
import pytest

import torsion
from conftest import SOURCE_DIR, cube_mesh


def snapshot(world):
    return [np.array(b.positions) for b in world.bodies] + [np.array(b.velocities) for b in world.bodies] + \
           [h.wrench for h in world.hands] + [s.wrench for s in world.node_sets] + \
           [np.concatenate([r.position, r.quaternion, r.linear_velocity, r.angular_velocity])
            for r in world.rigid_bodies]


# Scenes with hands, node sets and FEM-rigid contact. Not rigid-rigid contact: Bullet's persistent
# manifolds (its contact warm starts) are not part of a checkpoint (docs/python-checkpoints.md).
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


# Saved at step 30 (drop: still falling) and at step 80 (drop: resting on the ground, so the
# rigid-contact warm starts are in the bytes). Restored into the same world and into a new one.
@pytest.mark.parametrize("scene,steps", [("twist_cylinder_2430", 30), ("drop", 30), ("drop", 80),
                                         ("two_hands", 30)])
def test_a_pickled_state_continues_bit_for_bit_here_and_in_a_new_world(scene, steps):
    world = torsion.World.from_scene(scene, threads=1)
    world.step(steps)
    data = pickle.dumps(world.save_state())
    world.step(25)
    first = snapshot(world)
    state = pickle.loads(data)
    assert state.time == pytest.approx(0.01 * steps)
    world.restore_state(state)
    world.step(25)
    fresh = torsion.World.from_scene(scene, threads=1)
    fresh.restore_state(pickle.loads(data))
    assert fresh.step_count == steps
    fresh.step(25)
    for other in (snapshot(world), snapshot(fresh)):
        assert all(np.array_equal(a, b) for a, b in zip(first, other))


def test_a_pickled_state_keeps_a_grab_made_after_the_world_was_built():
    world = torsion.World(dt=0.01, threads=1)
    world.add_body("cyl", str(SOURCE_DIR / "assets/meshes/cylinder_2430.node"))
    world.add_node_set("base", "cyl", plane=((0, 0, 0), (0, 0, 1)))
    hand = world.add_hand("hand", "cyl")
    hand.grab(torsion.Frame(position=(0, 0, 10)))
    for k in range(20):
        hand.move_to(torsion.Frame.from_axis_angle((0, 0, 10), (0, 0, 1), 0.002 * k))
        world.step()
    data = pickle.dumps(world.save_state())
    world.step(20)
    first = snapshot(world)

    fresh = torsion.World(dt=0.01, threads=1)  # built the same way, never grabbed
    fresh.add_body("cyl", str(SOURCE_DIR / "assets/meshes/cylinder_2430.node"))
    fresh.add_node_set("base", "cyl", plane=((0, 0, 0), (0, 0, 1)))
    fresh.add_hand("hand", "cyl")
    fresh.restore_state(pickle.loads(data))
    assert fresh.hand("hand").grabbed
    fresh.step(20)
    assert all(np.array_equal(a, b) for a, b in zip(first, snapshot(fresh)))


def test_truncated_corrupted_or_foreign_bytes_raise_a_clear_error():
    data = torsion.World.from_scene("drop", threads=1).save_state().to_bytes()
    assert data.startswith(b"TRSNCKPT")
    for cut in (0, 5, 20, 27, 28, len(data) // 2, len(data) - 1):
        with pytest.raises(ValueError, match="truncated|not a torsion checkpoint"):
            torsion.State.from_bytes(data[:cut])
    flipped = bytearray(data)
    flipped[len(data) // 2] ^= 0x10
    with pytest.raises(ValueError, match="corrupted"):
        pickle.loads(pickle.dumps(torsion.State.from_bytes(data)).replace(data, bytes(flipped)))
    with pytest.raises(ValueError, match="not a torsion checkpoint"):
        torsion.State.from_bytes(b"PK\x03\x04 a zip file, not a checkpoint")
    newer = bytearray(data)
    newer[8] = 99  # the version
    with pytest.raises(ValueError, match="version 99"):
        torsion.State.from_bytes(bytes(newer))


def fnv1a(data):
    h = 14695981039346656037  # the standard FNV-1a 64 offset basis
    for byte in data:
        h = ((h ^ byte) * 1099511628211) & 0xFFFFFFFFFFFFFFFF
    return h


def test_bytes_altered_behind_a_valid_hash_are_refused_or_restored_never_a_crash():
    world = torsion.World.from_scene("drop", threads=1)
    world.step(80)  # resting on the ground: contacts in the bytes
    data = world.save_state().to_bytes()
    header, payload = data[:28], data[28:]
    rng = np.random.default_rng(7)
    refused = 0
    for trial in range(200):
        altered = bytearray(payload)
        for at in rng.integers(0, len(payload), size=3):
            altered[at] = int(rng.integers(0, 256))
        blob = header[:20] + fnv1a(altered).to_bytes(8, "little") + bytes(altered)
        try:
            world.restore_state(torsion.State.from_bytes(blob))
            world.step(1)
        except (ValueError, torsion.UnstableError):
            refused += 1
    assert refused > 0  # counts, sizes and indices are checked (most bytes are doubles)


def test_a_state_restored_into_another_world_says_so():
    twist = torsion.World.from_scene("twist_cylinder_2430", threads=1).save_state()
    with pytest.raises(ValueError, match="another world"):
        torsion.World.from_scene("drop", threads=1).restore_state(pickle.loads(pickle.dumps(twist)))

    def cube_world(cells):
        world = torsion.World(threads=1)
        nodes, tets = cube_mesh(cells)
        world.add_body("cube", nodes=nodes, tets=tets)
        return world

    state = pickle.dumps(cube_world(2).save_state())
    with pytest.raises(ValueError, match="another world: body 'cube' has another mesh"):
        cube_world(3).restore_state(pickle.loads(state))


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
    world.step(500)  # 0.3 s or more: long beside the 5 ms switch interval
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
