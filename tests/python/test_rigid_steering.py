"""Steering rigid bodies between steps, as a PyBullet or MuJoCo program does: poses, velocities,
forces and torques for the next step, kinematic targets, gravity and dt. Every bad argument is a
clear error that changes nothing."""

import math
import threading
import time

import numpy as np
import pytest

import torsion
from conftest import BULLET_RTOL, cube_mesh

DT = 0.01
# Bullet's rigid bodies are btScalar: float in a float-Bullet build.
RIGID_ATOL = 1e-12 if torsion.bullet_precision == "double" else 1e-5


def free_world(gravity=(0, 0, 0)):
    """A world with a dynamic ball (2 kg, r 0.25 m) at rest and a static slab, far apart."""
    world = torsion.World(gravity=gravity, dt=DT, threads=1)
    ball = world.add_rigid_body("ball", "sphere", radius=0.25, mass=2.0,
                                frame=torsion.Frame(position=(0, 0, 5)))
    slab = world.add_rigid_body("slab", "box", half_extents=(1, 1, 0.1), mass=0,
                                frame=torsion.Frame(position=(10, 0, 0)))
    return world, ball, slab


def snapshot(world, *bodies):
    """Everything a steering call could change."""
    return ([(b.kind, b.position.copy(), b.quaternion.copy(), b.linear_velocity.copy(),
              b.angular_velocity.copy(), b.applied_force.copy(), b.applied_torque.copy())
             for b in bodies], world.gravity.copy(), world.dt, world.time)


def assert_unchanged(before, after):
    (bodies_a, g_a, dt_a, t_a), (bodies_b, g_b, dt_b, t_b) = before, after
    assert np.array_equal(g_a, g_b) and dt_a == dt_b and t_a == t_b
    for a, b in zip(bodies_a, bodies_b):
        assert a[0] == b[0]
        for x, y in zip(a[1:], b[1:]):
            assert np.array_equal(x, y)


def test_set_pose_moves_a_body_at_once_and_keeps_its_velocity():
    world, ball, _ = free_world()
    ball.set_velocity(linear=(1, 0, 0))
    q = np.array([0, 0, math.sin(0.25), math.cos(0.25)])  # 0.5 rad about z
    ball.set_pose(np.array([3.0, 4.0, 5.0]), 2 * q)  # normalised
    assert np.allclose(ball.position, (3, 4, 5), atol=RIGID_ATOL, rtol=0)
    assert np.allclose(ball.quaternion, q, atol=RIGID_ATOL, rtol=0)
    assert np.allclose(ball.linear_velocity, (1, 0, 0), atol=RIGID_ATOL, rtol=0)
    world.step()
    assert ball.position[0] == pytest.approx(3 + DT, abs=1e-6)


def test_a_static_body_set_elsewhere_is_where_a_falling_ball_lands():
    # Collisions use the moved slab at once: the ball rests on its top, 2 m below where it was.
    world = torsion.World(gravity=(0, 0, -9.81), dt=DT, threads=1)
    slab = world.add_rigid_body("slab", "box", half_extents=(1, 1, 0.1), mass=0)
    ball = world.add_rigid_body("ball", "sphere", radius=0.25, mass=1.0,
                                frame=torsion.Frame(position=(0, 0, -1.0)))
    slab.set_pose((0, 0, -2))
    assert slab.kind == "static"
    world.step(150)
    assert ball.position[2] == pytest.approx(-2 + 0.1 + 0.25, abs=0.02)
    assert np.linalg.norm(ball.linear_velocity) < 0.05


def test_set_velocity_sets_either_or_both_velocities_of_a_dynamic_body():
    world, ball, _ = free_world()
    ball.set_velocity(linear=np.array([1.0, 2.0, 3.0]))
    ball.set_velocity(angular=[0, 0, 1])  # the linear velocity stays
    assert np.allclose(ball.linear_velocity, (1, 2, 3), atol=RIGID_ATOL, rtol=0)
    assert np.allclose(ball.angular_velocity, (0, 0, 1), atol=RIGID_ATOL, rtol=0)
    start = ball.position.copy()
    world.step(10)
    assert np.allclose(ball.position - start, np.array([1, 2, 3]) * 10 * DT, atol=1e-5)


