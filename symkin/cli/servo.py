"""``symkin servo``: servo to a target pose with RRMC, QRMC or MMC, optionally plotting manipulability
and error against time."""

from __future__ import annotations

import argparse
import json
from typing import Any

import numpy as np

from symkin.cli import common
from symkin.cli.checks import UserError, check_cflags_for, int_at_least, need_matplotlib, positive_float

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    s = common.add_robot_command(
        sub, "servo", "servo to a target pose with RRMC, QRMC or MMC, optionally plotting"
    )
    common.add_target_options(s, "start configuration (default: the ready pose qr, else qz)")
    s.add_argument(
        "--controller",
        choices=("mmc", "rrmc", "qrmc"),
        default="mmc",
        help="manipulability-maximising, plain resolved rate, or quadratic rate (through singularities)",
    )
    s.add_argument("--dt", type=positive_float, default=0.05, help="control period (s)")
    s.add_argument("--max-steps", type=int_at_least(0), default=500, help="give up after this many steps")
    s.add_argument("--joint-limits", action="store_true", help="MMC: velocity dampers keep joints in limits")
    s.add_argument("--plot", metavar="PNG", help="write manipulability and error against time")
    common.add_collision_options(
        s,
        "MMC: avoid self-collisions and the obstacles given (the robot's geometry; NEO's velocity "
        "dampers on the closest pairs)",
    )
    s.add_argument("--d-i", type=positive_float, default=0.3, help="--collision: influence distance (m)")
    s.add_argument("--d-s", type=positive_float, default=0.02, help="--collision: safety distance (m)")
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symkin.runtime.load import compile as compile_robot
    from symkin.runtime.loop import servo

    robot, env, collision = common.collision_model(args)
    if args.collision and args.controller != "mmc":
        raise UserError("--collision needs the MMC controller (--controller mmc)")
    if args.collision and not args.d_i > args.d_s:
        raise UserError(f"--d-i ({args.d_i}) must exceed --d-s ({args.d_s})")
    Tep = common.target(args, robot)
    need_matplotlib(args.plot)
    check_cflags_for(args.backend)
    q0 = common.floats(args.q0, "--q0", robot.n) if args.q0 else robot.configs.get("qr", robot.configs["qz"])
    kin = compile_robot(robot, backend=args.backend)
    controller: Any = args.controller
    if args.collision:
        from symkin.runtime.control import MMC

        controller = MMC(
            kin,
            joint_limits=args.joint_limits,
            dt=args.dt,
            collision=collision,
            d_i=args.d_i,
            d_s=args.d_s,
        )
    res = servo(
        kin,
        q0,
        Tep,
        controller=controller,
        dt=args.dt,
        max_steps=args.max_steps,
        joint_limits=args.joint_limits,
        progress=not args.json,
    )
    steps = len(res.q) - 1
    summary = {
        "arrived": bool(res.arrived),
        "reason": res.reason,
        "steps": steps,
        "final_error": float(np.abs(res.e[-1]).sum()) if len(res.e) else None,
        "mean_manipulability": float(np.mean(res.manipulability)),
        "q_final": res.q[-1].tolist(),
    }
    speeds = _speeds(res, kin)
    if speeds is not None:
        summary["max_speed_over_limit"] = {"requested": speeds[0], "applied": speeds[1]}
    if not res.arrived and res.info:
        last = res.info[-1]
        why = (
            ": no part of the next step was free of collision, so the run stopped before it"
            if res.blocked
            else ": the controller could not produce the requested velocity there (a singularity, or a "
            "target out of reach)"
            if last.status in ("singular", "max_iter", "infeasible")
            else ""
        )
        summary["stalled"] = (
            f"sum|e| = {summary['final_error']:.3g}; the last step was {last.status!r} at manipulability "
            f"{res.manipulability[-1]:.3g}{why}"
        )
    clearance = None
    if args.collision:  # the closest approach along the path: obstacles, and all pairs
        D = np.asarray(kin.distances(np.asarray(res.q), env))
        # per step: the closest obstacle (or, self only, the closest pair)
        near = (D[:, -len(robot.geometry.shapes) * len(env) :] if len(env) else D).min(axis=1)
        clearance = (near, args.d_s if len(env) else 0.0)
        summary["closest_obstacle"] = float(near.min()) if len(env) else None
        summary["closest_pair"] = float(D.min())
        summary["controller_backend"] = controller.backend
    if args.plot:
        title = f"{robot.name} {args.controller}"
        _plot_servo(res, args.dt, args.plot, title, clearance, _speed_ratios(res, kin))
        summary["plot"] = args.plot
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(
            f"{args.controller}: {_outcome(res.reason)} after {steps} steps "
            f"(dt {args.dt} s); mean manipulability {summary['mean_manipulability']:.4f}"
        )
        print(f"q final = {common.fmt(res.q[-1])}")
        if speeds is not None:
            print(
                f"joint speeds up to {speeds[1]:.3g} x the limits applied ({speeds[0]:.3g} x requested "
                "before the speed scaling)"
            )
        if "stalled" in summary:
            print(f"did not arrive: {summary['stalled']}")
        if args.collision:
            near = summary["closest_obstacle"]
            print(
                (f"closest approach to an obstacle {near:.4f} m; " if near is not None else "")
                + f"closest pair {summary['closest_pair']:.4f} m (signed distances; MMC step in "
                f"{summary['controller_backend']})"
            )
        if args.plot:
            print(f"plot written to {args.plot}")
    return 0 if res.arrived else 1


