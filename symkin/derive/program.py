"""Program derivations: a tree's kinematics, or a long chain's as the one-frame tree's, as named
intermediates, link frame by link frame.

Beyond about seven joints the multiplied-out link frames, pose and Jacobian have far more terms
than a reader can use (a generic 12-joint chain: about 2 million nodes). The derivation then
follows the O(n) algorithm of Haviland and Corke (Manipulator Differential Kinematics, Part 1,
2023, eqs 31-34) the way the compiler computes it
(:func:`symkin.symbolic.program.derive_tree_program`; a chain is the tree of
:meth:`symkin.Tree.from_robot`): the tree walked depth first, each link frame from its parent's,
every new quantity named (``zeta_k``), so a part several frames share (a torso, a hip) appears once;
then each frame's pose and the nonzero columns of its Jacobian, cross products of named axes and
origins (a mimic joint's column added by the chain rule); for one frame also the Hessian by its
rule. The results are checked at 3 random points, to 30 digits, against the literal products of the
elementary transforms along each path (eqs 1, 5, 26-28), the Hessian against central differences
of the Jacobian, and the poses and Jacobians against the numeric reference :class:`symkin.Tree`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from fractions import Fraction
from typing import Any

import mpmath
import numpy as np
import sympy as sp

from symkin.derive.common import Derivation, Printer, aligned, et_matrix, generator, hessian_pattern, products
from symkin.errors import SymkinError, check_choice
from symkin.model.ets import ET, Const, rational_text
from symkin.model.latex import AXIS_LATEX, display_name, et_latex
from symkin.model.robot import Robot
from symkin.model.tree import Tree
from symkin.symbolic.kinematics import const_to_sympy
from symkin.symbolic.program import TreeProgram, derive_tree_program

__all__ = ["program_derivation", "tree_derivation", "LINES_PER_BLOCK"]

LINES_PER_BLOCK = 12  # assignments per displayed equation block
CHECK_TOL = 1e-12  # against the double-precision reference symkin.Tree


def _program(
    tree: Tree, constant: Any, values: Mapping[sp.Symbol, sp.Expr], reference: Tree
) -> tuple[TreeProgram, dict[str, str], Printer]:
    """The walk of ``tree`` (Hessians too for one frame), its checks (:func:`_checks`) and its printer."""
    q = tuple(sp.Symbol(f"q_{j + 1}", real=True) for j in range(tree.n))
    tp = derive_tree_program(tree, q, constant, frame_jacobians=False, hessians=len(tree.frames) == 1)
    return tp, _checks(tree, tp, constant, values, reference), Printer(q, tp.lines)


def program_derivation(robot: Robot, symbolic_constants: bool) -> tuple[Derivation, dict[str, Any], str]:
    """The :class:`symkin.derive.chain.Derivation` of ``robot`` in program form, the derivation of
    its one-frame tree (see the module), with the context of ``derive/program.md.j2`` and the LaTeX
    summary for Jupyter."""
    from symkin.derive.common import constants, shared_context, summary

    ets, C = robot.ets, constants(robot.ets, symbolic_constants)
    tree = Tree.from_robot(replace(robot, ets=C.ets))
    tp, checks, P = _program(tree, C.constant, C.values, Tree.from_robot(robot))
    q, im = tp.q, sp.ImmutableMatrix
    eta = [e.sign * q[e.joint] if e.joint is not None else C.eta[k] for k, e in enumerate(ets)]
    links = {s.joint: im(tp.links[s.segment]) for s in tree.slots}
    assert tp.H0[0] is not None
    D = Derivation(
        robot=robot,
        q=q,
        constants=dict(C.values),
        E=tuple(im(et_matrix(e.axis, eta[k])) for k, e in enumerate(ets)),
        T=im(tp.T[0]),
        links=tuple(links[j] for j in range(len(q))),
        ee=(),
        dT=(),
        J0=im(tp.J0[0]),
        J0_fast=im(tp.J0[0]),
        H0=tuple(map(im, tp.H0[0])),
        simplified=True,
        checks=checks,
        form="program",
        intermediates=tp.lines,
        sections=tp.marks,
    )
    names = {e.const: C.names[k] for k, e in enumerate(C.ets) if k in C.names}
    ctx = {**shared_context(D, P, C), **_walk_context(tree, tp, checks, P, names)}
    ctx["legend"] = P.legend()
    return D, ctx, summary(D, P, C)


def tree_derivation(tree: Tree, fmt: str = "markdown", sections: Sequence[str] | str | None = None) -> str:
    """The derivation of ``tree`` as Markdown (or a LaTeX document with ``fmt="latex"``); ``sections``
    as in :func:`symkin.derive.chain.derive_steps`."""
    from symkin.core.version import __version__
    from symkin.derive.common import FORMATS, latex_document, shown_sections
    from symkin.emit.templates import render

    shown = shown_sections(sections, program=True)
    check_choice(fmt, FORMATS, "format")
    if tree.n == 0:
        raise SymkinError(f"tree {tree.name!r} has no joints: nothing to derive")
    tp, checks, P = _program(tree, const_to_sympy, {}, tree)
    ctx = _walk_context(tree, tp, checks, P, {})
    joints = []
    for j, name in enumerate(tree.joint_names):
        driven = [s for s in tree.slots if s.joint == j]
        moves = ", ".join(f"`{display_name(tree.segments[s.segment].link)}`" for s in driven)
        mimics = ", ".join(f"$\\theta_{{{k + 1}}} = {_theta(s)}$" for k, s in enumerate(tree.slots)
                           if s.joint == j and not _plain(s))  # fmt: skip
        kind = "revolute" if all(s.revolute for s in driven) else "prismatic"
        joints.append([f"$q_{{{j + 1}}}$", f"`q{j}`", f"`{display_name(name)}`", kind,
                       f"{moves} ({mimics})" if mimics else moves])  # fmt: skip
    source = display_name(tree.source).rstrip(".") + ". " if tree.source else ""
    text = render(
        "derive/program.md.j2",
        **ctx,
        robot=display_name(tree.name),
        n=tree.n,
        source=source,
        joint_map="$q_k$ is `q(k-1)`",
        version=__version__,
        joints=joints,
        joint_column="moves",
        ets="",
        factors=[],
        constants=[],
        legend=P.legend(),
        sections=shown,
    )
    return latex_document(text) if fmt == "latex" else text


# ---------------------------------------------------------------------------------------------
# The written walk


def _plain(s: Any) -> bool:
    """Whether a slot is its joint's own (theta = q_j)."""
    return s.multiplier == 1 and s.offset == 0


