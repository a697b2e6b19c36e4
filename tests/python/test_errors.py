"""Bad scenes, bad meshes and failing steps raise torsion's exceptions with the CLI's messages."""

import pathlib
import subprocess

import numpy as np
import pytest

import torsion
from conftest import cube_mesh


def cli_error(torsion_exe, *args, cwd):
    run = subprocess.run([torsion_exe, *args], capture_output=True, text=True, cwd=cwd)
    assert run.returncode != 0
    return [line[len("error: "):] for line in run.stderr.splitlines() if line.startswith("error: ")][0]


def test_an_unknown_scene_name_is_a_scene_error_listing_the_scenes():
    with pytest.raises(torsion.SceneError, match="twist_cylinder_2430") as info:
        torsion.World.from_scene("no_such_scene")
    assert isinstance(info.value, torsion.Error) and isinstance(info.value, RuntimeError)


def test_a_bad_scene_key_is_a_scene_error_with_the_clis_message(torsion_exe, scenes, tmp_path):
    text = (scenes / "twist_cylinder_2430.json").read_text()
    text = text.replace('"dt": 0.01', '"dt": -1').replace("../../assets", str(scenes.parents[1] / "assets"))
    path = tmp_path / "bad.json"
    path.write_text(text)
    with pytest.raises(torsion.SceneError) as info:
        torsion.World.from_scene(str(path))
    assert str(info.value) == cli_error(torsion_exe, "run", str(path), "--out", "o", cwd=tmp_path)
    assert info.value.file == str(path)
    assert info.value.key == "solver" and "time_step = -1" in str(info.value)


def test_a_json_syntax_error_is_a_scene_error_naming_the_line(tmp_path):
    path = tmp_path / "syntax.json"
    path.write_text('{"name": "x",\n "steps": ,}\n')
    with pytest.raises(torsion.SceneError, match="invalid JSON") as info:
        torsion.World.from_scene(str(path))
    assert info.value.file == str(path) and info.value.line == 2 and info.value.key is None


def test_a_malformed_mesh_in_a_scene_is_a_mesh_error_naming_file_and_line(torsion_exe, scenes, tmp_path):
    (tmp_path / "bad.node").write_text("4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 x 0\n3 0 0 1\n")
    (tmp_path / "bad.ele").write_text("1 4 0\n0 0 1 2 3\n")
    text = (scenes / "twist_cylinder_2430.json").read_text()
    text = text.replace("../../assets/meshes/cylinder_2430.node", "bad.node")
    (tmp_path / "scene.json").write_text(text)
    with pytest.raises(torsion.MeshError) as info:
        torsion.World.from_scene(str(tmp_path / "scene.json"))
    assert str(info.value) == cli_error(torsion_exe, "run", str(tmp_path / "scene.json"), "--out", "o",
                                        cwd=tmp_path)
    assert info.value.file.endswith("bad.node") and info.value.line == 4
    world = torsion.World()
    with pytest.raises(torsion.MeshError) as direct:
        world.add_body("b", str(tmp_path / "bad.node"))
    assert direct.value.line == 4 and "'x'" in str(direct.value)


def test_bad_tets_arrays_are_mesh_errors():
    nodes, tets = cube_mesh(1)
    world = torsion.World()
    with pytest.raises(torsion.MeshError, match="out of range"):
        world.add_body("b", nodes=nodes, tets=np.where(tets == 0, 99, tets))
    flat = tets.copy()
    flat[0, 3] = flat[0, 2]  # a repeated vertex
    with pytest.raises(torsion.MeshError):
        world.add_body("b", nodes=nodes, tets=flat)
    with pytest.raises(ValueError, match="duplicate|already|exists"):
        world.add_body("b", nodes=nodes, tets=tets)
        world.add_body("b", nodes=nodes, tets=tets)


def unstable_scene(scenes, tmp_path, max_speed):
    """The twist under gravity with a speed limit that the fall exceeds after max_speed / g s."""
    text = (scenes / "twist_cylinder_2430.json").read_text()
    text = (text.replace("../../assets", str(scenes.parents[1] / "assets"))
                .replace('"gravity": [0, 0, 0]', '"gravity": [0, 0, -9.81]')
                .replace('"tolerance": 1e-4', f'"tolerance": 1e-4, "max_speed": {max_speed}'))
    path = tmp_path / "unstable.json"
    path.write_text(text)
    return path


def test_a_failing_step_taken_one_call_at_a_time_leaves_the_state_of_the_call_before(scenes, tmp_path):
    world = torsion.World.from_scene(str(unstable_scene(scenes, tmp_path, 0.5)), threads=1)
    body = world.body("cylinder")
    push = np.zeros((body.node_count, 3))
    with pytest.raises(torsion.UnstableError):
        for _ in range(200):
            body.set_external_forces(push)  # a change between steps, each time
            world.step()
            last = body.positions.copy(), body.velocities.copy(), world.time
    assert np.array_equal(body.positions, last[0]) and np.array_equal(body.velocities, last[1])
    assert world.time == last[2]


def test_a_blow_up_is_an_unstable_error_and_leaves_the_last_good_state(torsion_exe, scenes, tmp_path):
    path = unstable_scene(scenes, tmp_path, 0.5)
    world = torsion.World.from_scene(str(path), threads=1)
    start = world.save_state()
    body = world.body("cylinder")
    with pytest.raises(torsion.UnstableError) as info:
        world.step(200)
    error = info.value
    assert error.body == "cylinder" and 1 < error.step <= 200
    failed_at = np.array(body.positions)
    assert world.step_count == error.step - 1  # back at the end of the last good step
    cli = cli_error(torsion_exe, "run", str(path), "--out", "o", "--steps", "200", "--threads", "1",
                    cwd=tmp_path)
    assert cli == "simulation unstable: " + str(error)
    assert np.isfinite(body.positions).all() and np.isfinite(body.velocities).all()
    with pytest.raises(torsion.UnstableError, match=str(error.step)):
        world.step()  # the world goes no further
    # the bodies hold the state after the last good step, error.step - 1
    world.restore_state(start)
    world.step(error.step - 1)
    assert np.array_equal(failed_at, body.positions)
    assert world.step_count == error.step - 1


def test_a_body_falling_past_max_speed_fails_at_the_step_free_fall_predicts():
    def falling_world():
        world = torsion.World(gravity=(0, 0, -9.81), dt=0.01, max_speed=7.0, threads=1)
        nodes, tets = cube_mesh(1)
        world.add_body("cube", nodes=nodes, tets=tets)
        return world

    world = falling_world()
    with pytest.raises(torsion.UnstableError) as info:
        world.step(200)
    # implicit Euler in free fall: v_k = g k dt, past 7 m/s at k = 72 (beyond the 64-step anchor)
    assert info.value.body == "cube" and info.value.step == 72
    again = falling_world()
    again.step(71)
    assert np.array_equal(world.body("cube").positions, again.body("cube").positions)
    assert world.time == again.time
