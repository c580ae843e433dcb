"""Numerical inverse kinematics (Haviland and Corke, Manipulator Differential Kinematics, Part 1, 2023, eqs
37-51), NumPy reference solver.

The error e (eq 37) is the base-frame translation error and the angle-axis vector alpha of
``R_target R^T`` (eqs 38-40); E = 1/2 e^T We e (eq 44). Steps:

- ``NR`` (eq 45): q += J^-1 e (``pinv``: pinv(We^1/2 J) We^1/2 e, the same for a square J);
- ``GN`` (eqs 46-47): q += (J^T We J)^-1 J^T We e (``pinv``: pinv of J^T We J);
- ``LM`` (eqs 48-51): q += (J^T We J + Wn)^-1 J^T We e with Wn = lam (``wampler``),
  lam E_k (``chan``, eq 50) or E_k + lam (``sugihara``, eq 51; lam is w_n);
- ``QP``: q += qd, qd the solution of a quadratic program with the joint limits as velocity
  dampers and a slack on the error (Haviland and Corke, Manipulator Differential Kinematics,
  Part 2, 2023): :mod:`symkin.runtime.ik_qp`.

Global search: a search runs at most ``ilimit`` iterations (one iteration evaluates the pose and,
unless it converged, takes a step); ``slimit`` searches start from q0, then ``starts[s]``, then
random configurations within the joint limits. A converged q has its revolute joints wrapped by
multiples of 2 pi into the limits; if it is still outside them it is rejected and the next search
starts. Iterations of failed searches count.

Convergence (``tol``): by default ``|e|_We = sqrt(e^T We e) < tol``, so with We = I and tol = 1e-6
the position is within 1 um and the orientation within 1 urad. The paper's criterion
``E < tol`` (``tol_on="E"``, Table 1) only bounds |e| by sqrt(2 tol): 1.4e-3 for tol = 1e-6.

Default: LM with Chan's damping, lam = 0.1, the fastest of Table 1 and the only damping that
keeps quadratic convergence near a solution (lam E_k -> 0). Constant damping (Wampler, Sugihara's
w_n) converges linearly where the solution is near a singularity: under ``|e| < 1e-6`` with
100 x 30 it failed 1.6% (Wampler 1e-4) to 7% (Sugihara 1e-3) of reachable UR5 targets, against
0% for Chan (``symkin.bench.ik``).

The C solver (:mod:`symkin.runtime.ik_c`) runs the same loop with the same random restarts
(splitmix64 streams), so the two agree iterate for iterate.
"""

from __future__ import annotations

import functools
import math
import weakref
from collections.abc import Sequence
from typing import Any, Literal

import numpy as np

from symkin.core.arrays import as_config, as_rows, name_of
from symkin.core.pose import POSE_ATOL  # noqa: F401 - re-exported
from symkin.errors import ParameterError, PoseError
from symkin.runtime.ik_problem import (  # noqa: F401 - re-exported
    DAMPINGS,
    M64,
    MAX_ITERATIONS,
    METHODS,
    PINV_RCOND,
    QP_RHO_I,
    QP_RHO_S,
    TWO_PI,
    Damping,
    IKOptions,
    IKResult,
    Method,
    SplitMix64,
    angle_axis,
    check_pose,
    ets_of,
    failure_reason,
    pose_error,
    pose_error_of,
    revolute_mask,
    sample_range,
    seed_of,
    shift_into,
    stacked,
)
from symkin.runtime.memo import per_object
from symkin.runtime.task import task_kinematics

__all__ = [
    "IKResult",
    "IKOptions",
    "ik",
    "ik_trace",
    "angle_axis",
    "pose_error",
    "check_pose",
    "revolute_mask",
    "SplitMix64",
]


# -- the solver -------------------------------------------------------------------------------
def wrap_into_limits(q: np.ndarray, opt: IKOptions) -> np.ndarray:
    """q with each revolute joint outside its limits moved by the multiple of 2 pi that brings it
    inside, if there is one (same as the C code)."""
    q = q.copy()
    lo, hi = opt.qlim
    for j in np.flatnonzero(opt.revolute):
        q[j] = shift_into(float(q[j]), lo[j], hi[j])
    return q


