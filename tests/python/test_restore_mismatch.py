"""A State restored into a world that differs from the one that saved it names the difference,
whether it is the object save_state returned or one unpickled in another process."""

import pickle

import numpy as np
import pytest

import torsion
from conftest import cube_mesh


def arrays(world):
    out = []
    for b in world.bodies:
        out += [np.array(b.positions), np.array(b.velocities)]
    return out + [h.wrench for h in world.hands]


def cube_world(E=1e5, hand=True, extra=False):
    world = torsion.World(threads=1)
    nodes, tets = cube_mesh(2)
    world.add_body("cube", nodes=nodes, tets=tets, material=torsion.Material(E=E))
    if extra:
        world.add_body("extra", nodes=nodes + (3, 0, 0), tets=tets)
    if hand:
        world.add_hand("hand", "cube")
    return world


def both_ways(state):
    """The state as the saving process holds it, and as another process receives it."""
    return [state, pickle.loads(pickle.dumps(state))]


@pytest.mark.parametrize("way", [0, 1])
def test_restoring_into_a_world_without_the_hand_names_the_hand(way):
    state = both_ways(cube_world().save_state())[way]
    with pytest.raises(ValueError) as error:
        cube_world(hand=False).restore_state(state)
    assert str(error.value) == (
        "restore_state: the checkpoint was saved from another world: it has 1 hand (the first "
        "'hand' on body 'cube'), this world none")


@pytest.mark.parametrize("way", [0, 1])
def test_restoring_into_a_world_with_another_material_names_the_body_and_the_values(way):
    state = both_ways(cube_world().save_state())[way]
    with pytest.raises(ValueError) as error:
        cube_world(E=2e5).restore_state(state)
    assert str(error.value) == (
        "restore_state: the checkpoint was saved from another world: body 'cube' was built with "
        "another material (E 100000 Pa in the checkpoint, 200000 Pa here)")


@pytest.mark.parametrize("way", [0, 1])
def test_restoring_into_a_world_with_an_extra_body_names_it(way):
    state = both_ways(cube_world().save_state())[way]
    with pytest.raises(ValueError) as error:
        cube_world(extra=True).restore_state(state)
    assert str(error.value) == (
        "restore_state: the checkpoint was saved from another world: it has 1 FEM body: 'cube'; "
        "this world also has 'extra'")


def test_a_material_set_while_running_is_part_of_the_state_not_a_difference():
    world = cube_world()
    world.step(3)
    world.body("cube").set_material(torsion.Material(E=3e5))
    state = world.save_state()
    world.step(5)
    first = arrays(world)
    for target in (world, cube_world()):  # the same world, and one built the same way
        target.restore_state(pickle.loads(pickle.dumps(state)))
        assert target.body("cube").material.E == 3e5
        target.step(5)
        assert all(np.array_equal(a, b) for a, b in zip(arrays(target), first))
