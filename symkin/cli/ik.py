"""``symkin ik``: inverse kinematics for one target pose, numerical (NR, GN, LM, QP) or in closed
form (``--method analytic``, ``--all``)."""

from __future__ import annotations

import argparse
import json
from typing import Any

import numpy as np

from symkin.cli import common
from symkin.cli.checks import UserError, at_least_1, check_cflags_for, non_negative_float, positive_float

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    s = common.add_robot_command(sub, "ik", "solve inverse kinematics for one target pose")
    common.add_target_options(s, "first start of the search (default: random within the joint limits)")
    s.add_argument(
        "--method",
        choices=("NR", "GN", "LM", "QP", "analytic"),
        default="LM",
        help="solver (QP: one QP per step, joint-limit dampers and a slack, Part 2)",
    )
    s.add_argument(
        "--all", action="store_true", help="print every closed-form solution (arms with a closed form)"
    )
    s.add_argument("--no-limits", action="store_true", help="--all: keep solutions outside the joint limits")
    s.add_argument(
        "--damping",
        choices=("wampler", "chan", "sugihara"),
        help="LM damping (default chan: lambda E_k, eq 50 of Manipulator Differential Kinematics, Part 1)",
    )
    s.add_argument(
        "--we",
        metavar="W",
        help="task weights: 'position' (position only), 'orientation', or six weights >= 0 for "
        "vx vy vz wx wy wz (default all 1)",
    )
    s.add_argument(
        "--lam",
        type=positive_float,
        help="damping lambda of LM (default 0.1); QP: joint-velocity weight (0.01)",
    )
    s.add_argument("--slack-gain", type=positive_float, help="QP: the slack's gain lambda_delta (default 1)")
    s.add_argument(
        "--manipulability",
        type=non_negative_float,
        help="QP: weight of the manipulability term (default 0: none; Part 2's 1 / lambda_m)",
    )
    s.add_argument(
        "--xi", type=positive_float, help="QP: gain of the joint-limit velocity dampers (default 1)"
    )
    s.add_argument(
        "--rho-i", type=positive_float, help="QP: dampers' influence distance, rad or m (default 0.9)"
    )
    s.add_argument(
        "--rho-s", type=non_negative_float, help="QP: dampers' stop distance, rad or m (default 0.01)"
    )
    s.add_argument("--tol", type=positive_float, help="converged when |e| < TOL (default 1e-6: 1 um, 1 urad)")
    s.add_argument("--ilimit", type=at_least_1, help="iterations per search (default 30)")
    s.add_argument("--slimit", type=at_least_1, help="searches from random starts (default 100)")
    s.add_argument("--seed", type=int, default=0, help="seed of the random restarts")
    common.add_collision_options(
        s,
        "only a solution free of self-collisions and of the obstacles given (the robot's geometry; "
        "a converged solution in collision starts the next search)",
    )
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symkin.bench.common import timed
    from symkin.runtime.load import compile as compile_robot

    if args.collision and (args.all or args.method == "analytic"):
        raise UserError("--collision applies to the numerical methods NR, GN and LM, not the closed form")
    robot, _, collision = common.collision_model(args)
    Tep = common.target(args, robot)
    numerical = {"--we": args.we, "--lam": args.lam, "--ilimit": args.ilimit, "--slimit": args.slimit}
    qp = {f"--{k.replace('_', '-')}": getattr(args, k) for k in _QP_OPTIONS}
    given_qp = [k for k, v in qp.items() if v is not None]
    if given_qp and args.method != "QP":
        raise UserError(f"{', '.join(given_qp)} set the QP method: add --method QP")
    numerical.update(qp)
    check_cflags_for(args.backend)
    if args.all or args.method == "analytic":
        given = [k for k, v in numerical.items() if v is not None]
        if given:
            raise UserError(
                f"{', '.join(given)} set the numerical methods NR, GN, LM and QP, not the closed form"
            )
        return _ik_analytic(args, compile_robot(robot, backend=args.backend), Tep)
    kin = compile_robot(robot, backend=args.backend)
    kwargs: dict[str, Any] = {"method": args.method, "seed": args.seed}
    if collision is not None:
        kwargs["collision"] = collision
    if args.q0 is not None:
        kwargs["q0"] = common.floats(args.q0, "--q0", robot.n)
    if args.we is not None:
        kwargs["we"] = _weights(args.we)
    for name in (
        "damping",
        "lam",
        "tol",
        "ilimit",
        "slimit",
        *_QP_OPTIONS,
    ):  # the solver's defaults unless given
        if getattr(args, name) is not None:
            kwargs[name] = getattr(args, name)
    res, dt = timed(lambda: kin.ik(Tep, **kwargs))
    if not args.json:
        print(f"target:\n{common.fmt(Tep)}")
    return _report(
        args, res, dt, f"in {res.iterations} iterations, {res.searches} searches, {dt * 1e3:.2f} ms"
    )


