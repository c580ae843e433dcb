"""Singular configurations of a chain as factors of the Jacobian's determinant (sympy).

J (6 x n, rows (v, omega)) loses rank exactly where all its maximal minors vanish: the
determinant of a square J, the ``C(n, 6)`` 6 x 6 column minors of a redundant one (Cauchy-Binet:
``det(J J^T)`` is the sum of their squares) or the ``C(6, n)`` row minors of a short one
(``det(J^T J)``). Their common factors are the singular configurations of codimension 1 (one
equation in q).

Keeping sympy fast: the rank of J, hence its minors' common factors up to a constant, does not
change when J is written in another frame, ``blkdiag(R, R) J``, or for another reference point p,
``[[I, -[p - p_e]x], [0, I]] J`` (both have determinant 1, at every configuration, even when R and
p depend on q). So J is built, from the ETS, in the link frame and for the point (a joint's origin
on its axis, or the end effector) that give the shortest entries: a middle frame and the wrist
centre (Corke, Robotics, Vision and Control, 3rd ed., 2023, sec 8.1.4 on singularities; Siciliano
et al., Robotics: Modelling, Planning and Control, 2009, sec 3.3, for the decoupling at the wrist
centre). With ``axes="trans"`` only rotations are used (the translational rows depend on the point).

Factoring: each entry is a polynomial in ``s_j = sin q_j``, ``c_j = cos q_j`` (and the lengths of
prismatic joints); each maximal minor is computed exactly over those polynomials, reduced with
``s_j^2 = 1 - c_j^2``, and split into its prime divisors by the tangent half-angle substitution
``t_j = tan(q_j / 2)``, where factorisation is unique (:mod:`symkin.symbolic.half_angle`). The
factors common to all minors are the primes of every minor, each with its least multiplicity (a
greatest common divisor modulo ``sin^2 + cos^2 = 1``, not the intersection of the minors' factor
sets: one minor may carry ``sin q_3``, another ``(cos q_3 - 1)(cos q_3 + 1)``), written back in
sines and cosines of joint angles and their sums (of half angles when a root is at ``q_j = 0`` or
``q_j = pi`` only).
"""

from __future__ import annotations

import itertools
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import sympy as sp
from sympy.polys.matrices import DomainMatrix

from symkin.errors import SymkinError, check_choice
from symkin.model.robot import Robot
from symkin.symbolic.cse import count_ops, tree_size
from symkin.symbolic.half_angle import HalfAngle, Piece
from symkin.symbolic.kinematics import _walk, const_to_sympy, joint_symbols
from symkin.symbolic.program import _jacobian_column

__all__ = ["SingularFactor", "SingularFactors", "singular_factors", "AXES", "MAX_TERMS"]

AXES = ("auto", "all", "trans", "rot")
#: A minor whose reduced determinant has more terms than this is not factored (reported as such).
MAX_TERMS = 20000
#: Largest trig expression handed to ``trigsimp`` to write products as sums of angles.
_TRIGSIMP_MAX_OPS = 400
_ROWS = {"all": range(6), "trans": range(3), "rot": range(3, 6)}


@dataclass(frozen=True, eq=False)
class SingularFactor:
    """One factor f(q) of the minors: J loses rank where f(q) = 0.

    Attributes:
        expr: f in the joint symbols q0 .. q{n-1} (sines and cosines, sums of angles merged; of half
            angles, ``sin(q_j / 2)``, when f has a root at q_j = 0 or pi alone).
        multiplicity: its power in the determinant (the least power over the minors).
        joints: the joint indices f depends on.
        kind: ``"sin"`` (f = sin q_j: q_j = 0 or pi), ``"cos"`` (f = cos q_j: q_j = +-pi/2),
            ``"half-sin"`` (f = sin(q_j / 2): q_j = 0), ``"half-cos"`` (f = cos(q_j / 2): q_j = pi) or
            ``"general"``.
        sc: f as a polynomial in s_j, c_j (sympy's sparse polynomial), None for a half-angle f.
    """

    expr: sp.Expr
    multiplicity: int
    joints: tuple[int, ...]
    kind: str
    sc: object = None


