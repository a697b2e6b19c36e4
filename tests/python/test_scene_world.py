"""A scene file becomes the same world in Python as in `torsion run`, and its arrays say so."""

import csv
import json
import os
import pathlib
import stat
import subprocess

import numpy as np
import pytest

import torsion
from conftest import BULLET_RTOL, read_vtk_points


def test_the_version_is_the_cmake_projects():
    expected = os.environ.get("TORSION_VERSION")
    assert isinstance(torsion.__version__, str) and torsion.__version__.count(".") == 2
    if expected:
        assert torsion.__version__ == expected


def test_a_demo_scene_name_and_its_path_build_the_same_world(scenes):
    by_name = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    by_path = torsion.World.from_scene(str(scenes / "twist_cylinder_2430.json"), threads=1)
    by_name.step(5)
    by_path.step(5)
    assert np.array_equal(by_name.body("cylinder").positions, by_path.body("cylinder").positions)
    assert by_name.time == pytest.approx(0.05, rel=BULLET_RTOL)
    assert by_name.step_count == 5 and by_name.dt == 0.01 and by_name.scene_steps == 6484


def test_data_path_is_the_folder_scene_names_are_found_in(scenes, monkeypatch):
    # In the build tree: <build>/share/torsion, whose demos/scenes is the source tree's.
    monkeypatch.delenv("TORSION_SCENE_PATH", raising=False)
    data = torsion.data_path()
    package = pathlib.Path(torsion.__file__).resolve().parent
    assert data == package.parent.parent / "share" / "torsion"
    assert (data / "demos" / "scenes").resolve() == scenes.resolve()
    assert (data / "assets" / "meshes" / "cylinder_2430.node").is_file()
    with pytest.raises(torsion.SceneError, match=str(data / "demos" / "scenes")):
        torsion.World.from_scene("no_such_scene")


def test_body_arrays_have_the_meshs_shapes_and_are_read_only_views(assets):
    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    body = world.bodies[0]
    assert body.name == "cylinder" and body.element == "tet4"
    n, m = body.node_count, body.element_count
    assert (n, m) == (661, 2408)  # assets/README.md's counts for cylinder_2430
    for array, shape, dtype in [(body.positions, (n, 3), np.float64),
                                (body.velocities, (n, 3), np.float64),
                                (body.rest_positions, (n, 3), np.float64),
                                (body.tets, (m, 4), np.int32),
                                (body.surface_triangles, (972, 3), np.int32)]:
        assert array.shape == shape and array.dtype == dtype
        assert not array.flags.writeable
        with pytest.raises(ValueError):
            array[0, 0] = 1
    # the rest positions and tets are the file's numbers (.node/.ele are 1-based)
    node_rows = np.loadtxt(assets / "cylinder_2430.node", comments="#", skiprows=1)
    ele_rows = np.loadtxt(assets / "cylinder_2430.ele", comments="#", skiprows=1, dtype=np.int64)
    assert np.array_equal(body.rest_positions, node_rows[:, 1:4])
    first = int(node_rows[0, 0])
    assert np.array_equal(body.tets, ele_rows[:, 1:5] - first)
    # every surface triangle is a face of some tet
    faces = {tuple(sorted(t[list(f)])) for t in body.tets for f in
             [(0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)]}
    assert all(tuple(sorted(tri)) in faces for tri in body.surface_triangles)
    masses = body.masses
    assert masses.shape == (n,) and masses.sum() == pytest.approx(1000 * 29.7352, rel=1e-4)


def test_a_positions_view_follows_the_world_and_a_copy_does_not():
    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    body = world.body("cylinder")
    view, copy = body.positions, body.positions.copy()
    world.step(20)
    assert np.array_equal(view, body.positions)
    assert not np.array_equal(view, copy)
    del world, body  # the view keeps the world alive: its memory is still valid
    assert np.isfinite(view).all()


def test_python_steps_match_torsion_run_to_the_bit(torsion_exe, tmp_path):
    steps = 60
    out = tmp_path / "run"
    subprocess.run([torsion_exe, "run", "twist_cylinder_2430", "--steps", str(steps),
                    "--threads", "1", "--out", str(out)], check=True, capture_output=True)
    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    world.step(steps)
    assert np.array_equal(read_vtk_points(out / "cylinder.vtk"), world.body("cylinder").positions)
    with open(out / "wrench.csv") as f:
        rows = list(csv.DictReader(f))
    last = rows[-1]
    assert int(last["step"]) == steps
    for name, wrench in [("base", world.node_set("base").wrench), ("hand", world.hand("hand").wrench)]:
        cli = [float(last[f"{name}.{c}"]) for c in ("fx", "fy", "fz", "tx", "ty", "tz")]
        np.testing.assert_allclose(wrench, cli, rtol=1e-9, atol=1e-9 * np.abs(cli).max())
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steps"] == steps


def test_twisting_the_hand_loads_base_and_hand_with_opposite_st_venant_sized_torques():
    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    world.step(600)  # 6 s at 0.1 rad/s: 0.6 rad
    hand, base = world.hand("hand"), world.node_set("base")
    assert hand.grabbed and hand.scripted and hand.grabbed_nodes.size > 0
    angle = 2 * np.arctan2(hand.frame.quaternion[2], hand.frame.quaternion[3])
    assert angle == pytest.approx(0.6, rel=1e-6)
    # St Venant: T = G J theta / L, J = pi r^4 / 2; r from the mesh's volume and length 9.9 m
    r = np.sqrt(29.7352 / (np.pi * 9.9))
    torque = 1e5 / 2.6 * np.pi * r ** 4 / 2 * angle / 9.9
    assert hand.wrench[5] < 0 < base.wrench[5]  # the body resists the twist at both ends
    for tz in (-hand.wrench[5], base.wrench[5]):
        assert 0.5 * torque < tz < 2 * torque  # torsional waves ring around the static value