def test_a_force_acts_for_the_next_step_only_and_calls_before_it_add_up():
    world, ball, _ = free_world()
    ball.apply_force((1, 0, 0))
    ball.apply_force(np.array([3, 0, 0]))
    assert np.array_equal(ball.applied_force, (4, 0, 0))
    world.step()
    # F / m dt = 4 N / 2 kg * 0.01 s
    assert ball.linear_velocity[0] == pytest.approx(0.02, rel=1e-6)
    assert np.array_equal(ball.applied_force, (0, 0, 0))
    world.step(3)
    assert ball.linear_velocity[0] == pytest.approx(0.02, rel=1e-6)  # not applied again


def test_a_force_off_the_centre_turns_the_body_as_its_torque_does():
    world, ball, _ = free_world()
    inertia = 0.4 * 2.0 * 0.25 ** 2  # solid sphere, kg m^2
    ball.apply_force((0, 1, 0), point=ball.position + (1, 0, 0))  # 1 N m about +z
    assert np.allclose(ball.applied_torque, (0, 0, 1), atol=1e-12)
    world.step()
    assert ball.angular_velocity[2] == pytest.approx(1 / inertia * DT, rel=1e-6)
    assert ball.linear_velocity[1] == pytest.approx(1 / 2.0 * DT, rel=1e-6)
    ball.apply_torque((0, 0, -2))
    world.step()
    assert ball.angular_velocity[2] == pytest.approx(-1 / inertia * DT, rel=1e-6)


def test_a_kinematic_target_is_reached_in_one_step_at_the_velocity_that_takes_it_there():
    world, _, slab = free_world()
    slab.set_kinematic_target((10.1, 0, 0))
    assert slab.kind == "kinematic" and slab.mass == 0
    world.step()
    assert np.allclose(slab.position, (10.1, 0, 0), atol=1e-6)
    assert np.allclose(slab.linear_velocity, (0.1 / DT, 0, 0), rtol=1e-4)
    world.step()  # no new target: it stays
    assert np.allclose(slab.position, (10.1, 0, 0), atol=1e-6)
    assert np.allclose(slab.linear_velocity, 0, atol=1e-6)
    half_turn = [0, 0, 1, 0]
    slab.set_kinematic_target((10.1, 0, 0), half_turn)
    world.step()
    assert abs(np.dot(slab.quaternion, half_turn)) == pytest.approx(1, abs=1e-6)
    assert slab.angular_velocity[2] == pytest.approx(math.pi / DT, rel=1e-4)


def test_a_kinematic_pusher_driven_step_by_step_pushes_a_ball_ahead_of_it():
    world = torsion.World(gravity=(0, 0, 0), dt=DT, threads=1)
    pusher = world.add_rigid_body("pusher", "box", half_extents=(0.25, 0.25, 0.25), mass=0)
    ball = world.add_rigid_body("ball", "sphere", radius=0.25, mass=1.0,
                                frame=torsion.Frame(position=(1, 0, 0)))
    for k in range(1, 101):  # 1 m/s along x for 1 s, as a mocap body follows its data
        pusher.set_kinematic_target((0.01 * k, 0, 0))
        world.step()
    assert pusher.position[0] == pytest.approx(1.0, abs=1e-6)
    assert ball.position[0] > pusher.position[0] + 0.45  # ahead of it, not passed through
    assert ball.linear_velocity[0] > 0.9


def test_set_pose_of_a_kinematic_body_moves_its_target_with_it():
    world, _, slab = free_world()
    slab.set_kinematic_target((10, 1, 0))
    slab.set_pose((10, 2, 0))
    world.step()
    assert np.allclose(slab.position, (10, 2, 0), atol=1e-6)


