"""Run by test_viewer.py under xvfb-run: worlds stepped with a passive viewer open, and again
without one; prints one JSON object of what it saw. Usage: passive_viewer_child.py ASSETS_DIR"""

import json
import sys

import numpy as np

import torsion
import torsion.viewer

STEPS = 12


def twisted_cylinder(assets):
    """The docs' twist, built in code: base held, a hand turning the top."""
    world = torsion.World(gravity=(0, 0, 0), dt=0.01, threads=1)
    body = world.add_body("cyl", assets + "/cylinder_2430.node",
                          material=torsion.Material(E=1e5, nu=0.3, rho=1000))
    world.add_node_set("base", body, plane=((0, 0, 0), (0, 0, 1)))
    hand = world.add_hand("hand", body)
    hand.grab(torsion.Frame(position=(0, 0, 9.9)))
    return world, hand


def step_twist(world, hand, k):
    hand.move_to(torsion.Frame.from_axis_angle((0, 0, 9.9), (0, 0, 1), 0.01 * (k + 1)))
    world.step()


def state_of(world):
    body = world.bodies[0]
    return {"time": world.time, "steps": world.step_count,
            "positions": body.positions.copy(), "velocities": body.velocities.copy()}


def same(a, b):
    return (a["time"] == b["time"] and a["steps"] == b["steps"]
            and np.array_equal(a["positions"], b["positions"])
            and np.array_equal(a["velocities"], b["velocities"]))


def main():
    assets = sys.argv[1]
    out = {}

    # 1. A world built in code, stepped and synced; then closed by the script.
    world, hand = twisted_cylinder(assets)
    viewer = torsion.viewer.launch_passive(world, width=320, height=240)
    out["running_at_start"] = viewer.is_running()
    for k in range(STEPS):
        step_twist(world, hand, k)
        viewer.sync()
    out["frames"] = viewer.frame_count
    image = viewer.capture()
    out["image_shape"] = list(image.shape)
    # The background is a light grey-blue gradient (every channel >= 204): the body, the HUD and
    # the hand's axes are darker.
    out["dark_fraction"] = float((image.max(axis=2) < 160).mean())
    out["colours"] = int(len(np.unique(image.reshape(-1, 3), axis=0)))
    out["real_time_factor"] = viewer.real_time_factor
    viewer.close()
    out["running_after_close"] = viewer.is_running()
    viewer.sync()  # closed: nothing, and no error
    out["frames_after_close"] = viewer.frame_count
    with_viewer = state_of(world)

    plain, plain_hand = twisted_cylinder(assets)
    for k in range(STEPS):
        step_twist(plain, plain_hand, k)
    out["same_state_code"] = same(with_viewer, state_of(plain))

    # 2. A scene's world in a context manager, its window closed as by the user's close button
    # half-way: the script goes on stepping.
    world = torsion.World.from_scene("drop", threads=1)
    with torsion.viewer.launch_passive(world, width=320, height=240) as viewer:
        for k in range(STEPS):
            world.step()
            if k == STEPS // 2:
                viewer._viewer._request_close()
            viewer.sync()
        out["scene_frames"] = viewer.frame_count
        out["scene_running_after_close_button"] = viewer.is_running()
    plain = torsion.World.from_scene("drop", threads=1)
    plain.step(STEPS)
    out["same_state_scene"] = same(state_of(world), state_of(plain))

    # 3. Two windows at once, and one after the other closed: GLFW stays up for the other.
    a = torsion.viewer.launch_passive(plain, width=200, height=150)
    b = torsion.viewer.launch_passive(plain, width=200, height=150)
    a.sync()
    a.close()
    b.sync()
    b.sync()
    out["second_window_frames"] = b.frame_count
    b.close()
    print(json.dumps(out))


if __name__ == "__main__":
    main()
