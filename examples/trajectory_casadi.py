"""A short-horizon trajectory / MPC problem in CasADi with symkin's generated kinematics.

Over N steps of length dt, with joint positions q_0..q_N and velocities qd_0..qd_{N-1}::

    minimise    sum_{k=1}^{N-1} w_s e(q_k) + w_N e(q_N) + w_qd sum_k |qd_k|^2
    subject to  q_0 = q_start,   q_{k+1} = q_k + dt qd_k          (integrator dynamics)
                qlim_lo <= q_k <= qlim_hi,   |qd_k| <= qd_max     (joint and speed limits)

where ``e(q) = |t(q) - t*|^2 + (3 - trace(R*^T R(q)))`` is the pose error of ``fkine(q)`` (the
CasADi backend's ``casadi.Function``) against the target pose ``T*``; ``3 - trace`` is
``2 (1 - cos angle)``, about the squared rotation angle. IPOPT solves it; :func:`run_mpc` applies
the first velocity, shifts the solution as the warm start and solves again (receding horizon).

Run ``python examples/trajectory_casadi.py [ROBOT] [--horizon N] [--mpc-steps S] [--small]``.
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
DEFAULT_QD_MAX = 1.0  # rad/s (or m/s) when the robot has no published joint speeds


@dataclass(frozen=True)
class TrajectoryProblem:
    """The NLP built once; the start configuration and the target pose are parameters."""

    robot: symkin.Robot
    opti: ca.Opti
    Q: ca.MX  # (n, N+1) joint positions
    QD: ca.MX  # (n, N) joint velocities
    q_start: ca.MX  # (n,) parameter
    T_target: ca.MX  # (4, 4) parameter
    dt: float
    qd_max: np.ndarray  # (n,)

    @property
    def horizon(self) -> int:
        return self.QD.shape[1]


@dataclass(frozen=True)
class Trajectory:
    """One solve; pose errors of the final configuration from the numeric reference ``robot``."""

    q: np.ndarray  # (N+1, n)
    qd: np.ndarray  # (N, n)
    success: bool
    status: str
    iterations: int
    position_error: float  # m, at q_N
    angle_error: float  # rad, at q_N
    seconds: float


def pose_errors(robot: symkin.Robot, q: np.ndarray, T_target: np.ndarray) -> tuple[float, float]:
    """Position error (m) and rotation angle error (rad) of ``robot.fkine(q)`` against the target,
    from symkin's pose error (eq 37), checked with the numeric reference FK."""
    e = symkin.pose_error(robot.fkine(q), T_target)
    return float(np.linalg.norm(e[:3])), float(np.linalg.norm(e[3:]))


def pose_cost(T: ca.MX, T_target: ca.MX) -> ca.MX:
    """|t - t*|^2 + 3 - trace(R*^T R): zero exactly at the target pose."""
    return ca.sumsqr(T[:3, 3] - T_target[:3, 3]) + 3 - ca.trace(T_target[:3, :3].T @ T[:3, :3])


def build_trajectory(
    kin: Any,
    horizon: int = 10,
    dt: float = 0.1,
    w_stage: float = 1.0,
    w_terminal: float = 1000.0,
    w_qd: float = 1e-3,
    ipopt: dict | None = None,
) -> TrajectoryProblem:
    """The NLP of the module docstring for ``kin`` (a CasADi-backend :class:`symkin.Kinematics`)."""
    robot = kin.robot
    fkine = kin.functions["fkine"]
    n = robot.n
    qd_max = np.asarray(robot.qd_max if robot.qd_max is not None else np.full(n, DEFAULT_QD_MAX), dtype=float)
    opti = ca.Opti()
    Q = opti.variable(n, horizon + 1)
    QD = opti.variable(n, horizon)
    q_start = opti.parameter(n)
    T_target = opti.parameter(4, 4)
    cost = w_qd * ca.sumsqr(QD)
    for k in range(1, horizon + 1):
        cost += (w_terminal if k == horizon else w_stage) * pose_cost(fkine(Q[:, k]), T_target)
    opti.minimize(cost)
    opti.subject_to(Q[:, 0] == q_start)
    opti.subject_to(Q[:, 1:] == Q[:, :-1] + dt * QD)
    lo, hi = robot.qlim
    for k in range(1, horizon + 1):
        opti.subject_to(opti.bounded(lo, Q[:, k], hi))
    for k in range(horizon):
        opti.subject_to(opti.bounded(-qd_max, QD[:, k], qd_max))
    opti.solver(
        "ipopt",
        {**IPOPT_QUIET, **(ipopt or {})},
        {"tol": 1e-10, "acceptable_tol": 1e-8, "bound_relax_factor": 0.0},
    )
    return TrajectoryProblem(robot, opti, Q, QD, q_start, T_target, dt, qd_max)


