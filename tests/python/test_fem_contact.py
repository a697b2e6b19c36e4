"""Contact between FEM bodies from Python (a scene's "fem_contact"): two soft cubes pushed into each
other stop each other with it on, keep the gap its settings ask for, pass through each other with it
off (or fail the step when touching is refused), and bad settings are refused."""

import numpy as np
import pytest

import torsion
from conftest import cube_mesh

DT = 0.01
SIZE = 0.5  # m, each cube's edge


def two_cubes(setup=None):
    """Two 0.5 m cubes (12.5 kg each, separate bodies) 0.5 m apart along x, each pushed towards
    the other by 20 N for 0.3 s (0.48 m/s), then free until 1.2 s; `setup(world)` runs before the
    first step. Returns the facing faces' smallest gap over the run (m: min over the pairs of facing
    nodes of x_b - x_a, a on the first cube's face x = 0.5, b at the same (y, z) on the second's
    face x = 1; negative where the faces crossed), its value at the end, and each cube's final
    mean velocity along x."""
    world = torsion.World(gravity=(0, 0, 0), dt=DT, threads=1)
    nodes, tets = cube_mesh(cells=2, size=SIZE)
    material = torsion.Material(E=1e5, nu=0.3, rho=100)
    a = world.add_body("a", nodes=nodes, tets=tets, material=material)
    b = world.add_body("b", nodes=nodes + (2 * SIZE, 0, 0), tets=tets, material=material)
    if setup:
        setup(world)
    push = np.zeros((len(nodes), 3))
    push[:, 0] = 20.0 / len(nodes)
    a.set_external_forces(push)
    b.set_external_forces(-push)
    face_a = np.flatnonzero(np.abs(nodes[:, 0] - SIZE) < 1e-9)  # sorted by (y, z) alike
    face_b = np.flatnonzero(np.abs(nodes[:, 0]) < 1e-9)
    smallest = np.inf
    for step in range(120):
        if step == 30:
            a.set_external_forces(np.zeros_like(push))
            b.set_external_forces(np.zeros_like(push))
        world.step()
        gap = (b.positions[face_b, 0] - a.positions[face_a, 0]).min()
        smallest = min(smallest, gap)
    return smallest, gap, a.velocities[:, 0].mean(), b.velocities[:, 0].mean()


def test_two_cubes_stop_each_other_with_fem_contact_on():
    world = torsion.World(threads=1)
    assert world.fem_contact  # on by default, as in a scene
    smallest, _, va, vb = two_cubes()
    # Never crossed: kept apart by the contact thickness, within the gap tolerance (1e-3 of the
    # 0.25 m surface edge: 0.25 mm).
    assert smallest > -2.5e-4
    # Stopped each other from 0.48 m/s each, equal and opposite (no momentum made).
    assert abs(va) < 0.05 and abs(vb) < 0.05
    assert va == pytest.approx(-vb, rel=1e-6, abs=1e-9)


def test_the_gap_settings_set_from_python_reach_the_solver():
    # A 5 mm gap tolerance with the default thickness factor 2: the faces come closest 10 mm
    # apart (the thickness, within the tolerance), where the default keeps them 0.5 mm apart
    # and thickness_factor=0 lets them meet.
    def wide(world):
        world.enable_fem_contact(gap_tolerance=5e-3)
    smallest, _, va, vb = two_cubes(wide)
    assert 5e-3 < smallest < 1.5e-2
    assert abs(va) < 0.05 and abs(vb) < 0.05
    default, _, _, _ = two_cubes()
    assert 2.5e-4 < default < 7.5e-4

    def thin(world):
        world.enable_fem_contact(gap_tolerance=5e-3, thickness_factor=0)
    touching, _, _, _ = two_cubes(thin)
    assert -5e-3 < touching < 5e-3


def test_without_fem_contact_the_cubes_pass_through_each_other():
    def off(world):
        world.disable_fem_contact()
        assert not world.fem_contact
    smallest, _, va, vb = two_cubes(off)
    assert smallest < -0.2
    assert va > 0 and vb < 0  # still going


def test_refused_touching_fails_the_step_that_touches():
    def refuse(world):
        world.disable_fem_contact(refuse_touching=True)
    with pytest.raises(torsion.UnstableError, match="contact between FEM bodies is off"):
        two_cubes(refuse)


def test_contact_turned_back_on_stops_the_cubes_again():
    def off_then_on(world):
        world.disable_fem_contact()
        world.enable_fem_contact(friction=0.5)
        assert world.fem_contact
    smallest, _, va, vb = two_cubes(off_then_on)
    assert smallest > -2.5e-4
    assert abs(va) < 0.05 and abs(vb) < 0.05


@pytest.mark.parametrize("settings, message", [
    (dict(friction=-0.1), "fem_contact: friction = -0.1"),
    (dict(gap_tolerance=float("nan")), "gap_tolerance"),
    (dict(gap_tolerance=-1.0), "gap_tolerance"),
    (dict(thickness_factor=-1.0), "thickness_factor"),
    (dict(margin=2.0), "margin"),
])
def test_bad_fem_contact_settings_are_refused_and_change_nothing(settings, message):
    def bad_then_off(world):
        with pytest.raises(ValueError, match=message):
            world.enable_fem_contact(**settings)
        assert world.fem_contact  # still on, with its settings
    smallest, _, va, vb = two_cubes(bad_then_off)
    reference = two_cubes()
    assert (smallest, va, vb) == (reference[0], reference[2], reference[3])
    off = torsion.World(threads=1)
    off.disable_fem_contact()
    with pytest.raises(ValueError, match=message):
        off.enable_fem_contact(**settings)
    assert not off.fem_contact
    with pytest.raises(TypeError):
        off.enable_fem_contact(0.3)  # keyword arguments only
