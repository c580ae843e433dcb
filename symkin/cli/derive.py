"""``symkin derive``: the derivation of FK, Jacobian and Hessian of a chain or tree, the
closed-form IK of a chain, its singular configurations or its derivatives of higher order
(Markdown or LaTeX)."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any

from symkin.cli.checks import UserError, output_file
from symkin.cli.common import add_command, add_link_options, add_robot_argument, chain_or_tree

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    s = add_command(sub, "derive", "write the derivation of FK, Jacobian and Hessian (Markdown or LaTeX)")
    add_robot_argument(s)
    s.add_argument("--format", choices=("markdown", "latex"), default="markdown", help="output format")
    s.add_argument("--symbolic-constants", action="store_true", help="keep link lengths as named symbols")
    s.add_argument("--no-simplify", action="store_true", help="show the literal products of eqs 1, 5, 26-28")
    s.add_argument(
        "--ik", action="store_true", help="write the closed-form inverse kinematics derivation instead"
    )
    s.add_argument(
        "--singularities",
        action="store_true",
        help="write the singular configurations instead: det(J) (or the minors of J J^T) factored, each "
        "factor's meaning, checked numerically",
    )
    s.add_argument(
        "--singular-axes",
        choices=("auto", "all", "trans", "rot"),
        default="auto",
        help="with --singularities, the rows of J: auto is trans for an arm with fewer joints than nonzero "
        "rows and as many translational rows as joints (a planar 2R arm), else all",
    )
    s.add_argument(
        "--order",
        type=int,
        metavar="K",
        help="write the partial derivatives of the pose up to order K instead (Part 2's higher-order "
        "derivatives; 2 is the Hessian)",
    )
    s.add_argument(
        "--form",
        choices=("auto", "expanded", "program"),
        default="auto",
        help="expanded: every result multiplied out; program: link frame by link frame with named "
        "intermediates; auto: program when the expanded form is too large to read",
    )
    s.add_argument(
        "--sections",
        metavar="LIST",
        help="only these parts, comma-separated, e.g. fk,jacobian (names: ets, transforms, links, fk, "
        "derivatives, jacobian, hessian, checks; default all)",
    )
    s.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of printing")
    add_link_options(s, frames=True)
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symkin.derive.chain import derivation

    robot = chain_or_tree(args)
    sections = args.sections
    output_file(args.output, "-o")
    if args.order is not None and (args.ik or args.singularities or sections is not None):
        raise UserError("--order writes its own derivation: leave out --ik, --singularities and --sections")
    if robot.single_path:
        robot = robot.chain()
    elif args.ik or args.singularities or args.order is not None:  # several frames, or a mimic on the path
        raise UserError("--ik, --singularities and --order analyse one chain: name it as ROBOT.urdf:FRAME")
    if args.singularities:
        if args.ik or sections is not None:
            raise UserError("--singularities writes its own report: leave out --ik and --sections")
        from symkin.derive.singularities import singularities

        text = singularities(robot, axes=args.singular_axes, fmt=args.format).text
    elif args.order is not None:
        from symkin.derive.higher_order import higher_order_derivation

        text = higher_order_derivation(
            robot, args.order, fmt=args.format, symbolic_constants=args.symbolic_constants
        )
    elif args.ik:
        if sections is not None:
            raise UserError("--sections chooses parts of the kinematics derivation, not of --ik")
        from symkin.derive.analytic_ik import ik_derivation

        text = ik_derivation(robot, fmt=args.format)
    else:  # a chain, or a tree: the same walk
        text = derivation(
            robot,
            fmt=args.format,
            symbolic_constants=args.symbolic_constants,
            simplify=not args.no_simplify,
            form=args.form,
            sections=sections,
        )
    if args.output:
        Path(args.output).write_text(text)
        print(f"wrote the derivation of {robot.name} to {args.output}")
    else:
        print(text)
    return 0
