"""Batched, differentiable numerical IK in JAX or PyTorch: many targets x many starts at once.

Every target of ``Tep`` (..., 4, 4) runs ``slimit`` searches side by side (the first from ``q0``,
then ``starts``, then random configurations within the joint limits, seeded), each at most
``ilimit`` iterations of the step of :func:`symkin.runtime.ik.ik` (Haviland and Corke,
Manipulator Differential Kinematics, Part 1, 2023, eqs 37-51): LM with Chan's, Wampler's or
Sugihara's damping, Gauss-Newton or Newton-Raphson, with the weights ``we`` and the options of the
C solver. A search stops moving once ``|e|_We < tol`` (or ``E < tol``); the loop ends when every
search has. A converged q has its revolute joints wrapped by multiples of 2 pi into the limits and,
with ``joint_limits``, counts only if it is then within them. Each target takes its first
successful search, else the one with the lowest residual.

The searches run without gradients; the result is then made differentiable with respect to the
targets by the implicit function theorem: at a solution e(q, T) = 0, so dq = pinv(We^1/2 J) We^1/2
de, which the returned q carries (its value is the search's, unchanged). ``jax.grad`` and
``torch.autograd`` through ``ik(...).q`` therefore give the sensitivity of the solution to the
target (the minimum-norm one for a redundant arm).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np

from symkin.errors import ParameterError, PoseError
from symkin.runtime.diff.ops import Ops
from symkin.runtime.diff.pose import pose_error

__all__ = ["DiffIKResult", "solve", "DEFAULT_SLIMIT"]

DEFAULT_SLIMIT = 10  # searches per target, side by side (the C solver's 100 run one after another)
_TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class DiffIKResult:
    """The outcome of :func:`solve` for targets (...): arrays of the targets' batch shape.

    Attributes:
        q: (..., n) the solution (on failure the search with the lowest residual), differentiable
            with respect to the targets.
        success: (...) converged to ``tol`` within the joint limits.
        residual: (...) ``|e|_We`` at q.
        iterations: (...) iterations of the search taken (until it converged, or ``ilimit``).
        search: (...) index of the search taken (0: from ``q0``).
    """

    q: Any
    success: Any
    residual: Any
    iterations: Any
    search: Any


@dataclass(frozen=True)
class _Plan:
    """The validated options that shape the computation (hashable: the JAX solver is compiled per plan)."""

    method: str
    damping: str
    pinv: bool
    ilimit: int
    slimit: int
    tol: float
    tol_on: str
    joint_limits: bool
    frame: Any


def _step(ops: Ops, plan: _Plan, lam: Any, we: Any, J: Any, e: Any, r2: Any, done: Any) -> Any:
    """dq of eqs 45-51 for every search (converged ones solve an identity system, unused)."""
    xp = ops.xp
    n = J.shape[-1]
    if plan.method == "NR" and plan.pinv:
        s = xp.sqrt(we)
        return (ops.pinv(s[:, None] * J) @ (s * e)[..., None])[..., 0]
    if plan.method == "NR":
        eye6 = ops.const(np.eye(6), J)
        return ops.solve(xp.where(done[..., None, None], eye6, J), e)
    Jt = xp.swapaxes(J, -1, -2)
    A = Jt @ (we[:, None] * J)
    g = (Jt @ (we * e)[..., None])[..., 0]
    eye = ops.const(np.eye(n), J)
    if plan.method == "GN" and plan.pinv:
        return (ops.pinv(A) @ g[..., None])[..., 0]
    if plan.method == "LM":
        E = 0.5 * r2
        wn = {
            "wampler": lam + 0.0 * E[..., None],
            "chan": lam * E[..., None],
            "sugihara": E[..., None] + lam,
        }[plan.damping]
        A = A + wn[..., None] * eye
    return ops.solve(xp.where(done[..., None, None], eye, A), g)


def _residual(ops: Ops, we: Any, e: Any) -> tuple[Any, Any]:
    r2 = (we * e * e).sum(-1)
    return r2, ops.xp.sqrt(r2)


def _converged(plan: _Plan, r2: Any, res: Any) -> Any:
    return (0.5 * r2 < plan.tol) if plan.tol_on == "E" else (res < plan.tol)


def _wrap(ops: Ops, q: Any, lo: Any, hi: Any, revolute: Any) -> Any:
    """Revolute joints moved by the multiple of 2 pi that brings them into [lo, hi], where one does."""
    xp = ops.xp
    up = q + _TWO_PI * xp.ceil((lo - q) / _TWO_PI)
    down = q - _TWO_PI * xp.ceil((q - hi) / _TWO_PI)
    y = xp.where(q < lo, up, xp.where(q > hi, down, q))
    ok = revolute & (y >= lo) & (y <= hi)
    return xp.where(ok, y, q)


def _search(ops: Ops, fkjac: Any, plan: _Plan, Tep: Any, Q: Any, lam: Any, we: Any) -> tuple:
    """Every search's loop: (Q, residual, converged, iterations), each (B, S...)."""
    xp = ops.xp
    Tb = Tep[:, None]

    def evaluate(Q: Any) -> tuple:
        T, J = fkjac(Q)
        e = pose_error(ops, T, Tb)
        r2, res = _residual(ops, we, e)
        return J, e, r2, res

    def done_of(state: Any) -> Any:
        return state[2] | state[4]

    def body(state: Any) -> Any:
        Q, it, done, _, dead = state
        J, e, r2, res = evaluate(Q)
        done = done | (_converged(plan, r2, res) & ~dead)
        dead = dead | ~xp.isfinite(res)
        moving = ~(done | dead)
        dq = _step(ops, plan, lam, we, J, e, r2, ~moving)
        bad = ~xp.isfinite(dq).all(-1)
        dead = dead | (moving & bad)
        moving = moving & ~bad
        Q = xp.where(moving[..., None], Q + xp.where(moving[..., None], dq, 0.0), Q)
        return Q, it + xp.where(moving, 1.0, 0.0), done, res, dead

    zeros = xp.zeros_like(Q[..., 0])  # the iteration counts, as floats (exact)
    false = zeros != 0.0
    state = (Q, zeros, false, zeros, false)
    Q, it, done, _, dead = ops.loop(plan.ilimit, done_of, body, state)
    J, e, r2, res = evaluate(Q)  # the last iterate's residual (the loop's last step moved it)
    done = done | (_converged(plan, r2, res) & ~dead)
    return Q, res, done, it


