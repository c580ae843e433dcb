"""Step-by-step kinematic derivations for teaching: Markdown with LaTeX math, or LaTeX.

:func:`derivation` writes out what a student does by hand the way Haviland and Corke build it
(Manipulator Differential Kinematics, Part 1, 2023): the ETS (eq 1), each elementary transform as
its 4x4 matrix (Fig. 2), the link frames (eq 5), the forward kinematics, the partial derivatives
dT/dq_j (eq 26), every Jacobian column by eqs 27-28 and by the fast form (eqs 31-34), and the
Hessian (eq 20 of Haviland and Corke, Maximising Manipulability During Resolved-Rate Motion
Control, 2020). :func:`derive_steps` returns the same results as sympy expressions in a
:class:`Derivation`; ``sections`` keeps only some parts of the text (:data:`SECTIONS`).

Joints are numbered from 1 as in the paper: the symbol ``q_1`` is symkin's joint ``q0``, and
``Derivation.q[j]`` is the symbol of joint index ``j``. With ``symbolic_constants`` every nonzero
translation constant of the ETS becomes its own positive symbol ``l_1, l_2, ...`` in chain order
(a negative constant reads ``-l_k``); angle constants stay exact (``pi/2`` gives 0 and 1).

Simplification: the literal results of the equations (products of cos and sin) are replaced by the
compact forms of :func:`symkin.symbolic.kinematics.derive` (rotations about one axis merged, so
``cos(q1 + q2)`` appears as such) once proved equal: the difference, with the trig functions of
sums expanded, expands to 0; differences too large for that are checked at random points with 30
digits instead, and the text says which check was used.
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from dataclasses import replace
from typing import Any, Literal

import mpmath
import sympy as sp

from symkin.derive.common import (  # noqa: F401
    CHECK_TEXT,
    DISPLAY_MAX_OPS,
    FORMATS,
    SECTIONS,
    Constants,
    Derivation,
    Printer,
    aligned,
    constants,
    et_matrix,
    generator,
    hessian_pattern,
    latex_document,
    ops_of,
    products,
    shared_context,
    shown_sections,
    summary,
)
from symkin.emit.templates import render
from symkin.errors import SymkinError, check_choice
from symkin.model.ets import ET, ETS, Axis
from symkin.model.latex import et_latex
from symkin.model.robot import Robot
from symkin.model.tree import Tree, as_tree, robot_of
from symkin.symbolic.kinematics import derive

__all__ = ["Derivation", "derive_steps", "derivation", "SECTIONS"]

Fmt = Literal["markdown", "latex"]
Form = Literal["auto", "expanded", "program"]
FORMS = ("auto", "expanded", "program")
SYMBOLIC_CHECK_MAX_OPS = 1500  # larger differences are checked at random points
MATRIX_MAX_OPS = 160  # larger matrices are printed entry by entry
FULL_MAX_N = 4  # dT/dq_j matrices and Hessian blocks are printed up to this many joints
_XYZ = "xyz"


# ---------------------------------------------------------------------------------------------
# Constants and elementary transforms


def _skew(w: Sequence[sp.Expr]) -> sp.Matrix:
    return sp.Matrix([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def _vee(S: sp.Matrix) -> sp.Matrix:
    return sp.Matrix([S[2, 1], S[0, 2], S[1, 0]])


# ---------------------------------------------------------------------------------------------
# Equality checks


def _is_zero(x: sp.Expr) -> bool:
    """Whether x is identically 0 as a polynomial in the sines and cosines of the joint angles:
    trig functions of sums are expanded, then sin^2 = 1 - cos^2 gives a unique normal form."""
    x = sp.expand(sp.expand_trig(x))
    if x == 0:
        return True
    pairs: dict[sp.Expr, tuple[sp.Dummy, sp.Dummy]] = {}
    for f in x.atoms(sp.sin, sp.cos):  # constant angles too (cos(1/10) is kept as such)
        pairs.setdefault(f.args[0], (sp.Dummy(), sp.Dummy()))
    subs = {}
    for arg, (s, c) in pairs.items():
        subs[sp.sin(arg)], subs[sp.cos(arg)] = s, c
    cos_of = dict(pairs.values())
    poly = sp.Poly(x.xreplace(subs), *cos_of, *cos_of.values())
    out = sp.Integer(0)
    for monom, coeff in poly.terms():
        term = coeff
        for g, e in zip(poly.gens, monom):
            term *= g ** (e % 2) * (1 - cos_of[g] ** 2) ** (e // 2) if g in cos_of else g**e
        out += term
    return sp.expand(out) == 0


def _check(a: sp.Matrix, b: sp.Matrix, symbols: Sequence[sp.Symbol]) -> str:
    """How a = b holds: "symbolic" when a - b is identically 0 (:func:`_is_zero`), else "numeric"
    when it vanishes at 3 random points to 30 digits (differences over ``SYMBOLIC_CHECK_MAX_OPS``
    are not expanded; constant angles such as cos(1/10) may hide identities), else "failed"."""
    d = sp.Matrix(a) - sp.Matrix(b)
    if sum(ops_of(x) for x in d) <= SYMBOLIC_CHECK_MAX_OPS and all(_is_zero(x) for x in d):
        return "symbolic"
    f = sp.lambdify(list(symbols), list(d), modules="mpmath")
    rng = random.Random(1)
    with mpmath.workdps(30):
        for _ in range(3):
            values = f(*[mpmath.mpf(rng.randint(100, 2000)) / 1000 for _ in symbols])
            if max((abs(v) for v in values), default=0) > mpmath.mpf(10) ** -20:
                return "failed"
    return "numeric"


def _suffix_pose(C: Constants, start: int, q: Sequence[sp.Symbol]) -> sp.Matrix:
    """The pose of the factors ``start..M`` of the ETS (jT_e for the frame before ``start``)."""
    part = C.ets.ets[start:]
    joints = sorted(e.joint for e in part if e.joint is not None)
    new = {j: i for i, j in enumerate(joints)}
    sub = tuple(e if e.joint is None else ET(e.axis, joint=new[e.joint], flip=e.flip) for e in part)
    if not sub:
        return sp.eye(4)
    return derive(ETS(sub), constant=C.constant, q=[q[j] for j in joints]).T


def _fast_column(e: ET, Tj: sp.Matrix, Tje: sp.Matrix) -> sp.Matrix:
    """Eqs 32 and 34: the column from (n, o, a) = rho(0T_j) and (x_e, y_e, z_e) = tau(jT_e)."""
    cols = [Tj[:3, c] for c in range(3)]
    n, o, a = cols
    xe, ye, ze = Tje[0, 3], Tje[1, 3], Tje[2, 3]
    i = e.axis.index
    if e.axis.is_rotation:
        v = (a * ye - o * ze, n * ze - a * xe, o * xe - n * ye)[i]
        w = cols[i]
    else:
        v, w = cols[i], sp.zeros(3, 1)
    return e.sign * sp.Matrix.vstack(v, w)


# ---------------------------------------------------------------------------------------------
# The derivation


def _steps(robot: Robot, symbolic_constants: bool, simplify: bool) -> Derivation:
    ets = robot.ets
    n = ets.n
    if n == 0:
        raise SymkinError(f"robot {robot.name!r} has no joints: nothing to derive")
    q = tuple(sp.Symbol(f"q_{j + 1}", real=True) for j in range(n))
    C = constants(ets, symbolic_constants)
    eta = [e.sign * q[e.joint] if e.joint is not None else C.eta[k] for k, e in enumerate(ets)]
    E = [et_matrix(e.axis, eta[k]) for k, e in enumerate(ets)]
    mu = {e.joint: k for k, e in enumerate(ets) if e.joint is not None}
    prefix, suffix = products(E, sp.eye(4))
    T_raw = prefix[-1]
    dT_raw = [prefix[mu[j]] * E[mu[j]].diff(q[j]) * suffix[mu[j] + 1] for j in range(n)]

    kin = derive(C.ets, constant=C.constant, q=q)
    symbols = list(q) + list(C.values)
    checks: dict[str, str] = {}
    if simplify:
        order = [e.joint for e in ets if e.joint is not None]
        links = [kin.links[order.index(j)] for j in range(n)]
        jTe = [_suffix_pose(C, mu[j] + 1, q) for j in range(n)]
        checks["eq 1: T"] = _check(T_raw, kin.T, symbols)
        checks["eq 5: link frames 0T_j and jT_e"] = _worst(
            _check(
                sp.Matrix.vstack(prefix[mu[j] + 1], suffix[mu[j] + 1]),
                sp.Matrix.vstack(links[j], jTe[j]),
                symbols,
            )
            for j in range(n)
        )
        T = kin.T
        dT = [T.diff(q[j]) for j in range(n)]
        checks["eq 26: dT/dq_j"] = _worst(_check(dT_raw[j], dT[j], symbols) for j in range(n))
        J = kin.J0
        Jv = [min(dT[j][:3, 3], J[:3, j], key=_matrix_ops) for j in range(n)]  # the shorter form
        J = sp.Matrix.hstack(*[sp.Matrix.vstack(Jv[j], J[3:, j]) for j in range(n)])
        # eq 27 gives J_w when rho(dT/dq_j) = [J_w]x rho(T), since rho(T) rho(T)^T = 1
        checks["eq 27: J_w"] = _worst(
            _check(dT[j][:3, :3], _skew(J[3:, j]) * T[:3, :3], symbols) for j in range(n)
        )
        checks["eq 28: J_v"] = _worst(_check(dT[j][:3, 3], J[:3, j], symbols) for j in range(n))
        Jfast = sp.Matrix.hstack(*[_fast_column(ets[mu[j]], links[j], jTe[j]) for j in range(n)])
        checks["eqs 31-34"] = _check(Jfast, J, symbols)
        checks["J0 = J0_fast"] = _worst(checks[k] for k in ("eq 27: J_w", "eq 28: J_v", "eqs 31-34"))
        J27 = Jfast = J
        bad = [k for k, v in checks.items() if v == "failed"]
        if bad:
            raise SymkinError(f"derivation of {robot.name!r}: the compact forms differ from {', '.join(bad)}")
    else:
        T, dT = T_raw, dT_raw
        links = [prefix[mu[j] + 1] for j in range(n)]
        jTe = [suffix[mu[j] + 1] for j in range(n)]
        J27 = sp.Matrix.hstack(
            *[sp.Matrix.vstack(dT[j][:3, 3], _vee(dT[j][:3, :3] * T[:3, :3].T)) for j in range(n)]
        )
        Jfast = sp.Matrix.hstack(*[_fast_column(ets[mu[j]], links[j], jTe[j]) for j in range(n)])
        checks["J0 = J0_fast"] = _check(J27, Jfast, symbols)
    im = sp.ImmutableMatrix
    return Derivation(
        robot,
        q,
        dict(C.values),
        tuple(map(im, E)),
        im(T),
        tuple(map(im, links)),
        tuple(map(im, jTe)),
        tuple(map(im, dT)),
        im(J27),
        im(Jfast),
        tuple(map(im, kin.H0)),
        simplify,
        checks,
    )


def _matrix_ops(M: sp.Matrix) -> int:
    return sum(ops_of(x) for x in M)


def _worst(results: Any) -> str:
    results = list(results)
    return next((level for level in ("failed", "numeric") if level in results), "symbolic")


# ---------------------------------------------------------------------------------------------
# Writing the derivation


def _vec(P: Printer, v: Sequence[sp.Expr]) -> str:
    return P.matrix(sp.Matrix(list(v)))


def _shown(M: sp.Matrix) -> bool:
    return _matrix_ops(M) <= MATRIX_MAX_OPS


def _pose_tex(P: Printer, M: sp.Matrix, lhs: str) -> str:
    """A pose as one matrix when short, else its columns n, o, a, t one per line."""
    if _shown(M):
        return f"{lhs} = {P.matrix(M)}"
    lines = [
        rf"{lhs} &= \begin{{pmatrix}} \mathbf{{n}} & \mathbf{{o}} & \mathbf{{a}} & \mathbf{{t}} \\ "
        r"0 & 0 & 0 & 1 \end{pmatrix}"
    ]
    lines += [rf"\mathbf{{{name}}} &= {_vec(P, M[:3, c])}" for c, name in enumerate("noat")]
    return aligned(lines)


_FAST_RULE = {
    Axis.Rz: r"\mathbf{o}_{#} x_e - \mathbf{n}_{#} y_e",
    Axis.Rx: r"\mathbf{a}_{#} y_e - \mathbf{o}_{#} z_e",
    Axis.Ry: r"\mathbf{n}_{#} z_e - \mathbf{a}_{#} x_e",
    Axis.tx: r"\mathbf{n}_{#}",
    Axis.ty: r"\mathbf{o}_{#}",
    Axis.tz: r"\mathbf{a}_{#}",
}


def _context(D: Derivation) -> tuple[dict[str, Any], str]:
    """The template's context (every math string ready-made) and the LaTeX summary for Jupyter."""
    q, n, ets = D.q, len(D.q), D.robot.ets
    C = constants(ets, bool(D.constants))
    mu = {e.joint: k for k, e in enumerate(ets) if e.joint is not None}
    P = Printer(q)
    full = n <= FULL_MAX_N
    ctx: dict[str, Any] = {
        **shared_context(D, P, C),
        "full": full,
        "full_max_n": FULL_MAX_N,
        "what": "compact forms, each proved equal to the literal products of the equations"
        if D.simplified
        else "the literal products of the equations, not simplified",
        "same": CHECK_TEXT[D.checks["J0 = J0_fast"]],
        "jacobian": P.matrix(D.J0_fast),
    }
    ctx["links"] = [_pose_tex(P, D.links[j], f"{{}}^{{0}}T_{{{j + 1}}}") for j in range(n)]
    T = D.T
    position = aligned(f"{_XYZ[r]} &= {P(T[r, 3])}" for r in range(3))
    rotation = aligned(f"r_{{{r + 1}{c + 1}}} &= {P(T[r, c])}" for r in range(3) for c in range(3))
    ctx["pose"] = [f"{{}}^{{0}}T_{{e}} = {P.matrix(T)}", position] if _shown(T) else [
        position, rf"R = (r_{{ij}}), \quad {rotation}"
    ]  # fmt: skip
    ctx["derivatives"], ctx["columns27"], ctx["columns_fast"] = [], [], []
    for j in range(n):
        k, e, J = mu[j], ets[mu[j]], str(j + 1)
        sign = "-" if e.flip else ""
        ctx["derivatives"].append(
            rf"\mu({J}) = {k + 1}, \quad \frac{{dE_{{{k + 1}}}}}{{dq_{{{J}}}}} = "
            rf"{sign}{P.matrix(generator(e.axis))}\, {et_latex(e)} = {P.matrix(D.E[k].diff(q[j]))}"
        )
        if full:
            ctx["derivatives"].append(
                rf"\frac{{\partial\, {{}}^0T_e}}{{\partial q_{{{J}}}}} = {P.matrix(D.dT[j])}"
            )
        skew = D.dT[j][:3, :3] * T[:3, :3].T if not D.simplified else _skew(D.J0[3:, j])
        skew_tex = P.matrix(skew) if _shown(skew) else r"[\omega]_\times"
        ctx["columns27"].append(
            rf"\rho\Big(\frac{{\partial T}}{{\partial q_{{{J}}}}}\Big)\rho(T)^\top = {skew_tex} "
            rf"\;\Rightarrow\; "
            rf"J_{{\omega_{{{J}}}}} = {_vec(P, D.J0[3:, j])}, \quad J_{{v_{{{J}}}}} = {_vec(P, D.J0[:3, j])}"
        )
        rule = _FAST_RULE[e.axis].replace("#", J)
        w = rf"{sign}\mathbf{{{'noa'[e.axis.index]}}}_{{{J}}}" if e.axis.is_rotation else "0"
        ctx["columns_fast"].append(
            rf"\tau({{}}^{{{J}}}T_e) = {_vec(P, D.ee[j][:3, 3])}, \quad J_{{v_{{{J}}}}} = "
            rf"{f'-({rule})' if sign else rule} = {_vec(P, D.J0_fast[:3, j])}, \quad "
            rf"J_{{\omega_{{{J}}}}} = {w} = {_vec(P, D.J0_fast[3:, j])}"
        )
    Jf = D.J0_fast
    planar = all(Jf[r, c] == 0 for r in (2, 3, 4) for c in range(n))
    ctx["planar"] = P.matrix(sp.Matrix.vstack(Jf[0:2, :], Jf[5:6, :])) if planar else ""
    if full:
        ctx["hessian"] = [
            rf"H_{{{i + 1}}} = \frac{{\partial J}}{{\partial q_{{{i + 1}}}}} = {P.matrix(D.H0[i])}"
            for i in range(n)
        ]
    else:
        ctx["hessian"] = [hessian_pattern(P, D.H0)]
    text = summary(D, P, C, *([rf"{{}}^0J &= {P.matrix(Jf)}"] if _shown(Jf) else []))
    ctx["legend"] = P.legend()
    return ctx, text