def test_gravity_and_dt_change_between_steps_for_rigid_and_fem_bodies():
    world = torsion.World(gravity=(0, 0, -9.81), dt=DT, threads=1)
    ball = world.add_rigid_body("ball", "sphere", radius=0.25, mass=1.0,
                                frame=torsion.Frame(position=(5, 0, 0)))
    nodes, tets = cube_mesh(cells=1)
    cube = world.add_body("cube", nodes=nodes, tets=tets)
    assert np.array_equal(world.gravity, (0, 0, -9.81))
    world.step()
    world.gravity = np.array([0.0, 0.0, -1.0])
    world.dt = 0.02
    assert np.array_equal(world.gravity, (0, 0, -1)) and world.dt == 0.02
    world.step()
    assert world.time == pytest.approx(0.03, rel=BULLET_RTOL)
    expected = -9.81 * 0.01 - 1.0 * 0.02
    assert ball.linear_velocity[2] == pytest.approx(expected, rel=1e-5)
    assert np.allclose(cube.velocities[:, 2], expected, rtol=1e-4)  # the CG tolerance


def test_a_python_thread_runs_while_a_steered_world_steps():
    # As test_state_and_threads.py checks for a scene: the queued force and the kinematic target
    # are handed to Bullet inside the step, which holds no GIL.
    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    ball = world.add_rigid_body("ball", "sphere", radius=0.25, mass=2.0,
                                frame=torsion.Frame(position=(20, 0, 5)))
    pusher = world.add_rigid_body("pusher", "box", mass=0, frame=torsion.Frame(position=(30, 0, 0)))
    counter = [0]
    stop = threading.Event()

    def count():
        while not stop.is_set():
            counter[0] += 1

    thread = threading.Thread(target=count)
    thread.start()
    time.sleep(0.05)
    ball.apply_force((1, 0, 0))
    pusher.set_kinematic_target((30, 1, 0))
    before = counter[0]
    start = time.perf_counter()
    world.step(300)
    elapsed = time.perf_counter() - start
    during = counter[0] - before
    stop.set()
    thread.join()
    assert elapsed > 0.1
    assert during > 100_000 * elapsed * 0.2, (during, elapsed)
    assert pusher.position[1] == pytest.approx(1, abs=1e-6)


BAD_BODY_CALLS = [
    # (call on the ball, exception, message)
    (lambda b: b.set_pose((1, 2)), ValueError, r"set_pose 'ball': position: expected 3 numbers"),
    (lambda b: b.set_pose((0, 0, np.nan)), ValueError,
     r"set_pose 'ball': position: must be finite"),
    (lambda b: b.set_pose((0, 0, 1j)), TypeError, r"set_pose 'ball': position: expected real"),
    (lambda b: b.set_pose("abc"), TypeError, r"set_pose 'ball': position: expected numbers"),
    (lambda b: b.set_pose((2e6, 0, 0)), ValueError,
     r"set_pose 'ball': position .* within 1e\+06 m"),
    (lambda b: b.set_pose((0, 0, 1), (0, 0, 0, 0)), ValueError,
     r"set_pose 'ball': quaternion: zero"),
    (lambda b: b.set_pose((0, 0, 1), (0, 0, 1)), ValueError, r"quaternion: expected 4 numbers"),
    (lambda b: b.set_pose((0, 0, 1), (0, 0, np.inf, 1)), ValueError, r"quaternion: must be finite"),
    (lambda b: b.set_velocity(), ValueError, r"set_velocity 'ball': give linear, angular or both"),
    (lambda b: b.set_velocity(linear=(np.inf, 0, 0)), ValueError, r"linear: must be finite"),
    (lambda b: b.set_velocity(linear=np.zeros(4)), ValueError, r"linear: expected 3 numbers"),
    (lambda b: b.set_velocity(angular=(2e6, 0, 0)), ValueError, r"angular .* at most 1e\+06 rad/s"),
    (lambda b: b.set_velocity(linear=(1, 0, 0), angular=(np.nan, 0, 0)), ValueError,
     r"angular: must be finite"),
    (lambda b: b.set_velocity(linear=(0, 2e6, 0)), ValueError, r"speed must be at most 1e\+06"),
    (lambda b: b.apply_force((1, 0, np.nan)), ValueError,
     r"apply_force 'ball': force: must be finite"),
    (lambda b: b.apply_force((1, 0, 0), point=(0, 0)), ValueError, r"point: expected 3 numbers"),
    (lambda b: b.apply_force(np.array([1, 0, 0], dtype=complex)), TypeError,
     r"force: expected real"),
    (lambda b: b.apply_torque([[1, 2, 3, 4]]), ValueError,
     r"apply_torque 'ball': torque: expected 3"),
    (lambda b: b.apply_torque((np.inf, 0, 0)), ValueError, r"torque: must be finite"),
    (lambda b: b.set_kinematic_target((0, 0, 1)), ValueError,
     r"set_kinematic_target 'ball': the body is dynamic \(mass 2 kg\); only a body of mass 0"),
]


