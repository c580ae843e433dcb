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

Factoring: each entry is a polynomial in ``s_j = sin q_j``, ``c_j = cos q_j``; the determinant is
computed exactly over those polynomials and reduced with ``s_j^2 = 1 - c_j^2``. In that ring a
factor ``sin q_j`` is found by the test ``N(s_j = 0, c_j = +-1) = 0`` (and divided out), a factor
``cos q_j`` by polynomial division; what remains is factored over the rationals and each factor
written back in sines and cosines of joint angles and their sums.
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
        expr: f in the joint symbols q0 .. q{n-1} (sines and cosines, sums of angles merged).
        multiplicity: its power in the determinant (the least power over the minors).
        joints: the joint indices f depends on.
        kind: ``"sin"`` (f = sin q_j), ``"cos"`` (f = cos q_j) or ``"general"``.
    """

    expr: sp.Expr
    multiplicity: int
    joints: tuple[int, ...]
    kind: str


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
    common: dict | None = None
    constant = sp.Integer(1)
    minors = unfactored = 0
    for rs, cs in subsets:
        M = D.extract(list(rs), list(cs))
        det = _reduce(M.det(), n, dom)
        if not det:
            continue
        minors += 1
        if len(det.terms()) > max_terms:
            unfactored += 1
            continue
        coeff, found = _factor(det, n, dom)
        constant = coeff
        common = found if common is None else {k: min(v, found[k]) for k, v in common.items() if k in found}
    factors = tuple(
        sorted(
            (_factor_of(p, mult, n, s, c, qs, dom) for p, mult in (common or {}).items()),
            key=lambda f: (f.kind == "general", f.joints, sp.default_sort_key(f.expr)),
        )
    )
    determinant = None
    if m == n and minors == 1 and not unfactored:
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


def _reduce(p, n: int, dom):  # noqa: ANN001, ANN202
    """p with every s_j^2 replaced by 1 - c_j^2 (degree <= 1 in each s_j)."""
    gens = dom.ring.gens
    out = dom.zero
    for monom, coeff in p.terms():
        term = dom.ring.ground_new(coeff)
        for i, e in enumerate(monom):
            if not e:
                continue
            if i < n:
                term *= gens[i] ** (e % 2) * (1 - gens[i + n] ** 2) ** (e // 2)
            else:
                term *= gens[i] ** e
        out += term
    return out


def _at(p, i: int, value: int):  # noqa: ANN001, ANN202
    """p with generator i set to 0, 1 or -1."""
    ring = p.ring
    out = {}
    for monom, coeff in p.terms():
        e = monom[i]
        if value == 0 and e:
            continue
        coeff = coeff * value**e if e else coeff
        key = monom[:i] + (0,) + monom[i + 1 :]
        out[key] = out.get(key, ring.domain.zero) + coeff
    return ring.from_dict({k: v for k, v in out.items() if v})


def _factor(det, n: int, dom) -> tuple[object, dict]:  # noqa: ANN001
    """(constant, {factor: multiplicity}) of a determinant: its rational factors, each reduced
    (s_j^2 = 1 - c_j^2), then sin q_j and cos q_j factors taken out modulo s_j^2 + c_j^2 = 1, then
    the rest factored again (each factor primitive with a positive leading coefficient)."""
    gens = dom.ring.gens
    found: dict = {}
    coeff, raw = det.factor_list()
    for g, gmult in raw:
        p = _reduce(g, n, dom)
        for j in range(n):
            s, c = gens[j], gens[j + n]
            while p and not _at(_at(p, j, 0), j + n, 1) and not _at(_at(p, j, 0), j + n, -1):
                b0 = _at(p, j, 0)  # p = b0 + s b1 with b0 = (1 - c^2) r, so p = s (b1 + s r)
                b1 = (p - b0).exquo(s)
                p = b1 + s * b0.exquo(1 - c**2)
                found[s] = found.get(s, 0) + gmult
            while p and not _at(p, j + n, 0):
                p = p.exquo(c)
                found[c] = found.get(c, 0) + gmult
        k, rest = p.factor_list()
        coeff *= k**gmult
        for f, mult in rest:
            k, split = _split(f, n, dom)
            coeff *= k ** (mult * gmult)
            for h, hmult in split:
                if h.LC < 0:
                    h, coeff = -h, coeff * (-1) ** (hmult * mult * gmult)
                found[h] = found.get(h, 0) + hmult * mult * gmult
    return coeff, found


def _split(p, n: int, dom) -> tuple[object, list[tuple[object, int]]]:  # noqa: ANN001
    """The factors of a reduced polynomial p in s_j, c_j modulo s_j^2 + c_j^2 = 1, found by the
    tangent half-angle substitution ``c = (1 - t^2) / (1 + t^2)``, ``s = 2 t / (1 + t^2)`` (no
    relation among the t_j: a unique factorisation), and written back in s_j, c_j:
    ``t^a / (1 + t^2)^(e/2)`` is ``sin^a(q/2) cos^(e-a)(q/2)``, a product of ``(1 - c)/2``,
    ``(1 + c)/2`` and ``s/2``. Factors of odd degree in some t_j are grouped (with the roots at
    q_j = pi, t_j = oo) so each group has even degree in every t_j, as ``sin(q_i + q_j)`` splits
    into ``(t_i + t_j) (1 - t_i t_j)``. Returns (constant, [(factor, multiplicity), ...]) with p =
    constant * prod(factor^multiplicity) modulo the circle relations; (1, [(p, 1)]) when p does not
    split."""
    from sympy.polys.rings import ring as poly_ring

    gens = dom.ring.gens
    revolute = [j for j in range(n) if any(m[j] or m[j + n] for m in p.monoms())]
    if not revolute:
        return dom.domain.one, [(p, 1)]
    names = [f"t{j}" for j in revolute] + [str(g) for g in gens[2 * n :]]
    tring, *tg = poly_ring(",".join(names), dom.domain)
    tv = dict(zip(revolute, tg))
    degree = {j: max(m[j] + m[j + n] for m in p.monoms()) for j in revolute}
    P = tring.zero
    for monom, coeff in p.terms():
        term = tring.ground_new(coeff)
        for j in revolute:
            b, a = monom[j], monom[j + n]
            t = tv[j]
            term *= (2 * t) ** b * (1 - t**2) ** a * (1 + t**2) ** (degree[j] - a - b)
        for i, e in enumerate(monom[2 * n :]):
            term *= tg[len(revolute) + i] ** e
        P += term
    _, tf = P.factor_list()
    pieces: list[tuple[object, dict[int, int]]] = []  # (t-polynomial, extra degree at infinity)
    for f, mult in tf:
        if any(f == 1 + t**2 for t in tv.values()):
            continue  # (1 + t_j^2): no real root, written back as 1
        pieces += [(f, {})] * mult
    for j in revolute:  # roots at t_j = oo (q_j = pi): the degree P lost
        pieces += [(tring.one, {j: 1})] * (2 * degree[j] - P.degree(tv[j]))
    if len(pieces) <= 1:
        return dom.domain.one, [(p, 1)]
    groups = _even_groups(pieces, tv)
    out: dict = {}
    for g, extra in groups:
        h = _from_half_angle(g, extra, tv, n, dom)
        if h.is_ground:
            continue
        h = h.primitive()[1]
        out[h] = out.get(h, 0) + 1
    if sum(out.values()) <= 1:
        return dom.domain.one, [(p, 1)]
    return _ratio(p, out, n, dom), list(out.items())


def _ratio(p, factors: dict, n: int, dom):  # noqa: ANN001, ANN202
    """The constant p / prod(h^m), evaluated exactly at rational points of the circles
    (c, s) = ((1 - t^2) / (1 + t^2), 2 t / (1 + t^2))."""
    K = dom.domain
    extra = len(dom.ring.gens) - 2 * n
    for k in range(1, 50):
        ts = [K.convert(sp.Rational(k + j, 3 * k + 2 * j + 7)) for j in range(n)]
        values = [2 * t / (1 + t * t) for t in ts] + [(1 - t * t) / (1 + t * t) for t in ts]
        values += [K.convert(sp.Rational(2 * k + j + 1, 5)) for j in range(extra)]
        den = K.one
        for h, m in factors.items():
            den *= h(*values) ** m
        if den:
            return p(*values) / den
    raise SymkinError("no point found to scale the factors of the determinant")  # not reached


def _odd(piece, tv) -> frozenset:  # noqa: ANN001
    f, extra = piece
    return frozenset(j for j, t in tv.items() if (f.degree(t) + extra.get(j, 0)) % 2)


def _even_groups(pieces: list, tv: dict) -> list:
    """Group pieces so each group has even degree in every t_j: even pieces alone, odd ones paired
    with a piece of the same odd set, the rest together."""
    groups, odd = [], []
    for piece in pieces:
        (odd if _odd(piece, tv) else groups).append(piece)
    while odd:
        first = odd.pop(0)
        key = _odd(first, tv)
        mate = next((k for k, other in enumerate(odd) if _odd(other, tv) == key), None)
        if mate is None:
            rest, odd = [first, *odd], []
        else:
            rest = [first, odd.pop(mate)]
        f, extra = rest[0][0], dict(rest[0][1])
        for g, e in rest[1:]:
            f = f * g
            for j, k in e.items():
                extra[j] = extra.get(j, 0) + k
        groups.append((f, extra))
    return groups


def _from_half_angle(g, extra: dict, tv: dict, n: int, dom):  # noqa: ANN001, ANN202
    """``g(t) / prod (1 + t_j^2)^(e_j / 2)`` as a polynomial in s_j, c_j (e_j = deg_t_j g + extra[j],
    even): ``t^a`` gives ``sin^a(q/2) cos^(e-a)(q/2)`` with ``sin^2 = (1 - c)/2``, ``cos^2 = (1 + c)/2``
    and ``sin cos = s/2``."""
    gens = dom.ring.gens
    revolute = list(tv)
    e = {j: g.degree(tv[j]) + extra.get(j, 0) for j in revolute}
    half = dom.domain.convert(sp.Rational(1, 2))
    out = dom.zero
    for monom, coeff in g.terms():
        term = dom.ring.ground_new(coeff)
        for k, j in enumerate(revolute):
            a, b = monom[k], e[j] - monom[k]
            s, c = gens[j], gens[j + n]
            if a % 2:
                term *= s * half
                a, b = a - 1, b - 1
            term *= ((1 - c) * half) ** (a // 2) * ((1 + c) * half) ** (b // 2)
        for i, x in enumerate(monom[len(revolute) :]):
            term *= gens[2 * n + i] ** x
        out += term
    return _reduce(out, n, dom)


def _factor_of(p, mult: int, n: int, s, c, qs, dom) -> SingularFactor:  # noqa: ANN001
    expr = dom.to_sympy(p)
    joints = tuple(j for j in range(n) if expr.has(s[j]) or expr.has(c[j]) or expr.has(qs[j]))
    if expr in s:
        return SingularFactor(sp.sin(qs[s.index(expr)]), mult, joints, "sin")
    if expr in c:
        return SingularFactor(sp.cos(qs[c.index(expr)]), mult, joints, "cos")
    trig = expr.xreplace(
        {**{s[j]: sp.sin(qs[j]) for j in range(n)}, **{c[j]: sp.cos(qs[j]) for j in range(n)}}
    )
    if count_ops(trig).total <= _TRIGSIMP_MAX_OPS:
        short = sp.trigsimp(trig)
        if count_ops(short).total < count_ops(trig).total:
            trig = short
    g = sp.gcd_terms(trig)
    return SingularFactor(g, mult, joints, "general")


def _axis_exprs(robot: Robot, qs: Sequence[sp.Symbol]) -> tuple:
    """Per joint (by index): (revolute, axis direction, a point on the axis), base frame."""
    _, frames = _walk(tuple(robot.ets), qs, const_to_sympy, 1)
    out = {f[0]: (f[1], tuple(f[2]), tuple(f[3])) for f in frames}
    return tuple(out[j] for j in range(robot.n))