@dataclass(frozen=True, eq=False)
class SingularFactors:
    """The factored determinant of a robot's Jacobian (see the module docstring).

    Attributes:
        name: the robot's name; q: the joint symbols.
        axes: the rows of J used (``"all"``, ``"trans"`` or ``"rot"``); rows: their indices.
        method: ``"det(J)"``, ``"det(J J^T)"`` or ``"det(J^T J)"``.
        frame: where J was written: ``(ETS position, point)``, the frame before that factor of the
            ETS and the reference point's name (``"joint 4"``: the origin of joint 4's frame).
        jacobian: the m x n Jacobian used (rows ``rows``), in that frame, for that point.
        determinant: ``constant * prod(f.expr ** f.multiplicity)`` for a square J, else None.
        factors: the common factors of all maximal minors, in joint order.
        minors: the number of nonzero maximal minors; unfactored: how many were too large to
            factor (then ``factors`` holds the common factors of the others only).
        axis_exprs: per joint (base frame), (revolute, axis direction, a point on the axis), the
            expressions the geometric description of a factor evaluates.
        seconds: the time the analysis took.
    """

    name: str
    q: tuple[sp.Symbol, ...]
    axes: str
    rows: tuple[int, ...]
    method: str
    frame: tuple[int, str]
    jacobian: sp.Matrix
    determinant: sp.Expr | None
    factors: tuple[SingularFactor, ...]
    minors: int
    unfactored: int
    axis_exprs: tuple[tuple[bool, tuple[sp.Expr, ...], tuple[sp.Expr, ...]], ...]
    seconds: float

    @property
    def full_rank(self) -> int:
        """The rank of J (its rows used) away from the singular configurations: min(m, n)."""
        return min(len(self.rows), len(self.q))


def singular_factors(robot: Robot | str, axes: str = "auto", max_terms: int = MAX_TERMS) -> SingularFactors:
    """Factor the determinant (or the maximal minors) of ``robot``'s Jacobian; see the module docstring.

    ``axes``: ``"all"`` (the 6 x n J), ``"trans"`` (the 3 x n translational rows), ``"rot"``, or
    ``"auto"``: ``"trans"`` when the base-frame J has more nonzero rows than joints and exactly n
    nonzero translational rows (a planar 2R arm: the 2 x 2 position Jacobian), else ``"all"``.
    Rows identically zero (a planar arm's v_z, omega_x, omega_y) are left out first.
    """
    from symkin.model.resolve import resolve_robot

    started = time.perf_counter()
    robot = resolve_robot(robot)
    check_choice(axes, AXES, "axes")
    n = robot.n
    if n == 0:
        raise SymkinError(f"robot {robot.name!r} has no joints: no Jacobian to factor")
    axes, rows = _choose_rows(robot, axes)
    m = len(rows)
    if m == 0:
        raise SymkinError(f"{robot.name}: the {axes} rows of the Jacobian are all zero")
    qs = joint_symbols(n)
    pos, point, J = _shortest_jacobian(robot, qs, axes, rows)
    s = [sp.Symbol(f"s{j}") for j in range(n)]
    c = [sp.Symbol(f"c{j}") for j in range(n)]
    to_sc = {}
    for j, q in enumerate(qs):
        to_sc[sp.sin(q)], to_sc[sp.cos(q)] = s[j], c[j]
    entries = [sp.expand(sp.expand_trig(x).xreplace(to_sc)) for x in J]
    prismatic = [q for q in qs if any(x.has(q) for x in entries)]  # what still holds q: a joint's length
    _, info = sp.parallel_poly_from_expr(entries, *s, *c, *prismatic)
    dom = info.domain.get_field()[tuple(s + c + prismatic)]  # polynomials over QQ (or an algebraic field)
    D = DomainMatrix([[dom.from_sympy(entries[r * n + k]) for k in range(n)] for r in range(m)], (m, n), dom)
    if m <= n:
        subsets = [(tuple(range(m)), cols) for cols in itertools.combinations(range(n), m)]
    else:
        subsets = [(rs, tuple(range(n))) for rs in itertools.combinations(range(m), n)]
    H = HalfAngle.of(n, dom)
    dets = [d for d in (H.reduce(D.extract(list(rs), list(cs)).det()) for rs, cs in subsets) if d]
    minors = len(dets)
    usable = sorted((d for d in dets if len(d.terms()) <= max_terms), key=lambda d: len(d.terms()))
    unfactored = minors - len(usable)
    common, sources = H.common(usable) if usable else ({}, {})  # the shortest minor is factored
    lengths = tuple(prismatic)
    factors = tuple(
        sorted(
            (_factor_of(H, piece, power, s, c, qs, lengths) for piece, power in H.group(common, sources)),
            key=lambda f: (f.kind == "general", f.joints, sp.default_sort_key(f.expr)),
        )
    )
    determinant = None
    if m == n and minors == 1 and not unfactored and all(f.sc is not None for f in factors):
        constant = H.scale(dets[0], {f.sc: f.multiplicity for f in factors})
        determinant = dom.domain.to_sympy(constant) * sp.Mul(*[f.expr**f.multiplicity for f in factors])
    method = "det(J)" if m == n else ("det(J J^T)" if m < n else "det(J^T J)")
    return SingularFactors(
        robot.name,
        qs,
        axes,
        tuple(rows),
        method,
        (pos, point),
        J,
        determinant,
        factors,
        minors,
        unfactored,
        _axis_exprs(robot, qs),
        time.perf_counter() - started,
    )