def derive_steps(
    robot: Robot | ETS | str,
    symbolic_constants: bool = False,
    simplify: bool = True,
    fmt: Fmt = "markdown",
    form: Form = "auto",
    sections: Sequence[str] | str | None = None,
) -> Derivation:
    """Derive ``robot``'s kinematics step by step: the results and the written derivation.

    Args:
        robot: a Robot, an ETS, or anything :func:`symkin.resolve_robot` takes (``"planar3"``).
        symbolic_constants: name the translation constants ``l_1, l_2, ...`` (values in
            ``Derivation.constants``).
        simplify: compact forms proved equal to the literal products of the equations; ``False``
            keeps the literal products (long beyond 3 joints; the text omits huge entries).
        fmt: ``"markdown"`` (Markdown with ``$$`` math) or ``"latex"`` (a standalone document).
        form: ``"expanded"`` (every result multiplied out), ``"program"`` (link frame by link
            frame, new quantities named: :mod:`symkin.derive.program`), or ``"auto"``: the
            program form when the expanded one would be too large to read or to check
            symbolically (the same size rule as the compiler's, about 8 joints and more).
        sections: write only these parts of the text (names in :data:`SECTIONS`, e.g.
            ``("fk", "jacobian")``); default all. The results are computed in full either way.
    """
    shown = shown_sections(sections)
    check_choice(fmt, FORMATS, "format")
    check_choice(form, FORMS, "form")
    from symkin.model.resolve import robot_with_joints

    robot = robot_with_joints(robot, "nothing to derive")
    if form == "auto":
        from symkin.symbolic.functions import expanded_if_small

        form = "expanded" if expanded_if_small(robot) is not None else "program"
    if form == "program":
        from symkin.derive.program import program_derivation

        D, ctx, summary = program_derivation(robot, symbolic_constants)
        shown = shown_sections(sections, program=True)
        text = render("derive/program.md.j2", **ctx, sections=shown)
    else:
        D = _steps(robot, symbolic_constants, simplify)
        ctx, summary = _context(D)
        text = render("derive/derivation.md.j2", **ctx, sections=shown)
    return replace(
        D,
        fmt=fmt,
        text=latex_document(text) if fmt == "latex" else text,
        latex_summary=summary,
        markdown=text,
        shown=tuple(k for k in SECTIONS if k in shown),
    )


def derivation(
    robot: Robot | ETS | Tree | str,
    fmt: Fmt = "markdown",
    symbolic_constants: bool = False,
    simplify: bool = True,
    form: Form = "auto",
    sections: Sequence[str] | str | None = None,
) -> str:
    """The derivation of ``robot``'s kinematics as Markdown or a LaTeX document (see :func:`derive_steps`);
    a tree with several frames or a mimic joint in the program form (:mod:`symkin.derive.program`)."""
    if not isinstance(robot, (str, ETS)):  # a model: ask it whether it is one serial chain
        tree = as_tree(robot)
        if not tree.single_path:
            from symkin.derive.program import tree_derivation

            return tree_derivation(tree, fmt, sections)
        robot = robot_of(robot) or tree.chain()
    return derive_steps(
        robot, symbolic_constants=symbolic_constants, simplify=simplify, fmt=fmt, form=form, sections=sections
    ).text