def _theta(s: Any) -> str:
    q = f"q_{{{s.joint + 1}}}"
    m, c = s.multiplier, s.offset
    text = q if m == 1 else f"-{q}" if m == -1 else f"{rational_text(m)}\\, {q}"
    if c != 0:
        text += f" {'+' if c > 0 else '-'} {rational_text(abs(c))}"
    return text


def _factor(tree: Tree, e: ET, names: Mapping[Const, str]) -> str:
    """One factor; a joint as its angle (or displacement) q_j, or theta_k when a mimic moves it."""
    if not e.is_joint:
        return et_latex(e, names.get(e.const))  # type: ignore[arg-type]
    s = tree.slots[e.joint]  # type: ignore[index]
    angle = f"q_{{{s.joint + 1}}}" if _plain(s) else f"\\theta_{{{e.joint + 1}}}"  # type: ignore[operator]
    return f"{AXIS_LATEX[e.axis.name]}({'-' if e.flip else ''}{angle})"


def _walk_context(
    tree: Tree, tp: TreeProgram, checks: Mapping[str, str], P: Printer, names: Mapping[Const, str]
) -> dict[str, Any]:
    """What the template writes of the walk: each link frame from its parent's (``steps``), each
    frame's pose and Jacobian columns (``frames``), the Hessian's pattern (one frame), the checks."""
    ends, lines, n, F = dict(tp.marks), tp.lines, len(tp.q), len(tree.frames)
    users: dict[int, list[str]] = {}
    for f in tree.frames:
        for s in tree.path(f):
            users.setdefault(s, []).append(display_name(f))

    def pose(k: int) -> str:
        return f"{{}}^{{0}}T_{{{k + 1}}}" if k >= 0 else ""

    steps, start = [], 0
    for k, seg in enumerate(tree.segments):
        end = ends[f"segment {k}"]
        parent = "base" if seg.parent < 0 else display_name(tree.segments[seg.parent].link)
        joint = f"joint `{display_name(seg.name)}`" if seg.slot is not None else "fixed"
        path = f"; on the path to {', '.join(f'`{u}`' for u in users.get(k, []))}" if F > 1 else ""
        product = " ".join(
            [pose(seg.parent)] * (seg.parent >= 0) + [_factor(tree, e, names) for e in seg.ets]
        )
        steps.append(
            {
                "title": f"link {k + 1}, `{display_name(seg.link)}` ({joint} from `{parent}`){path}",
                "lines": [f"{pose(k)} = {product or 'I'}", *_blocks(P, lines[start:end])],
                "matrix": f"{pose(k)} = {P.matrix(tp.links[k])}",
            }
        )
        start = end
    frames = []
    for f, name in enumerate(tree.frames):
        link = tree.frame_segments[f]
        J = tp.J0[f]
        cols = [f"J_{{{j + 1}}} = {P.matrix(sp.Matrix(J[:, j]).T)}^\\top" for j in range(n) if any(J[:, j])]
        lhs = "{}^{0}T_{e}" if F == 1 else pose(link)
        frames.append(
            {
                "name": display_name(name),
                "link": link + 1,
                "pose": [*_blocks(P, lines[start : ends[f"frame {f}"]]), f"{lhs} = {P.matrix(tp.T[f])}"],
                "jacobian": [*_blocks(P, lines[ends[f"frame {f}"] : ends[f"frame {f} J0"]]), *cols],
                "zero": n - len(cols),
            }
        )
        start = ends[f"frame {f} Je"]
    ctx: dict[str, Any] = {
        "F": F,
        "S": len(tree.segments),
        "shared": sum(1 for v in users.values() if len(v) > 1),
        "mimic": any(not _plain(s) for s in tree.slots),
        "nodes": len(lines),
        "steps": steps,
        "frames": frames,
        "checks": "; ".join(f"{k}: {'ok' if v != 'failed' else 'FAILED'}" for k, v in checks.items()),
        "hessian": "",
    }
    if F == 1 and tp.H0[0] is not None:
        ctx["hessian"], ctx["hessian_lines"] = hessian_pattern(P, tp.H0[0]), ends["H"] - ends["frame 0 Je"]
    return ctx


