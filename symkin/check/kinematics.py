"""Symbolic vs numeric: every generated function of every backend against two independent
references, for a chain or a tree alike.

For each backend and each function, :func:`check` reports the largest error (relative to the
magnitudes) against the numeric O(n) reference, and against central finite differences of the
backend's own lower-order function (J from FK, H from J, J dot from J, Jm from m), at random
configurations, at the model's named configurations and near them (where singularities usually
are). Space and body Jacobians and the condition number are compared with the reference. A tree
runs every row for each of its frames (a row reports the largest error over them), plus its
``*_all`` functions, each frame's reference against the serial :class:`symkin.Robot` to it, and
on C the functions the C controllers call. The JAX and PyTorch backends check FK, J and H (the
rows above up to ``jacob0_hessian0`` and the large-q rows) in float64, and in float32 within
:data:`symkin.check.tensor.F32_TOL`. A model with collision geometry adds, on C, the
collision kernel's distances against the NumPy reference and their gradients against finite
differences, and whether its verdicts agree with the distances.

Rows marked ``(large q)`` evaluate FK, J and H at revolute angles of up to :data:`LARGE_TURNS`
turns and next to large multiples of pi/2 (where an argument reduction for sin/cos is hardest).
Generated code adds joint angles before sin/cos (``sin(q1 + q2)``), which rounds, so their
tolerance grows with the angles: ``REF_TOL + 8 n max|q| 2^-53`` (see docs/guide/accuracy.md).
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np

from symkin.check.measure import relative_error as _rel
from symkin.check.tensor import F32_TOL, TENSOR_BACKENDS, NumpyView, available, missing_reason
from symkin.model.differential import rotate_rows
from symkin.model.tree import as_tree

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
    skipped: tuple[str, ...] = ()  # one line per optional backend whose library is not installed

    @property
    def ok(self) -> bool:
        return all(r.ok for r in self.rows)

    def as_dict(self) -> dict:
        return {
            "robot": self.robot,
            "samples": self.samples,
            "ok": self.ok,
            "rows": [{**r.__dict__, "ok": r.ok} for r in self.rows],
            "skipped": list(self.skipped),
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
            + (f"; (float32): {F32_TOL:g}" if any(r.ref_tol == F32_TOL for r in self.rows) else "")
        )
        lines += self.skipped
        lines.append("all ok" if self.ok else "FAILED")
        return "\n".join(lines)


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


def sample_configurations(robot: Any, n: int, seed: int = 0) -> np.ndarray:
    """Random configurations within limits, the named configurations and points 1e-5 away from them."""
    rng = np.random.default_rng(seed)
    named = np.array(list(robot.configs.values()))
    near = named + rng.normal(scale=1e-5, size=named.shape)
    return np.vstack((robot.random_q(n, seed=rng), named, near))


def large_angles(robot: Any, n: int, seed: int = 0) -> np.ndarray:
    """(2n, n_joints) configurations with large revolute angles: random ones moved by up to
    :data:`LARGE_TURNS` whole turns, and ones next to large multiples of pi/2 (the doubles nearest
    k pi/2 and their neighbours, k up to 4 LARGE_TURNS). Prismatic joints stay within limits."""
    rng = np.random.default_rng(seed)
    Q = np.vstack((robot.random_q(n, seed=rng), robot.random_q(n, seed=rng)))
    rev = robot.revolute
    turns = rng.integers(-LARGE_TURNS, LARGE_TURNS + 1, size=(n, robot.n))
    Q[:n] += np.where(rev, 2 * np.pi * turns, 0.0)
    k = rng.integers(-4 * LARGE_TURNS, 4 * LARGE_TURNS + 1, size=(n, robot.n))
    near = np.nextafter(k * (np.pi / 2), np.inf * rng.choice([-1, 1], size=k.shape))
    Q[n:] = np.where(rev, near, Q[n:])
    return Q


def check(
    model: Any,
    backends: Sequence[str] | Iterable[Any] = ("c", "numpy", "casadi"),
    samples: int = 20,
    seed: int = 0,
) -> CheckReport:
    """Compare every function of every backend (names, or compiled Kinematics objects) of ``model``
    (a Robot or a Tree) with the references (module docstring). "jax" and "torch" check FK, J and H
    (float64 and float32; :mod:`symkin.check.tensor`) and are skipped, with a line in the report's
    ``skipped``, where their library is not installed. ParameterError for a ``samples``
    that is not a count >= 1 or whose finite-difference Hessians would not fit in memory."""
    from symkin.core.sizes import count, room
    from symkin.runtime.load import compile as compile_model

    samples = count(samples, "samples")
    room(8.0 * 24 * model.n**3 * samples, f"checking {samples} configurations (finite-difference Hessians)")
    names = [b for b in backends if not isinstance(b, str) or available(b)]
    skipped = tuple(missing_reason(b) for b in backends if isinstance(b, str) and not available(b))
    kins = [_numpy_facing(b if not isinstance(b, str) else compile_model(model, backend=b)) for b in names]
    tree = as_tree(model)
    frames = tree.frames if len(tree.frames) > 1 else (None,)
    Q = sample_configurations(model, samples, seed)
    QL = large_angles(model, max(samples // 2, 1), seed + 1)
    gain = max((abs(float(s.multiplier)) for s in tree.slots), default=1.0)
    large_tol = REF_TOL + 8 * model.n * gain * float(np.abs(QL).max()) * 2.0**-53
    rows = _tree_reference_rows(tree, Q)
    for kin in kins:
        rows += _all_rows(kin, tree, Q)
        if kin.backend == "c":
            rows += _c_controller_rows(tree, kin, Q)
        if getattr(kin, "link_poses", None) is not None:
            rows.append(
                CheckRow(kin.backend, "link_poses", _rel(kin.link_poses(Q), tree.chain().link_poses(Q)), None)
            )
        for frame in frames:
            rows += _frame_rows(kin, model, Q, QL, large_tol, frame, seed)
        if kin.backend == "c" and model.geometry is not None and model.geometry.shapes:
            rows += _collision_rows(kin, Q)
    title = (
        model.name
        if frames == (None,)
        else f"{model.name} ({len(frames)} frames, each row the largest error over them)"
    )
    return CheckReport(title, len(Q), _merged(rows), skipped)


def _numpy_facing(kin: Any) -> Any:
    """``kin``, or a JAX/PyTorch kinematics as a :class:`symkin.check.tensor.NumpyView`."""
    return NumpyView(kin) if kin.backend in TENSOR_BACKENDS and not isinstance(kin, NumpyView) else kin


def _collision_rows(kin: Any, Q: np.ndarray) -> list[CheckRow]:
    """The compiled collision kernel against the NumPy reference (:mod:`symkin.geometry.reference`):
    signed distances (m, absolute), and their gradients against central differences of the
    kernel's own distances (pairs more than 1e-4 m apart: a gradient is unique there)."""
    from symkin.geometry import reference
    from symkin.model.geometry import Environment, Sphere

    env = Environment(spheres=(Sphere((0.3, 0.2, 0.4), 0.1), Sphere((-0.2, -0.3, 0.2), 0.05)))
    D, J = kin.distance_jacobians(Q, env)
    ref = float(np.abs(D - reference.distances(kin.model, Q, env)).max()) if D.size else 0.0
    verdicts = float(np.mean(kin.in_collision(Q, env) != (D < 0).any(axis=1)))
    fd_J = np.swapaxes(_fd(lambda x: kin.distances(x, env), Q, FD_STEP), 1, 2)  # (N, M, n)
    apart = D > 1e-4
    fd = float(np.abs(J - fd_J)[apart].max()) if apart.any() else 0.0
    return [
        CheckRow(kin.backend, "collision distances", ref, fd, REF_TOL),
        CheckRow(kin.backend, "collision verdicts", verdicts, None, 0.0),
    ]


