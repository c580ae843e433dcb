"""``symkin check``: every backend of a chain or tree against the numeric reference and finite
differences."""

from __future__ import annotations

import argparse
import json
from typing import Any

from symkin.cli.checks import UserError, check_cflags_for, int_at_least
from symkin.cli.common import BACKENDS, add_link_options, add_robot_command, chain_or_tree
from symkin.compiler.compile import OPTIONAL_BACKENDS

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    s = add_robot_command(
        sub, "check", "compare every backend with the numeric reference and finite differences"
    )
    s.add_argument(
        "--backend",
        action="append",
        choices=(*BACKENDS, *OPTIONAL_BACKENDS),
        help="only this backend (repeat for several; default all: jax and torch where installed, "
        "skipped with a note where not)",
    )
    s.add_argument("--samples", type=int_at_least(1), default=20, help="random configurations")
    s.add_argument("--seed", type=int, default=0, help="seed of the random configurations")
    s.add_argument("--json", action="store_true", help="print the table as JSON")
    s.add_argument(
        "--singularities",
        action="store_true",
        help="check the singular conditions of `symkin derive --singularities` instead: each is singular "
        "where it holds, and random lines through joint space find no rank drop that none explains",
    )
    s.add_argument(
        "--lines",
        type=int_at_least(0),
        default=200,
        help="with --singularities, how many random lines (400 samples each)",
    )
    add_link_options(s, frames=True)
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symkin.check.kinematics import check

    robot = chain_or_tree(args)
    if args.singularities:
        return _singularities(robot, args)
    backends = args.backend or (*BACKENDS, *OPTIONAL_BACKENDS)
    for b in args.backend or ("c",):
        check_cflags_for(b)
    report = check(robot, backends=backends, samples=args.samples, seed=args.seed)
    print(json.dumps(report.as_dict(), indent=2) if args.json else report.format())
    return 0 if report.ok else 1


def _singularities(robot: Any, args: argparse.Namespace) -> int:
    from symkin.derive.singular_lines import MAX_LINES
    from symkin.derive.singularities import singularities

    if not robot.single_path:  # several frames, or a mimic joint on the path
        raise UserError("--singularities analyses one chain: name it as ROBOT.urdf:FRAME")
    robot = robot.chain()
    if args.backend or args.json:
        raise UserError("--singularities checks the symbolic conditions: leave out --backend and --json")
    if args.lines > MAX_LINES:
        raise UserError(f"--lines: at most {MAX_LINES}, got {args.lines}")
    report = singularities(robot, seed=args.seed, lines=args.lines)
    print(report.summary())
    return 0 if report.ok else 1
