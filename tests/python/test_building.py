"""Worlds built in code: bodies from files or arrays, node sets, hands, forces, rigid bodies."""

import numpy as np
import pytest

import torsion
from conftest import BULLET_RTOL, cube_mesh


def test_a_free_body_under_external_forces_gains_momentum_f_times_t():
    world = torsion.World(gravity=(0, 0, 0), dt=0.01, tolerance=1e-10, threads=1)
    nodes, tets = cube_mesh(2)
    body = world.add_body("cube", nodes=nodes, tets=tets, material=torsion.Material(E=1e5, nu=0.3, rho=1000))
    forces = np.zeros((body.node_count, 3))
    forces[:, 0] = 2.0  # N per node
    body.set_external_forces(forces)
    np.testing.assert_array_equal(body.external_forces, forces)
    world.step(10)
    momentum = (body.masses[:, None] * body.velocities).sum(axis=0)
    # internal forces sum to zero, so the total impulse is sum(f) t
    expected = 2.0 * body.node_count * world.time
    np.testing.assert_allclose(momentum, [expected, 0, 0], rtol=1e-9, atol=1e-9 * expected)
    with pytest.raises(ValueError, match=r"\(27, 3\)"):
        body.set_external_forces(np.zeros((3, 3)))


def test_a_body_from_a_mesh_file_sits_at_its_frame(assets):
    world = torsion.World(gravity=(0, 0, 0), threads=1)
    frame = torsion.Frame(position=(1, 2, 3))
    body = world.add_body("c", str(assets / "cylinder_2430.node"), frame=frame)
    plain = torsion.World(gravity=(0, 0, 0), threads=1).add_body("c", str(assets / "cylinder_2430.node"))
    np.testing.assert_allclose(body.rest_positions, plain.rest_positions + [1, 2, 3], atol=1e-12)
    assert body.material.E == 1e5 and body.material.nu == 0.3


def test_node_sets_select_by_plane_box_sphere_and_index(assets):
    world = torsion.World(gravity=(0, 0, 0), threads=1)
    body = world.add_body("c", str(assets / "cylinder_2430.node"))
    x = body.rest_positions
    plane = world.add_node_set("bottom", body, plane=((0, 0, 0), (0, 0, 1)))
    box = world.add_node_set("box", "c", box=((-0.5, -0.5, 4), (0.5, 0.5, 6)))
    sphere = world.add_node_set("ball", body, sphere=((0, 0, 9.9), 0.7))
    chosen = world.add_node_set("some", body, indices=np.array([3, 1, 2]))
    np.testing.assert_array_equal(plane.nodes, np.flatnonzero(np.abs(x[:, 2]) <= 1e-6))
    inside = np.flatnonzero(np.all((x >= [-0.5, -0.5, 4]) & (x <= [0.5, 0.5, 6]), axis=1))
    np.testing.assert_array_equal(np.sort(box.nodes), inside)
    np.testing.assert_array_equal(np.sort(sphere.nodes),
                                  np.flatnonzero(np.linalg.norm(x - [0, 0, 9.9], axis=1) <= 0.7))
    assert sorted(chosen.nodes) == [1, 2, 3]
    assert [s.name for s in world.node_sets] == ["bottom", "box", "ball", "some"]
    with pytest.raises(ValueError, match="exactly one"):
        world.add_node_set("bad", body)
    with pytest.raises(ValueError, match="out of range"):
        world.add_node_set("bad", body, indices=[10 ** 6])
    with pytest.raises(KeyError):
        world.node_set("missing")


def test_a_hand_twisting_a_held_cylinder_feels_a_restoring_torque_and_stiffness(assets):
    world = torsion.World(gravity=(0, 0, 0), dt=0.01, threads=1)
    body = world.add_body("c", str(assets / "cylinder_2430.node"), material=torsion.Material(E=1e5, nu=0.3))
    base = world.add_node_set("base", body, plane=((0, 0, 0), (0, 0, 1)))
    hand = world.add_hand("hand", body)
    assert not hand.grabbed and not hand.scripted
    assert np.array_equal(hand.wrench, np.zeros(6))
    top = torsion.Frame(position=(0, 0, 9.9))
    assert hand.grab(top) > 0 and hand.grabbed
    for k in range(1, 201):  # 0.2 rad over 2 s, then hold
        hand.move_to(torsion.Frame.from_axis_angle((0, 0, 9.9), (0, 0, 1), 0.001 * min(k, 200)))
        world.step()
    world.step(200)
    assert hand.wrench[5] < 0 < base.wrench[5]
    K = hand.stiffness()
    assert K.shape == (6, 6)
    assert np.all(np.diag(K) < 0)  # pushing the patch any way, the body pushes back
    assert np.abs(K - K.T).max() < 0.02 * np.abs(K).max()
    # the same goal as a 4x4 matrix
    hand.move_to(hand.goal.matrix())
    np.testing.assert_allclose(hand.goal.quaternion, torsion.Frame.from_matrix(hand.goal.matrix()).quaternion)
    hand.release()
    world.step()
    assert not hand.grabbed and np.array_equal(hand.wrench, np.zeros(6))
    assert world.hand("hand").name == "hand"


