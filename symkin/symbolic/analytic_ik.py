"""Closed-form inverse kinematics derived with sympy from the exact model, as a list of subproblems.

The solution is a sequence of steps, each solving one angle (or a prismatic joint) from the
target pose and the angles solved before it, using the Paden-Kahan subproblems in the form of
IK-Geo (Elias and Wen, IK-Geo: Unified robot inverse kinematics using subproblem decomposition,
Mechanism and Machine Theory, 2025, Sec. 3):

- subproblem 1, ``rot(k, t) p1 = p2``: ``t = atan2(k . (p1 x p2), p1 . p2 - (k . p1)(k . p2))``;
- subproblem 4, ``h . rot(k, t) p = d``: with ``A = h . (k x p)``, ``B = h . (p - k (k . p))``,
  ``C = d - (h . k)(k . p)``, ``A sin t + B cos t = C``, so ``t = atan2(A, B) +- acos(C / sqrt(A^2 + B^2))``
  (two branches);
- subproblem 3, ``|rot(k, t) p1 - p2| = d``, is subproblem 4 with ``h = p2`` and
  ``d' = (|p1|^2 + |p2|^2 - d^2) / 2``; subproblem 2, ``rot(k1, t1) p1 = rot(k2, t2) p2``, is
  subproblem 4 for t1 (``k2 . rot(k1, t1) p1 = k2 . p2``) then subproblem 1 for t2;
- a prismatic joint along a line: ``|c + q h| = r``, ``q = -h.c +- sqrt((h.c)^2 - |c|^2 + r^2)``.

Every coefficient (A, B, C, ...) is an exact sympy expression in the target pose (``r11 .. r33``,
``px, py, pz``) and the cosines and sines of the angles already solved (``c0, s0, ...``): the
arm's constants are substituted exactly, so the emitted code does only the arithmetic this arm
needs. Branches: each subproblem 4 and each prismatic quadratic doubles them (at most 8 for 6R).

Constant ends: when the constants before the first joint (a base offset) or after the last (a
tool, fixed joints with rpy offsets) form a run that folds (:func:`symkin.symbolic.ik_geometry.fold_ik`),
they are taken off the chain and applied to the target instead, numerically: with
``T(q) = B T'(q) E`` the joints solve ``T' = B^{-1} T E^{-1}`` (``pose_map``), and the geometry and
the coefficients are those of the arm without its ends, exact as before. An arm with fewer than 6
joints solves the position of its tool point, so there only the rotation of ``E`` is moved and
its translation stays on the chain.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace
from fractions import Fraction

import sympy as sp

from symkin.model.ets import ET
from symkin.model.robot import Robot
from symkin.symbolic.fold import Fixed
from symkin.symbolic.ik_geometry import (
    IK_DIGITS,
    Geometry,
    NoAnalyticIKError,
    Structure,
    Vec,
    add,
    classify,
    cross,
    dot,
    fixed_matrix,
    fold_ik,
    geometry,
    is_constant,
    is_zero,
    parallel,
    random_point,
    reverse,
    scale,
    snap,
    sub,
    value_at,
)

__all__ = ["Step", "AnalyticIK", "derive_analytic", "pose_symbols", "given_symbols", "cs_names"]


@dataclass(frozen=True)
class Step:
    """One step of the solution.

    ``kind``: ``"sp4"`` (exprs A, B, C; two branches), ``"sp1"`` (exprs y, x), ``"quad"``
    (exprs b, D: ``var = -b +- sqrt(D)``; two branches), ``"lin"`` (expr value) or ``"sum"`` (exprs
    c, s: the cosine and sine of a summed angle by the addition formulas; no angle is formed).
    ``var`` is the solved variable (``q<j>`` for joint index j, or an auxiliary angle such as
    ``th``); ``joint`` its joint index (None for an auxiliary angle); ``revolute`` whether cos/sin
    of it are formed for later steps. ``title`` and ``statement`` (LaTeX) describe the step.
    """

    kind: str
    var: str
    joint: int | None
    revolute: bool
    exprs: tuple[tuple[str, sp.Expr], ...]
    title: str
    statement: str

    @property
    def branches(self) -> int:
        return 2 if self.kind in ("sp4", "quad") else 1


@dataclass(frozen=True, eq=False)
class AnalyticIK:
    """The derived closed form of one robot (see the module docstring).

    ``steps`` run in order, each nested in the branches of the ones before; ``outputs[j]`` is the
    variable holding joint index j; ``check`` is True when solutions must be verified against the
    full pose (arms with fewer than 6 joints solve only part of it); ``fk`` is the pose of the
    solved joints as 12 expressions (rows of the top 3x4 block) in ``c<j>, s<j>`` (revolute) or
    ``q<j>`` (prismatic), used to verify. ``base`` and ``tool`` (4x4, or None) are the constant ends
    taken off the chain (module docstring), ``T(q) = base T'(q) tool``; ``pose_map`` then assigns the
    pose symbols the steps use (:func:`pose_symbols`, the target of ``T'``) from the target as given
    (:func:`given_symbols`), and is empty when the arm has no such ends. ``geometry`` is that of the
    arm without its ends; ``fk`` is the whole arm's.
    """

    name: str
    n: int
    structure: Structure
    geometry: Geometry
    steps: tuple[Step, ...]
    outputs: tuple[str, ...]
    check: bool
    fk: tuple[sp.Expr, ...]
    revolute: tuple[bool, ...]
    base: sp.Matrix | None = None
    tool: sp.Matrix | None = None
    pose_map: tuple[tuple[sp.Symbol, sp.Expr], ...] = ()

    @property
    def max_solutions(self) -> int:
        return math.prod(st.branches for st in self.steps)


def pose_symbols() -> tuple[sp.Matrix, sp.Matrix]:
    """The target pose symbols: rotation ``r11 .. r33`` (3x3) and position ``px, py, pz`` (3x1)."""
    R = sp.Matrix(3, 3, lambda i, j: sp.Symbol(f"r{i + 1}{j + 1}", real=True))
    p = sp.Matrix([sp.Symbol(f"p{a}", real=True) for a in "xyz"])
    return R, p


def given_symbols() -> tuple[sp.Matrix, sp.Matrix]:
    """The target as given, for an arm whose constant ends are moved to it (``AnalyticIK.pose_map``):
    rotation ``g11 .. g33`` and position ``gx, gy, gz``."""
    R = sp.Matrix(3, 3, lambda i, j: sp.Symbol(f"g{i + 1}{j + 1}", real=True))
    p = sp.Matrix([sp.Symbol(f"g{a}", real=True) for a in "xyz"])
    return R, p


def cs_names(var: str) -> tuple[str, str]:
    """The names of the cosine and sine of the angle ``var`` (``q3``: ``c3``, ``s3``; ``th``: ``cth``)."""
    suffix = var[1:] if var.startswith("q") else var
    return f"c{suffix}", f"s{suffix}"


def _mat(v: Vec) -> sp.Matrix:
    return sp.Matrix(v)


def _vec(m: sp.Matrix) -> Vec:
    return (m[0], m[1], m[2])


def _rot(h: Vec, c: sp.Expr, s: sp.Expr) -> sp.Matrix:
    """rot(h, t) = c I + s [h]x + (1 - c) h h^T with c = cos t, s = sin t (h a unit vector)."""
    H = _mat(h)
    K = sp.Matrix([[0, -h[2], h[1]], [h[2], 0, -h[0]], [-h[1], h[0], 0]])
    return c * sp.eye(3) + s * K + (1 - c) * (H * H.T)


def _perp(h: Vec) -> Vec:
    """An exact vector perpendicular to the unit vector h."""
    for e in ((1, 0, 0), (0, 1, 0), (0, 0, 1)):
        v = cross(h, e)
        if not all(is_zero(x) for x in v):
            return v
    raise AssertionError("zero axis")


def _norm2(v: Vec) -> sp.Expr:
    return dot(v, v)


_ZERO_VALUE = 1e-25  # as is_zero


def _tidy(x: sp.Expr) -> sp.Expr:
    """``x`` as derived (nested dot products: about half the arithmetic of the expanded sum and
    no cancellation between its terms), exactly 0 or a single number when it expands to one.

    Only an ``x`` that is constant at random points is expanded (:func:`is_constant`): the expanded
    sum of a coefficient of an arm with general axes (a folded run of constants between joints)
    has thousands of terms. A constant with Floats in it (such an arm) is its value, 0 when that
    is 0 to 25 digits (:func:`is_zero`). One that cannot be evaluated at those points is expanded."""
    constant = is_constant(x)
    if constant is False:
        return x
    if constant and x.free_symbols and x.has(sp.Float):
        v = value_at(x, random_point(x.free_symbols, 1))
        return sp.Integer(0) if abs(v) < _ZERO_VALUE else sp.Float(v, IK_DIGITS)
    e = sp.expand(x)
    return e if e == 0 or not e.free_symbols else x


class _Builder:
    """Collects steps while the solution is derived."""

    def __init__(self, g: Geometry) -> None:
        self.g = g
        self.steps: list[Step] = []
        self.cs: dict[str, tuple[sp.Symbol, sp.Symbol]] = {}

    def name(self, k: int) -> str:
        return f"q{self.g.joint[k]}"

    def label(self, k: int) -> str:
        return f"q_{{{self.g.joint[k] + 1}}}"

    def cos_sin(self, var: str) -> tuple[sp.Symbol, sp.Symbol]:
        if var not in self.cs:
            c, s = cs_names(var)
            self.cs[var] = (sp.Symbol(c, real=True), sp.Symbol(s, real=True))
        return self.cs[var]

    def rot(self, h: Vec, var: str, sign: int = 1) -> sp.Matrix:
        c, s = self.cos_sin(var)
        return _rot(h, c, sign * s)

    def joint_rot(self, k: int, sign: int = 1) -> sp.Matrix:
        """rot(h_k, +-q_k) for a revolute joint, the identity for a prismatic one."""
        return self.rot(self.g.h[k], self.name(k), sign) if self.g.revolute[k] else sp.eye(3)

    def add(self, kind: str, k: int | str, exprs: dict[str, sp.Expr], title: str, statement: str) -> None:
        """A step solving joint ``k`` (chain position), or the auxiliary angle named ``k``."""
        exprs = {key: _tidy(v) for key, v in exprs.items()}
        constant = (
            not (exprs.get("A", 1).free_symbols | exprs.get("B", 1).free_symbols) if kind == "sp4" else False
        )
        if constant and is_zero(exprs["A"]) and is_zero(exprs["B"]):
            raise NoAnalyticIKError(
                f"{title}: the equation does not depend on the angle (degenerate geometry); "
                "use the numerical IK instead: kin.ik(T)"
            )
        if isinstance(k, str):
            var, joint, revolute = k, None, True
        else:
            var, joint, revolute = self.name(k), self.g.joint[k], self.g.revolute[k]
        self.steps.append(Step(kind, var, joint, revolute, tuple(exprs.items()), title, statement))

    # -- subproblems ---------------------------------------------------------------------------
    def sp4(self, k: int | str, h: Vec, p: Vec, axis: Vec, d: sp.Expr, title: str, st: str) -> None:
        A = dot(h, cross(axis, p))
        B = dot(h, sub(p, scale(dot(axis, p), axis)))
        C = d - dot(h, axis) * dot(axis, p)
        self.add("sp4", k, {"A": A, "B": B, "C": C}, title, st)

    def sp3(self, k: int | str, p1: Vec, p2: Vec, axis: Vec, d2: sp.Expr, title: str, st: str) -> None:
        """|rot(axis, t) p1 - p2|^2 = d2."""
        self.sp4(k, p2, p1, axis, (_norm2(p1) + _norm2(p2) - d2) / 2, title, st)

    def sp1(self, k: int | str, axis: Vec, p1: Vec, p2: Vec, title: str, st: str) -> None:
        y = dot(axis, cross(p1, p2))
        x = dot(p1, p2) - dot(axis, p1) * dot(axis, p2)
        self.add("sp1", k, {"y": y, "x": x}, title, st)

    def sp2(self, k1: int, k2: int, u: Vec, v: Vec, u_tex: str, v_tex: str) -> None:
        """Subproblem 2, ``R(h_k1, -q_k1) u = R(h_k2, q_k2) v``, as subproblem 4 for joint k1 then
        1 for joint k2; ``u_tex`` and ``v_tex`` write u and v in the statements."""
        h, L = self.g.h, self.label
        self.sp4(
            k1,
            h[k2],
            u,
            _neg(h[k1]),
            dot(h[k2], v),
            f"Subproblem 2 (4 then 1) for {L(k1)}",
            rf"h_{k2 + 1}^T R(h_{k1 + 1}, -{L(k1)})\,{u_tex} = h_{k2 + 1}^T {v_tex}",
        )
        self.sp1(
            k2,
            h[k2],
            v,
            _vec(self.joint_rot(k1, -1) * _mat(u)),
            f"Subproblem 1 for {L(k2)}",
            rf"R(h_{k2 + 1}, {L(k2)})\, {v_tex} = R(h_{k1 + 1}, -{L(k1)})\,{u_tex}",
        )

    def elbow(
        self, k: int, p_in: Vec, p_out: Vec, d: Vec, tex: tuple[str, str, str], where: str = ""
    ) -> None:
        """The elbow joint k by subproblem 3, ``|R(h_k, q_k) p_out + p_in| = |d|``, then joint k - 1
        by subproblem 1, ``R(h_k-1, q_k-1) (p_in + R(h_k, q_k) p_out) = d``; ``tex`` writes p_in,
        p_out and d in the statements (p_in, p_out as subscripts of p), ``where`` ends the first."""
        h, L = self.g.h, self.label
        t_in, t_out, t_d = tex
        self.sp3(
            k,
            p_out,
            _neg(p_in),
            h[k],
            _norm2(d),
            f"Subproblem 3 for {L(k)} (elbow)",
            rf"\| R(h_{k + 1}, {L(k)})\, p_{{{t_out}}} + p_{{{t_in}}} \| = \| {t_d} \|{where}",
        )
        self.sp1(
            k - 1,
            h[k - 1],
            add(p_in, _vec(self.joint_rot(k) * _mat(p_out))),
            d,
            f"Subproblem 1 for {L(k - 1)}",
            rf"R(h_{k}, {L(k - 1)})\,(p_{{{t_in}}} + R(h_{k + 1}, {L(k)})\, p_{{{t_out}}}) = {t_d}",
        )

    def from_sum(self, k: int, var: str, var_tex: str) -> None:
        """Joint k + 2 of the parallel axes k, k + 1, k + 2 from their summed angle ``var``:
        ``q_k+2 = sigma_k+2 (var - q_k - sigma_k+1 q_k+1)``, the sigmas +-1 as the axes point
        the way of axis k or not."""
        h, L = self.g.h, self.label
        s1, s2 = _same(h[k], h[k + 1]), _same(h[k], h[k + 2])
        total, q0, q1 = (sp.Symbol(x, real=True) for x in (var, self.name(k), self.name(k + 1)))
        self.add(
            "lin",
            k + 2,
            {"value": s2 * (total - q0 - s1 * q1)},
            f"{L(k + 2)} from the summed angle",
            rf"{L(k + 2)} = \sigma_{k + 3} ({var_tex} - {L(k)} - \sigma_{k + 2} {L(k + 1)})",
        )


def _neg(v: Vec) -> Vec:
    return (-v[0], -v[1], -v[2])


def _position(b: _Builder, s: Structure, w: Vec, w0: Vec) -> None:
    """Steps for joints 0, 1, 2 (chain order) placing the point at ``w0`` (q = 0) onto ``w``."""
    g = b.g
    h, p = g.h, g.p
    L = b.label
    if s.position == "parallel23":
        u = sub(w, p[0])
        p12, p23, p34 = sub(p[1], p[0]), sub(p[2], p[1]), sub(w0, p[2])
        b.sp4(
            0,
            h[1],
            u,
            _neg(h[0]),
            dot(h[1], add(add(p12, p23), p34)),
            f"Subproblem 4 for {L(0)}: axes 2 and 3 are parallel",
            rf"h_2^T R(h_1, -{L(0)})\,(w - p_1) = h_2^T (p_{{12}} + p_{{23}} + p_{{34}})",
        )
        v = sub(_vec(b.joint_rot(0, -1) * _mat(u)), p12)
        b.elbow(2, p23, p34, v, ("23", "34", "v"), rf",\quad v = R(h_1, -{L(0)})(w - p_1) - p_{{12}}")
        return
    if s.position == "intersect12":
        o = s.shoulder
        assert o is not None
        u = sub(w, o)
        p23, p34 = sub(p[2], o), sub(w0, p[2])
        if g.revolute[2]:
            b.sp3(
                2,
                p34,
                _neg(p23),
                h[2],
                _norm2(u),
                f"Subproblem 3 for {L(2)}: axes 1 and 2 meet at the shoulder o",
                rf"\| R(h_3, {L(2)})\, p_{{34}} + p_{{o3}} \| = \| w - o \|",
            )
            v = add(p23, _vec(b.joint_rot(2) * _mat(p34)))
        else:
            q2 = sp.Symbol(b.name(2), real=True)
            c = add(p23, p34)
            bb = dot(h[2], c)
            b.add(
                "quad",
                2,
                {"b": bb, "D": bb * bb - _norm2(c) + _norm2(u)},
                f"Prismatic {L(2)} from the distance to the shoulder o (axes 1 and 2 meet there)",
                rf"\| p_{{o3}} + {L(2)}\, h_3 + p_{{34}} \| = \| w - o \|",
            )
            v = add(c, scale(q2, h[2]))
        b.sp2(0, 1, u, v, "(w - o)", "v")
        return
    o = s.elbow
    assert o is not None and s.position == "intersect23"
    u = sub(w, p[0])
    p12, p34 = sub(o, p[0]), sub(w0, o)
    b.sp3(
        0,
        u,
        p12,
        _neg(h[0]),
        _norm2(p34),
        f"Subproblem 3 for {L(0)}: axes 2 and 3 meet at the elbow o",
        rf"\| R(h_1, -{L(0)})\,(w - p_1) - p_{{1o}} \| = \| p_{{o4}} \|",
    )
    v = sub(_vec(b.joint_rot(0, -1) * _mat(u)), p12)
    b.sp2(1, 2, v, p34, " v", "p_{o4}")


def _summed_rot(b: _Builder, k1: int, k2: int) -> sp.Matrix:
    """``R(h_k1, q_k1) R(h_k2, q_k2) = R(h_k1, q_k1 + sigma q_k2)`` for parallel axes (sigma = +-1 as
    they point the same way or not), with the summed angle's cosine and sine formed once by the
    addition formulas (a step ``"sum"``): the wrist coefficients then use two symbols, not four."""
    g = b.g
    sigma = _same(g.h[k1], g.h[k2])
    c1, s1 = b.cos_sin(b.name(k1))
    c2, s2 = b.cos_sin(b.name(k2))
    var = f"{g.joint[k1]}_{g.joint[k2]}"
    sign = "+" if sigma > 0 else "-"
    b.add(
        "sum",
        var,
        {"c": c1 * c2 - sigma * s1 * s2, "s": s1 * c2 + sigma * c1 * s2},
        f"The summed angle {b.label(k1)} {sign} {b.label(k2)} of the parallel axes {k1 + 1} and {k2 + 1}",
        rf"R(h_{k1 + 1}, {b.label(k1)})\, R(h_{k2 + 1}, {b.label(k2)}) = "
        rf"R(h_{k1 + 1}, {b.label(k1)} {sign} {b.label(k2)})",
    )
    return b.rot(g.h[k1], var)


def _wrist(b: _Builder, R0n: sp.Matrix) -> None:
    """Steps for the spherical wrist, joints 3, 4, 5 (chain order), given joints 0-2."""
    h = b.g.h
    if b.g.revolute[1] and b.g.revolute[2] and parallel(h[1], h[2]):
        R03 = b.joint_rot(0) * _summed_rot(b, 1, 2)
    else:
        R03 = b.joint_rot(0) * b.joint_rot(1) * b.joint_rot(2)
    v = _vec(R03.T * (R0n * _mat(h[5])))
    b.sp2(3, 4, v, h[5], " R_{03}^T R_{06} h_6", "h_6")
    _last_joint(b, [b.joint_rot(3, -1), R03.T, R0n])


def _last_joint(b: _Builder, back: list[sp.Matrix]) -> None:
    """Subproblem 1 for joint 5 (chain order), ``R(h_6, q_6) e = R_56 e`` for an ``e`` perpendicular
    to h_6, given joints 0-4: ``R_56 e = R(h_5, -q_5) B_1 B_2 ... e`` for the rotations ``back``."""
    h = b.g.h
    e = _perp(h[5])
    r56e = _mat(e)
    for R in reversed(back):
        r56e = R * r56e
    b.sp1(
        5,
        h[5],
        e,
        _vec(b.joint_rot(4, -1) * r56e),
        f"Subproblem 1 for {b.label(5)}",
        rf"R(h_6, {b.label(5)})\, e = R_{{56}} e,\quad e \perp h_6",
    )


def _same(a: Vec, b_: Vec) -> int:
    return 1 if is_zero(dot(a, b_) - 1) else -1


def _three_parallel(b: _Builder, s: Structure, R0n: sp.Matrix, pt: Vec, tM: Vec) -> None:
    g = b.g
    h, p = g.h, g.p
    L = b.label
    o = s.wrist
    assert o is not None
    p12, p23, p34, p45, p6T = sub(p[1], p[0]), sub(p[2], p[1]), sub(p[3], p[2]), sub(o, p[3]), sub(tM, o)
    p06 = sub(sub(pt, p[0]), _vec(R0n * _mat(p6T)))
    b.sp4(
        0,
        h[1],
        p06,
        _neg(h[0]),
        dot(h[1], add(add(p12, p23), add(p34, p45))),
        f"Subproblem 4 for {L(0)}: axes 2, 3, 4 are parallel",
        rf"h_2^T R(h_1, -{L(0)})\, p_{{16}} = h_2^T (p_{{12}} + p_{{23}} + p_{{34}} + p_{{45}})",
    )
    R10 = b.joint_rot(0, -1)
    b.sp4(
        4,
        h[1],
        h[5],
        h[4],
        dot(h[1], _vec(R10 * (R0n * _mat(h[5])))),
        f"Subproblem 4 for {L(4)}",
        rf"h_2^T R(h_5, {L(4)})\, h_6 = h_2^T R(h_1, -{L(0)})\, R_{{06}} h_6",
    )
    b.sp1(
        "th",
        h[1],
        _vec(b.joint_rot(4) * _mat(h[5])),
        _vec(R10 * (R0n * _mat(h[5]))),
        r"Subproblem 1 for $\theta$, the summed rotation of the parallel axes 2, 3, 4",
        rf"R(h_2, \theta)\, R(h_5, {L(4)})\, h_6 = R(h_1, -{L(0)})\, R_{{06}} h_6",
    )
    _last_joint(b, [b.rot(h[1], "th", -1), R10, R0n])
    d_inner = sub(sub(_vec(R10 * _mat(p06)), p12), _vec(b.rot(h[1], "th") * _mat(p45)))
    where = rf",\quad d = R(h_1, -{L(0)}) p_{{16}} - p_{{12}} - R(h_2, \theta)\, p_{{45}}"
    b.elbow(2, p23, p34, d_inner, ("23", "34", "d"), where)
    b.from_sum(1, "th", r"\theta")


def _planar(b: _Builder, R0n: sp.Matrix, pt: Vec, tM: Vec) -> None:
    g = b.g
    h, p = g.h, g.p
    if g.n == 3:
        e = _perp(h[0])
        b.sp1(
            "phi",
            h[0],
            e,
            _vec(R0n * _mat(e)),
            r"Subproblem 1 for the summed angle $\varphi$",
            r"R(h_1, \varphi)\, e = R_{0T} R_M^T e,\quad e \perp h_1",
        )
        u = sub(sub(pt, p[0]), _vec(R0n * _mat(sub(tM, p[2]))))
        tip = p[2]
    else:
        u = sub(pt, p[0])
        tip = tM
    p12, p2t = sub(p[1], p[0]), sub(tip, p[1])
    b.elbow(1, p12, p2t, u, ("12", "2t", "u"))
    if g.n == 3:
        b.from_sum(0, "phi", r"\varphi")


def _fk(b: _Builder) -> tuple[sp.Expr, ...]:
    """The top 3x4 block of T(q) = G_1 ... G_n M (product of exponentials)."""
    g = b.g
    T = sp.eye(4)
    for k in range(g.n):
        G = sp.eye(4)
        if g.revolute[k]:
            R = b.joint_rot(k)
            G[:3, :3] = R
            G[:3, 3] = _mat(g.p[k]) - R * _mat(g.p[k])
        else:
            G[:3, 3] = sp.Symbol(b.name(k), real=True) * _mat(g.h[k])
        T = T * G
    T = T * g.M
    return tuple(T[i, j] for i in range(3) for j in range(4))


_ONE, _ZERO = Fraction(1), Fraction(0)
_IDENTITY = ((_ONE, _ZERO, _ZERO), (_ZERO, _ONE, _ZERO), (_ZERO, _ZERO, _ONE))


def _split_ends(
    elements: tuple[ET | Fixed, ...], whole_tool: bool
) -> tuple[Fixed | None, tuple[ET | Fixed, ...], Fixed | None]:
    """(base, chain, tool): a folded run before the first joint and after the last taken off the
    chain (module docstring); without ``whole_tool`` the tool's translation stays on the chain."""
    if not any(e.is_joint for e in elements):
        return None, elements, None
    base = elements[0] if isinstance(elements[0], Fixed) else None
    tool = elements[-1] if isinstance(elements[-1], Fixed) else None
    chain = list(elements[int(base is not None) : len(elements) - int(tool is not None)])
    if tool is not None and not whole_tool:
        if any(tool.t):
            chain.append(Fixed(_IDENTITY, tool.t, tool.count, tool.digits))
        tool = Fixed(tool.cols, (_ZERO, _ZERO, _ZERO), tool.count, tool.digits)
    identity = (_IDENTITY, (_ZERO, _ZERO, _ZERO))
    base = None if base is None or (base.cols, base.t) == identity else base
    tool = None if tool is None or (tool.cols, tool.t) == identity else tool
    return base, tuple(chain), tool


def _pose_map(base: Fixed | None, tool: Fixed | None) -> tuple[tuple[sp.Symbol, sp.Expr], ...]:
    """The pose symbols of ``T' = base^{-1} T tool^{-1}`` from the given target ``T``."""
    if base is None and tool is None:
        return ()
    G, g = given_symbols()
    T = sp.eye(4)
    T[:3, :3], T[:3, 3] = G, g
    if base is not None:
        T = fixed_matrix(base.inverse()) * T
    if tool is not None:
        T = T * fixed_matrix(tool.inverse())
    R, p = pose_symbols()
    pairs = [(R[i, j], T[i, j]) for i in range(3) for j in range(3)] + [(p[i], T[i, 3]) for i in range(3)]
    return tuple((sym, sp.expand(e)) for sym, e in pairs)


def derive_analytic(robot: Robot) -> AnalyticIK:
    """Detect the arm's structure and derive its closed form; NoAnalyticIKError when there is none.

    A 6-joint arm whose structure only shows when the chain is read from the tool (three first
    axes meeting in a point: a spherical shoulder) is solved reversed, for the target ``T^{-1}``.
    Constant ends that fold are applied to the target (module docstring)."""
    elements = fold_ik(snap(robot.ets))
    base, chain, tool = _split_ends(elements, whole_tool=sum(e.is_joint for e in elements) == 6)
    g0 = geometry(chain)
    g = g0
    try:
        s = classify(g)
    except NoAnalyticIKError as forward:
        if g0.n != 6:
            raise
        g = reverse(g0)
        try:
            s = classify(g)
        except NoAnalyticIKError:
            raise forward from None
        s = replace(s, reversed=True, summary=s.summary + " (chain read from the tool)")
    b = _Builder(g)
    R, pvec = pose_symbols()
    if s.reversed:
        R, pvec = R.T, -R.T * pvec
    RM = g.M[:3, :3]
    tM = (g.M[0, 3], g.M[1, 3], g.M[2, 3])
    R0n = R * RM.T
    pt = _vec(pvec)
    if s.kind == "spherical_wrist":
        assert s.wrist is not None
        w = sub(pt, _vec(R0n * _mat(sub(tM, s.wrist))))
        _position(b, s, w, s.wrist)
        _wrist(b, R0n)
    elif s.kind == "three_parallel":
        _three_parallel(b, s, R0n, pt, tM)
    elif s.kind == "position3":
        _position(b, s, pt, tM)
    else:
        _planar(b, R0n, pt, tM)
    solved = {st.joint: st.var for st in b.steps if st.joint is not None}
    rev = [r for _, r in sorted(zip(g.joint, g.revolute))]  # by joint index
    fk = _fk(_Builder(g0))
    B = None if base is None else fixed_matrix(base)
    E = None if tool is None else fixed_matrix(tool)
    if B is not None or E is not None:
        T = sp.Matrix(3, 4, fk).col_join(sp.Matrix([[0, 0, 0, 1]]))
        T = (B if B is not None else sp.eye(4)) * T * (E if E is not None else sp.eye(4))
        fk = tuple(T[i, j] for i in range(3) for j in range(4))
    return AnalyticIK(
        robot.name,
        g.n,
        s,
        g,
        tuple(b.steps),
        tuple(solved.get(j, "") for j in range(g.n)),
        g.n < 6,
        fk,
        tuple(rev),
        B,
        E,
        _pose_map(base, tool),
    )
