"""Joint-axis geometry at q = 0 and which closed-form inverse kinematics it allows.

Any model (ETS text, DH, URDF, PoE) is an ETS; walking it at q = 0 with exact constants gives the
product-of-exponentials form ``T(q) = exp([S_1] q_1) ... exp([S_n] q_n) M`` (Lynch and Park,
Modern Robotics, 2017, eq 4.14): per joint, in chain order, a unit axis ``h_k`` and a point ``p_k``
on it (base frame), and the pose ``M`` at q = 0. As in IK-Geo (Elias and Wen, IK-Geo: Unified
robot inverse kinematics using subproblem decomposition, Mechanism and Machine Theory, 2025) the
position of the end effector is then ``p_0T = p_1 + R_1 (p_12 + R_2 (p_23 + ...))`` with
``p_{k,k+1} = p_{k+1} - p_k`` and ``R_k = rot(h_k, q_k)``, which the subproblems solve.

Which axes are parallel or intersect is decided on exact values (sympy, tested at 40 digits) after
snapping floating-point constants: a rotation constant within :data:`SNAP_TOL` rad of a multiple
of pi/2 becomes that multiple, a translation within :data:`SNAP_TOL` m of 0 becomes 0, so a DH
table written with ``1.5707963267948966`` is recognised as ``pi/2``. The closed form solves the
snapped model; it differs from the model as written by at most about ``SNAP_TOL`` times the reach.

Runs of constants that the kinematics fold (:func:`symkin.symbolic.fold.fold_constants`: two or
more rotations by angles other than multiples of pi/2, such as fixed joints with rpy offsets, or
long runs) are folded here too, into one transform whose inexact entries are
:data:`IK_DIGITS`-digit Floats (exact where the product is exact): walked exactly, the cos/sin of
their angles multiply out into expressions that grow with every rotation and that the
derivation's expansions cannot finish. At 50 digits the exact tests (40 digits, zero below
1e-25) decide as they would on the exact product.
"""

from __future__ import annotations

import math
import random
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from fractions import Fraction

import mpmath
import sympy as sp

from symkin.errors import NoAnalyticIKError
from symkin.model.ets import ET, ETS, Const
from symkin.symbolic.cse import _postorder
from symkin.symbolic.fold import Fixed, _mp, fold_constants
from symkin.symbolic.kinematics import const_to_sympy

__all__ = [
    "SNAP_TOL",
    "IK_DIGITS",
    "NoAnalyticIKError",
    "Geometry",
    "Structure",
    "fold_ik",
    "fixed_matrix",
    "value_at",
    "random_point",
    "is_constant",
    "same_value",
    "geometry",
    "classify",
    "snap",
    "reverse",
]

SNAP_TOL = 1e-10  # rad or m: floating-point constants this close to k*pi/2 or to 0 are snapped
_ZERO = sp.Float("1e-25", 40)  # |x| below this (40-digit evaluation of an exact value) counts as 0
IK_DIGITS = 50  # significant digits of the inexact entries of a folded run of constants
_PROBE_DIGITS = 60  # working precision of value_at
_PROBE_TOL = mpmath.mpf("1e-30")  # relative: two probes closer than this are the same value

Vec = tuple[sp.Expr, sp.Expr, sp.Expr]


def snap(ets: ETS) -> ETS:
    """``ets`` with floating-point constants within SNAP_TOL of k*pi/2 (rotations) or 0 (translations)
    replaced by the exact value."""
    out = []
    for e in ets:
        if e.const is not None and e.const.atan2 is None:
            v = e.const.value
            if e.axis.is_rotation:
                k = round(v / (math.pi / 2))
                exact = Const(Fraction(0), Fraction(k, 2))
                if abs(v - exact.value) < SNAP_TOL and e.const != exact:
                    e = ET(e.axis, const=exact)
            elif abs(v) < SNAP_TOL and not e.const.is_zero:
                e = ET(e.axis, const=Const())
        out.append(e)
    return ETS(tuple(out))


@dataclass(frozen=True)
class Geometry:
    """Exact joint geometry at q = 0, in chain order (``joint[k]`` is the joint index of the k-th).

    ``h[k]`` unit axis (the sign of a flipped joint folded in), ``p[k]`` a point on the axis (the
    joint's frame origin), ``revolute[k]``, ``M`` the end-effector pose at q = 0 (4x4).
    """

    joint: tuple[int, ...]
    revolute: tuple[bool, ...]
    h: tuple[Vec, ...]
    p: tuple[Vec, ...]
    M: sp.Matrix

    @property
    def n(self) -> int:
        return len(self.joint)