@pytest.mark.parametrize("call, error, message", BAD_BODY_CALLS)
def test_a_bad_argument_to_a_dynamic_body_is_an_error_that_changes_nothing(call, error, message):
    world, ball, slab = free_world()
    ball.apply_force((0.5, 0, 0))  # a queued load must survive the failed call too
    world.step()
    ball.apply_force((0.5, 0, 0))
    before = snapshot(world, ball, slab)
    with pytest.raises(error, match=message):
        call(ball)
    assert_unchanged(before, snapshot(world, ball, slab))


BAD_STATIC_CALLS = [
    (lambda s: s.set_velocity(linear=(1, 0, 0)), r"set_velocity 'slab': the body is static"),
    (lambda s: s.apply_force((1, 0, 0)), r"apply_force 'slab': the body is static"),
    (lambda s: s.apply_torque((1, 0, 0)), r"apply_torque 'slab': the body is static"),
    (lambda s: s.set_kinematic_target((0, 0, 2e6)),
     r"set_kinematic_target 'slab': position .* within 1e\+06 m"),
    (lambda s: s.set_kinematic_target((0, 0, 1), (0, 0, 0, 0)),
     r"set_kinematic_target 'slab': quaternion: zero length"),
]


@pytest.mark.parametrize("call, message", BAD_STATIC_CALLS)
def test_a_static_body_refuses_what_only_a_dynamic_one_takes_and_stays_static(call, message):
    world, ball, slab = free_world()
    before = snapshot(world, ball, slab)
    with pytest.raises(ValueError, match=message):
        call(slab)
    assert_unchanged(before, snapshot(world, ball, slab))
    assert slab.kind == "static"


def test_a_kinematic_body_refuses_velocities_and_forces():
    world, ball, slab = free_world()
    slab.set_kinematic_target((10, 0, 1))
    before = snapshot(world, ball, slab)
    with pytest.raises(ValueError, match=r"the body is kinematic: it follows its targets"):
        slab.set_velocity(linear=(1, 0, 0))
    with pytest.raises(ValueError, match=r"apply_force 'slab': the body is kinematic"):
        slab.apply_force((1, 0, 0))
    assert_unchanged(before, snapshot(world, ball, slab))


def test_a_body_its_scene_scripts_cannot_be_steered():
    world = torsion.World.from_scene("press", threads=1)
    plate = world.rigid_body("plate")
    assert plate.kind == "kinematic"
    before = snapshot(world, plate)
    with pytest.raises(ValueError, match=r"set_pose 'plate': .* follows its scene file's script"):
        plate.set_pose((0, 0, 3))
    with pytest.raises(ValueError, match=r"set_kinematic_target 'plate': .* kinematic script"):
        plate.set_kinematic_target((0, 0, 3))
    with pytest.raises(ValueError, match=r"apply_force 'plate': .* scene file's script"):
        plate.apply_force((0, 0, 1))
    assert_unchanged(before, snapshot(world, plate))


