"""Inverse kinematics as a nonlinear program in CasADi, solved with IPOPT.

The CasADi backend of ``symkin.compile`` gives ``casadi.Function`` objects (``fkine``, ``jacob0``,
``manipulability_all`` ...) that take symbolic arguments, so the generated kinematics drop straight
into ``casadi.Opti``::

    minimise    -w_m m(q) + w_r/2 |q - q_ref|^2          (m: Yoshikawa manipulability, eq 52)
    subject to  t(q) = t*                                 (position, 3 equations)
                vee(R*^T R(q) - R(q)^T R*) / 2 = 0        (orientation: sin(angle) * axis = 0)
                trace(R*^T R(q)) >= 1                     (angle error below 90 deg, not 180)
                qlim_lo <= q <= qlim_hi                   (joint limits as bounds)

For a redundant arm (the 7-joint Panda) the pose leaves a one-dimensional self-motion, along which
IPOPT climbs to the most manipulable configuration; started from symkin's numerical IK solution
(``kin.ik``, Manipulator Differential Kinematics, Part 1, eqs 37-51) the result reaches the same pose with
at least its manipulability.

Run ``python examples/ik_nlp_casadi.py [ROBOT] [--targets N] [--small]``.
"""

from __future__ import annotations

import argparse
import time
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

import symkin

IPOPT_QUIET = {"ipopt.print_level": 0, "print_time": 0, "ipopt.sb": "yes"}
# IPOPT relaxes bounds by 1e-8 by default; bound_relax_factor = 0 keeps q exactly within the limits


@dataclass(frozen=True)
class IKProblem:
    """The NLP built once per robot; the target and the reference are parameters."""

    robot: symkin.Robot
    opti: ca.Opti
    q: ca.MX  # (n,) decision variable
    T_target: ca.MX  # (4, 4) parameter
    q_ref: ca.MX  # (n,) parameter: regularisation centre
    manipulability: ca.MX  # m(q), the objective term


@dataclass(frozen=True)
class NLPSolution:
    """Outcome of one solve; errors and manipulability from the numeric reference ``robot``."""

    q: np.ndarray  # (n,)
    success: bool
    status: str  # IPOPT's return status
    iterations: int
    position_error: float  # m, |t(q) - t*|
    angle_error: float  # rad, angle of R*^T R(q)
    manipulability: float
    seconds: float


def pose_errors(robot: symkin.Robot, q: np.ndarray, T_target: np.ndarray) -> tuple[float, float]:
    """Position error (m) and rotation angle error (rad) of ``robot.fkine(q)`` against the target,
    from symkin's pose error (eq 37), checked with the numeric reference FK."""
    e = symkin.pose_error(robot.fkine(q), T_target)
    return float(np.linalg.norm(e[:3])), float(np.linalg.norm(e[3:]))


def build_ik_nlp(
    kin: Any, manipulability_weight: float = 0.1, regularisation: float = 1e-4, ipopt: dict | None = None
) -> IKProblem:
    """The IK NLP of the module docstring for ``kin`` (a CasADi-backend :class:`symkin.Kinematics`)."""
    robot = kin.robot
    fkine, manip = kin.functions["fkine"], kin.functions["manipulability_all"]
    opti = ca.Opti()
    q = opti.variable(robot.n)
    T_target = opti.parameter(4, 4)
    q_ref = opti.parameter(robot.n)
    T = fkine(q)
    E = T_target[:3, :3].T @ T[:3, :3]
    m = manip(q)
    opti.minimize(-manipulability_weight * m + 0.5 * regularisation * ca.sumsqr(q - q_ref))
    opti.subject_to(T[:3, 3] - T_target[:3, 3] == 0)
    opti.subject_to(ca.vertcat(E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]) / 2 == 0)
    opti.subject_to(ca.trace(E) >= 1)
    opti.subject_to(opti.bounded(robot.qlim[0], q, robot.qlim[1]))
    opti.solver(
        "ipopt",
        {**IPOPT_QUIET, **(ipopt or {})},
        {"tol": 1e-10, "acceptable_tol": 1e-8, "bound_relax_factor": 0.0},
    )
    return IKProblem(robot, opti, q, T_target, q_ref, m)


