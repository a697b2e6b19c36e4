"""World.remove_rigid_body: a rigid body taken out of the world lets go of the FEM bodies it pressed
on or held up, its handles raise a clear error instead of touching freed memory, an anchored body
is refused, and checkpoints go on working (states saved before are refused)."""

import pickle

import numpy as np
import pytest

import torsion
from conftest import cube_mesh

DT = 0.01
G = 9.81


def slab_under_box(with_box=True):
    """A soft 1 m x 1 m x 0.3 m slab (E 2e4 Pa, damped), its bottom held, and a 20 kg box resting
    on its top; 150 steps to settle."""
    world = torsion.World(gravity=(0, 0, -G), dt=DT, threads=1)
    nodes, tets = cube_mesh(cells=3)
    nodes = nodes * (1, 1, 0.3)
    slab = world.add_body("slab", nodes=nodes, tets=tets,
                          material=torsion.Material(E=2e4, nu=0.3, rho=100, mass_damping=5))
    world.add_node_set("bottom", slab, plane=((0, 0, 0), (0, 0, 1)))
    box = None
    if with_box:
        box = world.add_rigid_body("box", "box", half_extents=(0.3, 0.3, 0.1), mass=20,
                                   frame=torsion.Frame(position=(0.5, 0.5, 0.4)))
    world.step(150)
    return world, slab, box


def test_a_soft_slab_springs_back_when_the_box_on_it_is_removed():
    world, slab, box = slab_under_box()
    reference, free_slab, _ = slab_under_box(with_box=False)
    pressed = np.abs(slab.positions - free_slab.positions).max()
    assert pressed > 1e-3  # the box's 196 N press it in by millimetres
    assert any(b == "box" for b in world.contacts().body_b)
    world.remove_rigid_body(box)
    assert [r.name for r in world.rigid_bodies] == []
    assert len(world.contacts()) == 0  # until the next step
    world.step(200)
    reference.step(200)
    # Back to the shape the slab has under its own weight alone.
    assert np.abs(slab.positions - free_slab.positions).max() < 1e-3 * pressed
    assert len(world.contacts()) == 0


def test_a_soft_cube_falls_freely_once_the_slab_under_it_is_removed():
    world = torsion.World(gravity=(0, 0, -G), dt=DT, threads=1, tolerance=1e-8)
    nodes, tets = cube_mesh(cells=2, size=0.5)
    cube = world.add_body("cube", nodes=nodes + (0, 0, 0.1), tets=tets,
                          material=torsion.Material(E=1e5, nu=0.3, rho=200, mass_damping=0))
    slab = world.add_rigid_body("slab", "box", half_extents=(1, 1, 0.05), mass=0,
                                frame=torsion.Frame(position=(0.25, 0.25, 0.05)))
    world.step(100)
    m = cube.masses
    v0 = np.average(cube.velocities[:, 2], weights=m)
    z0 = np.average(cube.positions[:, 2], weights=m)
    assert abs(v0) < 0.01  # resting on the slab
    world.remove_rigid_body("slab")
    n = 20
    world.step(n)
    # Nothing but gravity acts on its momentum: implicit Euler gives v_n = v_0 - g n dt and
    # z_n = z_0 + n dt v_0 - g dt^2 n (n + 1) / 2 for the centre of mass, to the solve's tolerance.
    v = np.average(cube.velocities[:, 2], weights=m)
    z = np.average(cube.positions[:, 2], weights=m)
    assert v == pytest.approx(v0 - G * n * DT, rel=1e-4)
    assert z == pytest.approx(z0 + n * DT * v0 - G * DT ** 2 * n * (n + 1) / 2, abs=1e-4)
    with pytest.raises(ValueError, match="rigid body 'slab' was removed"):
        slab.position


