"""Motion planning around obstacles with the compiled collision checks: RRT-Connect in joint space.

A Panda moves its hand from the left of a post to its right above a table. The straight joint-space
motion hits the post, so the planner (Kuffner and LaValle, RRT-Connect: An Efficient Approach to
Single-Query Path Planning, ICRA 2000) grows two trees, from the start and from the goal, with
``kin.motion_valid`` checking every edge (the compiled FKCC kernel, all the edge's checks in one
batch call), then shortens the path by cutting corners that are collision-free. The result is a list
of configurations whose straight motions are all collision-free at the checking resolution.

Run ``python examples/plan_around_obstacles.py [--seed S]``.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass

import numpy as np

import symkin
from symkin import Box, Capsule, Environment

SCENE = Environment(
    capsules=(Capsule((0.5, 0.0, 0.0), (0.5, 0.0, 0.75), 0.06),),  # a post in front of the arm
    boxes=(Box((0.45, 0.0, -0.09), (0.45, 0.6, 0.05)),),  # the table top, 4 cm below the base frame
)


def start_and_goal(robot: symkin.Robot) -> tuple[np.ndarray, np.ndarray]:
    """The ready pose turned 0.8 rad to the left and to the right of the post."""
    q0, q1 = robot.qr.copy(), robot.qr.copy()
    q0[0], q1[0] = 0.8, -0.8
    return q0, q1


@dataclass(frozen=True)
class Plan:
    path: np.ndarray  # (K, n) configurations, start first, goal last
    raw_length: int  # waypoints before shortcutting
    iterations: int
    checks: int  # motion_valid calls
    seconds: float


class _Tree:
    def __init__(self, root: np.ndarray) -> None:
        self.nodes = [root]
        self.parent = [-1]

    def nearest(self, q: np.ndarray) -> int:
        return int(np.argmin(np.linalg.norm(np.asarray(self.nodes) - q, axis=1)))

    def add(self, q: np.ndarray, parent: int) -> int:
        self.nodes.append(q)
        self.parent.append(parent)
        return len(self.nodes) - 1

    def path_to(self, i: int) -> list[np.ndarray]:
        out = []
        while i >= 0:
            out.append(self.nodes[i])
            i = self.parent[i]
        return out[::-1]


def _steer(a: np.ndarray, b: np.ndarray, step: float) -> np.ndarray:
    d = np.linalg.norm(b - a)
    return b if d <= step else a + (b - a) * (step / d)


def rrt_connect(
    kin: symkin.Kinematics,
    q_start: np.ndarray,
    q_goal: np.ndarray,
    env: Environment,
    step: float = 0.4,
    resolution: float = 0.02,
    max_iterations: int = 4000,
    shortcuts: int = 200,
    seed: int = 0,
) -> Plan | None:
    """A collision-free path from ``q_start`` to ``q_goal`` (both collision-free), or None."""
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    checks = 0

    def valid(a: np.ndarray, b: np.ndarray) -> bool:
        nonlocal checks
        checks += 1
        return kin.motion_valid(a, b, env, resolution=resolution)

    trees = (_Tree(q_start), _Tree(q_goal))
    a, b = trees
    for it in range(max_iterations):
        target = kin.random_q(seed=rng)
        i = a.nearest(target)
        q_new = _steer(a.nodes[i], target, step)
        if not valid(a.nodes[i], q_new):
            a, b = b, a
            continue
        i_new = a.add(q_new, i)
        while True:  # connect: b grows toward q_new until it reaches it or is blocked
            j = b.nearest(q_new)
            q_b = _steer(b.nodes[j], q_new, step)
            if not valid(b.nodes[j], q_b):
                break
            j_new = b.add(q_b, j)
            if np.array_equal(q_b, q_new):
                pa, pb = a.path_to(i_new), b.path_to(j_new)
                raw = pa + pb[::-1][1:] if a is trees[0] else pb + pa[::-1][1:]
                path = _shortcut(raw, valid, rng, shortcuts)
                return Plan(np.array(path), len(raw), it + 1, checks, time.perf_counter() - t0)
        a, b = b, a
    return None


def _shortcut(path: list[np.ndarray], valid, rng: np.random.Generator, tries: int) -> list[np.ndarray]:
    """Remove waypoints between two whose straight motion is collision-free (random pairs)."""
    path = list(path)
    for _ in range(tries):
        if len(path) < 3:
            break
        i, j = sorted(rng.choice(len(path), size=2, replace=False))
        if j - i > 1 and valid(path[i], path[j]):
            path = path[: i + 1] + path[j:]
    return path


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    robot = symkin.load("panda")
    kin = symkin.compile(robot, backend="c")
    q0, q1 = start_and_goal(robot)
    print(f"straight motion collision-free: {kin.motion_valid(q0, q1, SCENE, resolution=0.02)}")
    plan = rrt_connect(kin, q0, q1, SCENE, seed=args.seed)
    if plan is None:
        print("no path found")
        return
    print(
        f"path of {len(plan.path)} waypoints ({plan.raw_length} before shortcuts), {plan.iterations} "
        f"iterations, {plan.checks} edge checks, {plan.seconds * 1e3:.1f} ms"
    )
    hand = kin.fkine(plan.path)[:, :3, 3]
    print("hand positions (m):\n", np.round(hand, 3))


if __name__ == "__main__":
    main()
