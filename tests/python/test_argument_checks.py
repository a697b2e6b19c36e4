"""Arguments are checked as strictly as the scene file's values: a bad one raises ValueError or
TypeError naming the argument and the value, before anything changes in the world."""

import math

import numpy as np
import pytest

import torsion
from conftest import cube_mesh

NAN = float("nan")


def small_world():
    world = torsion.World(gravity=(0, 0, -9.81), dt=0.01, threads=1)
    nodes, tets = cube_mesh(1)
    body = world.add_body("cube", nodes=nodes, tets=tets)
    return world, body


@pytest.mark.parametrize("kwargs, match", [
    (dict(shape="sphere", radius=-1), "radius -1"),
    (dict(shape="sphere", radius=NAN), "radius nan"),
    (dict(shape="sphere", radius=0), "radius 0"),
    (dict(shape="sphere", radius=1e7), "radius 1e\\+07"),
    (dict(shape="box", half_extents=(0, 1, 1)), "half_extents \\(0, 1, 1\\)"),
    (dict(shape="box", half_extents=(1, NAN, 1)), "half_extents"),
    (dict(shape="capsule", radius=0.1, half_height=-0.5), "half_height -0.5"),
    (dict(mass=-1), "mass -1 kg"),
    (dict(mass=NAN), "mass nan kg"),
    (dict(mass=1e-300), "mass 1e-300 kg"),
    (dict(mass=1e300), "mass 1e\\+300 kg"),
    (dict(friction=-0.1), "friction -0.1"),
    (dict(friction=NAN), "friction nan"),
    (dict(linear_velocity=(NAN, 0, 0)), "linear_velocity"),
    (dict(mass=0, linear_velocity=(1, 0, 0)), "linear_velocity"),
    (dict(frame=torsion.Frame(position=(0, 0, 1e9))), "frame position"),
])
def test_add_rigid_body_refuses_bad_values(kwargs, match):
    world = torsion.World(threads=1)
    with pytest.raises(ValueError, match=match):
        world.add_rigid_body("r", **kwargs)
    assert world.rigid_bodies == []


def test_add_rigid_body_takes_the_mass_bounds_and_a_static_body():
    world = torsion.World(threads=1)
    assert world.add_rigid_body("light", "sphere", mass=1e-9).mass == pytest.approx(1e-9)
    assert world.add_rigid_body("heavy", "sphere", mass=1e12).mass == pytest.approx(1e12)
    assert world.add_rigid_body("static", "box", mass=0).mass == 0


@pytest.mark.parametrize("name, match", [
    ("", "must not be empty"),
    ("../x", "character '/' not allowed"),
    ("a\0b", "character \\\\x00 not allowed"),
    ("..", "cannot name a file"),
    ("x" * 65, "at most 64"),
])
@pytest.mark.parametrize("part", ["body", "rigid body", "node set", "hand"])
def test_names_follow_the_scene_files_rule(part, name, match):
    world, body = small_world()
    with pytest.raises(ValueError, match=match) as info:
        if part == "body":
            nodes, tets = cube_mesh(1)
            world.add_body(name, nodes=nodes, tets=tets)
        elif part == "rigid body":
            world.add_rigid_body(name, "sphere")
        elif part == "node set":
            world.add_node_set(name, body, indices=[0])
        else:
            world.add_hand(name, body)
    assert str(info.value).startswith(part + " name")
    assert len(world.bodies) == 1 and world.rigid_bodies == [] and world.node_sets == []
    assert world.hands == []


@pytest.mark.parametrize("part", ["rigid body", "node set", "hand"])
def test_duplicate_names_are_refused(part):
    world, body = small_world()
    add = {"rigid body": lambda: world.add_rigid_body("x", "sphere"),
           "node set": lambda: world.add_node_set("x", body, indices=[0]),
           "hand": lambda: world.add_hand("x", body)}[part]
    add()
    with pytest.raises(ValueError, match=part + " name 'x': a " + part + " of that name exists"):
        add()


@pytest.mark.parametrize("height", [NAN, math.inf, 1e9])
def test_add_ground_refuses_a_height_it_cannot_carry(height):
    world = torsion.World(threads=1)
    with pytest.raises(ValueError, match="add_ground: height"):
        world.add_ground(height)


def test_add_ground_refuses_negative_friction():
    with pytest.raises(ValueError, match="add_ground: friction -1"):
        torsion.World(threads=1).add_ground(0, friction=-1)


@pytest.mark.parametrize("kwargs, error, match", [
    (dict(plane=((0, 0, 0), (0, 0, 0))), ValueError, "plane normal: must not be zero"),
    (dict(plane=((0, 0, NAN), (0, 0, 1))), ValueError, "plane point: must be finite"),
    (dict(plane=((0, 0, 0), (0, 0, 1)), tolerance=NAN), ValueError, "tolerance"),
    (dict(plane=((0, 0, 0), (0, 0, 1)), tolerance=-1), ValueError, "tolerance"),
    (dict(sphere=((0, 0, 0), NAN)), ValueError, "sphere radius"),
    (dict(sphere=((0, 0, 0), -1)), ValueError, "sphere radius"),
    (dict(box=((0, 0, 0), (1, 1, 1j))), TypeError, "box max: expected real numbers, got complex"),
    (dict(indices=[0, 1], wrench_about=(NAN, 0, 0)), ValueError, "wrench_about: must be finite"),
    (dict(indices=np.array([2 ** 32 + 1], dtype=np.int64)), ValueError,
     "indices: element 0 \\(4294967297\\) is outside the int32 range"),
    (dict(indices=np.array([2 ** 63], dtype=np.uint64)), ValueError, "outside the int32 range"),
    (dict(indices=[0.5]), ValueError, "indices: element 0 \\(0.5\\) is not a whole number"),
    (dict(indices=[NAN]), ValueError, "is not a whole number"),
    (dict(indices=[True]), TypeError, "indices: expected integer indices"),
    (dict(indices=np.array([1 + 1j])), TypeError, "indices: expected integer indices"),
])
def test_add_node_set_refuses_bad_selections(kwargs, error, match):
    world, body = small_world()
    with pytest.raises(error, match=match):
        world.add_node_set("s", body, **kwargs)
    assert world.node_sets == []