def solve_trajectory(
    problem: TrajectoryProblem, q_start: np.ndarray, T_target: np.ndarray, warm: Trajectory | None = None
) -> Trajectory:
    """Solve from ``q_start`` (n,) towards ``T_target`` (4, 4); ``warm`` is an initial guess."""
    opti, N = problem.opti, problem.horizon
    q_start = np.asarray(q_start, dtype=float)
    opti.set_value(problem.q_start, q_start)
    opti.set_value(problem.T_target, T_target)
    opti.set_initial(problem.Q, warm.q.T if warm is not None else np.tile(q_start[:, None], (1, N + 1)))
    opti.set_initial(problem.QD, warm.qd.T if warm is not None else np.zeros((problem.robot.n, N)))
    t0 = time.perf_counter()
    try:
        sol = opti.solve()
        value = sol.value
    except RuntimeError:  # IPOPT failed: report its last iterate
        value = opti.debug.value
    seconds = time.perf_counter() - t0
    q = np.asarray(value(problem.Q), dtype=float).reshape(problem.robot.n, N + 1).T
    qd = np.asarray(value(problem.QD), dtype=float).reshape(problem.robot.n, N).T
    stats = opti.stats()
    dp, dang = pose_errors(problem.robot, q[-1], T_target)
    return Trajectory(
        q=q,
        qd=qd,
        success=bool(stats.get("success", False)),
        status=str(stats.get("return_status", "")),
        iterations=int(stats.get("iter_count", -1)),
        position_error=dp,
        angle_error=dang,
        seconds=seconds,
    )


def run_mpc(
    problem: TrajectoryProblem, q_start: np.ndarray, T_target: np.ndarray, steps: int
) -> tuple[np.ndarray, np.ndarray, list[Trajectory]]:
    """Receding horizon: apply the first velocity of each solve for ``dt``; ``steps`` solves.

    Returns the visited configurations (steps+1, n), the applied velocities (steps, n) and the solves.
    """
    q = np.asarray(q_start, dtype=float)
    qs, qds, solves = [q], [], []
    warm = None
    for _ in range(steps):
        traj = solve_trajectory(problem, q, T_target, warm)
        solves.append(traj)
        qd = traj.qd[0]
        q = q + problem.dt * qd
        qs.append(q)
        qds.append(qd)
        # shift by one step, repeating the last state with zero velocity
        warm = Trajectory(
            np.vstack((traj.q[1:], traj.q[-1:])), np.vstack((traj.qd[1:], np.zeros_like(qd)[None])),
            traj.success, traj.status, traj.iterations, traj.position_error, traj.angle_error, 0.0,
        )  # fmt: skip
    return np.array(qs), np.array(qds), solves


def reachable_target(robot: symkin.Robot, q_start: np.ndarray, spread: float, seed: int) -> np.ndarray:
    """The pose at a configuration within ``spread`` rad of ``q_start`` (inside the joint limits)."""
    rng = np.random.default_rng(seed)
    lo, hi = robot.qlim
    q_goal = np.clip(q_start + rng.uniform(-spread, spread, robot.n), lo + 1e-3, hi - 1e-3)
    return robot.fkine(q_goal)


def main(
    robot: str = "ur5",
    horizon: int = 10,
    dt: float = 0.1,
    mpc_steps: int = 15,
    seed: int = 0,
    small: bool = False,
) -> dict[str, Any]:
    """One open-loop solve and a short MPC run towards a reachable target; print and return results.

    ``small`` uses a horizon of 5 steps and 3 MPC steps.
    """
    if small:
        horizon, mpc_steps = 5, 3
    r = symkin.load(robot)
    kin = symkin.compile(r, backend="casadi")
    problem = build_trajectory(kin, horizon=horizon, dt=dt)
    q_start = np.array(r.configs.get("qr", r.configs["qz"]))
    T_target = reachable_target(r, q_start, spread=0.4, seed=seed)
    traj = solve_trajectory(problem, q_start, T_target)
    print(f"{r.name}: {horizon} steps of {dt} s towards a target pose")
    print(
        f"  open loop: {traj.status} in {traj.iterations} iterations ({traj.seconds:.2f} s); final error "
        f"{traj.position_error:.2e} m, {traj.angle_error:.2e} rad; max |qd|/qd_max "
        f"{np.max(np.abs(traj.qd) / problem.qd_max):.2f}"
    )
    qs, qds, solves = run_mpc(problem, q_start, T_target, mpc_steps)
    dp, dang = pose_errors(r, qs[-1], T_target)
    print(
        f"  MPC: {mpc_steps} steps, {sum(s.success for s in solves)} solves converged, "
        f"{np.mean([s.seconds for s in solves]) * 1e3:.1f} ms per solve; error after {mpc_steps * dt:.1f} s: "
        f"{dp:.2e} m, {dang:.2e} rad"
    )
    return {"problem": problem, "q_start": q_start, "T_target": T_target, "trajectory": traj,
            "mpc_q": qs, "mpc_qd": qds, "mpc_solves": solves}  # fmt: skip


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("robot", nargs="?", default="ur5")
    parser.add_argument("--horizon", type=int, default=10)
    parser.add_argument("--dt", type=float, default=0.1)
    parser.add_argument("--mpc-steps", type=int, default=15)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--small", action="store_true", help="horizon 5, 3 MPC steps")
    args = parser.parse_args()
    main(args.robot, args.horizon, args.dt, args.mpc_steps, args.seed, args.small)