_QP_OPTIONS = ("slack_gain", "manipulability", "xi", "rho_i", "rho_s")


def _weights(text: str) -> np.ndarray:
    """--we: 'position' (1 1 1 0 0 0), 'orientation' (0 0 0 1 1 1) or six weights >= 0."""
    named = {"position": [1, 1, 1, 0, 0, 0], "orientation": [0, 0, 0, 1, 1, 1]}
    if text.strip().lower() in named:
        return np.array(named[text.strip().lower()], dtype=float)
    we = common.floats(text, "--we", 6)
    if (we < 0).any() or not we.any():
        raise UserError(f"--we needs six weights >= 0, not all 0 (or 'position'), got {text!r}")
    return we


def _ik_analytic(args: argparse.Namespace, kin: Any, Tep: np.ndarray) -> int:
    """``symkin ik --all`` (every closed-form solution) or ``--method analytic`` (the nearest)."""
    from symkin.bench.common import timed

    q0 = common.floats(args.q0, "--q0", kin.n) if args.q0 is not None else None
    if not args.all:
        extra = {} if args.tol is None else {"tol": args.tol}
        res, dt = timed(lambda: kin.ik(Tep, method="analytic", q0=q0, **extra))
        return _report(args, res, dt, f"(closed form) in {dt * 1e3:.3f} ms")
    sols, dt = timed(lambda: kin.ik_all(Tep, q0=q0, joint_limits=not args.no_limits))
    errors = [float(np.abs(kin.robot.fkine(q) - Tep).max()) for q in sols]
    if args.json:
        print(json.dumps({"solutions": sols.tolist(), "fk_error": errors, "seconds": dt}, indent=2))
    else:
        print(f"target:\n{common.fmt(Tep)}")
        where = "" if args.no_limits else " within the joint limits"
        print(f"{len(sols)} solution(s){where} (closed form, {kin.analytic.kind}) in {dt * 1e3:.3f} ms")
        for i, (q, e) in enumerate(zip(sols, errors)):
            print(f"  {i + 1}: q = {common.fmt(q)}  |T(q) - T| = {e:.1e}")
    return 0 if len(sols) else 1


def _report(args: argparse.Namespace, res: Any, dt: float, how: str) -> int:
    """One IK result (``how``: the solver's effort) as JSON or text; the exit status."""
    if args.json:
        print(json.dumps({**_result_dict(res), "seconds": dt}, indent=2))
    else:
        status = "solved" if res.success else f"not solved: {res.reason}"
        print(f"{status} {how}\nq = {common.fmt(res.q)}\nresidual = {res.residual:.3e}")
    return 0 if res.success else 1


def _result_dict(res: Any) -> dict:
    import dataclasses

    values = {f.name: getattr(res, f.name) for f in dataclasses.fields(res)}
    return {k: v.tolist() if isinstance(v, (np.ndarray, np.generic)) else v for k, v in values.items()}
