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
  for b > a, ``dJ_a/dq_b = (w_a x Jv_b; 0)`` when a is revolute and 0 when a is prismatic; the
  end-effector frame's likewise from the columns of Je (:class:`symkin.symbolic.cse.HessianLoop`).

It is the walk of :func:`symkin.symbolic.program.derive_tree_program` over the chain as a one-frame
tree, every value kept as one expression (an inline :class:`~symkin.symbolic.program.Program`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence

import sympy as sp

from symkin.errors import SymkinError
from symkin.model.ets import ET, ETS, Const
from symkin.model.robot import Robot
from symkin.symbolic.cse import tree_size
from symkin.symbolic.fold import Fixed
from symkin.symbolic.program import Frame, Program, _Walk, chain_program, derive_tree_program, walk_joints
from symkin.symbolic.program import KinematicProgram as SymbolicKinematics  # every entry one expression

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


def _walk(
    elements: Iterable[ET | Fixed],
    qs: Sequence[sp.Symbol],
    constant: Callable[[Const], sp.Expr],
    sign: int,
) -> tuple[_Walk, list[Frame]]:
    """Apply ``elements`` in order (``sign=-1``: their inverses) to a pose whose every entry is one
    expression, recording each joint's axis and origin just before it."""
    pose = _Walk(Program(inline=True))
    return pose, list(walk_joints(pose, elements, qs, constant, sign))


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
    from symkin.model.tree import Tree

    ets = robot if isinstance(robot, ETS) else robot.ets
    name = "robot" if isinstance(robot, ETS) else robot.name
    n = ets.n
    qs = tuple(q) if q is not None else joint_symbols(n)
    sizes: dict[sp.Basic, int] = {}
    total = 0

    def budget(exprs: Iterable[sp.Expr]) -> None:
        nonlocal total
        total += tree_size(list(exprs), sizes)
        if total > max_nodes:  # type: ignore[operator]
            raise ExpansionTooLargeError(f"{name}: over {max_nodes} nodes expanded")

    tree = Tree.from_robot(Robot(ets, name=name))
    tp = derive_tree_program(
        tree,
        qs,
        constant,
        name,
        fold=fold,
        hessians=True,
        inline=True,
        budget=None if max_nodes is None else budget,
    )
    return chain_program(tree, tp, ets)