def _rot(axis: int, angle: sp.Expr) -> sp.Matrix:
    c, s = sp.cos(angle), sp.sin(angle)
    if axis == 0:
        return sp.Matrix([[1, 0, 0], [0, c, -s], [0, s, c]])
    if axis == 1:
        return sp.Matrix([[c, 0, s], [0, 1, 0], [-s, 0, c]])
    return sp.Matrix([[c, -s, 0], [s, c, 0], [0, 0, 1]])


def fold_ik(ets: ETS) -> tuple[ET | Fixed, ...]:
    """``ets`` with the runs of constants that the kinematics fold folded into one :class:`Fixed`
    each, its inexact entries to :data:`IK_DIGITS` digits (module docstring)."""
    return fold_constants(ets, digits=IK_DIGITS)


def fixed_matrix(f: Fixed) -> sp.Matrix:
    """The 4x4 matrix of a folded run (Rationals where exact, else :data:`IK_DIGITS`-digit Floats)."""
    cols, t = f.exprs
    return _pose(sp.Matrix(cols).T, t)


def _pose(R: sp.Matrix, t: Iterable[sp.Expr]) -> sp.Matrix:
    """The 4x4 pose of rotation ``R`` and translation ``t``."""
    M = sp.eye(4)
    M[:3, :3], M[:3, 3] = R, sp.Matrix(list(t))
    return M


def _number(x: sp.Expr) -> sp.Expr:
    """``x`` as one number: itself when a Rational or Float, else evaluated to IK_DIGITS digits."""
    return x if x.is_Rational or x.is_Float else sp.Float(sp.N(x, IK_DIGITS), IK_DIGITS)


def geometry(ets: ETS | Iterable[ET | Fixed]) -> Geometry:
    """Walk ``ets`` at q = 0 with exact constants (snap it first for floating-point data; fold it
    with :func:`fold_ik` for runs of rotations). After a folded run the pose holds Floats: the
    rotations that follow are evaluated to IK_DIGITS digits too, so no entry grows."""
    R = sp.eye(3)
    t = sp.zeros(3, 1)
    joint, rev, hs, ps = [], [], [], []
    inexact = False
    for e in ets:
        if isinstance(e, Fixed):
            F = fixed_matrix(e)
            t, R = t + R * F[:3, 3], R * F[:3, :3]
            inexact = inexact or F.has(sp.Float)
            if inexact:
                t, R = t.applyfunc(_number), R.applyfunc(_number)
            continue
        i = e.axis.index
        if e.is_joint:
            joint.append(int(e.joint))  # type: ignore[arg-type]
            rev.append(e.axis.is_rotation)
            hs.append(tuple(R[:, i] * e.sign))
            ps.append(tuple(t))
            continue
        value = const_to_sympy(e.const)  # type: ignore[arg-type]
        if e.axis.is_rotation:
            if value == 0:
                continue
            if inexact:
                R = (R * _rot(i, value)).applyfunc(_number)
            else:
                R = sp.simplify(R * _rot(i, value))
        else:
            t = t + R[:, i] * value
            if inexact:
                t = t.applyfunc(_number)
    return Geometry(tuple(joint), tuple(rev), tuple(hs), tuple(ps), _pose(R, t))


def reverse(g: Geometry) -> Geometry:
    """The chain read from the tool: ``T(q)^{-1} = M^{-1} e^{-[S_n] q_n} ... e^{-[S_1] q_1}
    = e^{[S'_n] q_n} ... e^{[S'_1] q_1} M'`` with ``S' = -Ad_{M^{-1}} S`` (Lynch and Park, Modern
    Robotics, 2017, eq 3.83): axes ``h' = -R_M^T h`` through ``p' = R_M^T (p - t_M)``, ``M' = M^{-1}``,
    the joints in reverse order with the same variables. A spherical shoulder becomes a spherical wrist."""
    RM = g.M[:3, :3]
    tM = g.M[:3, 3]
    hs = tuple(tuple(-(RM.T * sp.Matrix(h))) for h in reversed(g.h))
    ps = tuple(tuple(sp.simplify(x) for x in RM.T * (sp.Matrix(p) - tM)) for p in reversed(g.p))
    return Geometry(
        tuple(reversed(g.joint)),
        tuple(reversed(g.revolute)),
        hs,  # type: ignore[arg-type]
        ps,  # type: ignore[arg-type]
        _pose(RM.T, -RM.T * tM).applyfunc(sp.simplify),
    )


# -- exact tests ------------------------------------------------------------------------------
def is_zero(x: sp.Expr) -> bool:
    """True when the exact value ``x`` is 0 (evaluated to 40 digits)."""
    return bool(abs(sp.N(x, 40)) < _ZERO)