def test_a_hand_whose_plane_misses_the_body_says_so(assets):
    world = torsion.World(gravity=(0, 0, 0), threads=1)
    body = world.add_body("c", str(assets / "cylinder_2430.node"))
    hand = world.add_hand("h", body)
    with pytest.raises(ValueError, match="hand 'h'"):
        hand.grab(torsion.Frame(position=(0, 0, 50)))


def test_a_rigid_sphere_falls_freely_then_rests_on_the_ground():
    world = torsion.World(gravity=(0, 0, -9.81), dt=0.01, threads=1)
    world.add_ground(height=0)
    ball = world.add_rigid_body("ball", "sphere", radius=0.25, mass=2.0,
                                frame=torsion.Frame(position=(0, 0, 2)))
    box = world.add_rigid_body("box", "box", half_extents=(0.2, 0.2, 0.2), mass=0.0,
                               frame=torsion.Frame(position=(3, 0, 0.2)))
    assert ball.mass == pytest.approx(2.0) and box.mass == 0
    world.step(10)
    assert ball.linear_velocity[2] == pytest.approx(-9.81 * 0.1, rel=max(1e-9, BULLET_RTOL))
    world.step(300)
    assert ball.position[2] == pytest.approx(0.25, abs=0.02)
    assert [r.name for r in world.rigid_bodies] == ["ball", "box"]


def test_material_and_frame_reject_bad_values():
    with pytest.raises(ValueError, match="poisson"):
        torsion.Material(nu=0.5)
    with pytest.raises(ValueError, match="volumetric_strain"):
        torsion.Material(volumetric_strain="x")
    with pytest.raises(ValueError, match="barrier_threshold"):
        torsion.Material(barrier_threshold=1.0)
    with pytest.raises(ValueError, match="barrier_stiffness"):
        torsion.Material(barrier_stiffness=-1.0)
    plain = torsion.Material(barrier_threshold=0.0)  # the volume barrier turned off
    assert plain.barrier_threshold == 0.0
    assert torsion.Material().barrier_threshold == pytest.approx(0.3)
    with pytest.raises(ValueError, match="rotation"):
        torsion.Frame.from_matrix(np.diag([2.0, 1, 1, 1]))
    with pytest.raises(ValueError, match="linear_solver"):
        torsion.World(linear_solver="lu")
    frame = torsion.Frame.from_axis_angle((1, 2, 3), (0, 0, 1), np.pi / 2)
    m = frame.matrix()
    np.testing.assert_allclose(m[:3, 3], [1, 2, 3])
    np.testing.assert_allclose(m[:3, :3] @ [1, 0, 0], [0, 1, 0], atol=1e-15)


def test_a_live_material_edit_takes_the_new_density_into_the_masses(assets):
    world = torsion.World(gravity=(0, 0, 0), threads=1)
    body = world.add_body("c", str(assets / "cylinder_2430.node"))
    before = body.masses
    body.set_material(torsion.Material(E=2e5, nu=0.25, rho=1500))
    assert body.material.E == 2e5 and body.material.nu == 0.25
    np.testing.assert_allclose(body.masses, 1.5 * before, rtol=1e-12)
    with pytest.raises(ValueError, match="poisson"):
        body.set_material(torsion.Material.__new__(torsion.Material)) if False else torsion.Material(nu=0.6)


def test_an_empty_world_steps_and_refuses_to_write_a_mesh_it_does_not_have(tmp_path):
    world = torsion.World(threads=1)
    world.step(3)
    assert world.bodies == [] and world.hands == [] and world.rigid_bodies == []
    with pytest.raises(ValueError, match="no body"):
        world.write_vtk(str(tmp_path / "x.vtk"))
    with pytest.raises(KeyError):
        world.body("nothing")


def test_a_hyperelastic_law_is_chosen_by_name_and_steps(assets):
    mooney = torsion.Material(nu=0.45, law="mooney_rivlin", mooney_rivlin_c2_fraction=0.25)
    assert mooney.law == "mooney_rivlin" and mooney.mooney_rivlin_c2_fraction == 0.25
    assert torsion.Material().law == "corotated"
    with pytest.raises(ValueError, match="law"):
        torsion.Material(law="neo")
    with pytest.raises(ValueError, match="mooney_rivlin_c2_fraction"):
        torsion.Material(law="mooney_rivlin", mooney_rivlin_c2_fraction=2.0)
    # Falling freely (nothing to touch), the body moves as a rigid one: backward Euler drops it
    # by g dt^2 k (k + 1) / 2 in k steps.
    world = torsion.World(threads=1)
    body = world.add_body("c", str(assets / "cylinder_2430.node"),
                          material=torsion.Material(nu=0.45, law="stable_neo_hookean"))
    z0 = body.positions[:, 2].mean()
    world.step(10)
    drop = z0 - body.positions[:, 2].mean()
    assert drop == pytest.approx(9.81 * 0.01**2 * 10 * 11 / 2, rel=1e-5)  # backward Euler
