"""A body whose mesh comes in a scattered node order is renumbered inside for speed (add_body's
node_order, default "cache_friendly"), and Python still speaks the mesh's numbers: arrays, node
lists, anchors, forces and errors are those of the same body kept in its file's order
(node_order="file"), to rounding."""

import numpy as np
import pytest

import torsion
from conftest import cube_mesh

DT = 0.01


def scattered_bar():
    """A 2 x 0.5 x 0.5 m bar of 4 x 1 x 1 cubes of 4^3 cells (6 tets each), its nodes scattered as a
    mesher's insertion order leaves them: node i becomes i * 97 mod n."""
    nodes, tets = cube_mesh(cells=4, size=0.5)
    blocks = [nodes + (0.5 * b, 0, 0) for b in range(4)]
    all_nodes = np.concatenate(blocks)
    # merge the shared faces' nodes
    keys = np.round(all_nodes / 0.125).astype(int)
    unique, index = np.unique(keys, axis=0, return_inverse=True)
    index = index.reshape(-1)
    all_tets = np.concatenate([index[tets + b * len(nodes)] for b in range(4)])
    merged = unique * 0.125
    n = len(merged)
    new_of_old = (np.arange(n) * 97) % n
    assert len(np.unique(new_of_old)) == n
    scattered = np.empty_like(merged)
    scattered[new_of_old] = merged
    return scattered, new_of_old[all_tets].astype(np.int32)


def bar_world(order, nodes, tets, element="tet4"):
    world = torsion.World(gravity=(0, 0, -9.81), dt=DT, threads=1)
    body = world.add_body("bar", nodes=nodes, tets=tets, node_order=order, element=element,
                          material=torsion.Material(E=1e6, nu=0.3, rho=1000))
    return world, body


@pytest.mark.parametrize("element", ["tet4", "tet10"])
def test_a_renumbered_body_shows_the_meshs_numbers_and_moves_as_the_file_ordered_one(element):
    nodes, tets = scattered_bar()
    wr, r = bar_world("cache_friendly", nodes, tets, element)
    wf, f = bar_world("file", nodes, tets, element)
    assert r.renumbered and not f.renumbered
    assert np.array_equal(r.rest_positions, f.rest_positions)
    assert np.array_equal(r.tets, f.tets)
    assert np.array_equal(r.surface_triangles, f.surface_triangles)
    assert np.allclose(r.masses, f.masses, rtol=1e-12, atol=0)
    # Clamp the end x = 0 by the mesh's node numbers, push one free node sideways by its number.
    end = np.flatnonzero(r.rest_positions[:, 0] < 1e-9)
    tip = int(np.argmax(r.rest_positions[:, 0] + r.rest_positions[:, 1] + r.rest_positions[:, 2]))
    force = np.zeros((r.node_count, 3))
    force[tip, 1] = 50.0
    for world, body in ((wr, r), (wf, f)):
        assert np.array_equal(world.add_node_set("clamp", body, indices=end).nodes, end)
        body.set_external_forces(force)
        assert np.array_equal(body.external_forces, force)
    view = r.positions
    wr.step(30)
    wf.step(30)
    motion = np.abs(f.positions - f.rest_positions).max()
    assert motion > 1e-3
    assert np.abs(r.positions - f.positions).max() < 1e-9 * motion
    assert np.abs(r.velocities - f.velocities).max() < 1e-9 * motion / (30 * DT)
    assert np.array_equal(view, r.positions)  # the view follows the world
    assert np.allclose(r.von_mises_stress(), f.von_mises_stress(), rtol=1e-9,
                       atol=1e-9 * f.von_mises_stress().max())


def test_anchors_take_the_meshs_numbers_and_their_errors_name_them():
    nodes, tets = scattered_bar()
    runs = {}
    for order in ("cache_friendly", "file"):
        world, body = bar_world(order, nodes, tets)
        plate = world.add_rigid_body("plate", "box", half_extents=(0.1, 0.4, 0.4), mass=0.0,
                                     frame=torsion.Frame(position=(-0.1, 0.25, 0.25)))
        end = np.flatnonzero(body.rest_positions[:, 0] < 1e-9)
        assert body.anchor(end, plate) == 0
        with pytest.raises(ValueError, match=f"node {end[0]} is anchored already"):
            body.anchor(end[:1], plate)
        with pytest.raises(ValueError, match=f"node {body.node_count} out of range"):
            body.anchor([body.node_count], plate)
        free = np.flatnonzero(body.rest_positions[:, 0] > 1.9)
        with pytest.raises(ValueError, match=f"node {free[1]} listed twice"):
            body.anchor([free[0], free[1], free[1]], plate)
        world.step(20)
        runs[order] = body.positions.copy()
    sag = np.abs(runs["file"] - nodes).max()
    assert sag > 1e-3
    assert np.abs(runs["cache_friendly"] - runs["file"]).max() < 1e-9 * sag


def test_a_mesh_in_a_local_order_is_not_renumbered_and_a_bad_order_is_refused():
    nodes, tets = cube_mesh(cells=3)
    world = torsion.World(dt=DT)
    assert not world.add_body("cube", nodes=nodes, tets=tets).renumbered
    with pytest.raises(ValueError, match="node_order 'rcm' is not a node order"):
        world.add_body("other", nodes=nodes, tets=tets, node_order="rcm")
