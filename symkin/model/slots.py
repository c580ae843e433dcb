"""The parts of a kinematic tree: segments (the constant ETS and the joint slot from a link to
its child) and joint slots (a slot's joint, with mimic multiplier and offset), and the Hessian of
one frame from the geometric Jacobian columns of the slots on its path."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

import numpy as np

from symkin.model.differential import path_hessian
from symkin.model.ets import ET

__all__ = ["Segment", "Slot", "hessian_of_columns"]


@dataclass(frozen=True)
class Segment:
    """One joint of the tree: from link ``parent`` (a segment index, -1 for the base link) to
    link ``link``; ``ets`` its origin and motion, the joint ET (if any) numbered ``slot``."""

    name: str
    parent: int
    link: str
    ets: tuple[ET, ...]
    slot: int | None = None


@dataclass(frozen=True)
class Slot:
    """A movable segment driven by joint ``joint`` of q: ``theta = multiplier q_joint + offset``.

    ``mimics`` names the joint it follows (its own name when it is an independent joint)."""

    name: str
    segment: int
    joint: int
    multiplier: Fraction
    offset: Fraction
    revolute: bool
    mimics: str = ""

    @property
    def is_mimic(self) -> bool:
        return self.mimics != self.name


def hessian_of_columns(Jv: np.ndarray, Jw: np.ndarray, slots: Sequence[Slot], n: int) -> np.ndarray:
    """Hessian (N, n, 6, n) from the geometric columns Jv, Jw (N, s, 3) of the slots on one path
    (base first; Jw = 0 for a prismatic slot), contracted onto the joints they follow."""
    A = np.zeros((len(slots), n))
    for i, sl in enumerate(slots):
        A[i, sl.joint] = float(sl.multiplier)
    return path_hessian(Jv, Jw, A)
