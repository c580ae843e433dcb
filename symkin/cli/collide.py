"""``symkin collide``: is the robot at q in collision with itself or with obstacles? Prints the
verdict, the closest pairs and their signed distances; exit status 1 when in collision."""

from __future__ import annotations

import argparse
import json
from typing import Any

import numpy as np

from symkin.cli import common
from symkin.cli.checks import UserError, check_cflags_for

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    s = common.add_robot_command(sub, "collide", "check a configuration for self- and environment collisions")
    s.add_argument(
        "q",
        nargs="*",
        metavar="Q",
        help="joint values (rad or m), or a named configuration such as qr (default qz)",
    )
    common.add_collision_options(s)
    s.add_argument("--backend", choices=("c", "numpy"), default="c", help="the kernel that answers")
    s.add_argument("--top", type=int, default=5, metavar="K", help="print the K closest pairs")
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symkin.geometry.pairs import layout_of
    from symkin.runtime.load import compile as compile_robot

    robot, env, _ = common.collision_model(args)
    if args.top < 0:
        raise UserError(f"--top must be >= 0, got {args.top}")
    q = common.configuration(" ".join(args.q), robot, "Q") if args.q else np.zeros(robot.n)
    check_cflags_for(args.backend)
    kin = compile_robot(robot, backend=args.backend)
    q = np.asarray(robot.check_q(q), dtype=float).reshape(robot.n)
    hit = kin.in_collision(q, env)
    d = kin.distances(q, env)
    labels = kin.collision_pairs(env)
    shapes = robot.geometry.shapes
    describe = layout_of(robot).describe
    order = np.argsort(d, kind="stable")[: args.top]
    colliding = [k for k in np.argsort(d, kind="stable") if d[k] < 0]
    if args.json:
        out = {
            "robot": robot.name,
            "q": q.tolist(),
            "in_collision": bool(hit),
            "pairs": len(d),
            "closest": [{"pair": describe(labels[k]), "distance": float(d[k])} for k in order],
            "colliding": [describe(labels[k]) for k in colliding],
        }
        print(json.dumps(out, indent=2))
        return 1 if hit else 0
    n_self = sum(1 for lab in labels if lab[0] == "self")
    print(
        f"{robot.name}: {len(shapes)} shapes, {n_self} self pairs, {len(env)} obstacles "
        f"({len(d) - n_self} pairs); q = {common.fmt(q)}"
    )
    print(f"IN COLLISION: {len(colliding)} overlapping pairs" if hit else "collision-free")
    if len(order):
        print("closest pairs (signed distance, m):")
        for k in order:
            print(f"  {d[k]: .5f}  {describe(labels[k])}")
    return 1 if hit else 0
