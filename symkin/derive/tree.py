"""The derivation of a kinematic tree: the shared walk once, then each frame's pose and Jacobian.

The tree is walked depth first exactly as the compiler does
(:func:`symkin.symbolic.program.derive_tree_program`): each link frame from its parent link's,
every new quantity named (``zeta_k``), so a part several frames share (a torso, a hip) appears
once, with the frames it serves. Then each frame's pose and the nonzero columns of its Jacobian
(Haviland and Corke, Manipulator Differential Kinematics, Part 1, 2023, eqs 31-34, frame f in
place of the end effector; a mimic joint's column added by the chain rule). The named quantities
are evaluated at random points and compared with the numeric reference :class:`symkin.Tree` (an
independent walk with 4x4 matrices).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import sympy as sp

from symkin.model.ets import rational_text
from symkin.model.latex import AXIS_LATEX, et_latex
from symkin.model.tree import Tree

__all__ = ["tree_derivation"]

CHECK_TOL = 1e-12


def _factor(e: Any) -> str:
    """One factor; a joint as the angle (or displacement) of its slot, theta_k."""
    if not e.is_joint:
        return et_latex(e)
    return f"{AXIS_LATEX[e.axis.name]}({'-' if e.flip else ''}\\theta_{{{e.joint + 1}}})"


def _theta(s: Any) -> str:
    q = f"q_{{{s.joint + 1}}}"
    m, c = s.multiplier, s.offset
    text = q if m == 1 else f"-{q}" if m == -1 else f"{rational_text(m)}\\, {q}"
    if c != 0:
        text += f" {'+' if c > 0 else '-'} {rational_text(abs(c))}"
    return text


def _checks(tree: Tree, tp: Any, samples: int = 3) -> float:
    """Largest difference of the program's poses and Jacobians from the numeric reference."""
    import mpmath

    from symkin.derive.common import mp_function

    outs = [x for T in tp.T for x in T] + [x for J in tp.J0 for x in J]
    f = mp_function(tp.lines, tp.q, outs)
    worst = 0.0
    F, n = len(tree.frames), tree.n
    for q in tree.random_q(samples, seed=1):
        with mpmath.workdps(30):
            got = np.array([float(v) for v in f(*[mpmath.mpf(float(x)) for x in q])])
        T, J = tree.fkine_jacob0_all(q)
        ref = np.concatenate((T.reshape(-1), J.reshape(-1)))
        assert got.size == 16 * F + 6 * n * F
        worst = max(worst, float(np.abs(got - ref).max()))
    return worst


def tree_derivation(tree: Tree, fmt: str = "markdown") -> str:
    """The derivation of ``tree`` as Markdown (or a LaTeX document with ``fmt="latex"``)."""
    from symkin.core.version import __version__
    from symkin.derive.common import FORMATS, Printer, latex_document
    from symkin.derive.program import _blocks
    from symkin.emit.templates import render
    from symkin.errors import SymkinError, check_choice
    from symkin.symbolic.kinematics import const_to_sympy
    from symkin.symbolic.program import derive_tree_program, safe_text

    check_choice(fmt, FORMATS, "format")
    if tree.n == 0:
        raise SymkinError(f"tree {tree.name!r} has no joints: nothing to derive")
    q = tuple(sp.Symbol(f"q_{j + 1}", real=True) for j in range(tree.n))
    tp = derive_tree_program(tree, q, const_to_sympy, frame_jacobians=False)
    P = Printer(q, tp.lines)
    ends = dict(tp.marks)
    users: dict[int, list[str]] = {}
    for f in tree.frames:
        for s in tree.path(f):
            users.setdefault(s, []).append(safe_text(f))
    kinds = {True: "revolute", False: "prismatic"}
    joints = []
    for j, name in enumerate(tree.joint_names):
        driven = [s for s in tree.slots if s.joint == j]
        follow = ", ".join(f"$\\theta_{{{k + 1}}} = {_theta(tree.slots[k])}$" for k in range(len(tree.slots))
                           if tree.slots[k].joint == j)  # fmt: skip
        joints.append([f"$q_{{{j + 1}}}$", f"`q{j}`", f"`{safe_text(name)}`",
                       kinds[all(s.revolute for s in driven)], follow])  # fmt: skip
    steps, start = [], 0
    for k, seg in enumerate(tree.segments):
        end = ends[f"segment {k}"]
        parent = "base" if seg.parent < 0 else safe_text(tree.segments[seg.parent].link)
        lhs = f"{{}}^{{0}}T_{{\\mathrm{{{k + 1}}}}}"
        before = "" if seg.parent < 0 else f"{{}}^{{0}}T_{{\\mathrm{{{seg.parent + 1}}}}}\\, "
        factors = " ".join(_factor(e) for e in seg.ets) or "I"
        rows = tp.lines[start:end]
        steps.append(
            {
                "title": f"link {k + 1}, `{safe_text(seg.link)}` (joint `{safe_text(seg.name)}` from "
                f"`{parent}`); on the path to {', '.join(f'`{u}`' for u in users.get(k, []))}",
                "product": f"{lhs} = {before}{factors}",
                "lines": _blocks(P, rows),
                "matrix": f"{lhs} = {P.matrix(tp.links[k])}",
            }
        )
        start = end
    frames = []
    for f, name in enumerate(tree.frames):
        end = ends[f"frame {f} J0"]
        rows = tp.lines[start:end]
        J = tp.J0[f]
        cols = [
            f"J_{{{j + 1}}} = {P.matrix(sp.Matrix(J[:, j]).T)}^\\top" for j in range(tree.n) if any(J[:, j])
        ]
        frames.append(
            {
                "name": safe_text(name),
                "link": tree.frame_segments[f] + 1,
                "lines": _blocks(P, rows),
                "pose": f"{{}}^{{0}}T_{{\\mathrm{{{tree.frame_segments[f] + 1}}}}} = {P.matrix(tp.T[f])}",
                "columns": cols,
                "zero": tree.n - len(cols),
            }
        )
        start = ends[f"frame {f} Je"]
    worst = _checks(tree, tp)
    verdict = "ok" if worst < CHECK_TOL else "FAILED"
    shared = sum(1 for v in users.values() if len(v) > 1)
    text = render(
        "derive/tree.md.j2",
        robot=safe_text(tree.name),
        n=tree.n,
        F=len(tree.frames),
        S=len(tree.segments),
        shared=shared,
        version=__version__,
        joints=joints,
        steps=steps,
        frames=frames,
        nodes=len(tp.lines),
        legend=P.legend(),
        check=f"largest difference {worst:.1e} ({verdict}, tolerance {CHECK_TOL:g})",
        source=safe_text(tree.source, limit=300),
    )
    if fmt == "latex":  # subsections as plain paragraphs
        return latex_document("\n".join(ln[4:] if ln.startswith("### ") else ln for ln in text.splitlines()))
    return text