def value_at(x: sp.Expr, point: Mapping[sp.Basic, Fraction | float | mpmath.mpf]) -> mpmath.mpf:
    """``x`` at ``point`` (a number for each of its free symbols), to 60 digits; each distinct
    subexpression is evaluated once (bottom-up, no recursion), so this costs the size of ``x`` as a
    graph, not as a tree, and no expansion."""
    memo: dict[sp.Basic, mpmath.mpf] = {}
    with mpmath.workdps(_PROBE_DIGITS):
        for e in _postorder([x]):
            if e.is_Symbol:
                v = _mp(point[e])
            elif e.is_Rational:
                v = mpmath.mpf(int(e.p)) / int(e.q)
            elif e.is_Float:
                v = mpmath.mpf(e)
            elif e.is_Add:
                v = mpmath.fsum(memo[a] for a in e.args)
            elif e.is_Mul:
                v = mpmath.fprod(memo[a] for a in e.args)
            elif e.is_Pow:
                v = memo[e.args[0]] ** memo[e.args[1]]
            elif not e.args:  # pi, E
                v = mpmath.mpf(sp.N(e, _PROBE_DIGITS))
            else:  # cos(3/10), atan2(..): evaluated by sympy from its arguments' values
                args = (sp.Float(memo[a], _PROBE_DIGITS) for a in e.args)
                v = mpmath.mpf(sp.N(e.func(*args), _PROBE_DIGITS))
            memo[e] = v
        return +memo[x]


def random_point(symbols: Iterable[sp.Basic], seed: int) -> dict[sp.Basic, Fraction]:
    """A reproducible random value in [-2, 2] for each symbol (by name)."""
    rng = random.Random(seed)
    return {s: Fraction(rng.randint(-(2**40), 2**40), 2**39) for s in sorted(symbols, key=str)}


def same_value(a: mpmath.mpf, b: mpmath.mpf, sign: int = 1) -> bool:
    """Whether ``a = sign * b`` to within 1e-30 (relative), for values of :func:`value_at` (at their
    precision: mpmath's default would round them to doubles)."""
    with mpmath.workdps(_PROBE_DIGITS):
        return bool(abs(a - sign * b) <= _PROBE_TOL * (1 + max(abs(a), abs(b))))


def is_constant(x: sp.Expr) -> bool | None:
    """Whether ``x``, a polynomial-like expression in its free symbols taken as independent
    variables, is constant: the same value at two random points (a non-constant one agrees at
    random points with probability 0). Costs two evaluations, not an expansion. None when ``x``
    cannot be evaluated there (a division by 0)."""
    syms = x.free_symbols
    if not syms:
        return True
    try:
        return same_value(value_at(x, random_point(syms, 1)), value_at(x, random_point(syms, 2)))
    except (ArithmeticError, ValueError):
        return None


def vzero(v: Vec) -> bool:
    return all(is_zero(x) for x in v)


def sub(a: Vec, b: Vec) -> Vec:
    return (a[0] - b[0], a[1] - b[1], a[2] - b[2])


def add(a: Vec, b: Vec) -> Vec:
    return (a[0] + b[0], a[1] + b[1], a[2] + b[2])


def scale(k: sp.Expr, a: Vec) -> Vec:
    return (k * a[0], k * a[1], k * a[2])


def dot(a: Vec, b: Vec) -> sp.Expr:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def cross(a: Vec, b: Vec) -> Vec:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def parallel(a: Vec, b: Vec) -> bool:
    return vzero(cross(a, b))


def intersection(h1: Vec, p1: Vec, h2: Vec, p2: Vec) -> Vec | None:
    """The common point of two non-parallel lines, or None when they are skew or parallel."""
    n = cross(h1, h2)
    if vzero(n) or not is_zero(dot(sub(p2, p1), n)):
        return None
    s = sp.simplify(dot(cross(sub(p2, p1), h2), n) / dot(n, n))
    return tuple(sp.simplify(p1[i] + s * h1[i]) for i in range(3))  # type: ignore[return-value]


def on_line(x: Vec, h: Vec, p: Vec) -> bool:
    return vzero(cross(sub(x, p), h))