def _choose_rows(robot: Robot, axes: str) -> tuple[str, list[int]]:
    """The axes and the rows of the base-frame J that are not identically zero (at 4 random q)."""
    J = np.abs(robot.jacob0(robot.random_q(4, seed=11))).max(axis=(0, 2))  # (6,)
    nonzero = [r for r in range(6) if J[r] > 1e-12]
    if axes == "auto":
        trans = [r for r in nonzero if r < 3]
        axes = "trans" if len(nonzero) > robot.n and len(trans) == robot.n else "all"
    return axes, [r for r in nonzero if r in _ROWS[axes]]


def _shortest_jacobian(
    robot: Robot, qs: Sequence[sp.Symbol], axes: str, rows: Sequence[int]
) -> tuple[int, str, sp.Matrix]:
    """The rows ``rows`` of J written in the frame at each ETS position next to a joint, for each
    reference point allowed (every joint's origin and the end effector for ``"all"``, the end
    effector otherwise), the one with the fewest nodes: (position, point name, J)."""
    elements = tuple(robot.ets)
    n = robot.n
    positions = sorted(
        {0, len(elements)} | {k + d for k, e in enumerate(elements) if e.is_joint for d in (0, 1)}
    )
    best: tuple[int, int, str, sp.Matrix] | None = None
    sizes: dict[sp.Basic, int] = {}
    for pos in positions:
        _, before = _walk(reversed(elements[:pos]), qs, const_to_sympy, -1)
        pose, after = _walk(elements[pos:], qs, const_to_sympy, 1)
        frames = {f[0]: f for f in before + after}
        points = [("end effector", list(pose.p))]
        if axes == "all":
            points += [(f"joint {j + 1}", frames[j][3]) for j in range(n) if frames[j][1]]
        for name, p in points:
            J = sp.zeros(len(rows), n)
            for j, (_, revolute, w, o) in frames.items():
                v, omega = _jacobian_column(pose.P, revolute, w, o, p)
                col = [*v, *omega]
                for i, r in enumerate(rows):
                    J[i, j] = col[r]
            ops = tree_size(list(J), sizes)
            if best is None or ops < best[0]:
                best = (ops, pos, name, J)
    assert best is not None
    return best[1], best[2], best[3]


def _factor_of(H: HalfAngle, piece: Piece, power: int, s, c, qs, lengths) -> SingularFactor:  # noqa: ANN001
    """A group of primes as a factor in the joint symbols: sines and cosines of the joint angles (and
    their sums, merged by ``trigsimp`` when that is shorter) when it has even degree in every t_j,
    else sines and cosines of half angles."""
    n = H.n
    if H.odd(piece):
        expr = H.to_expr(piece, qs, lengths)
        joints = tuple(j for j in range(n) if expr.has(qs[j]))
        half = {sp.sin(qs[j] / 2): "half-sin" for j in joints}
        half |= {sp.cos(qs[j] / 2): "half-cos" for j in joints}
        return SingularFactor(expr, power, joints, half.get(expr, "general"), None)
    p = H.to_sc(piece)
    p = p.primitive()[1]
    if p.LC < 0:
        p = -p
    expr = H.dom.to_sympy(p)
    joints = tuple(j for j in range(n) if expr.has(s[j]) or expr.has(c[j]) or expr.has(qs[j]))
    if expr in s:
        return SingularFactor(sp.sin(qs[s.index(expr)]), power, joints, "sin", p)
    if expr in c:
        return SingularFactor(sp.cos(qs[c.index(expr)]), power, joints, "cos", p)
    trig = expr.xreplace(
        {**{s[j]: sp.sin(qs[j]) for j in range(n)}, **{c[j]: sp.cos(qs[j]) for j in range(n)}}
    )
    if count_ops(trig).total <= _TRIGSIMP_MAX_OPS:
        short = sp.trigsimp(trig)
        if count_ops(short).total < count_ops(trig).total:
            trig = short
    return SingularFactor(sp.gcd_terms(trig), power, joints, "general", p)


def _axis_exprs(robot: Robot, qs: Sequence[sp.Symbol]) -> tuple:
    """Per joint (by index): (revolute, axis direction, a point on the axis), base frame."""
    _, frames = _walk(tuple(robot.ets), qs, const_to_sympy, 1)
    out = {f[0]: (f[1], tuple(f[2]), tuple(f[3])) for f in frames}
    return tuple(out[j] for j in range(robot.n))
