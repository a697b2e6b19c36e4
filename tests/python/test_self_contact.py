"""Self-contact from Python: one FEM body made of two separate cubes pushed into each other. With
self-contact on they meet, stop each other and never overlap; without it they pass through each
other. Bad settings are refused."""

import numpy as np
import pytest

import torsion
from conftest import cube_mesh

DT = 0.01
SIZE = 0.5  # m, each cube's edge


def two_cubes(self_contact):
    """Two 0.5 m cubes (12.5 kg each) 0.5 m apart along x, one body; each pushed towards the other
    by 20 N for 0.3 s (0.48 m/s each), then left to move freely until 1.2 s. Returns
    the worst overlap over the run (m: the largest x_a - x_b over the pairs of facing nodes, a on
    the first cube's face x = 0.5 and b at the same (y, z) on the second's face x = 1; positive
    where the faces have crossed) and each cube's final mean velocity along x."""
    world = torsion.World(gravity=(0, 0, 0), dt=DT, threads=1)
    nodes, tets = cube_mesh(cells=2, size=SIZE)
    both_nodes = np.vstack([nodes, nodes + (2 * SIZE, 0, 0)])
    both_tets = np.vstack([tets, tets + len(nodes)])
    body = world.add_body("pair", nodes=both_nodes, tets=both_tets,
                          material=torsion.Material(E=1e5, nu=0.3, rho=100))
    if self_contact:
        body.enable_self_contact(friction=0.0)
    a = np.arange(len(nodes))
    b = a + len(nodes)
    forces = np.zeros((len(both_nodes), 3))
    forces[a, 0] = 20.0 / len(a)
    forces[b, 0] = -20.0 / len(b)
    body.set_external_forces(forces)
    face_a = np.flatnonzero(np.abs(nodes[:, 0] - SIZE) < 1e-9)  # sorted by (y, z) alike
    face_b = np.flatnonzero(np.abs(nodes[:, 0]) < 1e-9) + len(nodes)
    assert np.allclose(both_nodes[face_a, 1:], both_nodes[face_b, 1:])
    worst_overlap = -np.inf
    for step in range(120):
        if step == 30:
            body.set_external_forces(np.zeros_like(forces))
        world.step()
        x = body.positions
        worst_overlap = max(worst_overlap, (x[face_a, 0] - x[face_b, 0]).max())
    v = body.velocities
    return worst_overlap, v[a, 0].mean(), v[b, 0].mean()


def test_two_parts_of_one_body_meet_and_stop_each_other_with_self_contact():
    overlap, va, vb = two_cubes(self_contact=True)
    # The faces never cross: the contacts keep every pair of facing nodes apart by the contact
    # thickness, within the gap tolerance (1e-3 of the 0.25 m surface edge: 0.25 mm).
    assert overlap < 2.5e-4
    # The contact is critically damped (docs/contact-solve.md) and the cubes' own rebound damped
    # out: they stop each other (from 0.48 m/s each), equal and opposite (no momentum made).
    assert abs(va) < 0.05 and abs(vb) < 0.05
    assert va == pytest.approx(-vb, rel=1e-6, abs=1e-9)


def test_without_self_contact_the_two_parts_pass_through_each_other():
    overlap, va, vb = two_cubes(self_contact=False)
    assert overlap > 0.2
    assert va > 0 and vb < 0  # still going


@pytest.mark.parametrize("settings, message", [
    (dict(friction=-0.1), "friction"),
    (dict(gap_tolerance=float("nan")), "gap"),
    (dict(margin=-1.0), "margin"),
])
def test_bad_self_contact_settings_are_refused_and_change_nothing(settings, message):
    world = torsion.World(gravity=(0, 0, 0), dt=DT, threads=1)
    nodes, tets = cube_mesh(cells=2, size=SIZE)
    body = world.add_body("cube", nodes=nodes, tets=tets)
    with pytest.raises(ValueError, match=message):
        body.enable_self_contact(**settings)
    assert not body.self_contact
    body.enable_self_contact()
    assert body.self_contact
    body.disable_self_contact()
    assert not body.self_contact