def _merged(rows: list[CheckRow]) -> tuple[CheckRow, ...]:
    """One row per (backend, function), in first-seen order: the largest errors (a tree's frames)."""
    out: dict[tuple[str, str], CheckRow] = {}
    for r in rows:
        old = out.get((r.backend, r.function))
        if old is not None:
            fd = None if r.fd_error is None else max(r.fd_error, old.fd_error or 0.0)
            r = CheckRow(
                r.backend, r.function, max(r.ref_error, old.ref_error), fd, max(r.ref_tol, old.ref_tol)
            )
        out[(r.backend, r.function)] = r
    return tuple(out.values())


def _frame_rows(
    kin: Any, ref: Any, Q: np.ndarray, QL: np.ndarray, large_tol: float, frame: Any, seed: int
) -> list[CheckRow]:
    """Every function of one frame of ``kin`` against the reference ``ref`` and finite differences."""
    h, b = FD_STEP, kin.backend

    def at(name: str, obj: Any = kin) -> Any:
        """Method ``name`` of ``obj`` (the backend, or the reference) for this frame."""
        method = getattr(obj, name)
        return method if frame is None else partial(method, frame=frame)

    rows: list[CheckRow] = []
    T = at("fkine")(Q)
    J0, Je = at("jacob0")(Q), at("jacobe")(Q)
    rows.append(CheckRow(b, "fkine", _rel(T, at("fkine", ref)(Q)), None))
    fd_J0 = _fd_jacobians(at("fkine"), Q, T, h)  # Je the same in the end-effector frame
    rows.append(CheckRow(b, "jacob0", _rel(J0, at("jacob0", ref)(Q)), _rel(fd_J0, J0)))
    fd_Je = rotate_rows(T, fd_J0)
    rows.append(CheckRow(b, "jacobe", _rel(Je, at("jacobe", ref)(Q)), _rel(fd_Je, Je)))
    for name, jac in (("hessian0", at("jacob0")), ("hessiane", at("jacobe"))):
        H = at(name)(Q)
        rows.append(CheckRow(b, name, _rel(H, at(name, ref)(Q)), _rel(_fd(jac, Q, h), H)))
    T2, J2 = at("fkine_jacob0")(Q)
    rows.append(CheckRow(b, "fkine_jacob0", max(_rel(T2, T), _rel(J2, J0)), None))
    J3, H3 = at("jacob0_hessian0")(Q)
    rows.append(CheckRow(b, "jacob0_hessian0", max(_rel(J3, J0), _rel(H3, at("hessian0", ref)(Q))), None))
    # large angles: FK, J and H against the reference, tolerance from the angle-sum rounding
    for name in ("fkine", "jacob0", "hessian0"):
        err = _rel(at(name)(QL), at(name, ref)(QL))
        rows.append(CheckRow(b, f"{name} (large q)", err, None, large_tol))
    if b in TENSOR_BACKENDS:  # FK, J, H and what the other backends add on top of them: below
        return rows + _float32_rows(b, at, ref, Q)
    return rows + _rate_rows(b, at, ref, Q, seed)


