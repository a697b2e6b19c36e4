"""The Newton solve of hyperelastic bodies from Python: World(newton_tolerance=...,
newton_max_iterations=...) and Body.newton_iterations (docs/materials.md, "Time step").

A 2430-tet cylinder with its base held has its end turned by 0.3 rad in a single 0.05 s step: a
large, fast deformation that one linearised solve does not settle. The default Newton solve
takes more than one iteration and ends converged; capped at one iteration the step is not a
backward-Euler step, and the world refuses it (UnstableError naming the body, the state back at
the last good step). A corotated body's step is one linear solve: 0 Newton iterations."""
import numpy as np
import pytest

import torsion

TURN = 0.3  # rad in one step


def turned_cylinder(assets, law="stable_neo_hookean", **settings):
    world = torsion.World(gravity=(0, 0, 0), dt=0.05, linear_solver="cholmod", threads=1,
                          **settings)
    body = world.add_body("bar", str(assets / "cylinder_2430.node"),
                          material=torsion.Material(E=1e5, nu=0.45, law=law))
    world.add_node_set("base", body, plane=((0, 0, 0), (0, 0, 1)))
    end = world.add_node_set("end", body, plane=((0, 0, 10), (0, 0, 1)), wrench_about=(0, 0, 10))
    end.move_to(torsion.Frame.from_axis_angle((0, 0, 10), (0, 0, 1), TURN))
    return world, body


def test_bad_newton_settings_are_refused_naming_them():
    with pytest.raises(ValueError, match="newton_tolerance"):
        torsion.World(newton_tolerance=0.0)
    with pytest.raises(ValueError, match="newton_tolerance"):
        torsion.World(newton_tolerance=float("nan"))
    with pytest.raises(ValueError, match="newton_max_iterations"):
        torsion.World(newton_max_iterations=0)


def test_a_large_fast_twist_takes_several_newton_iterations_and_a_cap_of_one_fails(assets):
    world, body = turned_cylinder(assets)
    world.step()
    assert body.newton_iterations >= 2  # the linearised solve, then corrections
    # The turned end is where it was sent: the nodes on the end circle turned by TURN.
    end = body.positions[np.abs(body.rest_positions[:, 2] - 10) < 1e-6]
    rest_end = body.rest_positions[np.abs(body.rest_positions[:, 2] - 10) < 1e-6]
    rim = np.hypot(rest_end[:, 0], rest_end[:, 1]) > 0.5
    angles = np.arctan2(end[rim, 1], end[rim, 0]) - np.arctan2(rest_end[rim, 1], rest_end[rim, 0])
    angles = np.mod(angles + np.pi, 2 * np.pi) - np.pi
    np.testing.assert_allclose(angles, TURN, atol=1e-9)

    capped, capped_body = turned_cylinder(assets, newton_max_iterations=1)
    before = capped_body.positions.copy()
    with pytest.raises(torsion.UnstableError, match="bar") as failure:
        capped.step()
    assert "Newton" in str(failure.value) and "newton_max_iterations 1" in str(failure.value)
    np.testing.assert_array_equal(capped_body.positions, before)  # back at the last good step

    corotated, corotated_body = turned_cylinder(assets, law="corotated")
    corotated.step()
    assert corotated_body.newton_iterations == 0
