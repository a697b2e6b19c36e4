"""Anchors from Python (PyBullet's createSoftBodyAnchor): nodes of an FEM body tied to a rigid
body move with it, the body hangs from it, a removed anchor lets go, and every bad argument is a
clear error that anchors nothing."""

import numpy as np
import pytest

import torsion
from conftest import cube_mesh

DT = 0.01
G = 9.81


def hanging_cube(handle_mass=0.0, plate_z=1.1):
    """A 1 m cube (3 cells a side, 100 kg) under gravity and a 0.2 m thick plate centred at
    plate_z (1.1: on its top face), static (mass 0) or dynamic; the cube's top nodes (z = 1)."""
    world = torsion.World(gravity=(0, 0, -G), dt=DT, threads=1)
    nodes, tets = cube_mesh(cells=3)
    cube = world.add_body("cube", nodes=nodes, tets=tets,
                          material=torsion.Material(E=1e6, nu=0.3, rho=100))
    plate = world.add_rigid_body("plate", "box", half_extents=(0.6, 0.6, 0.1), mass=handle_mass,
                                 frame=torsion.Frame(position=(0.5, 0.5, plate_z)))
    top = np.flatnonzero(np.abs(cube.rest_positions[:, 2] - 1.0) < 1e-9)
    return world, cube, plate, top


def test_anchored_nodes_follow_a_kinematic_plate_and_the_cube_hangs_below_it():
    world, cube, plate, top = hanging_cube()
    assert cube.anchor(top, plate) == 0
    start = cube.positions[top].copy()
    # 1 m/s along x for 0.3 s, then held there for 1 s.
    for k in range(1, 31):
        plate.set_kinematic_target((0.5 + 0.01 * k, 0.5, 1.1))
        world.step()
    for _ in range(100):
        world.step()
    moved = cube.positions[top] - start
    # The anchor rows are near-rigid springs (SAP's cap): under the cube's 100 kg they stretch by
    # g dt^2 / (4 pi^2) times a few, tens of micrometres; 1 mm is 0.1 % of the cube.
    assert np.allclose(moved, [0.3, 0, 0], atol=1e-3)
    # Hanging: the centre of mass has come to rest under the plate's centre.
    com = np.average(cube.positions, axis=0, weights=cube.masses)
    assert com[0] == pytest.approx(0.8, abs=1e-3)
    assert com[2] < 0.5 + 1e-3  # it sags (stretched by its weight), never rises
    assert np.abs(cube.velocities).max() < 0.05


def test_a_plate_anchored_under_a_held_cube_hangs_from_it_and_falls_once_let_go():
    # A 5 kg plate touching the cube's bottom face: only the anchor keeps it from falling.
    world, cube, plate, top = hanging_cube(handle_mass=5.0, plate_z=-0.1)
    world.add_node_set("top", cube, indices=top)
    bottom = np.flatnonzero(cube.rest_positions[:, 2] < 1e-9)
    anchor = cube.anchor(bottom, plate)
    for _ in range(50):
        world.step()
    assert abs(plate.linear_velocity[2]) < 1e-3
    assert plate.position[2] == pytest.approx(-0.1, abs=1e-3)
    cube.remove_anchor(anchor)
    for _ in range(10):
        world.step()
    # Free fall from rest (to the anchor's last small motion): v = -g t.
    assert plate.linear_velocity[2] == pytest.approx(-G * 10 * DT, rel=1e-2)
    with pytest.raises(ValueError, match="no anchor 0"):
        cube.remove_anchor(anchor)


@pytest.mark.parametrize("nodes, message", [
    ([[0, 1]], "1-D"),
    ([], "no nodes"),
    ([10 ** 6], "out of range"),
    ([0, 0], "twice"),
    ([0.5], "nodes"),
])
def test_a_bad_anchor_is_an_error_that_anchors_nothing(nodes, message):
    world, cube, plate, _ = hanging_cube()
    with pytest.raises(ValueError, match=message):
        cube.anchor(nodes, plate)
    assert cube.anchor([0], plate) == 0  # the failed call took no id


def test_an_anchor_to_another_worlds_body_and_a_double_anchor_are_refused():
    world, cube, plate, top = hanging_cube()
    _, _, other_plate, _ = hanging_cube()
    with pytest.raises(ValueError, match="another world"):
        cube.anchor(top, other_plate)
    cube.anchor(top, plate)
    with pytest.raises(ValueError, match="anchored already"):
        cube.anchor(top[:1], plate)


def test_restoring_a_state_keeps_the_anchors_there_are_now():
    # Anchors are part of the world around the bodies (docs/python-api.md, "Anchors"): one made
    # after a save still holds after the restore, and the nodes follow the plate.
    world, cube, plate, top = hanging_cube()
    state = world.save_state()
    cube.anchor(top, plate)
    world.restore_state(state)
    start = cube.positions[top].copy()
    for k in range(1, 11):
        plate.set_kinematic_target((0.5 + 0.01 * k, 0.5, 1.1))
        world.step()
    assert np.allclose(cube.positions[top] - start, [0.1, 0, 0], atol=1e-3)
