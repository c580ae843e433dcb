"""The set of functions every backend emits for a model, each a block of straight-line code.

A function has a kind (``fkine``, ``jacob0``, ...), the frame it is of (or None for every frame)
and named outputs with fixed shapes (per single configuration). Backends render the same
:class:`KinFunction` list, so their entry points match one to one. A chain is the one-frame tree
of :meth:`symkin.Tree.from_robot`: the kinds of its frame, named as the kinds
(:func:`symkin.core.names.function_name`), and ``link_poses``; a tree with more frames has them
per frame (``fkine_3``) and the ``*_all`` functions of every frame.

Two strategies, chosen by size (:func:`choose_strategy`), both exact:

- ``"expanded"``: one expression per output (:func:`symkin.symbolic.kinematics.derive`), then one
  CSE per function. Smallest code for arms of up to about 7 joints, whose outputs read like the
  textbook (``cos(q1 + q2)``).
- ``"program"``: a straight-line program of named link frames and Jacobian columns
  (:func:`symkin.symbolic.program.derive_tree_program`). Size and derivation time of FK and J grow
  linearly with the number of joints; the Hessians (an O(n^2) output) of a one-frame model are
  written out up to :data:`UNROLL_MAX_JOINTS` joints and written as loops over the Jacobian
  columns beyond, and for every frame of a model with several.

The expanded strategy needs one serial chain (:attr:`symkin.Tree.single_path`). Both derive from
the chain with its long runs of constants, and runs with two or more rotations by
arbitrary angles, folded into one numeric transform each (:mod:`symkin.symbolic.fold`: fixed
joints with rpy offsets, thousands of fixed links). Choosing between them builds the expanded
form only up to :data:`EXPANDED_MAX_NODES` (:func:`expanded_if_small`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import sympy as sp

from symkin.core.names import function_name
from symkin.model.tree import Tree, as_tree
from symkin.symbolic.cse import CSEResult, HessianLoop, OpCounts, cse_outputs
from symkin.symbolic.kinematics import (
    ExpansionTooLargeError,
    SymbolicKinematics,
    const_to_sympy,
    derive,
    joint_symbols,
)
from symkin.symbolic.program import TreeProgram, derive_tree_program, program_code, safe_text

__all__ = [
    "KinFunction",
    "FUNCTION_DOCS",
    "FRAME_DOCS",
    "REFERENCES",
    "STRATEGIES",
    "EXPANDED_MAX_NODES",
    "UNROLL_MAX_JOINTS",
    "kin_functions",
    "derive_kinematics",
    "build_functions",
    "choose_strategy",
    "expanded_if_small",
    "fk_j_h_counts",
]

FUNCTION_DOCS: dict[str, str] = {  # "Part 1": Haviland and Corke 2023; "MMC": Haviland and Corke 2020
    "fkine": "End-effector pose in the base frame, 4x4 (Part 1 eq 1).",
    "link_poses": "Base-frame pose of each link frame right after its joint, (n, 4, 4), chain order "
    "(Part 1 eq 5).",
    "jacob0": "Base-frame Jacobian, (6, n), rows (v, omega) (Part 1 eqs 31-34).",
    "jacobe": "End-effector-frame Jacobian, (6, n), rows (v, omega) (Part 1 eq 16).",
    "hessian0": "Base-frame Hessian, (n, 6, n), H[i] = dJ0/dq_i (MMC eq 20).",
    "hessiane": "End-effector-frame Hessian, (n, 6, n), H[i] = dJe/dq_i.",
    "fkine_jacob0": "Pose (4, 4) and base-frame Jacobian (6, n) together.",
    "jacob0_hessian0": "Base-frame Jacobian (6, n) and Hessian (n, 6, n) together.",
    "fkine_all": "Pose of every frame in the base frame, (F, 4, 4), frames in order.",
    "jacob0_all": "Base-frame Jacobian of every frame, (F, 6, n), rows (v, omega); 0 off a frame's path.",
    "fkine_jacob0_all": "Poses (F, 4, 4) and base-frame Jacobians (F, 6, n) of every frame together.",
}
FRAME_DOCS: dict[str, str] = {  # a model of several frames: the functions of frame {k}
    "fkine": "Pose of frame {k} ({name}) in the base frame, 4x4.",
    "jacob0": "Base-frame Jacobian of frame {k} ({name}), (6, n), rows (v, omega); 0 off its path.",
    "jacobe": "Jacobian of frame {k} ({name}) in that frame, (6, n), rows (v, omega) (eq 16).",
    "hessian0": "Base-frame Hessian of frame {k} ({name}), (n, 6, n), H[i] = dJ0/dq_i (MMC eq 20).",
    "hessiane": "Hessian of frame {k} ({name}) in that frame, (n, 6, n), H[i] = dJe/dq_i.",
    "fkine_jacob0": "Pose (4, 4) and base-frame Jacobian (6, n) of frame {k} ({name}) together.",
    "jacob0_hessian0": "Base-frame Jacobian (6, n) and Hessian (n, 6, n) of frame {k} ({name}) together.",
}
REFERENCES = (
    "Part 1 = Haviland and Corke, Manipulator Differential Kinematics, Part 1, IEEE Robotics and "
    "Automation Magazine, 2023; MMC = Haviland and Corke, Maximising Manipulability During "
    "Resolved-Rate Motion Control, 2020"
)
STRATEGIES = ("expanded", "program")
# Expanded trees of T, J0 and H0 above this many nodes use the program strategy: the Panda has
# 8.8e4, a generic 8-joint chain 1.1e5; CSE time and code size of the expanded form grow about
# 2x per joint beyond (see `symkin bench compile`).
EXPANDED_MAX_NODES = 100_000
# The program strategy writes the Hessians of a one-frame model out (zeros and exact axes shrink
# them) up to this many joints, and as loops over the Jacobian columns beyond (O(n) code for an
# O(n^2) output): measured at 12 joints, written out 883 operations and 3.3 s of gcc, loops 1822
# operations and 1.7 s.
UNROLL_MAX_JOINTS = 10
Derived = SymbolicKinematics | TreeProgram


@dataclass(frozen=True, eq=False)
class KinFunction:
    """One emitted function: its ``kind``, the ``frame`` it is of (None: every frame, or the link
    frames), its ``name`` (:func:`~symkin.core.names.function_name`), docstring, and its code with
    outputs in order.

    With ``delegate`` set, the function calls that other function (whose code ``code`` is) and
    returns the outputs not listed in ``code.scratch``: one copy of the code, compiled once.
    """

    kind: str
    frame: int | None
    name: str
    doc: str
    code: CSEResult
    delegate: str | None = None

    @property
    def outputs(self) -> list[tuple[str, tuple[int, ...], tuple[sp.Expr, ...]]]:
        return [(k, shape, exprs) for k, (shape, exprs) in self.code.outputs.items()]


def choose_strategy(model: Any) -> tuple[str, Derived]:
    """The strategy for ``model`` (a Robot or a Tree) and its derivation: the program when the
    model is not one serial chain, or when the expanded T, J0 and H0 written out as trees exceed
    :data:`EXPANDED_MAX_NODES` nodes (their CSE and code then grow about 2x per joint), else
    whichever gives fewer operations for FK + J + H after CSE (the expanded one on a tie: its code
    reads like the textbook, ``cos(q1 + q2)``)."""
    program = _derive_program(as_tree(model))
    sk = expanded_if_small(model)
    if sk is None:
        return "program", program
    if fk_j_h_counts(sk).total <= fk_j_h_counts(program).total:
        return "expanded", sk
    return "program", program


def expanded_if_small(model: Any) -> SymbolicKinematics | None:
    """The expanded derivation of a serial chain when its T, J0 and H0 written out as trees stay
    under :data:`EXPANDED_MAX_NODES` nodes, else None (its CSE and code then grow about 2x per
    joint; a model of several frames or with a mimic joint has none).

    The derivation stops as soon as one of T, J0 and H0 takes the size over the limit, so asking
    costs no more than building an expanded form of that size (sympy shares the subtrees;
    printing and CSE are what grow)."""
    tree = as_tree(model)
    if tree.n > 10 or not tree.single_path:  # a generic 10-joint chain has 3e5 nodes: no need to build it
        return None
    try:
        return derive(tree.chain(), fold=True, max_nodes=EXPANDED_MAX_NODES)
    except ExpansionTooLargeError:
        return None


def _derive_program(tree: Tree) -> TreeProgram:
    written = len(tree.frames) == 1 and tree.n <= UNROLL_MAX_JOINTS  # the Hessians written out
    return derive_tree_program(tree, joint_symbols(tree.n), const_to_sympy, fold=True, hessians=written)


def _function(
    kind: str, frame: int | None, frames: tuple[str, ...], code: CSEResult, **kw: Any
) -> KinFunction:
    F = len(frames)
    if F == 1 or frame is None:
        doc = FUNCTION_DOCS[kind]
    else:
        doc = FRAME_DOCS[kind].format(k=frame, name=safe_text(frames[frame]))
    return KinFunction(kind, frame, function_name(kind, frame, F), doc, code, **kw)


def _expanded(sk: SymbolicKinematics) -> list[KinFunction]:
    links = sk.links if sk.links else (sp.eye(4),)
    spec: dict[str, dict[str, sp.Matrix | tuple[sp.Matrix, ...]]] = {
        "fkine": {"T": sk.T},
        "link_poses": {"links": tuple(links)},
        "jacob0": {"J": sk.J0},
        "jacobe": {"J": sk.Je},
        "hessian0": {"H": sk.H0 or (sp.zeros(6, 0),)},
        "hessiane": {"H": sk.He or (sp.zeros(6, 0),)},
        "fkine_jacob0": {"T": sk.T, "J": sk.J0},
        "jacob0_hessian0": {"J": sk.J0, "H": sk.H0 or (sp.zeros(6, 0),)},
    }
    one = ("ee",)
    return [_function(kind, None if kind == "link_poses" else 0, one, cse_outputs(outs, sk.q))
            for kind, outs in spec.items()]  # fmt: skip


def _loops(tp: TreeProgram, f: int) -> tuple[tuple[dict, tuple[str, ...], tuple[HessianLoop, ...]], ...]:
    """(outputs, scratch, loops) of ``jacob0_hessian0`` and ``hessiane`` of frame ``f``: written out,
    or loops over J's columns (a plain frame) or over the slot columns C (multipliers applied)."""
    J0, Je = {"J": tp.J0[f]}, {"J": tp.Je[f]}
    if tp.H0[f] is not None:
        return ({**J0, "H": tp.H0[f]}, (), ()), ({"H": tp.He[f]}, (), ())
    order = tuple(j for j, _ in tp.paths[f])
    if tp.plain(f):
        return (
            (J0, (), (HessianLoop("H", "J", "base", order),)),
            (Je, ("J",), (HessianLoop("H", "J", "ee", order),)),
        )
    cols, mult = tuple(range(len(order))), tuple(float(m) for _, m in tp.paths[f])
    return (
        ({**J0, "C": tp.C0[f]}, ("C",), (HessianLoop("H", "C", "base", order, cols, mult),)),
        ({"C": tp.Ce[f]}, ("C",), (HessianLoop("H", "C", "ee", order, cols, mult),)),
    )