def test_von_mises_stress_and_strain_are_zero_at_rest_and_grow_with_the_twist():
    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    body = world.body("cylinder")
    assert body.von_mises_stress().shape == (body.element_count,)
    assert np.abs(body.von_mises_stress()).max() < 1e-6 * 1e5
    assert np.abs(body.von_mises_strain()).max() < 1e-9
    world.step(300)
    stress, strain = body.von_mises_stress(), body.von_mises_strain()
    assert stress.max() > 100 and strain.max() > 1e-3
    # linear isotropic: sigma_vm = 3 G eps_eq for a deviatoric state; the twist is mostly shear
    ratio = np.median(stress / np.maximum(strain, 1e-12))
    assert ratio == pytest.approx(3 * 1e5 / 2.6, rel=0.1)


def test_rigid_bodies_report_poses_and_velocities(scenes):
    world = torsion.World.from_scene("rigid_mix", threads=1)
    rigid = world.rigid_bodies
    assert rigid, "rigid_mix has rigid bodies"
    for r in rigid:
        assert r.position.shape == (3,) and r.quaternion.shape == (4,)
        assert np.linalg.norm(r.quaternion) == pytest.approx(1, abs=1e-9)
        assert world.rigid_body(r.name).name == r.name
    world.step(20)
    moving = [r for r in rigid if r.mass > 0]
    assert any(np.linalg.norm(r.linear_velocity) > 0 for r in moving)


def test_write_vtk_reads_back_as_the_positions_to_the_bit(tmp_path):
    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    world.step(10)
    world.write_vtk(str(tmp_path / "c.vtk"))
    assert np.array_equal(read_vtk_points(tmp_path / "c.vtk"), world.body("cylinder").positions)


def test_write_vtk_replaces_only_a_regular_file(tmp_path):
    # A FIFO or a symbolic link at the path (a device node likewise) is refused and left as it is.
    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    fifo, link, target = tmp_path / "pipe.vtk", tmp_path / "link.vtk", tmp_path / "target.vtk"
    os.mkfifo(fifo)
    with pytest.raises(RuntimeError, match="pipe.vtk: cannot write: is a FIFO, not a regular file"):
        world.write_vtk(str(fifo))
    assert stat.S_ISFIFO(os.lstat(fifo).st_mode)
    target.write_text("kept\n")
    link.symlink_to(target)
    with pytest.raises(RuntimeError, match="link.vtk: cannot write: is a symbolic link"):
        world.write_vtk(str(link))
    assert link.is_symlink() and target.read_text() == "kept\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["link.vtk", "pipe.vtk", "target.vtk"]


def test_render_gives_a_picture_with_the_body_in_it():
    world = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    image = world.render(160, 120)
    assert image.shape == (120, 160, 3) and image.dtype == np.uint8
    # not one flat colour: the body and its mesh lines stand out from the background
    assert len(np.unique(image.reshape(-1, 3), axis=0)) > 20
    closer = world.render(160, 120, camera={"distance": 5.0})
    assert not np.array_equal(image, closer)


def test_a_device_hand_in_lockstep_steps_as_in_torsion_run_to_the_bit(torsion_exe, tmp_path):
    steps = 40
    out = tmp_path / "run"
    subprocess.run([torsion_exe, "run", "haptic_cylinder", "--steps", str(steps), "--threads", "1",
                    "--haptics", "lockstep", "--out", str(out)], check=True, capture_output=True)
    world = torsion.World.from_scene("haptic_cylinder", threads=1, haptics="lockstep")
    assert world.hand("hand").scripted
    world.step(steps)
    assert np.array_equal(read_vtk_points(out / "cylinder.vtk"), world.body("cylinder").positions)
    with pytest.raises(ValueError, match="cannot be wound back"):
        world.save_state()


def test_a_device_override_replaces_a_hands_script_as_the_device_option_does(source_dir):
    trajectory = str(source_dir / "assets" / "trajectories" / "figure_6_7.json")
    scripted = torsion.World.from_scene("twist_cylinder_2430", threads=1)
    driven = torsion.World.from_scene("twist_cylinder_2430", threads=1, haptics="lockstep",
                                      devices={"hand": "scripted:" + trajectory})
    as_list = torsion.World.from_scene("twist_cylinder_2430", threads=1, haptics="lockstep",
                                       devices=["hand=scripted:" + trajectory])
    for world in (scripted, driven, as_list):
        world.step(30)
    assert np.array_equal(driven.body("cylinder").positions, as_list.body("cylinder").positions)
    assert not np.array_equal(driven.body("cylinder").positions, scripted.body("cylinder").positions)
    with pytest.raises(ValueError, match="no hand or dynamic rigid body named 'nohand'"):
        torsion.World.from_scene("twist_cylinder_2430", devices={"nohand": "scripted:" + trajectory})


def test_a_tet10_body_lists_ten_nodes_per_element():
    world = torsion.World.from_scene("twist_cylinder_2430_tet10", threads=1)
    body = world.bodies[0]
    assert body.element == "tet10" and body.tets.shape == (body.element_count, 10)
    assert body.tets.max() == body.node_count - 1  # every node, mid-edge ones too, is in an element
    # mid-edge nodes sit halfway along their edges at rest (Tet10 order: corners, then edges)
    x = body.rest_positions
    t = body.tets[0]
    edges = [(0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3)]
    midpoints = {tuple(np.round((x[t[a]] + x[t[b]]) / 2, 12)) for a, b in edges}
    assert {tuple(np.round(x[t[k]], 12)) for k in range(4, 10)} == midpoints
    world.step(3)
    assert body.von_mises_stress().shape == (8 * body.element_count,)
