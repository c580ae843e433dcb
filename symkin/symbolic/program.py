"""Kinematics of chains and trees as a straight-line program: link frames and Jacobian columns as
named intermediates.

The derivation of :mod:`symkin.symbolic.kinematics` multiplies the chain out into one expression
per output; its trees grow about 2x per joint, and common-subexpression elimination then has to
find the sharing again. This module builds the same quantities the way the O(n) algorithm of
Haviland and Corke (Manipulator Differential Kinematics, Part 1, IEEE RAM 2023, eqs 31-34)
computes them: one walk along the chain that names every rotation column and origin it produces,
so each assignment is a small local expression (a rotation of two columns, a translation along
one, a cross product) and the program grows linearly with the number of joints.

The local rules are the same as the expanded derivation's: exact constants, a rotation by a
multiple of pi/2 is a signed column swap (no assignment), rotations about one axis separated by
translations are merged into one rotation by the summed angle, and an assignment whose value is
a number, a symbol or a negated symbol is not materialised. Identical right-hand sides share one
name (value numbering), so nothing is computed twice and no CSE pass is needed afterwards. With
``fold``, a run of constants folded into one transform (:mod:`symkin.symbolic.fold`) is applied
as one step: each new column and the origin a combination of the old columns.

Hessians are not expanded: ``H0`` and ``He`` are written from the Jacobian columns by the
pairwise cross products of :class:`HessianLoop` (eq 20 and Appendix I of Haviland and Corke,
Maximising Manipulability During Resolved-Rate Motion Control, 2020), which the emitters turn
into loops.

A tree (:func:`derive_tree_program`) is walked depth first with the same running pose; at a
branch the walk is forked, so the part of the tree two frames share (a torso, a hip) is computed
once. Every frame's pose and base-frame Jacobian columns ``(w_a x (p_f - p_a) ; w_a)`` (eqs 31-34
with frame f in place of the end effector) are written through one :class:`Program`. A mimic
slot moves by ``m q_j + c`` and adds ``m`` times its column to joint j's (the chain rule). Size
and time grow linearly with the number of segments plus, per frame, the joints on its path.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from fractions import Fraction
from typing import Any

import sympy as sp

from symkin.model.ets import ET, ETS, Const
from symkin.symbolic.cse import CSEResult, HessianLoop, _flat, _total, floatify
from symkin.symbolic.fold import MIX, Fixed, fold_constants

__all__ = [
    "Program",
    "KinematicProgram",
    "derive_program",
    "chain_program",
    "HessianLoop",
    "program_code",
    "walk_joints",
    "TreeProgram",
    "derive_tree_program",
    "safe_text",
]

_HALF_PI = sp.pi / 2
_ZERO3 = [sp.Integer(0)] * 3


def _is_cheap(e: sp.Expr) -> bool:
    """Values used in place rather than named: numbers (exact constants), symbols, negated symbols."""
    if e.is_Atom or e.is_number:
        return True
    return bool(e.is_Mul and len(e.args) == 2 and e.args[0] == -1 and e.args[1].is_Atom)


class Program:
    """Straight-line code under construction: ``lines`` of (symbol, expression), in order.

    :meth:`let` names an expression (or returns the name it already has) and keeps numbers,
    symbols and negated symbols as they are. With ``inline`` nothing is named: every value stays
    one expression (the expanded derivation, :mod:`symkin.symbolic.kinematics`, walks so).
    """

    def __init__(self, prefix: str = "t", inline: bool = False) -> None:
        self.prefix = prefix
        self.inline = inline
        self.lines: list[tuple[sp.Symbol, sp.Expr]] = []
        self._names: dict[sp.Expr, sp.Symbol] = {}

    def let(self, expr: sp.Expr | int) -> sp.Expr:
        expr = sp.sympify(expr)
        if self.inline or _is_cheap(expr):
            return expr
        name = self._names.get(expr)
        if name is not None:
            return name
        neg = self._names.get(-expr)
        if neg is not None:
            return -neg
        name = sp.Symbol(f"{self.prefix}{len(self.lines)}", real=True)
        self.lines.append((name, expr))
        self._names[expr] = name
        return name

    def vec(self, exprs: Sequence[sp.Expr]) -> list[sp.Expr]:
        return [self.let(e) for e in exprs]


def _cos_sin(angle: sp.Expr) -> tuple[sp.Expr, sp.Expr]:
    if angle.is_number:
        k = angle / _HALF_PI
        if k.is_integer:
            return tuple(sp.Integer(v) for v in ((1, 0), (0, 1), (-1, 0), (0, -1))[int(k) % 4])  # type: ignore[return-value]
    return sp.cos(angle), sp.sin(angle)


def _cross(P: Program, a: Sequence[sp.Expr], b: Sequence[sp.Expr]) -> list[sp.Expr]:
    return P.vec([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


class _Walk:
    """The running pose of a walk along the chain, every column and origin a value of ``P`` (named,
    or one expression when ``P`` is inline)."""

    def __init__(self, P: Program) -> None:
        self.P = P
        one, zero = sp.Integer(1), sp.Integer(0)
        self.cols = [[one if i == j else zero for i in range(3)] for j in range(3)]
        self.p = [zero] * 3
        self.axis: int | None = None
        self.angle: sp.Expr = zero
        self._trig: tuple[sp.Expr, sp.Expr] | None = None

    def fork(self) -> _Walk:
        """A copy to walk on from here (a branch of a tree); both share the program."""
        W = _Walk.__new__(_Walk)
        W.P, W.cols, W.p = self.P, [list(c) for c in self.cols], list(self.p)
        W.axis, W.angle, W._trig = self.axis, self.angle, self._trig
        return W

    def _cs(self) -> tuple[sp.Expr, sp.Expr]:
        if self._trig is None:
            c, s = _cos_sin(self.angle)
            self._trig = (self.P.let(c), self.P.let(s))
        return self._trig

    def column(self, i: int) -> list[sp.Expr]:
        if self.axis is None or self.axis == i:
            return self.cols[i]
        j, k = MIX[self.axis]
        c, s = self._cs()
        cj, ck = self.cols[j], self.cols[k]
        if i == j:
            return self.P.vec([c * x + s * y for x, y in zip(cj, ck)])
        return self.P.vec([c * y - s * x for x, y in zip(cj, ck)])

    def effective(self) -> list[list[sp.Expr]]:
        return [self.column(i) for i in range(3)]

    def flush(self) -> None:
        if self.axis is not None:
            self.cols = self.effective()
            self.axis, self.angle, self._trig = None, sp.Integer(0), None

    def rotate(self, i: int, angle: sp.Expr) -> None:
        if self.axis is not None and self.axis != i:
            self.flush()
        self.axis = i
        self.angle = self.angle + angle
        self._trig = None

    def translate(self, i: int, d: sp.Expr) -> None:
        col = self.column(i)
        self.p = self.P.vec([p + d * x for p, x in zip(self.p, col)])

    def transform(self, f: Fixed) -> None:
        """Apply a folded constant transform (:mod:`symkin.symbolic.fold`), each entry of the new
        columns and origin one named value."""
        cols, p = f.apply(self.effective(), self.p)
        self.axis, self.angle, self._trig = None, sp.Integer(0), None
        self.p = self.P.vec(p)
        self.cols = [self.P.vec(c) for c in cols]

    def pose(self) -> tuple[list[list[sp.Expr]], list[sp.Expr]]:
        return self.effective(), list(self.p)


Frame = tuple[int, bool, list[sp.Expr], list[sp.Expr]]  # (joint, revolute, signed axis, origin)


def walk_joints(
    pose: Any,
    elements: Iterable[ET | Fixed],
    qs: Sequence[sp.Symbol],
    constant: Callable[[Const], sp.Expr],
    sign: int,
) -> Iterator[Frame]:
    """Apply ``elements`` in order to the running ``pose`` (``sign=-1``: their inverses; constants
    that are 0 skipped), and after each joint yield its frame: (joint, revolute, signed axis,
    origin) just before it."""
    for e in elements:
        if isinstance(e, Fixed):
            pose.transform(e if sign > 0 else e.inverse())
            continue
        frame: Frame | None = None
        if e.is_joint:
            value = sign * qs[e.joint] * e.sign
            axis = [x * e.sign for x in pose.column(e.axis.index)]
            frame = (e.joint, e.axis.is_rotation, axis, list(pose.p))
        else:
            value = sign * constant(e.const)
            if value == 0:
                continue
        (pose.rotate if e.axis.is_rotation else pose.translate)(e.axis.index, value)
        if frame is not None:
            yield frame


def _matrix(cols: list[list[sp.Expr]], p: list[sp.Expr]) -> sp.Matrix:
    return sp.Matrix([[cols[0][r], cols[1][r], cols[2][r], p[r]] for r in range(3)] + [[0, 0, 0, 1]])


def _jacobian_column(
    P: Program, revolute: bool, w: list[sp.Expr], p: list[sp.Expr], pe: Sequence[sp.Expr]
) -> tuple[list[sp.Expr], list[sp.Expr]]:
    """(v, omega) of a joint with signed axis ``w`` through ``p`` for the point ``pe`` (eqs 31-34):
    ``(w x (pe - p); w)`` when revolute, ``(w; 0)`` when prismatic."""
    if not revolute:
        return w, _ZERO3
    return _cross(P, w, P.vec([a - b for a, b in zip(pe, p)])), w


@dataclass(frozen=True, eq=False)
class KinematicProgram:
    """The kinematics of a chain (the one-frame case of :func:`derive_tree_program`): as a
    straight-line program (:func:`derive_program`), or every entry one expression
    (:func:`symkin.symbolic.kinematics.derive`; ``lines`` then empty).

    ``lines`` assign the intermediates ``t0, t1, ...`` in order (each a small expression of the
    joint symbols and earlier intermediates). The outputs are matrices over those names: ``T``
    (4x4, eq 1), ``links`` (the pose right after each joint, chain order, eq 5), ``J0`` and
    ``Je`` (6xn, rows (v, omega), eqs 31-34 and eq 16). ``order`` lists the joint index of each
    joint along the chain and ``revolute`` its kind. ``H0`` and ``He`` (n matrices 6xn,
    ``H[i] = dJ/dq_i``) are the Hessians written out by the rules of :class:`HessianLoop`, or None
    when they are left to loops. ``marks`` ends each section of ``lines``: ``("link k", end)``
    for each link frame, then ``"T"``, ``"J0"``, ``"Je"`` and ``"H"``.
    """

    name: str
    ets: ETS
    q: tuple[sp.Symbol, ...]
    lines: tuple[tuple[sp.Symbol, sp.Expr], ...]
    T: sp.Matrix
    links: tuple[sp.Matrix, ...]
    J0: sp.Matrix
    Je: sp.Matrix
    order: tuple[int, ...]
    revolute: tuple[bool, ...]
    H0: tuple[sp.Matrix, ...] | None = None
    He: tuple[sp.Matrix, ...] | None = None
    marks: tuple[tuple[str, int], ...] = ()

    @property
    def n(self) -> int:
        return len(self.q)


def derive_program(
    ets: ETS,
    qs: Sequence[sp.Symbol],
    constant: Callable[[Const], sp.Expr],
    name: str = "robot",
    hessians: bool = True,
    fold: bool = False,
) -> KinematicProgram:
    """Derive the pose, link frames and both Jacobians of the chain ``ets`` as one straight-line
    program, by :func:`derive_tree_program` of the chain as a one-frame tree; with ``hessians``
    also both Hessians, written out (O(n^2) lines; zeros and exact axes of the Jacobian columns
    make many of their cross products vanish or shrink). ``fold``: long runs of constants, and
    runs with two or more rotations by arbitrary angles, become one numeric transform each first
    (:func:`symkin.symbolic.fold.fold_constants`; ``constant`` then does not see them)."""
    from symkin.model.robot import Robot
    from symkin.model.tree import Tree

    tree = Tree.from_robot(Robot(ets, name=name))
    tp = derive_tree_program(tree, qs, constant, name, fold=fold, hessians=hessians)
    return chain_program(tree, tp, ets)


def chain_program(tree: Any, tp: TreeProgram, ets: ETS) -> KinematicProgram:
    """The :class:`KinematicProgram` of ``tp``, derived from the one-frame tree of the chain ``ets``."""
    n = len(tree.slots)
    marks = {"frame 0": "T", "frame 0 J0": "J0", "frame 0 Je": "Je", "H": "H"}
    marks.update({f"segment {k}": f"link {k}" for k in range(n)})
    return KinematicProgram(
        name=tp.name,
        ets=ets,
        q=tp.q,
        lines=tp.lines,
        T=tp.T[0],
        links=tuple(tp.links[:n]),  # type: ignore[arg-type]
        J0=tp.J0[0],
        Je=tp.Je[0],
        order=tuple(j for j, _ in tp.paths[0]),
        revolute=tuple(s.revolute for s in tree.slots),
        H0=tp.H0[0],
        He=tp.He[0],
        marks=tuple((marks[k], end) for k, end in tp.marks if k in marks),
    )


def _hessians(
    P: Program, J0: sp.Matrix, Je: sp.Matrix | None, order: Sequence[int]
) -> tuple[tuple[sp.Matrix, ...], tuple[sp.Matrix, ...]]:
    """Both Hessians (He only with ``Je``, else zeros) by the rules of :class:`HessianLoop`, each
    cross product a value of ``P``; ``order`` is the joint index of each joint along the chain."""
    n = len(order)
    H0 = [sp.zeros(6, n) for _ in range(n)]
    He = [sp.zeros(6, n) for _ in range(n)]

    def col(J: sp.Matrix, j: int) -> tuple[list[sp.Expr], list[sp.Expr]]:
        return list(J[:3, j]), list(J[3:, j])

    for kb, b in enumerate(order):
        vb, wb = col(J0, b)
        for a in order[kb:]:
            va, wa = col(J0, a)
            x = _cross(P, wb, va)
            H0[b][:3, a] = sp.Matrix(x)
            H0[b][3:, a] = sp.Matrix(_cross(P, wb, wa))
            if a != b:
                H0[a][:3, b] = sp.Matrix(x)
        if Je is None:
            continue
        vb, wb = col(Je, b)
        for a in order[:kb]:
            va, wa = col(Je, a)
            d = [x - y for x, y in zip(_cross(P, wa, vb), _cross(P, wb, va))]
            He[b][:3, a] = sp.Matrix(P.vec(d))
            He[b][3:, a] = sp.Matrix(_cross(P, wa, wb))
    return tuple(H0), tuple(He)


def needed_lines(lines: Sequence[tuple[sp.Symbol, sp.Expr]], roots: list[sp.Expr]) -> list[int]:
    """Indices of the lines the ``roots`` depend on, in program order (dead code dropped)."""
    index = {s: i for i, (s, _) in enumerate(lines)}
    need: set[int] = set()
    stack = [s for r in roots for s in r.free_symbols if s in index]
    while stack:
        i = index[stack.pop()]
        if i in need:
            continue
        need.add(i)
        stack.extend(s for s in lines[i][1].free_symbols if s in index and index[s] not in need)
    return sorted(need)


def program_code(
    kp: KinematicProgram | TreeProgram,
    outputs: Mapping[str, sp.Matrix | tuple[sp.Matrix, ...]],
    scratch: tuple[str, ...] = (),
    hessians: tuple[HessianLoop, ...] = (),
    gathered: tuple[str, ...] = (),
) -> CSEResult:
    """The lines of ``kp`` that ``outputs`` need, as straight-line code (see :class:`CSEResult`)."""
    memo: dict[sp.Basic, sp.Expr] = {}
    flat = _flat(outputs, memo)
    entries = [e for _, exprs in flat.values() for e in exprs]
    lines = tuple((kp.lines[i][0], floatify(kp.lines[i][1], memo)) for i in needed_lines(kp.lines, entries))
    counts = sum((h.counts for h in hessians), _total([e for _, e in lines] + entries))
    return CSEResult(lines, flat, counts, kp.q, scratch, hessians, "program", gathered)


# -- the walk over a tree, of which a chain is the one-frame case --------------------------------


@dataclass(frozen=True, eq=False)
class TreeProgram:
    """A model's kinematics as straight-line code: ``lines`` assign ``t0, t1, ...`` in order.

    Per frame (in ``frames`` order): ``paths`` (the joint and multiplier of each slot on its path,
    base first), ``T`` (4x4), ``J0`` and ``Je`` (6xn, contracted onto the joints); ``C0`` and
    ``Ce`` the slot columns of J0 and Je (6 x slots, before the multipliers) where the frame is not
    plain (a joint met twice or a multiplier other than 1: its Hessians come from them), else
    None; ``H0`` and ``He`` the Hessians written out (``hessians``, plain frames) or None.
    ``links`` holds the pose after each segment (depth first; None for a fixed segment whose
    constants were folded into the next one); ``link_frames`` the link frames of a serial chain
    (one plain frame whose every segment ends in its joint): the pose right after each joint, along
    the chain (eq 5), else (). ``marks`` ends each section of ``lines``:
    ``("segment k", end)`` per segment, then per frame ``("frame f", end)`` (its pose),
    ``("frame f J0", end)`` and ``("frame f Je", end)``, then ``("H", end)``.
    """

    name: str
    q: tuple[sp.Symbol, ...]
    lines: tuple[tuple[sp.Symbol, sp.Expr], ...]
    frames: tuple[str, ...]
    paths: tuple[tuple[tuple[int, Fraction], ...], ...]
    T: tuple[sp.Matrix, ...]
    J0: tuple[sp.Matrix, ...]
    Je: tuple[sp.Matrix, ...]
    C0: tuple[sp.Matrix | None, ...]
    Ce: tuple[sp.Matrix | None, ...]
    H0: tuple[tuple[sp.Matrix, ...] | None, ...]
    He: tuple[tuple[sp.Matrix, ...] | None, ...]
    links: tuple[sp.Matrix | None, ...]
    marks: tuple[tuple[str, int], ...]
    link_frames: tuple[sp.Matrix, ...] = ()

    @property
    def n(self) -> int:
        return len(self.q)

    def plain(self, f: int) -> bool:
        """Whether frame ``f``'s Jacobian columns are its slots' own (each joint met once, multipliers 1)."""
        joints = [j for j, _ in self.paths[f]]
        return len(set(joints)) == len(joints) and all(m == 1 for _, m in self.paths[f])


def _contract(
    P: Program, J: sp.Matrix, joint: int, m: Fraction, v: Sequence[sp.Expr], o: Sequence[sp.Expr]
) -> None:
    """Add ``m`` times the slot column (v ; o) to column ``joint`` of J (the chain rule of
    ``theta = m q_joint + c``)."""
    if m != 1:
        r = sp.Rational(m)
        v, o = P.vec([r * x for x in v]), P.vec([r * x for x in o])
    if any(x != 0 for x in J[:, joint]):  # another slot of this joint came first
        v = P.vec([a + b for a, b in zip(J[:3, joint], v)])
        o = P.vec([a + b for a, b in zip(J[3:, joint], o)])
    J[:3, joint], J[3:, joint] = sp.Matrix(v), sp.Matrix(o)


def _slot_matrix(columns: Sequence[tuple[Sequence[sp.Expr], Sequence[sp.Expr]]]) -> sp.Matrix:
    return sp.Matrix([[*v, *o] for v, o in columns]).T if columns else sp.zeros(6, 0)


def derive_tree_program(
    tree: object,
    qs: Sequence[sp.Symbol],
    constant: Callable[[Const], sp.Expr],
    name: str | None = None,
    frame_jacobians: bool = True,
    fold: bool = False,
    hessians: bool = False,
    inline: bool = False,
    budget: Callable[[Iterable[sp.Expr]], None] | None = None,
) -> TreeProgram:
    """Derive the pose, base-frame and (``frame_jacobians``) frame-expressed Jacobian of every
    frame of ``tree`` (a :class:`symkin.Tree`; a chain is the one-frame tree of
    :meth:`symkin.Tree.from_robot`) as one program (module docstring); with ``hessians`` also both
    Hessians of each plain frame, written out (:func:`_hessians`).

    The frame-expressed Jacobian comes from the inverse of the frame's path walked from the frame
    (eq 16 without the R^T products): with u_a the slot axes and p'_a the slot origins in the
    frame, its slot columns are ``(p'_a x u_a ; u_a)`` (revolute) or ``(u_a ; 0)`` (prismatic).

    ``fold``: the constants of a fixed segment that is no frame and has one child are walked with
    the child's, and each long run of constants, or run with two or more rotations by arbitrary
    angles, becomes one numeric transform (:func:`symkin.symbolic.fold.fold_constants`;
    ``constant`` then does not see them): a chain of many fixed links costs one transform.

    ``inline``: every value one expression (nothing named: the expanded derivation of
    :mod:`symkin.symbolic.kinematics`); ``budget`` is called with each frame's T, J0 and H0 as they
    are derived (it may raise to stop a derivation that grows too large)."""
    segments, slots = tree.segments, tree.slots  # type: ignore[attr-defined]
    n = len(qs)
    P = Program(inline=inline)
    check = budget or (lambda exprs: None)
    walks: list[_Walk] = []
    walked: list[tuple[ET | Fixed, ...]] = []  # per segment: the elements its walk applied
    joint_axes: dict[int, tuple[list[sp.Expr], list[sp.Expr]]] = {}  # slot -> (signed axis, origin)
    thetas = [sp.Rational(s.multiplier) * qs[s.joint] + sp.Rational(s.offset) for s in slots]  # by slot
    links: list[sp.Matrix | None] = []
    marks: list[tuple[str, int]] = []
    children = Counter(seg.parent for seg in segments)
    ends = set(tree.frame_segments)  # type: ignore[attr-defined]
    carried: list[tuple[ET, ...]] = []  # per segment: constants left for its child to walk
    for k, seg in enumerate(segments):
        ets = (carried[seg.parent] if seg.parent >= 0 else ()) + tuple(seg.ets)
        if fold and seg.slot is None and k not in ends and children[k] == 1:
            carried.append(ets)
            walks.append(_Walk(P) if seg.parent < 0 else walks[seg.parent])  # forked by the child
            walked.append(())
            links.append(None)
            marks.append((f"segment {k}", len(P.lines)))
            continue
        carried.append(())
        W = _Walk(P) if seg.parent < 0 else walks[seg.parent].fork()
        elements = fold_constants(ets) if fold else ets
        for slot, _, w, p in walk_joints(W, elements, thetas, constant, 1):
            joint_axes[slot] = (w, p)
        walks.append(W)
        walked.append(tuple(elements))
        links.append(_matrix(*W.pose()))  # dead code in the kernels unless a frame needs it
        marks.append((f"segment {k}", len(P.lines)))
    paths, Ts, J0s, Jes, C0s, Ces, H0s, Hes = [], [], [], [], [], [], [], []
    for f, frame in enumerate(tree.frames):  # type: ignore[attr-defined]
        on = [slots[k] for k in tree.path_slots(frame)]  # type: ignore[attr-defined]
        paths.append(tuple((s.joint, s.multiplier) for s in on))
        cols, pe = walks[tree.frame_segments[f]].pose()  # type: ignore[attr-defined]
        Ts.append(_matrix(cols, pe))
        check(Ts[-1])
        marks.append((f"frame {f}", len(P.lines)))
        J0, base = sp.zeros(6, n), []
        for k in tree.path_slots(frame):  # type: ignore[attr-defined]
            v, o = _jacobian_column(P, slots[k].revolute, *joint_axes[k], pe)
            base.append((v, o))
            _contract(P, J0, slots[k].joint, slots[k].multiplier, v, o)
        check(J0)
        marks.append((f"frame {f} J0", len(P.lines)))
        Je, own = sp.zeros(6, n), []
        if frame_jacobians:  # the path's inverse, walked from the frame
            elements = reversed([e for seg in tree.path(frame) for e in walked[seg]])  # type: ignore[attr-defined]
            inv = list(walk_joints(_Walk(P), elements, thetas, constant, -1))
            # slot columns (u x r ; u), r = -p' the frame's origin from the slot's (or (u ; 0))
            own = [(_cross(P, u, [-x for x in p]), u) if rev else (u, _ZERO3) for _, rev, u, p in inv]
            own.reverse()
            for s, (v, o) in zip(on, own):
                _contract(P, Je, s.joint, s.multiplier, v, o)
        marks.append((f"frame {f} Je", len(P.lines)))
        J0s.append(J0)
        Jes.append(Je)
        plain = len({s.joint for s in on}) == len(on) and all(s.multiplier == 1 for s in on)
        C0s.append(None if plain else _slot_matrix(base))
        Ces.append(None if plain or not frame_jacobians else _slot_matrix(own))
        H0, He = _hessians(P, J0, Je, [s.joint for s in on]) if hessians and plain else (None, None)
        check(x for h in H0 or () for x in h)
        H0s.append(H0)
        Hes.append(He)
    marks.append(("H", len(P.lines)))
    chain = [segments[s.segment] for s in slots]
    serial = len(paths) == 1 and len(paths[0]) == len(slots) and C0s[0] is None
    serial = serial and all(seg.ets and seg.ets[-1].is_joint for seg in chain)
    serial = serial and not any(s.is_mimic for s in slots)  # no chain Robot (Tree.chain refuses it)
    return TreeProgram(
        name=name or tree.name,  # type: ignore[attr-defined]
        q=tuple(qs),
        lines=tuple(P.lines),
        frames=tuple(tree.frames),  # type: ignore[attr-defined]
        paths=tuple(paths),
        T=tuple(Ts),
        J0=tuple(J0s),
        Je=tuple(Jes),
        C0=tuple(C0s),
        Ce=tuple(Ces),
        H0=tuple(H0s),
        He=tuple(Hes),
        links=tuple(links),
        marks=tuple(marks),
        link_frames=tuple(links[s.segment] for s in slots) if serial else (),  # type: ignore[misc]
    )


def safe_text(text: str, limit: int = 80) -> str:
    """A name as text safe inside any generated comment, docstring or string literal."""
    out = "".join(c if c.isascii() and (c.isalnum() or c in "_-.:/+ ',()") else "?" for c in text)
    return out if len(out) <= limit else out[: limit - 3] + "..."
