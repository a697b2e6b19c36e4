"""torsion.viewer.launch_passive: a window on a world the script steps. The windows open under a
virtual X server (xvfb-run, Debian's xvfb) in a child process (passive_viewer_child.py); the test
is skipped only when xvfb-run is not installed."""

import json
import os
import shutil
import subprocess
import sys

import pytest

import torsion
import torsion.viewer

HERE = os.path.dirname(os.path.abspath(__file__))


def child_env():
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in sys.path if p)
    return env


@pytest.mark.skipif(shutil.which("xvfb-run") is None,
                    reason="xvfb-run not found (Debian: xvfb, installed by scripts/setup.sh)")
def test_passive_viewer_draws_closes_and_leaves_the_physics_alone(assets):
    result = subprocess.run(
        ["xvfb-run", "-a", "-s", "-screen 0 640x480x24", sys.executable,
         os.path.join(HERE, "passive_viewer_child.py"), str(assets)],
        capture_output=True, text=True, timeout=240, env=child_env())
    assert result.returncode == 0, result.stdout + result.stderr
    out = json.loads(result.stdout.strip().splitlines()[-1])
    # Drawn: a frame per sync, a picture of the window's size that is not just the background.
    assert out["running_at_start"]
    assert out["frames"] == 12
    assert out["image_shape"] == [240, 320, 3]
    assert out["dark_fraction"] > 0.01, out
    assert out["colours"] > 20, out
    assert out["real_time_factor"] > 0
    # Closed by the script: no longer running, sync() does nothing, the script went on.
    assert not out["running_after_close"]
    assert out["frames_after_close"] == 12
    # Closed as by the user's close button at step 7: that sync drew nothing, later ones neither.
    assert out["scene_frames"] == 6
    assert not out["scene_running_after_close_button"]
    assert out["second_window_frames"] == 2
    # The viewer does not change the physics: the same steps without it, bit for bit.
    assert out["same_state_code"]
    assert out["same_state_scene"]


def test_launch_passive_without_a_display_raises_a_clear_error():
    env = child_env()
    for name in ("DISPLAY", "WAYLAND_DISPLAY"):
        env.pop(name, None)
    code = (
        "import torsion, torsion.viewer\n"
        "world = torsion.World()\n"
        "try:\n"
        "    torsion.viewer.launch_passive(world)\n"
        "except torsion.viewer.DisplayError as e:\n"
        "    print('DisplayError:', e)\n"
        "world.step(2)\n"
        "print('went on', world.step_count)\n")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                            timeout=60, env=env)
    assert result.returncode == 0, result.stdout + result.stderr
    assert "DisplayError: launch_passive: no display for a window" in result.stdout
    assert "run under xvfb-run" in result.stdout
    assert "went on 2" in result.stdout


def test_launch_passive_checks_its_arguments():
    world = torsion.World()
    with pytest.raises(ValueError, match=r"width and height in \[64, 16384\]"):
        torsion.viewer.launch_passive(world, width=10, height=480)
    with pytest.raises(TypeError):
        torsion.viewer.launch_passive("not a world")


def test_the_viewer_module_is_documented():
    assert torsion.viewer.__doc__
    for name in torsion.viewer.__all__:
        assert getattr(torsion.viewer, name).__doc__, name
    for method in ["sync", "is_running", "close", "capture", "frame_count", "real_time_factor"]:
        assert getattr(torsion.viewer.PassiveViewer, method).__doc__, method