def solve_ik_nlp(problem: IKProblem, T_target: np.ndarray, q0: np.ndarray) -> NLPSolution:
    """Solve for one target pose (4, 4) from ``q0`` (n,), which is also the regularisation centre.

    m = sqrt(det(J J^T)) has no gradient where it is 0, so a singular ``q0`` (m < 1e-6, such as a
    stretched-out arm) is first moved by 0.01 rad per joint.
    """
    robot, opti = problem.robot, problem.opti
    lo, hi = robot.qlim
    q0 = np.asarray(q0, dtype=float)
    if robot.manipulability(q0) < 1e-6:
        q0 = q0 + 0.01 * np.where(np.arange(robot.n) % 2, -1.0, 1.0)
    q0 = np.clip(q0, lo, hi)
    opti.set_value(problem.T_target, T_target)
    opti.set_value(problem.q_ref, q0)
    opti.set_initial(problem.q, q0)
    t0 = time.perf_counter()
    try:
        sol = opti.solve()
        q = np.asarray(sol.value(problem.q), dtype=float).reshape(-1)
    except RuntimeError:  # IPOPT failed: report its last iterate
        q = np.asarray(opti.debug.value(problem.q), dtype=float).reshape(-1)
    seconds = time.perf_counter() - t0
    stats = opti.stats()
    dp, dang = pose_errors(robot, q, T_target)
    return NLPSolution(
        q=q,
        success=bool(stats.get("success", False)),
        status=str(stats.get("return_status", "")),
        iterations=int(stats.get("iter_count", -1)),
        position_error=dp,
        angle_error=dang,
        manipulability=float(robot.manipulability(q)),
        seconds=seconds,
    )


def numerical_ik(kin: Any, T_target: np.ndarray, seed: int) -> Any | None:
    """symkin's numerical IK (``kin.ik``, Levenberg-Marquardt) if this symkin has it, else None."""
    if not hasattr(kin, "ik"):
        return None
    try:
        return kin.ik(T_target, seed=seed)
    except ImportError:
        return None


def main(robot: str = "panda", targets: int = 5, seed: int = 0, small: bool = False) -> list[dict[str, Any]]:
    """Solve IK for random reachable targets with symkin's IK and with the NLP; print and return rows.

    The NLP starts from the numerical IK solution when there is one (else from ``qr`` or ``qz``),
    so it keeps the pose and raises the manipulability. ``small`` uses 2 targets.
    """
    r = symkin.load(robot)
    kin = symkin.compile(r, backend="casadi")
    problem = build_ik_nlp(kin)
    rng = np.random.default_rng(seed)
    start = r.configs.get("qr", r.configs["qz"])
    rows = []
    for i in range(2 if small else targets):
        T_target = r.fkine(r.random_q(seed=rng))
        num = numerical_ik(kin, T_target, seed + i)
        q0 = num.q if num is not None and num.success else start
        nlp = solve_ik_nlp(problem, T_target, q0)
        row: dict[str, Any] = {"target": i, "nlp": nlp}
        if num is not None:
            dp, dang = pose_errors(r, num.q, T_target)
            row["ik"] = {"success": bool(num.success), "position_error": dp, "angle_error": dang,
                         "manipulability": float(r.manipulability(num.q))}  # fmt: skip
        rows.append(row)
    print(f"{r.name}: IK as an NLP (IPOPT) vs symkin's numerical IK")
    print(f"{'target':>6} {'method':>6} {'ok':>3} {'pos err [m]':>12} {'ang err [rad]':>13} {'manip':>8}")

    def line(i: int, method: str, ok: bool, dp: float, dang: float, m: float, extra: str = "") -> None:
        print(f"{i:>6} {method:>6} {'yes' if ok else 'no':>3} {dp:>12.2e} {dang:>13.2e} {m:>8.4f} {extra}")

    for row in rows:
        if "ik" in row:
            ik = row["ik"]
            line(
                row["target"],
                "ik",
                ik["success"],
                ik["position_error"],
                ik["angle_error"],
                ik["manipulability"],
            )
        s = row["nlp"]
        extra = f"  ({s.iterations} iterations, {s.seconds:.2f} s)"
        line(row["target"], "nlp", s.success, s.position_error, s.angle_error, s.manipulability, extra)
    return rows


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robot", nargs="?", default="panda")
    parser.add_argument("--targets", type=int, default=5)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--small", action="store_true", help="2 targets only")
    args = parser.parse_args()
    main(args.robot, targets=args.targets, seed=args.seed, small=args.small)
