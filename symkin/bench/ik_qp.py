"""QP inverse kinematics against roboticstoolbox-python's ``IK_QP`` (Python + qpsolvers with
quadprog, the solver of Haviland and Corke, Manipulator Differential Kinematics, Part 2, 2023) on
the targets of Table 1 of Part 1, in the same run: success rate, solutions outside the joint
limits, iterations and time per solve.

Both solve the first ``problems`` targets of :func:`symkin.bench.ik.table1_problems` with the 100
shared start points (setting b, 100 searches x 30 iterations) and the same criterion (``E <
tol``), with the QP's parameters mapped onto ``IK_QP(kj, ks, kq, km, ps, pi)`` (see
:mod:`symkin.runtime.ik_qp`). symkin's QP leaves revolute joints whose range spans a full turn
undamped (their limits exclude no pose), so when every joint is such a joint (the UR5) RTB runs
without dampers (``kq = 0``, as in Part 2's UR5 experiment); otherwise ``kq = 1 / xi``. RTB counts
the steps of a search, symkin the pose evaluations (one more per search); both are reported as the
solvers count them. Times are CPU times of the calling thread (``time.thread_time``): symkin's the
best of three interleaved rounds, RTB's one round (it takes seconds).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symkin.bench.common import best_of, optional

__all__ = ["QP_ROW", "compare_rtb_qp", "format_rtb_qp"]

#: the Table 1 row whose options RTB's IK_QP gets
QP_ROW = "QP (lambda_q=0.01)"


def _rtb_parameters(opt: Any) -> dict[str, Any]:
    """IK_QP's keyword arguments for symkin's QP options ``opt`` (an IKOptions)."""
    from symkin.runtime.ik_qp import damped_limits

    damped = np.isfinite(damped_limits(opt)).any() and opt.joint_limits
    return {
        "kj": float(opt.lam[0]),
        "ks": opt.slack_gain,
        "kq": 1.0 / opt.xi if damped else 0.0,
        "km": 1.0 / opt.manipulability if opt.manipulability > 0 else 0.0,
        "ps": float(opt.rho_s[0]),
        "pi": np.asarray(opt.rho_i, dtype=float),
    }


def compare_rtb_qp(
    robot: Any, kin: Any, Tep: np.ndarray, starts: np.ndarray, options: dict[str, Any], tol: float,
    problems: int = 1000, seed: int = 0,
) -> dict[str, Any] | None:  # fmt: skip
    """symkin's QP (``kin``, C) and RTB's ``IK_QP`` on the first ``problems`` targets ``Tep``
    (setting b); None when roboticstoolbox-python or quadprog is missing. Each side reports
    success %, solutions outside the limits (by the reference's ``within_limits``), mean
    iterations (solved problems, as the solver counts them), us per solve; ``ratio`` is RTB's
    time over symkin's."""
    rtb = optional("roboticstoolbox")
    if rtb is None or optional("quadprog") is None:
        return None
    from symkin.bench.kin import rtb_ets, rtb_solve
    from symkin.runtime.ik import ik
    from symkin.runtime.ik_problem import IKOptions

    T = Tep[: int(problems)]
    run = dict(options, slimit=100, ilimit=30, tol=tol, tol_on="E")
    ours = ik(kin, T, backend="c", starts=starts, seed=seed, **run)
    t_ours = best_of(lambda: ik(kin, T, backend="c", starts=starts, seed=seed, **run)) / len(T)
    params = _rtb_parameters(IKOptions.of(kin, **run))
    ets = rtb_ets(rtb, robot)
    ets.qlim = np.asarray(robot.qlim, dtype=float)  # its dampers and limit check need the limits
    solver = rtb.IK_QP(ilimit=30, slimit=100, tol=tol, joint_limits=True, seed=seed, **params)
    t_rtb, rtb_q, rtb_success, rtb_iterations = rtb_solve(lambda x: solver.solve(ets, x, q0=starts), T)
    return {
        "problems": len(T),
        "rtb_parameters": {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in params.items()},
        "symkin": _side(robot, ours.q, ours.success, ours.iterations, t_ours),
        "rtb": _side(robot, rtb_q, rtb_success, rtb_iterations, t_rtb),
        "ratio": t_rtb / t_ours,
    }


def _side(robot: Any, q: np.ndarray, success: np.ndarray, iterations: np.ndarray, seconds: float) -> dict:
    outside = sum(not robot.within_limits(x) for x in q[success])
    return {
        "success_pct": 100.0 * float(success.mean()),
        "outside_limits": int(outside),
        "mean_iterations": float(iterations[success].mean()) if success.any() else float("nan"),
        "us_per_solve": 1e6 * seconds,
    }


def format_rtb_qp(result: dict[str, Any] | None) -> str:
    """The comparison of :func:`compare_rtb_qp` as text lines."""
    if result is None:
        return "roboticstoolbox-python IK_QP: not compared (needs roboticstoolbox-python and quadprog)"
    p = result["rtb_parameters"]
    head = (
        f"{QP_ROW} against roboticstoolbox-python IK_QP (kj={p['kj']:g}, ks={p['ks']:g}, kq={p['kq']:g}, "
        f"km={p['km']:g}, ps={p['ps']:g}, pi={p['pi'][0]:g}) on the first {result['problems']} targets, "
        "100 x 30, E < tol:"
    )
    lines = [head]
    for who, label in (("symkin", "symkin QP (C)"), ("rtb", "RTB IK_QP")):
        s = result[who]
        lines.append(
            f"  {label:15s} success {s['success_pct']:.2f}%, outside the limits {s['outside_limits']}, "
            f"mean iterations {s['mean_iterations']:.2f}, {s['us_per_solve']:.1f} us/solve"
        )
    lines.append(f"  symkin is {result['ratio']:.0f}x faster (RTB counts steps, symkin pose evaluations)")
    return "\n".join(lines)