def test_a_removed_body_handle_raises_and_removing_twice_raises():
    world, slab, box = slab_under_box()
    other = world.rigid_body("box")
    world.remove_rigid_body(box)
    assert box.name == "box"  # its name stays readable
    for use in (lambda: box.position, lambda: box.quaternion, lambda: box.linear_velocity,
                lambda: box.mass, lambda: box.kind, lambda: box.applied_force,
                lambda: box.set_pose((0, 0, 1)), lambda: box.set_velocity(linear=(0, 0, 1)),
                lambda: box.apply_force((0, 0, 1)), lambda: other.apply_torque((0, 0, 1)),
                lambda: slab.anchor([0], box)):
        with pytest.raises(ValueError, match="rigid body 'box' was removed from its world"):
            use()
    with pytest.raises(ValueError, match="rigid body 'box' was removed from its world"):
        world.remove_rigid_body(box)
    with pytest.raises(KeyError, match="no rigid body named 'box'"):
        world.remove_rigid_body("box")
    with pytest.raises(KeyError, match="no rigid body named 'box'"):
        world.rigid_body("box")
    # A new body of the same name is another body: the old handles stay dead.
    again = world.add_rigid_body("box", "box", half_extents=(0.3, 0.3, 0.1), mass=20,
                                 frame=torsion.Frame(position=(0.5, 0.5, 2)))
    with pytest.raises(ValueError, match="was removed"):
        box.position
    assert again.position[2] == pytest.approx(2)
    world.step()


def test_an_anchored_body_is_refused_until_its_anchor_is_removed():
    world = torsion.World(gravity=(0, 0, -G), dt=DT, threads=1)
    nodes, tets = cube_mesh(cells=2)
    cube = world.add_body("cube", nodes=nodes, tets=tets,
                          material=torsion.Material(E=1e5, nu=0.3, rho=100))
    plate = world.add_rigid_body("plate", "box", half_extents=(0.6, 0.6, 0.1), mass=0,
                                 frame=torsion.Frame(position=(0.5, 0.5, 1.1)))
    top = np.flatnonzero(np.abs(cube.rest_positions[:, 2] - 1) < 1e-9)
    anchor = cube.anchor(top, plate)
    world.step(5)
    with pytest.raises(ValueError, match="remove_rigid_body 'plate': FEM body 'cube' anchors "
                                         "nodes to it \\(anchor 0\\); remove the anchors first"):
        world.remove_rigid_body(plate)
    assert plate.position[2] == pytest.approx(1.1)  # still there, still holding the cube
    world.step(5)
    assert abs(np.average(cube.velocities[:, 2], weights=cube.masses)) < 0.05
    cube.remove_anchor(anchor)
    world.remove_rigid_body(plate)
    world.step(10)  # now it falls
    assert np.average(cube.velocities[:, 2], weights=cube.masses) < -0.5


def test_states_after_removal_restore_and_states_before_are_refused():
    world, slab, box = slab_under_box()
    before = world.save_state()
    world.remove_rigid_body(box)
    with pytest.raises(ValueError, match="a rigid body was removed since the state was saved"):
        world.restore_state(before)
    world.step(3)
    after = world.save_state()
    world.step(20)
    x = slab.positions.copy()
    world.restore_state(after)
    world.step(20)
    assert np.array_equal(slab.positions, x)
    # Its bytes, unpickled, are read for the world as it is now.
    world.restore_state(pickle.loads(pickle.dumps(after)))
    world.step(20)
    assert np.array_equal(slab.positions, x)
    # Bytes from before the removal do not fit the world any more.
    with pytest.raises(ValueError, match="restore_state: .*rigid"):
        world.restore_state(pickle.loads(pickle.dumps(before)))


def test_a_scene_body_removed_scripted_or_not_leaves_a_world_that_steps():
    world = torsion.World.from_scene("press", threads=1)
    world.step(30)  # the scripted plate presses on the block
    plate = world.rigid_body("plate")
    assert plate.kind == "kinematic"
    world.remove_rigid_body("plate")
    with pytest.raises(ValueError, match="was removed"):
        plate.kind
    world.step(30)
    block = world.body("block")
    assert np.isfinite(block.positions).all()
    with pytest.raises(TypeError, match="removed rigid bodies"):
        pickle.dumps(world)


def test_another_worlds_body_is_refused():
    world, _, _ = slab_under_box(with_box=False)
    other, _, box = slab_under_box()
    with pytest.raises(ValueError, match="another world's"):
        world.remove_rigid_body(box)
    assert box.position[2] > 0