# -- classification ---------------------------------------------------------------------------
@dataclass(frozen=True)
class Structure:
    """What closed form applies: ``kind`` and the facts the derivation uses.

    kinds: ``"spherical_wrist"`` (6 joints, axes 4-6 meet at ``wrist``; ``position`` says how the
    first three place it), ``"three_parallel"`` (6R, axes 2-4 parallel, axes 5-6 meet at
    ``wrist``), ``"position3"`` (3 joints placing the tool point; orientation checked),
    ``"planar3"`` (3R, all axes parallel), ``"planar2"`` (2R, parallel axes).
    ``position`` (for spherical_wrist and position3): ``"parallel23"`` (axes 2, 3 parallel),
    ``"intersect12"`` (axes 1, 2 meet at ``shoulder``; joint 3 may be prismatic) or
    ``"intersect23"`` (axes 2, 3 meet at ``elbow``). ``reversed``: the structure is that of the
    chain read from the tool (:func:`reverse`; e.g. a spherical shoulder), and the axes, points and
    numbers above refer to the reversed chain.
    """

    kind: str
    position: str = ""
    wrist: Vec | None = None
    shoulder: Vec | None = None
    elbow: Vec | None = None
    summary: str = ""
    reversed: bool = False


def _position(g: Geometry, k0: int) -> tuple[str, Vec | None, Vec | None] | None:
    """How joints k0..k0+2 place a point: (position kind, shoulder, elbow) or None."""
    h, p, rev = g.h[k0 : k0 + 3], g.p[k0 : k0 + 3], g.revolute[k0 : k0 + 3]
    if all(rev) and parallel(h[1], h[2]) and not parallel(h[0], h[1]):
        return "parallel23", None, None
    if rev[0] and rev[1]:
        o = intersection(h[0], p[0], h[1], p[1])
        if o is not None:
            return "intersect12", o, None
    if all(rev):
        o = intersection(h[1], p[1], h[2], p[2])
        if o is not None and not on_line(o, h[0], p[0]):
            return "intersect23", None, o
    return None


_NUMERIC_HINT = "use the numerical IK instead: kin.ik(T) (method='LM')"


def classify(g: Geometry) -> Structure:
    """The closed form that applies to ``g``, or NoAnalyticIKError naming what the arm lacks."""
    n = g.n
    if n == 6:
        h, p, rev = g.h, g.p, g.revolute
        if all(rev[3:]):
            w = intersection(h[3], p[3], h[4], p[4])
            if w is not None and on_line(w, h[5], p[5]) and not parallel(h[4], h[5]):
                pos = _position(g, 0)
                if pos is None:
                    raise NoAnalyticIKError(
                        "the arm has a spherical wrist (axes 4, 5, 6 meet in one point) but its first "
                        "three joints have neither two parallel axes (2 and 3) nor two intersecting axes "
                        "(1 and 2, or 2 and 3): the general Pieper case (a quartic) is not derived; "
                        + _NUMERIC_HINT
                    )
                return Structure("spherical_wrist", pos[0], w, pos[1], pos[2], "spherical wrist")
        if all(rev) and parallel(h[1], h[2]) and parallel(h[2], h[3]) and not parallel(h[0], h[1]):
            w = intersection(h[4], p[4], h[5], p[5])
            if w is not None and not parallel(h[4], h[1]):
                return Structure("three_parallel", wrist=w, summary="three parallel axes")
            raise NoAnalyticIKError(
                "axes 2, 3, 4 are parallel but axes 5 and 6 do not intersect (or axis 5 is parallel "
                "to them): no closed form derived; " + _NUMERIC_HINT
            )
        raise NoAnalyticIKError(
            "this 6-joint arm has neither a spherical wrist (axes 4, 5, 6 meeting in one point) nor "
            "three parallel axes (2, 3, 4) with intersecting axes 5 and 6, so symkin derives no closed "
            "form; " + _NUMERIC_HINT
        )
    if n == 3:
        if all(g.revolute) and parallel(g.h[0], g.h[1]) and parallel(g.h[1], g.h[2]):
            return Structure("planar3", summary="planar 3R arm")
        pos = _position(g, 0)
        if pos is not None:
            return Structure("position3", pos[0], None, pos[1], pos[2], "3-joint positioning arm")
        raise NoAnalyticIKError(
            "this 3-joint arm has neither all axes parallel (planar) nor two parallel axes (2 and 3) "
            "nor two intersecting axes: no closed form derived; " + _NUMERIC_HINT
        )
    if n == 2:
        if all(g.revolute) and parallel(g.h[0], g.h[1]):
            return Structure("planar2", summary="planar 2R arm")
        raise NoAnalyticIKError(
            "only 2-joint arms with two parallel revolute axes (planar) are solved; " + _NUMERIC_HINT
        )
    if n == 7:
        raise NoAnalyticIKError(
            "a 7-joint arm is redundant: it has infinitely many solutions per pose and no finite closed "
            "form; " + _NUMERIC_HINT
        )
    raise NoAnalyticIKError(
        f"closed forms are derived for arms with 2, 3 or 6 joints, not {n}; " + _NUMERIC_HINT
    )