def _step(opt: IKOptions, J: np.ndarray, e: np.ndarray, r2: float) -> np.ndarray:
    """dq of eqs 45-51; raises LinAlgError when the system is singular."""
    we = opt.we
    if opt.method == "NR":
        if opt.pinv:
            s = np.sqrt(we)
            return np.linalg.pinv(s[:, None] * J, rcond=PINV_RCOND) @ (s * e)
        return np.linalg.solve(J, e)
    A = J.T @ (we[:, None] * J)
    g = J.T @ (we * e)
    if opt.method == "GN":
        return np.linalg.pinv(A, rcond=PINV_RCOND) @ g if opt.pinv else np.linalg.solve(A, g)
    E = 0.5 * r2
    wn = {"wampler": opt.lam, "chan": opt.lam * E, "sugihara": E + opt.lam}[opt.damping]
    return np.linalg.solve(A + np.diag(wn), g)


def _fkjac(kin: Any, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(kin.fkine(q), dtype=float), np.asarray(kin.jacob0(q), dtype=float)


def _stepper(kin: Any, opt: IKOptions) -> Any:
    """``step(q, J, e, r2) -> dq`` of ``opt.method``: eqs 45-51, or the QP's
    (:func:`symkin.runtime.ik_qp.qp_step`); raises LinAlgError when there is no step."""
    if opt.method == "QP":
        from symkin.runtime.ik_qp import qp_step

        return lambda q, J, e, r2: qp_step(kin, opt, q, J, e)
    return lambda q, J, e, r2: _step(opt, J, e, r2)


def _solve_one(kin: Any, opt: IKOptions, Tep: np.ndarray, q0: np.ndarray | None, rng: SplitMix64) -> tuple:
    """One target: (q, success, iterations, searches, residual, reason)."""
    step = _stepper(kin, opt)
    lo, hi = opt.qlim
    best, best_q = math.inf, None
    iterations = limit_rejects = singular = 0
    q = np.zeros(opt.n)
    for s in range(opt.slimit):
        if s == 0 and q0 is not None:
            q = q0.copy()
        elif s < len(opt.starts):
            q = opt.starts[s].copy()
        else:
            q = rng.random_q(opt.sample)
        for i in range(opt.ilimit):
            T, J = _fkjac(kin, q)
            e = pose_error_of(T, Tep)
            iterations += 1
            r2 = float(opt.we @ (e * e))
            res = math.sqrt(r2) if r2 >= 0 else math.nan
            if not res < math.inf:
                singular += 1
                break
            if res < best:
                best, best_q = res, q.copy()
            if (0.5 * r2 < opt.tol) if opt.tol_on == "E" else (res < opt.tol):
                q = wrap_into_limits(q, opt)
                if not opt.joint_limits or bool(((q >= lo) & (q <= hi)).all()):
                    return q, True, iterations, s + 1, res, "success"
                limit_rejects += 1
                break
            if i + 1 == opt.ilimit:
                break
            try:
                with np.errstate(all="ignore"):
                    q = q + step(q, J, e, r2)
            except np.linalg.LinAlgError:
                singular += 1
                break
    q = wrap_into_limits(best_q if best_q is not None else q, opt)
    reason = failure_reason(False, best, limit_rejects, singular, opt.ilimit, opt.slimit)
    return q, False, iterations, opt.slimit, best, reason


def ik(
    kin: Any,
    Tep: Any,
    method: Method = "LM",
    damping: Damping = "chan",
    lam: float | Sequence[float] | None = None,
    pinv: bool = False,
    ilimit: int = 30,
    slimit: int = 100,
    tol: float = 1e-6,
    q0: Any = None,
    seed: int | None = None,
    joint_limits: bool = True,
    we: Sequence[float] | None = None,
    tol_on: Literal["e", "E"] = "e",
    starts: Any = None,
    backend: Literal["numpy", "c"] = "numpy",
    frame: Any = None,
    slack_gain: float = 1.0,
    manipulability: float = 0.0,
    xi: float = 1.0,
    rho_i: float | Sequence[float] = QP_RHO_I,
    rho_s: float | Sequence[float] = QP_RHO_S,
) -> IKResult:
    """Numerical IK: joint values q with ``kin.fkine(q)`` = ``Tep`` (eqs 37-51).

    Args:
        kin: kinematics with ``n``, ``qlim`` (2, n), ``fkine(q)`` (4, 4) and ``jacob0(q)`` (6, n)
            (a :class:`symkin.Robot` or a compiled backend); ``revolute`` or ``ets`` tells which
            joints wrap by 2 pi.
        Tep: target pose(s) 0T_e*, (4, 4) or (N, 4, 4); invalid SE(3) raises PoseError.
        method: the step, ``"NR"``, ``"GN"``, ``"LM"`` (module docstring) or ``"QP"`` (a quadratic
            program with joint-limit dampers and a slack: :mod:`symkin.runtime.ik_qp`).
        damping: LM's damping, ``"wampler"``, ``"chan"`` or ``"sugihara"`` (module docstring).
        lam: the damping constant (module docstring), a scalar or (n,), default 0.1; for QP the
            joint-velocity weight lambda_q, one number, default 0.01.
        pinv: NR and GN steps through the pseudo-inverse (module docstring).
        ilimit: iterations per search.
        slimit: searches.
        tol: converged when ``|e|_We < tol`` (``tol_on="e"``) or ``E < tol`` (``tol_on="E"``, the paper's).
        tol_on: ``"e"`` or ``"E"``, see ``tol``.
        q0: first start, (n,) or (N, n) for N targets; then ``starts`` (S, n) for searches 1..S-1
            (search 0 too when q0 is None), then random restarts drawn from ``seed``.
        joint_limits: reject solutions outside ``kin.qlim`` (after wrapping revolute joints).
        we: the diagonal of We (6,), default ones (eq 44).
        backend: ``"numpy"`` (this module) or ``"c"`` (:class:`symkin.runtime.ik_c.CIKSolver`).
        frame: the frame whose pose is the task: a tree's frame name (:class:`symkin.Tree` or
            its compiled kinematics) or link frame k of a chain; the joints off its path are free
            (they keep their start values).
        slack_gain: method="QP": the slack's gain lambda_delta (:mod:`symkin.runtime.ik_qp`).
        manipulability: method="QP": the manipulability term's weight (0: none).
        xi: method="QP": the joint-limit velocity dampers' gain.
        rho_i: method="QP": their influence distance (rad or m), a scalar or (n,).
        rho_s: method="QP": their stop distance (rad or m), a scalar or (n,).

    Returns:
        IKResult; unreachable targets give ``success=False`` and a ``reason``.
    """
    kin = task_kinematics(kin, frame)  # a chain itself, or one frame of a model
    args = (method, damping, lam, pinv, ilimit, slimit, tol, tol_on, joint_limits, we, starts, slack_gain,
            manipulability, xi, rho_i, rho_s)  # fmt: skip
    if backend == "c":
        return _c_solver(kin, args).solve(Tep, q0, seed)
    opt = _options(kin, *args)
    if backend != "numpy":
        raise ParameterError(f"backend must be 'numpy' or 'c', not {backend!r}")
    T, single = check_pose(Tep)
    Q0 = None if q0 is None else as_rows(q0, opt.n, len(T), single, name_of(kin), "q0")  # the rule of q
    seed = seed_of(seed)
    out = [
        _solve_one(kin, opt, T[i], None if Q0 is None else Q0[i], SplitMix64(seed, i)) for i in range(len(T))
    ]
    return IKResult(*out[0]) if single else stacked(out, opt.n)  # no targets: empty arrays, like the C solver


_OPTIONS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_C_SOLVERS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _c_solver(kin: Any, args: tuple) -> Any:
    """The C solver for ``ik(kin, ..., backend="c")``, memoised per kinematics object and the
    arguments' values (arrays by their contents: see :func:`_value_key`), so a repeated call skips
    validating them (validation costs far more than a C solve of one target)."""
    try:  # the arguments as given: found without making their key
        return _C_SOLVERS[kin][args]
    except (KeyError, TypeError):
        from symkin.runtime.ik_c import solver_for

        return _memo(_C_SOLVERS, kin, args, lambda: solver_for(kin, _options(kin, *args)))


def _memo(table: weakref.WeakKeyDictionary, kin: Any, args: tuple, make: Any) -> Any:
    """``make()`` memoised in ``table`` per kinematics object and the arguments' values; made afresh
    when an argument is unhashable or ``kin`` takes no weak reference."""
    try:
        key = _value_key(args)
    except TypeError:
        return make()
    return per_object(table, kin, key, make)


def _value_key(value: Any) -> Any:
    """``value`` as a hashable key equal for equal values: an array becomes its shape, dtype and
    bytes (so a changed array is a new key), a list or tuple the tuple of its items' keys; other
    values stay as they are (TypeError when one is unhashable or an array is large)."""
    if isinstance(value, np.ndarray):
        if value.size > 65536 or value.dtype.hasobject:
            raise TypeError("no key for this array")
        return ("ndarray", value.shape, value.dtype.str, value.tobytes())
    if isinstance(value, (list, tuple)):
        return tuple(_value_key(v) for v in value)
    hash(value)
    return value


def _options(kin: Any, *args: Any) -> IKOptions:
    """IKOptions.of, memoised per kinematics object and the arguments' values (validation costs
    tens of microseconds, more than a C solve)."""
    return _memo(_OPTIONS, kin, args, lambda: IKOptions.of(kin, *args))


def ik_trace(kin: Any, Tep: Any, q0: Any, steps: int, **options: Any) -> np.ndarray:
    """The iterates q_0 .. q_steps of one search from q0, not stopping at convergence:
    (k + 1, n), fewer rows if a step fails. For checking solvers against each other."""
    from symkin.core.sizes import count, room

    steps = count(steps, "steps", minimum=0)
    opt = IKOptions.of(kin, **options)
    room(8.0 * (steps + 1) * opt.n, f"a trace of {steps} IK steps")
    T, single = check_pose(Tep)
    if not single:
        raise PoseError("ik_trace takes one target pose (4, 4)")
    q = as_config(q0, opt.n, name_of(kin), "q0").copy()  # the rule of q, as the C solver's trace
    step = _stepper(kin, opt)
    out = [q.copy()]
    for _ in range(steps):
        Te, J = _fkjac(kin, q)
        e = pose_error_of(Te, T[0])
        r2 = float(opt.we @ (e * e))
        if not math.isfinite(r2):
            break
        try:
            with np.errstate(all="ignore"):
                q = q + step(q, J, e, r2)
        except np.linalg.LinAlgError:
            break
        out.append(q.copy())
    return np.array(out)


IK_OPTIONS = ("method", "damping", "lam", "pinv", "ilimit", "slimit", "tol", "tol_on", "joint_limits", "we",
              "starts", "slack_gain", "manipulability", "xi", "rho_i", "rho_s")  # fmt: skip
"""The options of :func:`ik` that make a solver (``q0`` and ``seed`` vary per call)."""


def c_solver_with(kin: Any, options: dict[str, Any]) -> Any:
    """The C solver of ``ik(kin, Tep, backend="c", **options)`` (``options``: names of
    :data:`IK_OPTIONS`, the others at their defaults), memoised like any other."""
    defaults = _ik_defaults()
    return _c_solver(kin, tuple(options[k] if k in options else defaults[k] for k in IK_OPTIONS))


def default_c_solver(kin: Any) -> Any:
    """The C solver of ``ik(kin, Tep, backend="c")`` with every other option at its default."""
    return c_solver_with(kin, {})


@functools.cache
def _ik_defaults() -> dict[str, Any]:
    import inspect

    return {k: p.default for k, p in inspect.signature(ik).parameters.items()}
