"""The set of functions every backend emits, each a block of straight-line code.

A function has named outputs with fixed shapes (per single configuration). Backends render the
same :class:`KinFunction` list, so their entry points match one to one.

Two strategies, chosen by size (:func:`choose_strategy`), both exact:

- ``"expanded"``: one expression per output (:func:`symkin.symbolic.kinematics.derive`), then one
  CSE per function. Smallest code for arms of up to about 7 joints, whose outputs read like the
  textbook (``cos(q1 + q2)``).
- ``"program"``: a straight-line program of named link frames and Jacobian columns
  (:func:`symkin.symbolic.program.derive_program`). Size and derivation time of FK and J grow
  linearly with the number of joints; the Hessians (an O(n^2) output) are written out up to
  :data:`UNROLL_MAX_JOINTS` joints and written as loops over the Jacobian columns beyond.

Both derive from the chain with its long runs of constants, and runs with two or more rotations by
arbitrary angles, folded into one numeric transform each (:mod:`symkin.symbolic.fold`: fixed
joints with rpy offsets, thousands of fixed links). Choosing between them builds the expanded
form only up to :data:`EXPANDED_MAX_NODES` (:func:`expanded_if_small`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import sympy as sp

from symkin.model.robot import Robot
from symkin.symbolic.cse import CSEResult, OpCounts, cse_outputs
from symkin.symbolic.kinematics import (
    ExpansionTooLargeError,
    SymbolicKinematics,
    const_to_sympy,
    derive,
    joint_symbols,
)
from symkin.symbolic.program import (
    PER_FRAME,
    TREE_FUNCTIONS,
    HessianLoop,
    KinematicProgram,
    TreeProgram,
    derive_program,
    program_code,
    safe_text,
)

__all__ = [
    "KinFunction",
    "FUNCTION_DOCS",
    "REFERENCES",
    "STRATEGIES",
    "EXPANDED_MAX_NODES",
    "UNROLL_MAX_JOINTS",
    "kin_functions",
    "derive_kinematics",
    "build_functions",
    "choose_strategy",
    "expanded_if_small",
    "total_counts",
    "fk_j_h_counts",
    "tree_functions",
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
# The program strategy writes the Hessians out (zeros and exact axes shrink them) up to this many
# joints, and as loops over the Jacobian columns beyond (O(n) code for an O(n^2) output): measured
# at 12 joints, written out 883 operations and 3.3 s of gcc, loops 1822 operations and 1.7 s.
UNROLL_MAX_JOINTS = 10


@dataclass(frozen=True, eq=False)
class KinFunction:
    """One emitted function: ``name``, docstring, and its code with outputs in order.

    With ``delegate`` set, the function calls that other function (whose code ``code`` is) and
    returns the outputs not listed in ``code.scratch``: one copy of the code, compiled once.
    """

    name: str
    doc: str
    code: CSEResult
    delegate: str | None = None

    @property
    def outputs(self) -> list[tuple[str, tuple[int, ...], tuple[sp.Expr, ...]]]:
        return [(k, shape, exprs) for k, (shape, exprs) in self.code.outputs.items()]


def choose_strategy(robot: Robot) -> tuple[str, SymbolicKinematics | KinematicProgram]:
    """The strategy for ``robot`` and its derivation: the program when the expanded T, J0 and H0
    written out as trees exceed :data:`EXPANDED_MAX_NODES` nodes (their CSE and code then grow
    about 2x per joint), else whichever gives fewer operations for FK + J + H after CSE (the
    expanded one on a tie: its code reads like the textbook, ``cos(q1 + q2)``)."""
    program = _derive_program(robot)
    sk = expanded_if_small(robot)
    if sk is None:
        return "program", program
    if fk_j_h_counts(sk).total <= fk_j_h_counts(program).total:
        return "expanded", sk
    return "program", program


def expanded_if_small(robot: Robot) -> SymbolicKinematics | None:
    """The expanded derivation when its T, J0 and H0 written out as trees stay under
    :data:`EXPANDED_MAX_NODES` nodes, else None (its CSE and code then grow about 2x per joint).

    The derivation stops as soon as one of T, J0 and H0 takes the size over the limit, so asking
    costs no more than building an expanded form of that size (sympy shares the subtrees;
    printing and CSE are what grow)."""
    if robot.n > 10:  # a generic 10-joint chain has 3e5 nodes: no need to build it to know
        return None
    try:
        return derive(robot, fold=True, max_nodes=EXPANDED_MAX_NODES)
    except ExpansionTooLargeError:
        return None


def _derive_program(robot: Robot) -> KinematicProgram:
    qs = joint_symbols(robot.n)
    return derive_program(robot.ets, qs, const_to_sympy, robot.name, robot.n <= UNROLL_MAX_JOINTS, fold=True)


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
    return [KinFunction(name, FUNCTION_DOCS[name], cse_outputs(outs, sk.q)) for name, outs in spec.items()]


def _program(kp: KinematicProgram) -> list[KinFunction]:
    J0, Je = {"J": kp.J0}, {"J": kp.Je}
    hessians: dict[str, tuple[dict, tuple[str, ...], tuple[HessianLoop, ...]]]
    if kp.H0 is not None and kp.He is not None:  # written out
        hessians = {"hessiane": ({"H": kp.He}, (), ()), "jacob0_hessian0": ({**J0, "H": kp.H0}, (), ())}
    else:  # loops over the Jacobian columns
        hessians = {
            "hessiane": (Je, ("J",), (HessianLoop("H", "J", "ee", kp.order),)),
            "jacob0_hessian0": (J0, (), (HessianLoop("H", "J", "base", kp.order),)),
        }
    spec = {
        "fkine": ({"T": kp.T}, (), ()),
        "link_poses": ({"links": kp.links}, (), ()),
        "jacob0": (J0, (), ()),
        "jacobe": (Je, (), ()),
        "fkine_jacob0": ({"T": kp.T, **J0}, (), ()),
        **hessians,
    }
    functions = {
        name: KinFunction(name, FUNCTION_DOCS[name], program_code(kp, outs, scratch, loops))
        for name, (outs, scratch, loops) in spec.items()
    }
    # hessian0 calls jacob0_hessian0 (its Jacobian a local array): the Hessian code compiles once
    both = functions["jacob0_hessian0"].code
    functions["hessian0"] = KinFunction(
        "hessian0", FUNCTION_DOCS["hessian0"], replace(both, scratch=("J",)), delegate="jacob0_hessian0"
    )
    return [functions[name] for name in FUNCTION_DOCS]


def tree_functions(tp: TreeProgram) -> list[KinFunction]:
    """The emitted functions of a tree kernel
    (:data:`~symkin.symbolic.program.TREE_FUNCTIONS`, then per frame
    :data:`~symkin.symbolic.program.PER_FRAME`), each the lines its outputs need."""
    T, J0 = tp.T, tp.J0
    every = {"fkine_all": {"T": T}, "jacob0_all": {"J": J0}, "fkine_jacob0_all": {"T": T, "J": J0}}
    out = [KinFunction(name, TREE_FUNCTIONS[name], program_code(tp, outs)) for name, outs in every.items()]
    for k, frame in enumerate(tp.frames):
        spec = {
            "fkine": {"T": T[k]},
            "jacob0": {"J": J0[k]},
            "jacobe": {"J": tp.Je[k]},
            "fkine_jacob0": {"T": T[k], "J": J0[k]},
        }
        for base, outs in spec.items():
            doc = PER_FRAME[base].format(k=k, name=safe_text(frame))
            out.append(KinFunction(f"{base}_{k}", doc, program_code(tp, outs)))
    return out


def derive_kinematics(robot: Robot, strategy: str | None = None) -> SymbolicKinematics | KinematicProgram:
    """The derivation of ``robot`` by ``strategy`` (default: by size, :func:`choose_strategy`)."""
    if strategy is None:
        return choose_strategy(robot)[1]
    if strategy == "expanded":
        return derive(robot, fold=True)
    if strategy == "program":
        return _derive_program(robot)
    raise ValueError(f"unknown strategy {strategy!r}: choose one of {', '.join(STRATEGIES)}")


def build_functions(derived: SymbolicKinematics | KinematicProgram) -> list[KinFunction]:
    """Every emitted function's code from a derivation (CSE for the expanded one)."""
    if isinstance(derived, KinematicProgram):
        return _program(derived)
    return _expanded(derived)


def kin_functions(robot: Robot, strategy: str | None = None) -> list[KinFunction]:
    """Derive ``robot`` and build every emitted function, by ``strategy`` (default: by size)."""
    return build_functions(derive_kinematics(robot, strategy))


def fk_j_h_counts(derived: SymbolicKinematics | KinematicProgram, hessian: bool = True) -> OpCounts:
    """Operations of FK + J0 (+ H0) computed together, after CSE: the size measure of the
    derivation (Panda: 525 with the expanded strategy)."""
    if isinstance(derived, KinematicProgram):
        outs = {"T": derived.T, "J": derived.J0}
        if hessian and derived.H0 is not None:
            return program_code(derived, {**outs, "H": derived.H0}).counts
        loops = (HessianLoop("H", "J", "base", derived.order),) if hessian else ()
        return program_code(derived, outs, hessians=loops).counts
    outs: dict[str, sp.Matrix | tuple[sp.Matrix, ...]] = {"T": derived.T, "J": derived.J0}
    if hessian:
        outs["H"] = derived.H0
    return cse_outputs(outs, derived.q).counts


def total_counts(functions: list[KinFunction]) -> dict[str, OpCounts]:
    return {f.name: f.code.counts for f in functions}
