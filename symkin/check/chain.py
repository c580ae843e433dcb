"""Symbolic vs numeric: every generated function of every backend against two independent references.

For each backend and each function, :func:`check` reports the largest error (relative to the
magnitudes) against the numeric O(n) reference, and against central finite differences of the
backend's own lower-order function (J from FK, H from J, J dot from J, Jm from m), at random
configurations, at the robot's named configurations and near them (where singularities usually are).
Space and body Jacobians and the condition number are compared with the reference.

Rows marked ``(large q)`` evaluate FK, J and H at revolute angles of up to :data:`LARGE_TURNS`
turns and next to large multiples of pi/2 (where an argument reduction for sin/cos is hardest).
Generated code adds joint angles before sin/cos (``sin(q1 + q2)``), which rounds, so their
tolerance grows with the angles: ``REF_TOL + 8 n max|q| 2^-53`` (see the README, "Accuracy").
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from symkin.model.robot import Robot
from symkin.runtime.kinematics import Kinematics

__all__ = ["CheckRow", "CheckReport", "check", "REF_TOL", "FD_TOL", "FD_STEP", "LARGE_TURNS", "large_angles"]

REF_TOL = 1e-10  # against the numeric reference (the tests hold 1e-12 for FK/J, 1e-10 for H)
LARGE_TURNS = 10_000  # large-angle samples: revolute joints up to this many turns (|q| <~ 6.3e4 rad)
FD_STEP = 1e-6  # central difference step
FD_TOL = 1e-6  # central differences are accurate to O(h^2) truncation + O(eps/h) rounding ~ 1e-9


@dataclass(frozen=True)
class CheckRow:
    backend: str
    function: str
    ref_error: float
    fd_error: float | None
    ref_tol: float = REF_TOL

    @property
    def ok(self) -> bool:
        fd_ok = self.fd_error is None or self.fd_error <= FD_TOL
        return bool(self.ref_error <= self.ref_tol and fd_ok)


@dataclass(frozen=True)
class CheckReport:
    robot: str
    samples: int
    rows: tuple[CheckRow, ...]

    @property
    def ok(self) -> bool:
        return all(r.ok for r in self.rows)

    def as_dict(self) -> dict:
        return {
            "robot": self.robot,
            "samples": self.samples,
            "ok": self.ok,
            "rows": [{**r.__dict__, "ok": r.ok} for r in self.rows],
        }

    def _large_tol(self) -> float:
        return max((r.ref_tol for r in self.rows if r.function.endswith("(large q)")), default=REF_TOL)

    def format(self) -> str:
        head = f"{'backend':8} {'function':21} {'vs reference':>13} {'vs finite diff':>15}  result"
        lines = [f"symkin check {self.robot}: {self.samples} configurations per function", head]
        lines.append("-" * len(head))
        for r in self.rows:
            fd = "-" if r.fd_error is None else f"{r.fd_error:.2e}"
            lines.append(
                f"{r.backend:8} {r.function:21} {r.ref_error:13.2e} {fd:>15}  {'ok' if r.ok else 'FAIL'}"
            )
        lines.append(
            f"tolerances: {REF_TOL:g} vs reference, {FD_TOL:g} vs central differences (h = {FD_STEP:g});"
            f" (large q): up to {LARGE_TURNS} turns, {self._large_tol():.2g} vs reference"
        )
        lines.append("all ok" if self.ok else "FAILED")
        return "\n".join(lines)


def _rel(a: np.ndarray, b: np.ndarray) -> float:
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape or not np.isfinite(a).all():
        return float("inf")
    return float(np.abs(a - b).max(initial=0.0) / max(1.0, np.abs(b).max(initial=0.0)))


def _vee_rate(Tp: np.ndarray, Tm: np.ndarray, T: np.ndarray, h: float) -> np.ndarray:
    """(v, omega) from central differences of poses: v = dp/dq, [omega]x = dR/dq R^T."""
    dT = (Tp - Tm) / (2 * h)
    S = dT[..., :3, :3] @ np.swapaxes(T[..., :3, :3], -1, -2)
    w = np.stack((S[..., 2, 1], S[..., 0, 2], S[..., 1, 0]), axis=-1)
    return np.concatenate((dT[..., :3, 3], w), axis=-1)


def _fd(f, Q: np.ndarray, h: float) -> np.ndarray:  # noqa: ANN001
    """Central differences of f over each joint: (N, n, *f.shape)."""
    plus, minus = _shifted(f, Q, h)
    return (plus - minus) / (2 * h)


def _shifted(f, Q: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:  # noqa: ANN001
    """f at Q + h e_i and Q - h e_i for each joint i: two (N, n, *f.shape) arrays."""
    eye = np.eye(Q.shape[1]) * h
    plus = np.stack([np.asarray(f(Q + d)) for d in eye], axis=1)
    minus = np.stack([np.asarray(f(Q - d)) for d in eye], axis=1)
    return plus, minus


def sample_configurations(robot: Robot, n: int, seed: int = 0) -> np.ndarray:
    """Random configurations within limits, the named configurations and points 1e-5 away from them."""
    rng = np.random.default_rng(seed)
    named = np.array(list(robot.configs.values()))
    near = named + rng.normal(scale=1e-5, size=named.shape)
    return np.vstack((robot.random_q(n, seed=rng), named, near))


def large_angles(robot: Robot, n: int, seed: int = 0) -> np.ndarray:
    """(2n, n_joints) configurations with large revolute angles: random ones moved by up to
    :data:`LARGE_TURNS` whole turns, and ones next to large multiples of pi/2 (the doubles nearest
    k pi/2 and their neighbours, k up to 4 LARGE_TURNS). Prismatic joints stay within limits."""
    rng = np.random.default_rng(seed)
    Q = np.vstack((robot.random_q(n, seed=rng), robot.random_q(n, seed=rng)))
    rev = np.array([e.is_revolute for e in robot.ets.joints])
    turns = rng.integers(-LARGE_TURNS, LARGE_TURNS + 1, size=(n, robot.n))
    Q[:n] += np.where(rev, 2 * np.pi * turns, 0.0)
    k = rng.integers(-4 * LARGE_TURNS, 4 * LARGE_TURNS + 1, size=(n, robot.n))
    near = np.nextafter(k * (np.pi / 2), np.inf * rng.choice([-1, 1], size=k.shape))
    Q[n:] = np.where(rev, near, Q[n:])
    return Q


def check(
    robot: Robot,
    backends: Sequence[str] | Iterable[Kinematics] = ("c", "numpy", "casadi"),
    samples: int = 20,
    seed: int = 0,
) -> CheckReport:
    """Compare every function of every backend (names, or compiled Kinematics objects) with the references."""
    from symkin.runtime.load import compile as compile_robot

    kins = [b if isinstance(b, Kinematics) else compile_robot(robot, backend=b) for b in backends]
    Q = sample_configurations(robot, samples, seed)
    h = FD_STEP
    rows: list[CheckRow] = []
    for kin in kins:
        T = kin.fkine(Q)
        J0, Je = kin.jacob0(Q), kin.jacobe(Q)
        rows.append(CheckRow(kin.backend, "fkine", _rel(T, robot.fkine(Q)), None))
        rows.append(CheckRow(kin.backend, "link_poses", _rel(kin.link_poses(Q), robot.link_poses(Q)), None))
        # J0 from FK: columns are (dp/dq, vee(dR/dq R^T)); Je the same in the end-effector frame
        fd_J0 = np.swapaxes(_vee_rate(*_shifted(kin.fkine, Q, h), T[:, None], h), 1, 2)
        rows.append(CheckRow(kin.backend, "jacob0", _rel(J0, robot.jacob0(Q)), _rel(fd_J0, J0)))
        Rt = np.swapaxes(T[:, :3, :3], 1, 2)
        fd_Je = np.concatenate((Rt @ fd_J0[:, :3], Rt @ fd_J0[:, 3:]), axis=1)
        rows.append(CheckRow(kin.backend, "jacobe", _rel(Je, robot.jacobe(Q)), _rel(fd_Je, Je)))
        for name, jac in (("hessian0", kin.jacob0), ("hessiane", kin.jacobe)):
            H = getattr(kin, name)(Q)
            rows.append(
                CheckRow(kin.backend, name, _rel(H, getattr(robot, name)(Q)), _rel(_fd(jac, Q, h), H))
            )
        T2, J2 = kin.fkine_jacob0(Q)
        rows.append(CheckRow(kin.backend, "fkine_jacob0", max(_rel(T2, T), _rel(J2, J0)), None))
        J3, H3 = kin.jacob0_hessian0(Q)
        rows.append(
            CheckRow(kin.backend, "jacob0_hessian0", max(_rel(J3, J0), _rel(H3, robot.hessian0(Q))), None)
        )
        # dJ0/dt = sum_i H0[i] qd_i against d/dt J0(q + t qd) by central differences
        qd = np.random.default_rng(seed + 1).uniform(-1.0, 1.0, Q.shape)
        Jd = kin.jacob0_dot(Q, qd)
        fd_Jd = (kin.jacob0(Q + h * qd) - kin.jacob0(Q - h * qd)) / (2 * h)
        rows.append(CheckRow(kin.backend, "jacob0_dot", _rel(Jd, robot.jacob0_dot(Q, qd)), _rel(fd_Jd, Jd)))
        rows.append(CheckRow(kin.backend, "jacobs", _rel(kin.jacobs(Q), robot.jacobs(Q)), None))
        rows.append(CheckRow(kin.backend, "jacobb", _rel(kin.jacobb(Q), robot.jacobb(Q)), None))
        c_ref = robot.cond(Q)
        fine = c_ref < 1e6  # the condition number itself is ill-conditioned near a singularity
        if fine.any():
            ratio = np.asarray(kin.cond(Q[fine])) / c_ref[fine]
            rows.append(CheckRow(kin.backend, "cond", _rel(ratio, np.ones_like(ratio)), None))
        # manipulability: compare m^2 (sqrt amplifies rounding at singularities); Jm where well conditioned
        for axes in ("all", "trans", "rot"):
            m = np.asarray(kin.manipulability(Q, axes=axes))
            rows.append(
                CheckRow(
                    kin.backend,
                    f"manipulability:{axes}",
                    _rel(m**2, robot.manipulability(Q, axes=axes) ** 2),
                    None,
                )
            )
            good = robot.cond(Q, axes=axes) < 100
            if good.any():
                Qg = Q[good]
                Jm = kin.jacobm(Qg, axes=axes)
                fd_m = _fd(lambda x, a=axes, k=kin: k.manipulability(x, axes=a), Qg, h)
                rows.append(
                    CheckRow(
                        kin.backend, f"jacobm:{axes}", _rel(Jm, robot.jacobm(Qg, axes=axes)), _rel(fd_m, Jm)
                    )
                )
        # large angles: FK, J and H against the reference, tolerance from the angle-sum rounding
        QL = large_angles(robot, max(samples // 2, 1), seed + 1)
        tol = REF_TOL + 8 * robot.n * float(np.abs(QL).max()) * 2.0**-53
        for name in ("fkine", "jacob0", "hessian0"):
            err = _rel(getattr(kin, name)(QL), getattr(robot, name)(QL))
            rows.append(CheckRow(kin.backend, f"{name} (large q)", err, None, tol))
    return CheckReport(robot.name, len(Q), tuple(rows))
