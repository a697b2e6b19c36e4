"""World.contacts(): the last step's contacts, as PyBullet's getContactPoints lists them. The
impulses are those the bodies received: a rigid body's momentum changes by exactly its contact
impulses plus gravity's."""

import numpy as np
import pytest

import torsion
from conftest import cube_mesh

DT = 0.01
G = 9.81


def impulse_on(contacts, name):
    """The sum of the impulses `name` received (as A: +impulse; as B: -impulse), N s."""
    a, b = np.array(contacts.body_a), np.array(contacts.body_b)
    return contacts.impulses[a == name].sum(0) - contacts.impulses[b == name].sum(0)


def test_contacts_are_empty_before_the_first_step_and_after_a_restore_until_the_next():
    world = torsion.World(gravity=(0, 0, -G), dt=DT, threads=1)
    world.add_rigid_body("slab", "box", half_extents=(1, 1, 0.1), mass=0)
    world.add_rigid_body("box", "box", half_extents=(0.2, 0.2, 0.2), mass=2.0,
                         frame=torsion.Frame(position=(0, 0, 0.3)))
    contacts = world.contacts()
    assert len(contacts) == 0 and contacts.points.shape == (0, 3)
    world.step(10)
    assert len(world.contacts()) > 0
    world.restore_state(world.save_state())
    assert len(world.contacts()) == 0
    world.step()
    assert len(world.contacts()) > 0


def test_a_sliding_rigid_box_changes_momentum_by_exactly_its_contact_impulses_and_gravity():
    world = torsion.World(gravity=(0, 0, -G), dt=DT, threads=1)
    world.add_rigid_body("slab", "box", half_extents=(5, 5, 0.1), mass=0)
    box = world.add_rigid_body("box", "box", half_extents=(0.2, 0.2, 0.2), mass=2.0,
                               frame=torsion.Frame(position=(0, 0, 0.3)))
    world.step(20)
    box.set_velocity(linear=(1, 0.5, 0))  # friction slows it down
    start = box.linear_velocity.copy()
    received = np.zeros(3)
    for _ in range(30):
        world.step()
        contacts = world.contacts()
        assert set(contacts.body_a) | set(contacts.body_b) == {"slab", "box"}
        received += impulse_on(contacts, "box")
    momentum_change = 2.0 * (box.linear_velocity - start)
    assert momentum_change[0] < -1  # friction took a good part of it
    assert np.allclose(momentum_change, received + (0, 0, -2.0 * G * DT * 30), atol=1e-9)


def test_fem_rigid_contacts_name_the_body_and_partner_and_push_the_box_up_by_its_weight():
    world = torsion.World(gravity=(0, 0, -G), dt=DT, threads=1)
    nodes, tets = cube_mesh(cells=3, size=1.0)
    slab = world.add_body("slab", nodes=nodes, tets=tets, material=torsion.Material(E=1e6))
    world.add_node_set("base", slab, plane=((0, 0, 0), (0, 0, 1)))
    box = world.add_rigid_body("box", "box", half_extents=(0.2, 0.2, 0.1), mass=1.0,
                               frame=torsion.Frame(position=(0.5, 0.5, 1.1)))
    world.step(100)
    start = box.linear_velocity.copy()
    received = np.zeros(3)
    for _ in range(100):
        world.step()
        contacts = world.contacts()
        assert set(contacts.body_a) == {"slab"} and set(contacts.body_b) == {"box"}
        received += impulse_on(contacts, "box")
    # Exact momentum balance of the box, and on average its weight per step.
    assert np.allclose(1.0 * (box.linear_velocity - start),
                       received + (0, 0, -1.0 * G * DT * 100), atol=1e-9)
    assert received[2] / 100 == pytest.approx(1.0 * G * DT, rel=1e-3)
    contacts = world.contacts()
    # The box's bottom face pushes down on the slab's top nodes, and its corners on the slab's
    # triangles: normals from B (box) to A, within the box's tilt (< 1e-3 rad) and the dented
    # triangles' (< 2e-3 rad).
    assert np.allclose(contacts.normals, (0, 0, -1), atol=2e-3)
    assert np.all(contacts.normal_impulses > 0)
    assert np.allclose(contacts.normal_impulses,
                       np.einsum("ij,ij->i", contacts.impulses, contacts.normals))
    bottom = box.position[2] - 0.1
    assert np.allclose(contacts.points[:, 2], bottom, atol=2e-3)


@pytest.mark.parametrize("law", ["corotated", "stable_neo_hookean"])
def test_an_fem_body_sliding_on_the_ground_changes_momentum_by_its_contact_impulses(law):
    # The impulses the contact solve reports are the ones the body's nodes received, friction
    # included; for a hyperelastic body too, whose contacts are solved about its Newton step's
    # free motion (docs/contact.md, "Hyperelastic bodies").
    world = torsion.World(gravity=(0, 0, -G), dt=DT, threads=1, tolerance=1e-8)
    nodes, tets = cube_mesh(cells=2, size=0.5)
    cube = world.add_body("cube", nodes=nodes, tets=tets,
                          material=torsion.Material(E=1e6, law=law))
    world.add_ground(height=0, friction=0.5)
    world.step(20)
    cube.set_velocity((1, 0, 0))
    masses = cube.masses
    start = (masses[:, None] * cube.velocities).sum(0)
    received = np.zeros(3)
    for _ in range(20):
        world.step()
        contacts = world.contacts()
        assert set(contacts.body_a) == {"cube"} and set(contacts.body_b) == {"ground"}
        assert np.allclose(contacts.normals, (0, 0, 1))
        received += contacts.impulses.sum(0)
    change = (masses[:, None] * cube.velocities).sum(0) - start
    assert change[0] < -10  # friction
    # Each step's solve stops within its optimality tolerance, a few 1e-6 of the step's momentum
    # change (about 6 N s): measured 1.5e-5 N s over the 20 steps.
    assert np.allclose(change, received + (0, 0, -masses.sum() * G * DT * 20), atol=1e-4)


def test_contacts_of_a_scene_name_its_bodies():
    world = torsion.World.from_scene("rigid_mix", threads=1)
    world.step(50)
    contacts = world.contacts()
    names = {b.name for b in world.bodies} | {r.name for r in world.rigid_bodies} | {"ground"}
    assert len(contacts) > 0
    assert set(contacts.body_a) <= names and set(contacts.body_b) <= names
    assert np.allclose(np.linalg.norm(contacts.normals, axis=1), 1)
    assert np.all(np.isfinite(contacts.points)) and np.all(np.isfinite(contacts.impulses))
