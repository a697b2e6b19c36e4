"""A device holding a rigid tool (docs/haptics.md, Tools) from Python: the scene's tools run as in
`torsion run`, and the wrench their device renders is read after each step."""

import csv
import subprocess

import numpy as np
import pytest

import torsion


def test_a_tool_scene_steps_as_in_torsion_run_and_its_device_wrench_is_the_loops(torsion_exe,
                                                                                tmp_path):
    steps = 250  # pressed 4 mm into the organ and sliding
    out = tmp_path / "run"
    # One step more: the loop renders a step's wrench in the ticks before the next step.
    subprocess.run([torsion_exe, "run", "palpation", "--steps", str(steps + 1), "--threads", "1",
                    "--out", str(out)], check=True, capture_output=True)
    world = torsion.World.from_scene("palpation", threads=1, haptics="lockstep")
    world.step(steps)
    wrench = world.device_wrench("probe")
    assert wrench.shape == (6,)
    assert wrench[2] > 0.1  # N: the organ pushes the probe, and the device, back up
    # The loop's log holds the wrench each step published (device frame = world here: the
    # mapping has no rotation and unit scales); that of step `steps` is the one Python reads.
    with open(out / "haptic_probe.csv") as f:
        rows = [r for r in csv.DictReader(f) if int(r["sim_step"]) == steps]
    assert rows, "step %d's wrench reached the loop" % steps
    logged = np.array([float(rows[0][k]) for k in
                       ("sim_fx", "sim_fy", "sim_fz", "sim_tx", "sim_ty", "sim_tz")])
    assert np.allclose(wrench, logged, rtol=1e-9, atol=1e-12)


def test_a_dynamic_rigid_body_gets_a_device_by_name_and_only_what_has_one_has_a_wrench(
        source_dir):
    trajectory = str(source_dir / "assets" / "trajectories" / "palpation.json")
    world = torsion.World.from_scene("rigid_mix", threads=1, haptics="lockstep",
                                     devices={"slab_ball": "scripted:" + trajectory})
    world.step(2)
    assert np.all(np.isfinite(world.device_wrench("slab_ball")))
    with pytest.raises(KeyError, match="no hand or tool named .slab_crate. has a device"):
        world.device_wrench("slab_crate")
    with pytest.raises(ValueError, match="no hand or dynamic rigid body named 'slab'"):
        torsion.World.from_scene("rigid_mix", threads=1, devices={"slab": "scripted:" + trajectory})


def test_a_manual_device_is_torsion_views_only_and_refused_naming_the_tool():
    # A manual device is moved by torsion view's mouse and keys: a scene built here has none.
    with pytest.raises(torsion.SceneError,
                       match="device 'manual' of tool 'probe' is moved by the mouse and keys "
                             "of torsion view, which this run has not"):
        torsion.World.from_scene("palpation", threads=1, devices={"probe": "manual"})
