"""The kinematics of a tree as one straight-line program: every frame's pose and Jacobian.

The tree is walked depth first with the running pose of :mod:`symkin.symbolic.program` (exact
constants, quarter turns as column swaps, merged rotations about one axis); at a branch the walk
is forked, so the part of the tree two frames share (a torso, a hip) is computed once. Every
frame's pose and base-frame Jacobian columns ``(w_a x (p_f - p_a) ; w_a)`` (Haviland and Corke,
Manipulator Differential Kinematics, Part 1, IEEE RAM 2023, eqs 31-34, with frame f in place
of the end effector) are written through :class:`~symkin.symbolic.program.Program`, whose value
numbering names every shared subexpression once. A mimic slot moves by ``m q_j + c`` and adds
``m`` times its column to joint j's (the chain rule). Size and time grow linearly with the number
of segments plus, per frame, the joints on its path.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import sympy as sp

from symkin.model.ets import ET, Const
from symkin.symbolic.cse import OpCounts
from symkin.symbolic.fold import Fixed, fold_constants
from symkin.symbolic.program import Program, _cross, _matrix, _Walk, move, program_code

__all__ = ["TreeProgram", "derive_tree_program", "tree_functions", "TREE_FUNCTIONS"]

# The functions every tree kernel has; per frame k also fkine_k, jacob0_k, jacobe_k, fkine_jacob0_k.
TREE_FUNCTIONS: dict[str, str] = {
    "fkine_all": "Pose of every frame in the base frame, (F, 4, 4), frames in order.",
    "jacob0_all": "Base-frame Jacobian of every frame, (F, 6, n), rows (v, omega); 0 off a frame's path.",
    "fkine_jacob0_all": "Poses (F, 4, 4) and base-frame Jacobians (F, 6, n) of every frame together.",
}
PER_FRAME: dict[str, str] = {
    "fkine": "Pose of frame {k} ({name}) in the base frame, 4x4.",
    "jacob0": "Base-frame Jacobian of frame {k} ({name}), (6, n), rows (v, omega); 0 off its path.",
    "jacobe": "Jacobian of frame {k} ({name}) in that frame, (6, n), rows (v, omega) (eq 16).",
    "fkine_jacob0": "Pose (4, 4) and base-frame Jacobian (6, n) of frame {k} ({name}) together.",
}


@dataclass(frozen=True, eq=False)
class TreeProgram:
    """A tree's kinematics as straight-line code: ``lines`` assign ``t0, t1, ...`` in order.

    Per frame (in ``frames`` order): ``T`` (4x4), ``J0`` and ``Je`` (6xn). ``links`` holds the
    pose after each segment (depth first; used by the derivation; None for a fixed segment whose
    constants were folded into the next one). ``marks`` ends each section of ``lines``:
    ``("segment k", end)`` per segment, then ``("frame k", end)`` per frame.
    """

    name: str
    q: tuple[sp.Symbol, ...]
    lines: tuple[tuple[sp.Symbol, sp.Expr], ...]
    frames: tuple[str, ...]
    T: tuple[sp.Matrix, ...]
    J0: tuple[sp.Matrix, ...]
    Je: tuple[sp.Matrix, ...]
    links: tuple[sp.Matrix | None, ...]
    marks: tuple[tuple[str, int], ...]

    @property
    def n(self) -> int:
        return len(self.q)


def derive_tree_program(
    tree: object,
    qs: Sequence[sp.Symbol],
    constant: Callable[[Const], sp.Expr],
    name: str | None = None,
    frame_jacobians: bool = True,
    fold: bool = False,
) -> TreeProgram:
    """Derive the pose, base-frame and (``frame_jacobians``) frame-expressed Jacobian of every
    frame of ``tree`` (a :class:`symkin.Tree`) as one program (module docstring).

    ``fold``: the constants of a fixed segment that is no frame and has one child are walked with
    the child's, and each long run of constants, or run with two or more rotations by arbitrary
    angles, becomes one numeric transform (:func:`symkin.symbolic.fold.fold_constants`;
    ``constant`` then does not see them): a chain of many fixed links costs one transform."""
    segments, slots = tree.segments, tree.slots  # type: ignore[attr-defined]
    n = len(qs)
    P = Program()
    walks: list[_Walk] = []
    joint_axes: dict[int, tuple[list[sp.Expr], list[sp.Expr]]] = {}  # slot -> (signed axis, origin)
    links: list[sp.Matrix | None] = []
    marks: list[tuple[str, int]] = []
    children = [0] * len(segments)
    for seg in segments:
        if seg.parent >= 0:
            children[seg.parent] += 1
    ends = set(tree.frame_segments)  # type: ignore[attr-defined]
    carried: list[tuple[ET, ...]] = []  # per segment: constants left for its child to walk
    for k, seg in enumerate(segments):
        ets = (carried[seg.parent] if seg.parent >= 0 else ()) + tuple(seg.ets)
        if fold and seg.slot is None and k not in ends and children[k] == 1:
            carried.append(ets)
            walks.append(_Walk(P) if seg.parent < 0 else walks[seg.parent])  # forked by the child
            links.append(None)
            marks.append((f"segment {k}", len(P.lines)))
            continue
        carried.append(())
        W = _Walk(P) if seg.parent < 0 else walks[seg.parent].fork()
        for e in fold_constants(ets) if fold else ets:
            if isinstance(e, Fixed):
                W.transform(e)
                continue
            i = e.axis.index
            if e.is_joint:
                s = slots[seg.slot]
                theta = sp.Rational(s.multiplier) * qs[s.joint] + sp.Rational(s.offset)
                joint_axes[seg.slot] = ([x * e.sign for x in W.column(i)], list(W.p))
                value = e.sign * theta
            else:
                value = constant(e.const)
                if value == 0:
                    continue
            move(W, e, value)
        walks.append(W)
        links.append(_matrix(*W.pose()))  # dead code in the kernels unless a frame needs it
        marks.append((f"segment {k}", len(P.lines)))
    zero3 = [sp.Integer(0)] * 3
    Ts, J0s, Jes = [], [], []
    for f, frame in enumerate(tree.frames):  # type: ignore[attr-defined]
        cols, pe = walks[tree.frame_segments[f]].pose()  # type: ignore[attr-defined]
        J0, Je = sp.zeros(6, n), sp.zeros(6, n)
        for k in tree.path_slots(frame):  # type: ignore[attr-defined]
            s = slots[k]
            w, p = joint_axes[k]
            v = _cross(P, w, P.vec([a - b for a, b in zip(pe, p)])) if s.revolute else w
            o = w if s.revolute else zero3
            m = sp.Rational(s.multiplier)
            if m != 1:
                v, o = P.vec([m * x for x in v]), P.vec([m * x for x in o])
            if s.is_mimic and any(x != 0 for x in J0[:, s.joint]):  # the joint it follows is on the path
                v = P.vec([a + b for a, b in zip(J0[:3, s.joint], v)])
                o = P.vec([a + b for a, b in zip(J0[3:, s.joint], o)])
            J0[:3, s.joint], J0[3:, s.joint] = sp.Matrix(v), sp.Matrix(o)
        for j in range(n if frame_jacobians else 0):  # in the frame: R^T v and R^T omega
            for r0 in (0, 3):
                col = list(J0[r0 : r0 + 3, j])
                if any(x != 0 for x in col):
                    Je[r0 : r0 + 3, j] = sp.Matrix(
                        P.vec([sum(c[r] * col[r] for r in range(3)) for c in cols])
                    )
        Ts.append(_matrix(cols, pe))
        J0s.append(J0)
        Jes.append(Je)
        marks.append((f"frame {f}", len(P.lines)))
    return TreeProgram(
        name=name or tree.name,  # type: ignore[attr-defined]
        q=tuple(qs),
        lines=tuple(P.lines),
        frames=tuple(tree.frames),  # type: ignore[attr-defined]
        T=tuple(Ts),
        J0=tuple(J0s),
        Je=tuple(Jes),
        links=tuple(links),
        marks=tuple(marks),
    )


def tree_functions(tp: TreeProgram) -> list:
    """The emitted functions of a tree kernel (:data:`TREE_FUNCTIONS`, then per frame
    :data:`PER_FRAME`), each the lines its outputs need."""
    from symkin.symbolic.functions import KinFunction

    T, J0 = tp.T, tp.J0
    out = [
        KinFunction("fkine_all", TREE_FUNCTIONS["fkine_all"], program_code(tp, {"T": T})),  # type: ignore[arg-type]
        KinFunction("jacob0_all", TREE_FUNCTIONS["jacob0_all"], program_code(tp, {"J": J0})),  # type: ignore[arg-type]
        KinFunction(
            "fkine_jacob0_all",
            TREE_FUNCTIONS["fkine_jacob0_all"],
            program_code(tp, {"T": T, "J": J0}),  # type: ignore[arg-type]
        ),
    ]
    for k, frame in enumerate(tp.frames):
        spec = {
            "fkine": {"T": T[k]},
            "jacob0": {"J": J0[k]},
            "jacobe": {"J": tp.Je[k]},
            "fkine_jacob0": {"T": T[k], "J": J0[k]},
        }
        for base, outs in spec.items():
            doc = PER_FRAME[base].format(k=k, name=safe_text(frame))
            out.append(KinFunction(f"{base}_{k}", doc, program_code(tp, outs)))  # type: ignore[arg-type]
    return out


def safe_text(text: str, limit: int = 80) -> str:
    """A name as text safe inside any generated comment, docstring or string literal."""
    out = "".join(c if c.isascii() and (c.isalnum() or c in "_-.:/+ ',()") else "?" for c in text)
    return out if len(out) <= limit else out[: limit - 3] + "..."


def total_ops(functions: list) -> OpCounts:
    return sum((f.code.counts for f in functions), OpCounts())
