"""The smaller parts of the API, each with the fact it should report."""

import numpy as np
import pytest

import torsion
from conftest import cube_mesh


def held_cube():
    world = torsion.World(gravity=(0, 0, -9.81), dt=0.01, threads=1)
    nodes, tets = cube_mesh(2)
    body = world.add_body("cube", nodes=nodes, tets=tets,
                          material=torsion.Material(E=1e5, nu=0.3, rho=1000, mass_damping=1.0))
    base = world.add_node_set("base", body, plane=((0, 0, 0), (0, 0, 1)))
    return world, body, base


def test_a_held_base_carries_the_bodys_weight_and_lets_go_when_released():
    world, body, base = held_cube()
    assert base.body.name == "cube" and base.name == "base" and len(base.nodes) == 9
    world.step(300)  # damped: settled
    # the body pushes down on the base with the weight of its free nodes (the held nodes' own
    # weight goes straight into their constraint)
    free = np.setdiff1d(np.arange(body.node_count), base.nodes)
    weight = body.masses[free].sum() * 9.81
    assert base.wrench[2] == pytest.approx(-weight, rel=1e-3)
    base.release()
    world.step()
    assert np.array_equal(base.wrench, np.zeros(6))
    world.step(10)
    assert body.velocities[:, 2].mean() < -0.05  # now it falls


def test_set_velocity_moves_a_free_body_rigidly_and_kinetic_energy_follows():
    world = torsion.World(gravity=(0, 0, 0), dt=0.01, threads=1)
    nodes, tets = cube_mesh(1)
    body = world.add_body("cube", nodes=nodes, tets=tets)
    body.set_velocity((0.5, 0, 0))
    np.testing.assert_array_equal(body.velocities, np.tile([0.5, 0, 0], (body.node_count, 1)))
    world.step(10)
    np.testing.assert_allclose(body.positions - body.rest_positions,
                               np.tile([0.05, 0, 0], (body.node_count, 1)), atol=1e-12)
    assert body.kinetic_energy == pytest.approx(0.5 * body.masses.sum() * 0.25, rel=1e-9)
    assert body.solver_iterations >= 0
    assert "cube" in repr(body) and "8 nodes" in repr(body)


def test_material_reports_what_it_was_given_and_its_shear_modulus():
    m = torsion.Material(E=2e5, nu=0.25, rho=800, mass_damping=0.1, stiffness_damping=0.02,
                         volumetric_strain="nodal_average")
    assert (m.E, m.nu, m.rho, m.mass_damping, m.stiffness_damping) == (2e5, 0.25, 800, 0.1, 0.02)
    assert m.volumetric_strain == "nodal_average"
    assert m.shear_modulus == pytest.approx(2e5 / 2.5)
    assert "E=200000" in repr(m)


def test_a_hand_knows_its_body_and_its_speed_limit_from_the_shear_wave_speed(assets):
    world = torsion.World(gravity=(0, 0, 0), threads=1)
    body = world.add_body("c", str(assets / "cylinder_2430.node"))
    hand = world.add_hand("h", body, max_drag_strain=0.2)
    hand.grab(torsion.Frame(position=(0, 0, 9.9)))
    assert hand.body.name == "c"
    assert hand.speed_limit == pytest.approx(0.2 * np.sqrt(1e5 / 2.6 / 1000), rel=1e-12)
    unlimited = world.add_hand("free", body, max_drag_strain=0)
    unlimited.grab(torsion.Frame(position=(0, 0, 5.0)))
    assert np.isinf(unlimited.speed_limit)


def test_a_capsule_set_moving_coasts_at_its_velocity_without_gravity():
    world = torsion.World(gravity=(0, 0, 0), threads=1)
    capsule = world.add_rigid_body("cap", "capsule", radius=0.2, half_height=0.5, mass=1.0,
                                   linear_velocity=(1, 0, 0))
    world.step(10)
    np.testing.assert_allclose(capsule.position, [0.1, 0, 0], atol=1e-9)
    np.testing.assert_allclose(capsule.angular_velocity, [0, 0, 0], atol=1e-12)
    with pytest.raises(ValueError, match="shape"):
        world.add_rigid_body("cone", "cone")


def test_a_frame_prints_its_origin_and_rotation():
    text = repr(torsion.Frame(position=(1, 2, 3)))
    assert "1.0" in text and "quaternion=(0.0" in text


def box_on_a_tilted_slab(degrees):
    """A 1 kg box on a soft slab (1 x 1 x 0.2 m, base held) under gravity tilted by `degrees`
    about y; mu = 0.5 (the body's 1.0 times the box's 0.5). Returns the box's x after 0.5 s."""
    a = np.radians(degrees)
    world = torsion.World(gravity=(9.81 * np.sin(a), 0, -9.81 * np.cos(a)), dt=0.01,
                          tolerance=1e-6, max_iterations=1000, threads=1)
    nodes, tets = cube_mesh(4)
    nodes = nodes * [1.0, 1.0, 0.2]
    slab = world.add_body("slab", nodes=nodes, tets=tets,
                          material=torsion.Material(E=1e6, nu=0.3, rho=200, stiffness_damping=0.01))
    world.add_node_set("base", slab, plane=((0, 0, 0), (0, 0, 1)))
    box = world.add_rigid_body("box", "box", half_extents=(0.15, 0.15, 0.05), mass=1.0,
                               frame=torsion.Frame(position=(0.35, 0.5, 0.2 + 0.05 + 1e-4)),
                               friction=0.5)
    x0 = box.position[0]
    world.step(50)
    return box.position[0] - x0


def test_a_box_on_a_soft_slab_holds_below_the_friction_angle_and_slides_as_coulomb_above():
    # atan(0.5) = 26.6 deg. 20 deg below: held (the landing's slip and the slab's shear only).
    assert abs(box_on_a_tilted_slab(20)) < 2e-3
    # 35 deg: Coulomb's 0.5 g (sin a - mu cos a) t^2 = 0.201 m in 0.5 s; dropped 0.1 mm onto the
    # slope, the box first falls freely along it for 5 ms (+4 %), hence 10 %.
    a = np.radians(35)
    coulomb = 0.5 * 9.81 * (np.sin(a) - 0.5 * np.cos(a)) * 0.5 ** 2
    assert box_on_a_tilted_slab(35) == pytest.approx(coulomb, rel=0.1)