def test_add_node_set_takes_whole_float_indices():
    world, body = small_world()
    assert list(world.add_node_set("s", body, indices=[1.0, 2.0]).nodes) == [1, 2]


@pytest.mark.parametrize("tets, error, match", [
    (lambda t: t.astype(np.int64) + 2 ** 32, ValueError, "tets: element 0 .* outside the int32 range"),
    (lambda t: t + 0.5, ValueError, "tets: element 0 \\(.*\\) is not a whole number"),
    (lambda t: t.astype(np.complex128), TypeError, "tets: expected integer indices"),
])
def test_add_body_refuses_tets_numpy_would_wrap_or_truncate(tets, error, match):
    nodes, t = cube_mesh(1)
    world = torsion.World(threads=1)
    with pytest.raises(error, match=match):
        world.add_body("b", nodes=nodes, tets=tets(t))
    assert world.bodies == []


@pytest.mark.parametrize("nodes, error, match", [
    (lambda x: x + 1j, TypeError, "nodes: expected real numbers, got complex"),
    (lambda x: np.where(x == 1, NAN, x), ValueError, "nodes: row .* is not finite"),
])
def test_add_body_refuses_complex_or_non_finite_nodes(nodes, error, match):
    x, tets = cube_mesh(1)
    with pytest.raises(error, match=match):
        torsion.World(threads=1).add_body("b", nodes=nodes(x), tets=tets)


@pytest.mark.parametrize("velocity, error, match", [
    ((NAN, 0, 0), ValueError, "velocity: must be finite, got \\(nan, 0, 0\\)"),
    ((0, math.inf, 0), ValueError, "velocity: must be finite"),
    ((1j, 0, 0), TypeError, "velocity: expected real numbers, got complex"),
])
def test_set_velocity_refuses_non_finite_and_complex(velocity, error, match):
    world, body = small_world()
    world.step(3)
    with pytest.raises(error, match=match):
        body.set_velocity(velocity)
    assert np.isfinite(body.velocities).all()
    world.step(3)  # no NaN went in, so nothing fails and nothing is rewound to one
    assert np.isfinite(body.velocities).all() and world.step_count == 6


@pytest.mark.parametrize("forces, error, match", [
    (lambda f: np.where(f == 0, NAN, f), ValueError, "forces: row 0 is not finite"),
    (lambda f: f + 1j, TypeError, "forces: expected real numbers, got complex"),
])
def test_set_external_forces_refuses_non_finite_and_complex(forces, error, match):
    world, body = small_world()
    with pytest.raises(error, match=match):
        body.set_external_forces(forces(np.zeros((body.node_count, 3))))


@pytest.mark.parametrize("tolerance", [NAN, 0.0, -1e-6, 1.0, math.inf])
def test_stiffness_refuses_a_tolerance_outside_0_1(tolerance):
    world, body = small_world()
    hand = world.add_hand("hand", body)
    with pytest.raises(ValueError, match="stiffness: tolerance must be in \\(0, 1\\), got "):
        hand.stiffness(tolerance=tolerance)


@pytest.mark.parametrize("make, error, match", [
    (lambda: torsion.Frame(position=(NAN, 0, 0)), ValueError, "position: must be finite"),
    (lambda: torsion.Frame(quaternion=(0, 0, 0, NAN)), ValueError, "quaternion: must be finite"),
    (lambda: torsion.Frame(quaternion=(0, 0, 1j, 1)), TypeError, "quaternion: expected real numbers"),
    (lambda: torsion.Frame.from_axis_angle((0, 0, 0), (0, 0, 1), NAN), ValueError, "angle: must be finite"),
    (lambda: torsion.Frame.from_axis_angle((0, 0, 0), (0, 0, 0), 1.0), ValueError, "axis: must not be zero"),
    (lambda: torsion.Frame.from_matrix(np.full((4, 4), NAN)), ValueError, "not finite"),
    (lambda: torsion.World(gravity=(0, 0, NAN)), ValueError, "gravity: must be finite"),
])
def test_frames_and_vectors_refuse_non_finite_and_complex(make, error, match):
    with pytest.raises(error, match=match):
        make()


@pytest.mark.parametrize("camera, match", [
    ({"distance": NAN}, "camera distance: must be finite"),
    ({"distance": -1.0}, "camera distance: must be > 0 m, got -1"),
    ({"yaw": math.inf}, "camera yaw: must be finite"),
    ({"pitch": NAN}, "camera pitch: must be finite"),
    ({"fov_y": 0.0}, "camera fov_y: must be in \\(0, pi\\) rad"),
    ({"up": (0, 0, 0)}, "camera up: must not be zero"),
    ({"target": (NAN, 0, 0)}, "camera target: must be finite"),
])
def test_render_refuses_a_camera_it_cannot_look_through(camera, match):
    world, _ = small_world()
    with pytest.raises(ValueError, match=match):
        world.render(16, 16, camera=camera)