def _core(ops: Ops, fkjac: Any, plan: _Plan, Tep: Any, Q0: Any, lam: Any, we: Any, lo: Any, hi: Any,
          revolute: Any) -> tuple:  # fmt: skip
    """The searches of targets Tep (B, 4, 4) from Q0 (B, S, n) and the pick per target:
    (q (B, n), success, residual, iterations, search), all without gradients."""
    xp = ops.xp
    Q, res, done, it = _search(ops, fkjac, plan, Tep, Q0, lam, we)
    Q = xp.where(done[..., None], _wrap(ops, Q, lo, hi, revolute), Q)
    inside = ((lo <= Q) & (hi >= Q)).all(-1) if plan.joint_limits else done
    success = done & inside
    S = Q.shape[1]
    index = ops.const(np.arange(S) - S, res)  # successes first, by search order
    key = xp.where(success, index, xp.where(xp.isfinite(res), res, math.inf))
    pick = xp.argmin(key, -1)[:, None]
    take = partial(ops.take, index=pick, axis=1)
    q = ops.take(Q, pick[..., None], 1)[:, 0]
    return q, take(success)[:, 0], take(res)[:, 0], take(it)[:, 0], pick[:, 0]


def _implicit(ops: Ops, fkjac: Any, q: Any, Tep: Any, we: Any) -> Any:
    """q whose derivative with respect to Tep is pinv(We^1/2 J) We^1/2 de/dTep (its value q's)."""
    T, J = fkjac(ops.detach(q))
    T, J = ops.detach(T), ops.detach(J)
    s = ops.xp.sqrt(we)
    dq = (ops.pinv(s[:, None] * J) @ (s * pose_error(ops, T, Tep))[..., None])[..., 0]
    return q + (dq - ops.detach(dq))


