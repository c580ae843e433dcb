"""Exact symbolic kinematics of an ETS (sympy): pose, link frames, Jacobians and Hessians.

Built the way that keeps the expressions small (see ``shared/notes/measurements.md``):

- the pose is kept as three rotation columns and a translation; an elementary transform touches
  only the columns it acts on, and a rotation by a multiple of pi/2 is a signed column swap;
- consecutive rotations about the same axis, separated only by translations, are merged into one
  rotation by the summed angle (``cos(q1 + q2)``, the ``c12`` of a planar arm), since translations
  do not change the orientation;
- Jacobian columns come from the frames before each joint (eqs 31-34):
  ``J_a = (w_a x (p_e - p_a); w_a)`` for revolute and ``(w_a; 0)`` for prismatic joints;
- Hessian blocks come from Jacobian columns (eq 20 and Appendix I of Haviland and Corke, Maximising
  Manipulability During Resolved-Rate Motion Control, 2020): for b <= a (chain
  order), ``dJ_a/dq_b = (w_b x Jv_a; w_b x Jw_a)`` when b is revolute and 0 when b is prismatic;
  for b > a, ``dJ_a/dq_b = (w_a x Jv_b; 0)`` when a is revolute and 0 when a is prismatic.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass

import sympy as sp

from symkin.errors import SymkinError
from symkin.model.ets import ET, ETS, Const
from symkin.model.robot import Robot
from symkin.symbolic.cse import tree_size
from symkin.symbolic.fold import Fixed, fold_constants
from symkin.symbolic.program import Frame, Program, _base_jacobian, _hessians, _matrix, _Walk, walk_joints

__all__ = ["SymbolicKinematics", "ExpansionTooLargeError", "derive", "const_to_sympy", "joint_symbols"]


def const_to_sympy(c: Const) -> sp.Expr:
    """The exact sympy value of an ETS constant."""
    out = sp.Rational(c.a.numerator, c.a.denominator) + sp.Rational(c.b.numerator, c.b.denominator) * sp.pi
    if c.atan2 is not None:

        def surd(s):  # noqa: ANN001, ANN202
            r = sp.Rational(abs(s.numerator), s.denominator)
            return sp.sqrt(r) if s >= 0 else -sp.sqrt(r)

        out += sp.atan2(surd(c.atan2[0]), surd(c.atan2[1]))
    return out


def joint_symbols(n: int) -> tuple[sp.Symbol, ...]:
    """The real joint symbols q0 .. q{n-1}."""
    return tuple(sp.Symbol(f"q{j}", real=True) for j in range(n))


def _cross(a: Sequence[sp.Expr], b: Sequence[sp.Expr]) -> list[sp.Expr]:
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _walk(
    elements: Iterable[ET | Fixed],
    qs: Sequence[sp.Symbol],
    constant: Callable[[Const], sp.Expr],
    sign: int,
    links: list[sp.Matrix] | None = None,
) -> tuple[_Walk, list[Frame]]:
    """Apply ``elements`` in order (``sign=-1``: their inverses) to a pose whose every entry is one
    expression, recording each joint's axis and origin just before it, and (into ``links``) the pose
    right after it."""
    pose = _Walk(Program(inline=True))
    frames: list[Frame] = []
    for frame in walk_joints(pose, elements, qs, constant, sign):
        frames.append(frame)
        if links is not None:
            links.append(_matrix(*pose.pose()))
    return pose, frames


def _ee_frame(
    elements: Sequence[ET | Fixed], qs: Sequence[sp.Symbol], constant: Callable[[Const], sp.Expr]
) -> tuple[sp.Matrix, list[sp.Matrix]]:
    """End-effector-frame Jacobian and Hessian from the inverse chain walked from the end effector.

    With u_a the joint axes and p'_a the joint origins in the end-effector frame (the inverse ETS
    E_M^-1 ... E_1^-1), ``Je_a = (p'_a x u_a; u_a)`` (revolute) or ``(u_a; 0)`` (prismatic). For
    b <= a (chain order) dJe_a/dq_b = 0; for b > a, with du = u_a x u_b and
    dr = u_b x (p'_a - p'_b) when b is revolute (du = 0, dr = u_b when b is prismatic):
    ``dJe_a/dq_b = (du x r_a + u_a x dr; du)`` for revolute a (r_a = -p'_a), ``(du; 0)`` for prismatic a.
    """
    n = len(qs)
    _, frames = _walk(reversed(tuple(elements)), qs, constant, -1)
    ordered = frames[::-1]  # chain order
    zero3 = [sp.Integer(0)] * 3
    Je = sp.zeros(6, n)
    cols = []
    for j, revolute, u, p in ordered:
        r = [-x for x in p]
        v = _cross(u, r) if revolute else u
        w = u if revolute else zero3
        cols.append((v, w, r))
        Je[:3, j], Je[3:, j] = sp.Matrix(v), sp.Matrix(w)
    He = [sp.zeros(6, n) for _ in range(n)]
    for kb, (jb, rev_b, ub, pb) in enumerate(ordered):
        for ka, (ja, rev_a, ua, pa) in enumerate(ordered[:kb]):
            if rev_b:
                du = _cross(ua, ub)
                dr = _cross(ub, [x - y for x, y in zip(pa, pb)])
            else:
                du, dr = zero3, ub
            if rev_a:
                r_a = cols[ka][2]
                dv = [x + y for x, y in zip(_cross(du, r_a), _cross(ua, dr))]
                dw = du
            else:
                dv, dw = du, zero3
            He[jb][:3, ja], He[jb][3:, ja] = sp.Matrix(dv), sp.Matrix(dw)
    return Je, He


@dataclass(frozen=True, eq=False)
class SymbolicKinematics:
    """Exact kinematics of a robot. Joint-indexed outputs; ``links`` in chain order.

    Attributes:
        q: the joint symbols, by joint index.
        T: end-effector pose in the base frame, 4x4 (eq 1).
        links: pose of each link frame right after its joint (eq 5), chain order.
        J0, Je: base- and end-effector-frame Jacobians, 6xn, rows (v, omega).
        H0, He: Hessians, n matrices 6xn, ``H[i] = dJ/dq_i``.
    """

    name: str
    ets: ETS
    q: tuple[sp.Symbol, ...]
    T: sp.Matrix
    links: tuple[sp.Matrix, ...]
    J0: sp.Matrix
    Je: sp.Matrix
    H0: tuple[sp.Matrix, ...]
    He: tuple[sp.Matrix, ...]

    @property
    def n(self) -> int:
        return len(self.q)


class ExpansionTooLargeError(SymkinError):
    """Raised by :func:`derive` when the expanded T, J0 and H0 exceed ``max_nodes`` tree nodes."""


def derive(
    robot: Robot | ETS,
    constant: Callable[[Const], sp.Expr] = const_to_sympy,
    q: Sequence[sp.Symbol] | None = None,
    fold: bool = False,
    max_nodes: int | None = None,
) -> SymbolicKinematics:
    """Derive the exact pose, link frames, Jacobians and Hessians of ``robot``.

    ``constant`` maps each ETS constant to a sympy expression (exact by default; a teaching
    derivation can map link lengths to named symbols instead). ``fold``: long runs of constants,
    and runs with two or more rotations by arbitrary angles, become one numeric transform each
    first (:func:`symkin.symbolic.fold.fold_constants`; ``constant`` then does not see them), as
    the compiler derives. ``max_nodes``: raise :class:`ExpansionTooLargeError` as soon as T, J0 and H0
    written out as trees (:func:`symkin.symbolic.cse.tree_size`) exceed that many nodes, checked
    after each of them, so sizing the expanded form costs no more than building it up to that size.
    """
    ets = robot.ets if isinstance(robot, Robot) else robot
    name = robot.name if isinstance(robot, Robot) else "robot"
    n = ets.n
    qs = tuple(q) if q is not None else joint_symbols(n)
    elements = fold_constants(ets) if fold else tuple(ets)
    sizes: dict[sp.Basic, int] = {}
    total = 0

    def budget(exprs: Iterable[sp.Expr]) -> None:
        nonlocal total
        if max_nodes is not None:
            total += tree_size(list(exprs), sizes)
            if total > max_nodes:
                raise ExpansionTooLargeError(f"{name}: over {max_nodes} nodes expanded")

    links: list[sp.Matrix] = []
    pose, frames = _walk(elements, qs, constant, 1, links)
    cols, pe = pose.pose()
    T = _matrix(cols, pe)
    budget(T)
    J0 = _base_jacobian(pose.P, frames, pe, n)
    budget(J0)
    H0, _ = _hessians(pose.P, J0, None, [f[0] for f in frames])
    budget(x for h in H0 for x in h)
    Je, He = _ee_frame(elements, qs, constant)
    return SymbolicKinematics(name, ets, qs, T, tuple(links), J0, Je, tuple(H0), tuple(He))