def _program(tp: TreeProgram) -> list[KinFunction]:
    frames, out = tp.frames, []
    if len(frames) > 1:
        every = {
            "fkine_all": {"T": tp.T},
            "jacob0_all": {"J": tp.J0},
            "fkine_jacob0_all": {"T": tp.T, "J": tp.J0},
        }
        out += [_function(kind, None, frames, program_code(tp, outs)) for kind, outs in every.items()]
    for f in range(len(frames)):
        both, ee = _loops(tp, f)
        spec = {
            "fkine": ({"T": tp.T[f]}, (), ()),
            "link_poses": ({"links": tp.link_frames}, (), ()) if f == 0 and tp.link_frames else None,
            "jacob0": ({"J": tp.J0[f]}, (), ()),
            "jacobe": ({"J": tp.Je[f]}, (), ()),
            "hessian0": None,
            "hessiane": ee,
            "fkine_jacob0": ({"T": tp.T[f], "J": tp.J0[f]}, (), ()),
            "jacob0_hessian0": both,
        }
        functions = {
            kind: _function(kind, None if kind == "link_poses" else f, frames, program_code(tp, *args))
            for kind, args in spec.items()
            if args is not None
        }
        # hessian0 calls jacob0_hessian0 (its Jacobian a local array): the Hessian code compiles once
        jh = functions["jacob0_hessian0"].code
        outs = {k: v for k, v in jh.outputs.items() if k not in jh.scratch}  # what jacob0_hessian0 returns
        code = replace(jh, outputs=outs, scratch=("J",))
        functions["hessian0"] = _function(
            "hessian0", f, frames, code, delegate=functions["jacob0_hessian0"].name
        )
        out += [functions[kind] for kind in spec if kind in functions]
    return out


