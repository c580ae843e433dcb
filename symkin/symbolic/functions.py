"""The set of functions every backend emits, each a CSE'd block of straight-line code.

A function has named outputs with fixed shapes (per single configuration). Backends render the
same :class:`KinFunction` list, so their entry points match one to one.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from symkin.model.robot import Robot
from symkin.symbolic.cse import CSEResult, OpCounts, cse_outputs
from symkin.symbolic.kinematics import SymbolicKinematics, derive

__all__ = ["KinFunction", "FUNCTION_DOCS", "kin_functions", "total_counts"]

FUNCTION_DOCS: dict[str, str] = {
    "fkine": "End-effector pose in the base frame, 4x4 (eq 1).",
    "link_poses": "Base-frame pose of each link frame right after its joint (eq 5), (n, 4, 4), chain order.",
    "jacob0": "Base-frame Jacobian, (6, n), rows (v, omega) (eqs 31-34).",
    "jacobe": "End-effector-frame Jacobian, (6, n), rows (v, omega) (eq 16).",
    "hessian0": "Base-frame Hessian, (n, 6, n), H[i] = dJ0/dq_i (seed 001 eq 20).",
    "hessiane": "End-effector-frame Hessian, (n, 6, n), H[i] = dJe/dq_i.",
    "fkine_jacob0": "Pose (4, 4) and base-frame Jacobian (6, n) together.",
    "jacob0_hessian0": "Base-frame Jacobian (6, n) and Hessian (n, 6, n) together.",
}


@dataclass(frozen=True, eq=False)
class KinFunction:
    """One emitted function: ``name``, docstring, and its CSE'd code with outputs in order."""

    name: str
    doc: str
    code: CSEResult

    @property
    def outputs(self) -> list[tuple[str, tuple[int, ...], tuple[sp.Expr, ...]]]:
        return [(k, shape, exprs) for k, (shape, exprs) in self.code.outputs.items()]


def kin_functions(robot: Robot, sk: SymbolicKinematics | None = None) -> list[KinFunction]:
    """Derive ``robot`` (unless ``sk`` is given) and CSE each emitted function."""
    sk = sk or derive(robot)
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


def total_counts(functions: list[KinFunction]) -> dict[str, OpCounts]:
    return {f.name: f.code.counts for f in functions}