def plan_of(kin: Any, options: dict[str, Any]) -> tuple[_Plan, Any, int]:
    """The validated options (:class:`symkin.runtime.ik_problem.IKOptions`: the NumPy and C
    solvers' checks) as a :class:`_Plan`, the IKOptions themselves and the seed of the random
    starts (not in the plan: the JAX solver compiled for a plan serves every seed)."""
    from symkin.runtime.ik_problem import IKOptions

    frame = options.pop("frame", None)
    seed = options.pop("seed", None)
    slimit = options.setdefault("slimit", DEFAULT_SLIMIT)
    opt = IKOptions.of(kin, **options)
    if opt.method == "QP":
        raise ParameterError("the JAX and PyTorch IK take method 'LM', 'GN' or 'NR', not 'QP'")
    if len(opt.starts) > slimit:
        raise ParameterError(f"{len(opt.starts)} starts given for slimit={slimit} searches per target")
    seed = int(np.random.SeedSequence().entropy % 2**63) if seed is None else int(seed)
    plan = _Plan(opt.method, opt.damping, opt.pinv, opt.ilimit, opt.slimit, opt.tol, opt.tol_on,
                 opt.joint_limits, frame)  # fmt: skip
    return plan, opt, seed


def solve(kin: Any, Tep: Any, q0: Any = None, **options: Any) -> DiffIKResult:
    """Targets ``Tep`` (..., 4, 4) -> :class:`DiffIKResult` (see the module docstring); ``q0`` (n,)
    or (..., n): the first start of every target; ``options``: those of :func:`symkin.ik` (``slimit``
    searches per target, default :data:`DEFAULT_SLIMIT`), ``seed`` for the random starts and
    ``frame``."""
    ops = kin.ops
    plan, opt, seed = plan_of(kin, dict(options))
    if not ops.is_array(Tep) or not ops.floating(Tep) or Tep.ndim < 2 or tuple(Tep.shape[-2:]) != (4, 4):
        raise PoseError(
            f"{kin.name}: Tep must be a {kin.backend} array (..., 4, 4) of float32 or float64, "
            f"got {type(Tep).__name__} {tuple(getattr(Tep, 'shape', ()))}"
        )
    batch = tuple(Tep.shape[:-2])
    Tb = Tep.reshape((-1, 4, 4))
    B, S, n = Tb.shape[0], plan.slimit, kin.n
    c = partial(ops.const, like=Tb[..., 0, 0])
    lo, hi = c(opt.qlim[0]), c(opt.qlim[1])
    sample_lo, sample_hi = c(opt.sample[0]), c(opt.sample[1])
    Q = ops.uniform(seed, (B, S, n), sample_lo, sample_hi)
    first = 0
    if q0 is not None:
        q0 = ops.cast(kin.check_q(q0), Tb)
        Q = ops.xp.concatenate((ops.xp.broadcast_to(q0.reshape((-1, 1, n)), (B, 1, n)), Q[:, 1:]), 1)
        first = 1
    if len(opt.starts):
        k = min(len(opt.starts), S - first)
        given = ops.xp.broadcast_to(c(opt.starts[:k])[None], (B, k, n))
        Q = ops.xp.concatenate((Q[:, :first], given, Q[:, first + k :]), 1)
    fkjac = partial(kin.fkine_jacob0, frame=plan.frame)
    lam, we = c(opt.lam), c(opt.we)
    revolute = ops.const(opt.revolute, Tb) > 0.5
    args = (ops.detach(Tb), ops.detach(Q), lam, we, lo, hi, revolute)
    if ops.name == "jax":
        q, success, res, it, pick = kin.jitted_ik(plan, fkjac)(*args)
    else:
        with ops.xp.no_grad():
            q, success, res, it, pick = _core(ops, fkjac, plan, *args)
    q = _implicit(ops, fkjac, q, Tb, we)
    return DiffIKResult(
        q.reshape(batch + (n,)),
        success.reshape(batch),
        res.reshape(batch),
        ops.cast(it, None).reshape(batch),
        pick.reshape(batch),
    )


def jax_core(ops: Ops, plan: _Plan, fkjac: Any) -> Any:
    """:func:`_core` compiled by ``jax.jit`` for one plan (the caller memoises it)."""
    return ops.jax.jit(partial(_core, ops, fkjac, plan))  # type: ignore[attr-defined]
