"""examples/plan_around_obstacles.py: the planner's path avoids the obstacles, checked with the NumPy
reference (not the compiled kernel the planner used)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

import numpy as np

import symkin
from symkin.geometry import in_collision

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "plan_around_obstacles.py"


def _example():
    spec = importlib.util.spec_from_file_location("symkin_example_planning", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def test_rrt_connect_finds_a_collision_free_path_around_the_post():
    ex = _example()
    robot = symkin.load("panda")
    kin = symkin.compile(robot, backend="c")
    q0, q1 = ex.start_and_goal(robot)
    assert not kin.motion_valid(q0, q1, ex.SCENE, resolution=0.02)  # the straight motion hits the post
    plan = ex.rrt_connect(kin, q0, q1, ex.SCENE, seed=0)
    assert plan is not None and len(plan.path) >= 3
    assert np.array_equal(plan.path[0], q0) and np.array_equal(plan.path[-1], q1)
    assert robot.within_limits(plan.path).all()
    for a, b in zip(plan.path[:-1], plan.path[1:]):  # every edge, at the planner's resolution
        steps = max(1, int(np.ceil(np.abs(b - a).max() / 0.02)))
        Q = a + np.linspace(0, 1, steps + 1)[:, None] * (b - a)
        assert not in_collision(robot, Q, ex.SCENE).any()