def _blocks(P: Printer, lines: Sequence[tuple[sp.Symbol, sp.Expr]]) -> list[str]:
    """Assignments as aligned blocks of at most :data:`LINES_PER_BLOCK` lines."""
    out = []
    for i in range(0, len(lines), LINES_PER_BLOCK):
        out.append(aligned(f"{P.names[s]} &= {P(e)}" for s, e in lines[i : i + LINES_PER_BLOCK]))
    return out


# ---------------------------------------------------------------------------------------------
# Checks at random points, 30 digits


def _checks(
    tree: Tree, tp: TreeProgram, constant: Any, values: Mapping[sp.Symbol, sp.Expr], reference: Tree
) -> dict[str, str]:
    """Compare the program at 3 random points, to 30 digits, with the literal products of the
    elementary transforms along each path (eqs 1 and 5; each Jacobian column from the derivative of
    its factor, eqs 26-28, times a mimic joint's multiplier), its Hessian (one frame) with central
    differences of its Jacobian along a random direction (eq 20), and, in double precision, its poses
    and Jacobians with the numeric ``reference`` (``tree`` with the constants' values)."""
    from symkin.derive.common import mp_function

    consts, q, n = list(values), list(tp.q), len(tp.q)
    H0 = tp.H0[0] if len(tp.H0) == 1 else None
    groups = [tp.T, tp.links, tp.J0, H0 or ()]
    f = mp_function(tp.lines, q + consts, [x for g in groups for M in g for x in M])
    keys = ["eq 1: T", "eq 5: link frames", "eqs 26-28 and 31-34: J0", "symkin.Tree"] + ["eq 20: H0"] * bool(
        H0
    )
    worst = dict.fromkeys(keys, 0.0)
    v = [mpmath.mpf(float(x)) for x in np.random.default_rng(1).uniform(-1, 1, n)]  # a direction for eq 20

    def diff(key: str, a: Sequence[Any], b: Any) -> None:  # the largest |a - b| so far (b: a list or matrix)
        b = [x for row in b.tolist() for x in row] if isinstance(b, mpmath.matrix) else b
        worst[key] = max(worst[key], float(max((abs(x - y) for x, y in zip(a, b, strict=True)), default=0)))

    with mpmath.workdps(30):
        cvals = [mpmath.mpf(sp.N(values[c], 40)) for c in consts]
        for qf in reference.random_q(3, seed=1):
            qv = [mpmath.mpf(float(x)) for x in qf]
            flat = iter(f(*qv, *cvals))
            T, links, J0, H = ([[next(flat) for _ in range(len(M))] for M in g] for g in groups)
            E = {e: _literal(tree, e, qv, constant, values) for s in tree.segments for e in s.ets}
            poses: list[Any] = []
            for s in tree.segments:
                start = poses[s.parent] if s.parent >= 0 else mpmath.eye(4)
                poses.append(products([E[e] for e in s.ets], start)[0][-1])
                diff("eq 5: link frames", links[len(poses) - 1], poses[-1])
            Tr, Jr = reference.fkine_jacob0_all(np.array(qf, float))
            for fr, frame in enumerate(tree.frames):
                path = [e for k in tree.path(frame) for e in tree.segments[k].ets]
                prefix, suffix = products([E[e] for e in path], mpmath.eye(4))
                diff("eq 1: T", T[fr], prefix[-1])
                J = mpmath.zeros(6, n)
                for i, e in enumerate(path):
                    if e.is_joint:  # dT/dtheta (eq 26) and its column (eqs 27-28), times the multiplier
                        s = tree.slots[e.joint]  # type: ignore[index]
                        dT = prefix[i] * (e.sign * generator(e.axis, mpmath)) * E[e] * suffix[i + 1]
                        S = dT[:3, :3] * prefix[-1][:3, :3].T
                        col = [dT[0, 3], dT[1, 3], dT[2, 3], S[2, 1], S[0, 2], S[1, 0]]
                        for r in range(6):
                            J[r, s.joint] += _mp(s.multiplier) * col[r]
                diff("eqs 26-28 and 31-34: J0", J0[fr], J)
                diff("symkin.Tree", T[fr] + J0[fr], [*Tr[fr].flat, *Jr[fr].flat])
            if H0:  # eq 20 along v: sum_i v_i H_i = dJ(q + h v)/dh, by central differences
                h = mpmath.mpf(10) ** -12
                Ju, Jd = (f(*[a + sign * h * b for a, b in zip(qv, v)], *cvals) for sign in (1, -1))
                k = 16 * len(tp.T) + 16 * len(tp.links)
                fd = [(a - b) / (2 * h) for a, b in zip(Ju[k : k + 6 * n], Jd[k : k + 6 * n])]
                diff("eq 20: H0", [sum(v[i] * H[i][m] for i in range(n)) for m in range(6 * n)], fd)
    # central differences with step 1e-12 at 30 digits are exact to about 1e-18
    bound = {"eq 20: H0": 1e-15, "symkin.Tree": CHECK_TOL}
    out = {k: ("numeric" if v < bound.get(k, 1e-20) else "failed") for k, v in worst.items()}
    out[f"symkin.Tree: largest difference {worst['symkin.Tree']:.1e} (tolerance {CHECK_TOL:g})"] = out.pop(
        "symkin.Tree"
    )
    return out


def _literal(tree: Tree, e: ET, q: Sequence[Any], constant: Any, values: Mapping[sp.Symbol, sp.Expr]) -> Any:
    """The elementary transform ``e`` of a segment as an mpmath matrix (Fig. 2): a joint's at the
    angle of its slot, ``sign (m q_j + c)``; a constant's value with ``values`` substituted."""
    if e.is_joint:
        s = tree.slots[e.joint]  # type: ignore[index]
        return et_matrix(e.axis, e.sign * (_mp(s.multiplier) * q[s.joint] + _mp(s.offset)), mpmath)
    return et_matrix(e.axis, mpmath.mpf(sp.N(constant(e.const).xreplace(dict(values)), 40)), mpmath)


def _mp(x: Fraction) -> Any:
    return mpmath.mpf(x.numerator) / x.denominator