def _float32_rows(b: str, at: Any, ref: Any, Q: np.ndarray) -> list[CheckRow]:
    """FK, J and H evaluated in float32 against the float64 reference at the same float32-rounded
    configurations (JAX and PyTorch, whose functions keep q's dtype), within :data:`F32_TOL`."""
    Q32 = Q.astype(np.float32).astype(float)
    errors = {
        name: _rel(at(name)(Q32, dtype="float32"), at(name, ref)(Q32))
        for name in ("fkine", "jacob0", "hessian0")
    }
    return [CheckRow(b, f"{name} (float32)", err, None, F32_TOL) for name, err in errors.items()]


def _rate_rows(b: str, at: Any, ref: Any, Q: np.ndarray, seed: int) -> list[CheckRow]:
    """J dot, the space and body Jacobians, the condition number, manipulability and its Jacobian
    of one frame (``at(name)`` its method) against the reference and finite differences."""
    h, rows = FD_STEP, []
    # dJ0/dt = sum_i H0[i] qd_i against d/dt J0(q + t qd) by central differences
    qd = np.random.default_rng(seed + 1).uniform(-1.0, 1.0, Q.shape)
    Jd = at("jacob0_dot")(Q, qd)
    fd_Jd = (at("jacob0")(Q + h * qd) - at("jacob0")(Q - h * qd)) / (2 * h)
    rows.append(CheckRow(b, "jacob0_dot", _rel(Jd, at("jacob0_dot", ref)(Q, qd)), _rel(fd_Jd, Jd)))
    rows += [CheckRow(b, name, _rel(at(name)(Q), at(name, ref)(Q)), None) for name in ("jacobs", "jacobb")]
    c_ref = at("cond", ref)(Q)
    fine = c_ref < 1e6  # the condition number itself is ill-conditioned near a singularity
    if fine.any():
        ratio = np.asarray(at("cond")(Q[fine])) / c_ref[fine]
        rows.append(CheckRow(b, "cond", _rel(ratio, np.ones_like(ratio)), None))
    # manipulability: compare m^2 (sqrt amplifies rounding at singularities); Jm where well conditioned
    for axes in ("all", "trans", "rot"):
        m = np.asarray(at("manipulability")(Q, axes=axes))
        rows.append(
            CheckRow(
                b, f"manipulability:{axes}", _rel(m**2, at("manipulability", ref)(Q, axes=axes) ** 2), None
            )
        )
        good = at("cond", ref)(Q, axes=axes) < 100
        if good.any():
            Qg = Q[good]
            Jm = at("jacobm")(Qg, axes=axes)
            fd_m = _fd(lambda x, a=axes: at("manipulability")(x, axes=a), Qg, h)
            rows.append(
                CheckRow(b, f"jacobm:{axes}", _rel(Jm, at("jacobm", ref)(Qg, axes=axes)), _rel(fd_m, Jm))
            )
    return rows


