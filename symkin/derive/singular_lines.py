"""Random lines through joint space: rank drops of J that no listed singular factor explains.

The other half of the check of :func:`symkin.derive.singularities.singularities` (which shows that
every factor's zeros are singular): every singular family of codimension 1 is the zero set of a
listed factor. A line ``q(s) = q_0 + s d`` through joint space in a random direction crosses a
hypersurface (a family given by one equation in q) at isolated points, where the smallest singular
value of J, ``sigma_min(s)``, has a V-shaped minimum that reaches 0; it meets a set of codimension 2
or more with probability 0. So ``sigma_min`` is sampled along each line (the numeric Jacobian, the
O(n) reference of eqs 31-34 of Haviland and Corke, Manipulator Differential Kinematics, Part 1,
2023, independent of sympy), every local minimum is refined by golden-section search, and each
minimum below :data:`SINGULAR_TOL` must be a zero of a listed factor: ``|f(q)|`` at most
:data:`FACTOR_TOL` times the largest ``|f|`` along the line, for some factor f.

Revolute joints range over [-pi, pi] (a singular family outside the joint limits counts too, as in
the factor check), prismatic ones over their limits, or [-2, 2] m where they are unbounded.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp

from symkin.core.progress import bar
from symkin.model.robot import Robot

__all__ = ["LineCheck", "line_check", "SINGULAR_TOL", "FACTOR_TOL", "LINES", "SAMPLES", "MAX_LINES"]

#: The smallest singular value of J counts as 0 below this (at a crossing it is ~1e-16).
SINGULAR_TOL = 1e-9
#: A factor vanishes at a rank drop when |f| there is at most this times its largest |f| on the line.
FACTOR_TOL = 1e-7
#: Lines and samples per line of :func:`symkin.derive.singularities.singularities`' check.
LINES = 12
SAMPLES = 400
#: The most lines one check samples (400 Jacobians each).
MAX_LINES = 100_000
_CHUNK = 64  # lines sampled at once (64 x 400 Jacobians, 8.6 MB for 7 joints)
_GOLDEN_STEPS = 70  # bracket shrinks by 0.618 per step: 2 samples' width to ~1e-16 of it
_REACH = 2.0  # s in [-REACH, REACH]; d has the joint ranges' half-widths as its scale


@dataclass(frozen=True, eq=False)
class LineCheck:
    """Rank drops of J found along random lines, and those no factor explains.

    Attributes:
        lines, samples: how many lines, and samples of sigma_min on each.
        drops: (k, n) configurations where sigma_min has a local minimum below SINGULAR_TOL.
        unexplained: (u, n) those of ``drops`` at which no factor vanishes.
        sigma: (k,) sigma_min at ``drops``.
    """

    lines: int
    samples: int
    drops: np.ndarray
    unexplained: np.ndarray
    sigma: np.ndarray

    @property
    def ok(self) -> bool:
        """Every rank drop found is a zero of a listed factor."""
        return len(self.unexplained) == 0


def line_check(
    robot: Robot,
    rows: Sequence[int],
    q: Sequence[sp.Symbol],
    factors: Sequence[sp.Expr],
    lines: int = LINES,
    samples: int = SAMPLES,
    seed: int | np.random.Generator = 0,
) -> LineCheck:
    """sigma_min of the rows ``rows`` of the base-frame J along ``lines`` random lines, and whether each
    rank drop is a zero of one of ``factors`` (expressions in ``q``); see the module docstring."""
    rng = np.random.default_rng(seed)
    n = robot.n
    lo, hi = _box(robot)
    rows = list(rows)

    def sigma(Q: np.ndarray) -> np.ndarray:  # (..., n) -> (...)
        flat = Q.reshape(-1, n)
        s = np.linalg.svd(robot.jacob0(flat)[:, rows, :], compute_uv=False)[:, -1]
        return s.reshape(Q.shape[:-1])

    f = sp.lambdify(q, list(factors), "numpy") if factors else None
    s = np.linspace(-_REACH, _REACH, samples)
    Q0 = rng.uniform(lo, hi, size=(lines, n))
    U = rng.standard_normal((lines, n))
    D = 0.5 * (hi - lo) * U / np.linalg.norm(U, axis=1, keepdims=True)
    drops, sig, unexplained = [], [], []
    for start in bar(range(0, lines, _CHUNK), desc="lines", unit="chunk"):
        q0, d = Q0[start : start + _CHUNK], D[start : start + _CHUNK]
        along = sigma(q0[:, None, :] + s[None, :, None] * d[:, None, :])  # (lines, samples)
        mid = along[:, 1:-1]
        line, k = np.nonzero((mid < along[:, :-2]) & (mid <= along[:, 2:]))  # local minima
        q0, d = q0[line], d[line]  # one row per minimum
        best = _golden(lambda x, q0=q0, d=d: sigma(q0 + x[:, None] * d), s[k], s[k + 2])
        Qs = q0 + best[:, None] * d
        sb = sigma(Qs)
        for i in np.flatnonzero(sb < SINGULAR_TOL):
            drops.append(Qs[i])
            sig.append(float(sb[i]))
            scale = _factor_scale(f, q0[i] + s[:, None] * d[i], len(factors))
            if not _explained(f, Qs[i], scale):
                unexplained.append(Qs[i])
    return LineCheck(
        lines, samples, np.array(drops).reshape(-1, n), np.array(unexplained).reshape(-1, n), np.array(sig)
    )


def _box(robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """The sampled joint ranges: revolute [-pi, pi], prismatic their limits or [-2, 2] m."""
    lo, hi = (np.array(x, dtype=float) for x in robot.qlim)
    rev = np.array(robot.revolute, dtype=bool)
    lo = np.where(rev, -math.pi, np.where(np.isfinite(lo), lo, -2.0))
    hi = np.where(rev, math.pi, np.where(np.isfinite(hi), hi, 2.0))
    return lo, hi


def _golden(g, a: np.ndarray, b: np.ndarray) -> np.ndarray:  # noqa: ANN001
    """The minimisers of g on the brackets [a, b] (one per bracket, evaluated together)."""
    r = (math.sqrt(5) - 1) / 2
    a, b = a.copy(), b.copy()
    for _ in range(_GOLDEN_STEPS):
        x1, x2 = b - r * (b - a), a + r * (b - a)
        left = g(x1) < g(x2)
        b = np.where(left, x2, b)
        a = np.where(left, a, x1)
    return 0.5 * (a + b)


def _values(f, Q: np.ndarray, count: int) -> np.ndarray:  # noqa: ANN001
    """(count, N) values of the factors at configurations Q (N, n)."""
    out = f(*Q.T)
    return np.array([np.broadcast_to(np.asarray(v, dtype=float), (len(Q),)) for v in out]).reshape(count, -1)


def _factor_scale(f, Q: np.ndarray, count: int) -> np.ndarray:  # noqa: ANN001
    """The largest |f| along the line, per factor (1 where a factor is 0 throughout)."""
    if f is None:
        return np.zeros(0)
    m = np.abs(_values(f, Q, count)).max(axis=1)
    return np.where(m > 0, m, 1.0)


def _explained(f, qk: np.ndarray, scale: np.ndarray) -> bool:  # noqa: ANN001
    if f is None:
        return False
    v = np.abs(_values(f, qk[None], len(scale)))[:, 0]
    return bool((v <= FACTOR_TOL * scale).any())
