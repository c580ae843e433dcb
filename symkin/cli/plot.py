"""``symkin plot``: draw a robot (links, joint frames, collision shapes and obstacles, optionally the
velocity ellipsoid) to a PNG."""

from __future__ import annotations

import argparse
from typing import Any

from symkin.cli import common
from symkin.cli.checks import UserError

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    s = common.add_robot_command(
        sub, "plot", "draw a robot (links, frames, collision shapes, obstacles, velocity ellipsoid) as PNG"
    )
    s.add_argument(
        "--q", metavar="'Q...'", help="joint values, or a configuration name like qr (default qr, else qz)"
    )
    s.add_argument("-o", "--output", metavar="PNG", help="file to write (default <robot>.png)")
    s.add_argument(
        "--ellipsoid", action="store_true", help="draw the manipulability ellipsoid of linear velocity"
    )
    s.add_argument("--no-frames", action="store_true", help="draw only the base and end-effector frames")
    s.add_argument(
        "--no-geometry",
        action="store_true",
        help="leave out the collision shapes (drawn when the robot has them)",
    )
    common.add_collision_options(s)
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    robot, env, _ = common.collision_model(args)
    if args.q is None:
        q = robot.configs.get("qr", robot.configs["qz"])
    else:
        q = common.configuration(args.q, robot, "--q")
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise UserError("plot needs matplotlib: pip install 'symkin[plot]'") from None
    highlight: list[int] = []
    note = ""
    if robot.geometry is not None and not args.no_geometry:
        from symkin.runtime.collision import Collision

        check = Collision(robot, "numpy")
        d = check.distances(q, env)
        for k, (kind, i, j) in enumerate(check.labels(env)):
            if d[k] < 0:
                highlight += [i, j] if kind == "self" else [i]
        note = f"; {len(set(highlight))} shapes in collision (red)" if highlight else "; collision-free"
    out = args.output or f"{robot.identifier}.png"
    robot.plot(
        q, frames=not args.no_frames, ellipsoid=args.ellipsoid, path=out, geometry=not args.no_geometry,
        env=env if len(env) else None, highlight=highlight,
    )  # fmt: skip
    print(f"wrote {out}: {robot.name} at q = {common.fmt(q)}{note}")
    return 0