def derive_kinematics(model: Any, strategy: str | None = None) -> Derived:
    """The derivation of ``model`` (a Robot or a Tree) by ``strategy`` (default: by size,
    :func:`choose_strategy`)."""
    if strategy is None:
        return choose_strategy(model)[1]
    if strategy == "expanded":
        tree = as_tree(model)
        if not tree.single_path:
            raise ValueError(f"{tree.name} is not one serial chain: it derives as one program, not expanded")
        return derive(tree.chain(), fold=True)
    if strategy == "program":
        return _derive_program(as_tree(model))
    raise ValueError(f"unknown strategy {strategy!r}: choose one of {', '.join(STRATEGIES)}")


def build_functions(derived: Derived) -> list[KinFunction]:
    """Every emitted function's code from a derivation (CSE for the expanded one)."""
    if isinstance(derived, TreeProgram):
        return _program(derived)
    return _expanded(derived)


def kin_functions(model: Any, strategy: str | None = None) -> list[KinFunction]:
    """Derive ``model`` and build every emitted function, by ``strategy`` (default: by size)."""
    return build_functions(derive_kinematics(model, strategy))


def fk_j_h_counts(derived: Derived, hessian: bool = True) -> OpCounts:
    """Operations of FK + J0 (+ H0) of the first frame computed together, after CSE: the size
    measure of the derivation (Panda: 525 with the expanded strategy)."""
    if isinstance(derived, TreeProgram):
        outs = {"T": derived.T[0], "J": derived.J0[0]}
        if not hessian:
            return program_code(derived, outs).counts
        both = _loops(derived, 0)[0]
        return program_code(derived, {**outs, **both[0]}, *both[1:]).counts
    outs: dict[str, sp.Matrix | tuple[sp.Matrix, ...]] = {"T": derived.T, "J": derived.J0}
    if hessian:
        outs["H"] = derived.H0
    return cse_outputs(outs, derived.q).counts