def _outcome(reason: str) -> str:
    """How a servo run ended, in words."""
    return {
        "arrived": "arrived",
        "collision": "stopped (no part of the next step was free of collision)",
    }.get(reason, "did not arrive")


def _speed_ratios(res: Any, kin: Any) -> tuple[np.ndarray, np.ndarray] | None:
    """(requested, applied) max_i |qd_i| / qd_max_i per step, or None without speed limits."""
    from symkin.bench.qrmc import speed_ratios

    qd_max = getattr(kin, "qd_max", None)
    if qd_max is None or not res.steps:
        return None
    return speed_ratios(res, np.broadcast_to(np.asarray(qd_max, dtype=float), (kin.n,)))


def _speeds(res: Any, kin: Any) -> tuple[float, float] | None:
    """(requested, applied) largest joint speed over its limit along the run, or None without limits."""
    ratios = _speed_ratios(res, kin)
    return None if ratios is None else (float(ratios[0].max()), float(ratios[1].max()))


def _plot_servo(
    res: Any, dt: float, path: str, title: str, clearance: Any = None, speeds: Any = None
) -> None:
    """Manipulability and error against time; with ``speeds`` ((requested, applied) max_i |qd_i| /
    qd_max_i per step) a panel of the joint speeds; with ``clearance`` ((steps,) distances, the
    safety distance) a panel with the closest approach; matplotlib was checked by need_matplotlib."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.arange(len(res.manipulability)) * dt
    panels = 2 + (clearance is not None) + (speeds is not None)
    fig, axes = plt.subplots(panels, 1, figsize=(7, 2.5 * panels), sharex=True)
    a1, a2 = axes[0], axes[1]
    a1.plot(t, res.manipulability)
    a1.set_ylabel("manipulability")
    a1.set_title(title)
    a2.plot(np.arange(len(res.e)) * dt, np.abs(np.asarray(res.e)).sum(axis=1))
    a2.set_ylabel("sum |e|")
    if speeds is not None:
        requested, applied = speeds
        axes[2].semilogy(t[:-1], np.maximum(requested, 1e-6), "--", label="requested")
        axes[2].semilogy(t[:-1], np.maximum(applied, 1e-6), label="applied")
        axes[2].axhline(1.0, color="k", linewidth=0.8, linestyle=":", label="speed limit")
        axes[2].set_ylabel("max |qd_i| / qd_max_i")
        axes[2].legend(loc="best", fontsize="small")
    if clearance is not None:
        d, d_s = clearance
        axes[-1].plot(np.arange(len(d)) * dt, d, label="closest distance")
        axes[-1].axhline(d_s, color="tab:orange", linestyle="--", label="safety distance")
        axes[-1].axhline(0.0, color="tab:red", linewidth=0.8, label="contact")
        axes[-1].set_ylabel("clearance (m)")
        axes[-1].legend(loc="best", fontsize="small")
    axes[-1].set_xlabel("time (s)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
