"""``symkin derive ROBOT --ik``: the closed-form IK derivation written out (Markdown or LaTeX).

Shows the joint axes and points at q = 0, the structure found, the wrist centre, and each step
of :func:`symkin.symbolic.analytic_ik.derive_analytic` with its equation and exact coefficients.
"""

from __future__ import annotations

from typing import Literal

import sympy as sp

from symkin.derive.common import latex_document
from symkin.emit.templates import render
from symkin.model.latex import display_name
from symkin.model.robot import Robot
from symkin.symbolic.analytic_ik import derive_analytic

__all__ = ["ik_derivation"]

DISPLAY_MAX_OPS = 400  # larger coefficients are summarised by their size
_NAMES = {"value": r"\text{value}", "c": r"\cos", "s": r"\sin"}  # A, B, C, x, y, b, D: as they are


def _short(x: sp.Basic) -> sp.Basic:
    """``x`` with its Floats (a folded run of constants, 50 digits) shown to 17 digits."""
    return x.xreplace({f: sp.Float(f, 17) for f in x.atoms(sp.Float)})


def _latex(x: sp.Expr) -> str:
    if sp.count_ops(x) > DISPLAY_MAX_OPS:
        return rf"\text{{(an expression of {sp.count_ops(x)} operations; see the generated code)}}"
    return sp.latex(_short(x))


def _vec(v: tuple) -> str:
    return r"\begin{pmatrix} " + r" \\ ".join(sp.latex(_short(x)) for x in v) + r" \end{pmatrix}"


_RESULT = {
    "sp4": "Two branches: ${v} = \\operatorname{{atan2}}(A, B) \\pm \\arccos(C / \\sqrt{{A^2 + B^2}})$; when "
    "$A = B = 0$ the angle is free (a singularity) and takes the value of `q0` (0 without it).",
    "sp1": "${v} = \\operatorname{{atan2}}(y, x)$; free (a singularity) when $x = y = 0$.",
    "quad": "Two branches: ${v} = -b \\pm \\sqrt{{D}}$ (no solution when $D < 0$).",
    "lin": "",
    "sum": "",
}


def _ends(base: sp.Matrix | None, tool: sp.Matrix | None) -> str:
    """The paragraph on the constant ends moved to the target (empty without them)."""
    if base is None and tool is None:
        return ""
    B, E = r"T_{\mathrm{base}}", r"T_{\mathrm{tool}}"
    chain = " ".join(x for x in (B if base is not None else "", "T'(q)", E if tool is not None else "") if x)
    target = " ".join(
        x
        for x in (f"{B}^{{-1}}" if base is not None else "", "T", f"{E}^{{-1}}" if tool is not None else "")
        if x
    )
    shown = [(n, m) for n, m in ((B, base), (E, tool)) if m is not None]
    mats = "\n\n".join(f"$$\n{n} = {sp.latex(_short(m))}\n$$" for n, m in shown)
    return (
        "The constant transforms before the first joint and after the last hold rotations by angles other "
        "than multiples of $\\pi/2$: they are taken off the chain (the table above is the arm without them), "
        f"${{}}^0T_e(q) = {chain}$, and applied to the target numerically: the joints solve "
        f"$T' = {target}$ (below, $r_{{ij}}$ and $p$ are those of $T'$). On an arm with fewer than 6 "
        "joints only the rotation of the tool transform is moved (its translation, the tool point, stays in "
        "$M$).\n\n" + mats
    )


def ik_derivation(robot: Robot, fmt: Literal["markdown", "latex"] = "markdown") -> str:
    """The derivation of ``robot``'s closed-form IK; raises NoAnalyticIKError when there is none."""
    from symkin.core.version import __version__

    plan = derive_analytic(robot)
    g, s = plan.geometry, plan.structure
    joints = [
        [f"$q_{{{j + 1}}}$", "R" if rev else "P", f"${_vec(h)}$", f"${_vec(p)}$"]
        for j, rev, h, p in zip(g.joint, g.revolute, g.h, g.p)
    ]
    steps = []
    for st in plan.steps:
        label = (
            f"q_{{{st.joint + 1}}}" if st.joint is not None else (r"\theta" if st.var == "th" else r"\varphi")
        )
        if st.kind == "sum":
            label = st.var
        exprs = [(_NAMES.get(k, k), _latex(v)) for k, v in st.exprs]
        steps.append({"title": st.title.replace("$", ""), "statement": st.statement, "exprs": exprs,
                      "result": _RESULT[st.kind].format(v=label)})  # fmt: skip
    text = {
        "spherical_wrist": "Spherical wrist: axes 4, 5, 6 meet in one point (Pieper), "
        "so joints 1-3 place the "
        "wrist centre and joints 4-6 set the orientation. ",
        "three_parallel": "Axes 2, 3 and 4 are parallel and axes 5 and 6 intersect (as on the UR arms): the "
        "component along the parallel axes fixes $q_1$, the orientation then $q_5$, the summed angle "
        "$\\theta = q_2 + q_3 + q_4$ and $q_6$, and a planar two-link problem $q_3$, $q_2$, $q_4$. ",
        "position3": "Three joints place the tool point; the orientation follows and is checked. ",
        "planar3": "All three axes are parallel (planar arm): the summed angle, then a two-link problem. ",
        "planar2": "Both axes are parallel (planar arm): a two-link problem; the orientation is checked. ",
    }[s.kind]
    if s.reversed:
        text = (
            "Read from the tool: the chain reversed, $T^{-1} = e^{[S'_n] q_n} \\cdots e^{[S'_1] q_1} M^{-1}$ "
            "with $h'_k = -R_M^T h_k$ through $R_M^T (p_k - t_M)$, solved for the target $T^{-1}$ "
            "(the table above and the axis numbers below are those of the reversed chain). " + text
        )
    if s.position == "parallel23":
        text += "Axes 2 and 3 are parallel."
    elif s.position == "intersect12" and s.shoulder is not None:
        text += f"Axes 1 and 2 meet at the shoulder point $o = {_vec(s.shoulder)}$."
    elif s.position == "intersect23" and s.elbow is not None:
        text += f"Axes 2 and 3 meet at the elbow point $o = {_vec(s.elbow)}$."
    splits = [st for st in plan.steps if st.branches == 2]
    branches = (
        f"{len(splits)} two-branch steps ({', '.join(st.var for st in splits)}) give at most "
        f"{plan.max_solutions} solutions. Every branch is computed; rows whose subproblem was clamped or "
        "singular are verified against the pose, revolute joints are wrapped by $2\\pi$ "
        "into the joint limits, "
        "duplicates are merged."
    )
    md = render(
        "derive/analytic_ik.md.j2",
        robot=display_name(robot.name),
        n=plan.n,
        structure=robot.ets.structure,
        version=__version__,
        joints=joints,
        M=sp.latex(_short(sp.Matrix(g.M))),
        ends=_ends(plan.base, plan.tool),
        structure_text=text,
        wrist=_vec(s.wrist) if s.wrist is not None and s.kind == "spherical_wrist" else "",
        steps=steps,
        branches=branches,
    )
    return md if fmt == "markdown" else latex_document(md)
