"""What a program hands to another process pickles: Material, Frame, and a World loaded from a
scene (as its scene and its state), each copy stepping bit for bit as the original; and Contacts,
a result a worker sends back."""

import math
import pickle

import numpy as np
import pytest

import torsion
from conftest import cube_mesh


def arrays(world):
    out = []
    for b in world.bodies:
        out += [np.array(b.positions), np.array(b.velocities)]
    out += [h.wrench for h in world.hands] + [s.wrench for s in world.node_sets]
    for r in world.rigid_bodies:
        out.append(np.concatenate([r.position, r.quaternion, r.linear_velocity,
                                   r.angular_velocity]))
    return out


def identical(a, b):
    return len(a) == len(b) and all(np.array_equal(x, y) for x, y in zip(a, b))


def twisted_cube(material, frame=torsion.Frame()):
    """A cube on its base, turned by a hand at its top: every material value and the frame act."""
    world = torsion.World(gravity=(0, 0, -9.81), dt=0.01, threads=1)
    nodes, tets = cube_mesh(2)
    cube = world.add_body("cube", nodes=nodes, tets=tets, material=material, frame=frame)
    base = frame.matrix()[:3, 3]
    normal = frame.matrix()[:3, 2]
    world.add_node_set("base", cube, plane=(base, normal))
    hand = world.add_hand("hand", cube)
    hand.grab(torsion.Frame(base + 0.9 * normal, frame.quaternion))
    for k in range(15):
        hand.move_to(torsion.Frame.from_axis_angle(hand.goal.position, normal, 0.01 * k))
        world.step()
    return arrays(world)


MATERIALS = [
    torsion.Material(),
    torsion.Material(E=1.234567e5, nu=0.3141592653589793, rho=987.6, mass_damping=0.1,
                     stiffness_damping=1 / 3, volumetric_strain="nodal_average",
                     barrier_threshold=0.25, barrier_stiffness=12.5),
]


@pytest.mark.parametrize("material", MATERIALS)
def test_a_material_pickles_to_an_equal_one_that_steps_bit_for_bit_alike(material):
    copy = pickle.loads(pickle.dumps(material))
    assert copy == material and copy is not material
    for name in ["E", "nu", "rho", "mass_damping", "stiffness_damping", "volumetric_strain",
                 "barrier_threshold", "barrier_stiffness"]:
        assert getattr(copy, name) == getattr(material, name), name
    assert hash(copy) == hash(material)
    assert copy != torsion.Material(E=material.E * 2)
    assert (material == "not a material") is False
    assert identical(twisted_cube(copy), twisted_cube(material))


def test_a_material_unpickled_from_bad_values_is_refused_as_the_constructor_refuses_them():
    values = list(torsion.Material().__getstate__())
    values[1] = 0.5  # nu
    blank = torsion.Material.__new__(torsion.Material)
    with pytest.raises(ValueError, match="poisson"):
        blank.__setstate__(tuple(values))


def test_a_frame_pickles_to_an_equal_one_that_steps_bit_for_bit_alike():
    frame = torsion.Frame.from_axis_angle((0.1, -0.2, 0.3), (1, 2, 3), math.pi / 7)
    copy = pickle.loads(pickle.dumps(frame))
    assert copy == frame and hash(copy) == hash(frame)
    assert np.array_equal(copy.position, frame.position)
    assert np.array_equal(copy.quaternion, frame.quaternion)  # not normalised again
    assert copy != torsion.Frame(position=(0.1, -0.2, 0.3))
    assert identical(twisted_cube(torsion.Material(), copy), twisted_cube(torsion.Material(), frame))


# Scenes with hands, node sets and FEM-rigid contact (drop at 80 steps: resting on the ground).
@pytest.mark.parametrize("scene,steps", [("twist_cylinder_2430", 30), ("drop", 80)])
def test_a_world_from_a_scene_pickles_as_its_scene_and_state_and_goes_on_bit_for_bit(scene, steps):
    world = torsion.World.from_scene(scene, threads=1)
    world.step(steps)
    world.gravity = (0.5, 0, -9.0)
    world.dt = 0.008
    copy = pickle.loads(pickle.dumps(world))
    assert copy is not world
    assert (copy.time, copy.step_count, copy.dt) == (world.time, world.step_count, world.dt)
    assert np.array_equal(copy.gravity, world.gravity)
    assert identical(arrays(copy), arrays(world))
    world.step(20)
    copy.step(20)
    assert identical(arrays(copy), arrays(world))


def test_a_world_its_scene_does_not_describe_refuses_to_pickle_saying_why():
    with pytest.raises(TypeError, match="built in code"):
        pickle.dumps(torsion.World(threads=1))
    extended = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    extended.add_hand("another", "cylinder")
    with pytest.raises(TypeError, match="Python added"):
        pickle.dumps(extended)


def test_contacts_pickle_with_every_array_as_it_was():
    world = torsion.World.from_scene("drop", threads=1)
    world.step(80)  # resting on the ground
    contacts = world.contacts()
    assert len(contacts) > 0
    copy = pickle.loads(pickle.dumps(contacts))
    assert len(copy) == len(contacts)
    assert (copy.body_a, copy.body_b) == (contacts.body_a, contacts.body_b)
    for name in ["points", "normals", "impulses", "normal_impulses"]:
        assert np.array_equal(getattr(copy, name), getattr(contacts, name)), name
