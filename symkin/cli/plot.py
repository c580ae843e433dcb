"""``symkin plot``: draw a robot (links, joint frames, optionally the velocity ellipsoid) to a PNG."""

from __future__ import annotations

import argparse
from typing import Any

from symkin.cli.checks import UserError
from symkin.cli.common import add_command, add_robot_argument, floats, fmt, single_chain

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    s = add_command(
        sub, "plot", "draw a robot (links, joint frames, optionally the velocity ellipsoid) to a PNG"
    )
    add_robot_argument(s)
    s.add_argument(
        "--q", metavar="'Q...'", help="joint values, or a configuration name like qr (default qr, else qz)"
    )
    s.add_argument("-o", "--output", metavar="PNG", help="file to write (default <robot>.png)")
    s.add_argument(
        "--ellipsoid", action="store_true", help="draw the manipulability ellipsoid of linear velocity"
    )
    s.add_argument("--no-frames", action="store_true", help="draw only the base and end-effector frames")
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    robot = single_chain(args)
    if args.q is None:
        q = robot.configs.get("qr", robot.configs["qz"])
    elif args.q.strip() in robot.configs:
        q = robot.configs[args.q.strip()]
    else:
        q = floats(args.q, "--q", robot.n)
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise UserError("plot needs matplotlib: pip install 'symkin[plot]'") from None
    out = args.output or f"{robot.identifier}.png"
    robot.plot(q, frames=not args.no_frames, ellipsoid=args.ellipsoid, path=out)
    print(f"wrote {out}: {robot.name} at q = {fmt(q)}")
    return 0