def _tree_reference_rows(tree: Any, Q: np.ndarray) -> list[CheckRow]:
    """The tree reference against the serial chain to each frame (no mimic joint on the path) and
    its ``jacob0_all`` against central differences of ``fkine_all``."""
    from symkin.errors import URDFError

    T_ref, J_ref = tree.fkine_jacob0_all(Q)
    rows: list[CheckRow] = []
    for f in tree.frames:
        try:
            robot = tree.chain(f)
        except URDFError:
            continue  # a mimic joint on the path: no chain Robot
        cols = sorted(tree.slots[k].joint for k in tree.path_slots(f))  # the chain's q
        k = tree.frame_position(f)
        err = max(
            _rel(T_ref[:, k], robot.fkine(Q[:, cols])), _rel(J_ref[:, k][..., cols], robot.jacob0(Q[:, cols]))
        )
        rows.append(CheckRow("ref", f"chain:{f}"[:40], err, None))
    rows.append(
        CheckRow("ref", "jacob0_all", 0.0, _rel(_fd_jacobians(tree.fkine_all, Q, T_ref, FD_STEP), J_ref))
    )
    return rows


def _fd_jacobians(fkine: Any, Q: np.ndarray, T: np.ndarray, h: float) -> np.ndarray:
    """Base-frame Jacobians (N, 6, n), or (N, F, 6, n) of every frame of ``fkine_all``, from central
    differences of the poses T (N, 4, 4) or (N, F, 4, 4): columns (dp/dq, vee(dR/dq R^T))."""
    return np.moveaxis(_vee_rate(*_shifted(fkine, Q, h), T[:, None], h), 1, -1)  # rate (N, n, [F,] 6)


def _all_rows(kin: Any, tree: Any, Q: np.ndarray) -> list[CheckRow]:
    """A tree's ``fkine_all``, ``jacob0_all`` and ``fkine_jacob0_all`` against the reference."""
    T_ref, J_ref = tree.fkine_jacob0_all(Q)
    T, J = kin.fkine_all(Q), kin.jacob0_all(Q)
    T2, J2 = kin.fkine_jacob0_all(Q)
    return [
        CheckRow(kin.backend, "fkine_all", _rel(T, T_ref), None),
        CheckRow(
            kin.backend, "jacob0_all", _rel(J, J_ref), _rel(_fd_jacobians(kin.fkine_all, Q, T, FD_STEP), J)
        ),
        CheckRow(kin.backend, "fkine_jacob0_all", max(_rel(T2, T_ref), _rel(J2, J_ref)), None),
    ]


def _c_controller_rows(tree: Any, kin: Any, Q: np.ndarray) -> list[CheckRow]:
    """The C functions the C controllers call (per frame without mimic joints on its path:
    ``jacob0_hessian0_<k>``, ``manipulability_<k>``) against the reference, through ctypes."""
    import ctypes

    P = ctypes.POINTER(ctypes.c_double)
    n, e_H, e_m, seen = tree.n, 0.0, 0.0, False
    for f in tree.frames:
        fns = kin.c_controller_functions(f)
        if fns is None:
            continue
        seen = True
        jh, manip = fns["jacob0_hessian0"], fns["manipulability"]
        jh.argtypes, jh.restype = [P, P, P], None
        manip.argtypes, manip.restype = [P, ctypes.c_int], ctypes.c_double
        H_ref = tree.hessian0(Q, f)
        for axes, code in (("all", 0), ("trans", 1), ("rot", 2)):
            m = [manip(np.ascontiguousarray(q).ctypes.data_as(P), code) for q in Q]
            e_m = max(e_m, _rel(np.array(m) ** 2, tree.manipulability(Q, f, axes) ** 2))  # as the rows above
        for i, q in enumerate(np.ascontiguousarray(Q)):
            J, H = np.zeros(6 * n), np.zeros(n * 6 * n)
            jh(q.ctypes.data_as(P), J.ctypes.data_as(P), H.ctypes.data_as(P))
            e_H = max(e_H, _rel(H.reshape(n, 6, n), H_ref[i]))
    if not seen:
        return []
    return [
        CheckRow("c", "C jacob0_hessian0_<k>", e_H, None),
        CheckRow("c", "C manipulability_<k>", e_m, None),
    ]