@pytest.mark.parametrize("value, error, message", [
    ((0, 0, np.nan), ValueError, r"gravity: must be finite"),
    ((0, 0, 2e6), ValueError, r"gravity: magnitude 2e\+06 m/s\^2 is above the bound 1e\+06"),
    ((0, -9.81), ValueError, r"gravity: expected 3 numbers"),
    ((0, 0, 1j), TypeError, r"gravity: expected real numbers"),
])
def test_bad_gravity_is_an_error_that_changes_nothing(value, error, message):
    world, ball, slab = free_world(gravity=(0, 0, -9.81))
    before = snapshot(world, ball, slab)
    with pytest.raises(error, match=message):
        world.gravity = value
    assert_unchanged(before, snapshot(world, ball, slab))
    world.step()
    assert ball.linear_velocity[2] == pytest.approx(-9.81 * DT, rel=1e-6)


@pytest.mark.parametrize("value, error, message", [
    (0.0, ValueError, r"dt: solver: time_step = 0: must be in"),
    (-0.01, ValueError, r"dt: solver: time_step = -0.01"),
    (2.0, ValueError, r"dt: solver: time_step = 2"),
    (float("nan"), ValueError, r"dt: solver: time_step = nan"),
    ("0.01", TypeError, r""),
])
def test_a_bad_dt_is_an_error_that_changes_nothing(value, error, message):
    world, ball, slab = free_world()
    before = snapshot(world, ball, slab)
    with pytest.raises(error, match=message):
        world.dt = value
    assert_unchanged(before, snapshot(world, ball, slab))


def test_dt_stays_with_device_hands_whose_haptic_loops_run_at_it():
    world = torsion.World.from_scene("haptic_cylinder", threads=1, haptics="lockstep")
    with pytest.raises(ValueError, match=r"dt: the scene's device hands run haptic loops"):
        world.dt = 0.005
    assert world.dt == 0.01


def test_a_step_that_fails_after_a_force_rewinds_to_what_the_good_steps_made_with_it():
    # After a failed step the world replays its good steps from an earlier checkpoint
    # (docs/python-api.md, Argument checks). The force queued for the first of them is replayed with
    # it: the rewound world is bit for bit the one that took the good steps.
    def build():
        world, ball, _ = free_world()
        nodes, tets = cube_mesh(cells=1)
        cube = world.add_body("cube", nodes=nodes, tets=tets,
                              frame=torsion.Frame(position=(0, 5, 0)))
        # 4e4 m/s^2 on every node: past the world's max_speed (1e3 m/s) in the third step.
        cube.set_external_forces(cube.masses[:, None] * np.array([4e4, 0, 0]))
        ball.apply_force((100, 0, 0))
        return world, ball, cube

    reference, reference_ball, reference_cube = build()
    reference.step(2)
    world, ball, cube = build()
    with pytest.raises(torsion.UnstableError, match=r"step 3"):
        world.step(10)
    assert world.step_count == 2
    assert ball.linear_velocity[0] == pytest.approx(100 / 2.0 * DT, rel=1e-6)
    assert np.array_equal(ball.linear_velocity, reference_ball.linear_velocity)
    assert np.array_equal(ball.position, reference_ball.position)
    assert np.array_equal(cube.positions, reference_cube.positions)


def test_a_restored_kinematic_body_is_back_at_its_pose_and_heads_for_its_last_target():
    world, _, slab = free_world()
    slab.set_kinematic_target((10, 1, 0))
    world.step()
    state = world.save_state()
    slab.set_kinematic_target((10, 2, 0))
    world.step()
    world.restore_state(state)
    assert np.allclose(slab.position, (10, 1, 0), atol=1e-6)
    world.step()
    assert np.allclose(slab.position, (10, 2, 0), atol=1e-6)
