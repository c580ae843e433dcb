"""The parts of a kinematic tree: segments (the constant ETS and the joint slot from a link to
its child) and joint slots (a slot's joint, with mimic multiplier and offset), and a serial chain's
segments and slots (:func:`chain_segments`)."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction

from symkin.model.ets import ET

__all__ = ["Segment", "Slot", "chain_segments"]


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


def chain_segments(
    ets: Sequence[ET], joint_names: Sequence[str], frame: str = "ee"
) -> tuple[tuple[Segment, ...], tuple[Slot, ...]]:
    """The segments and slots of a serial chain ``ets``: one segment per joint (the constant
    transforms before it, then the joint; its link ``link<k>``, k along the chain from 1), then a
    fixed one to ``frame`` with the constants after the last joint."""
    segments: list[Segment] = []
    slots: list[Slot] = []
    consts: list[ET] = []
    for e in ets:
        if not e.is_joint:
            consts.append(e)
            continue
        k, name = len(slots), joint_names[e.joint]  # type: ignore[index]
        segments.append(Segment(name, k - 1, f"link{k + 1}", (*consts, ET(e.axis, joint=k, flip=e.flip)), k))
        slots.append(Slot(name, k, e.joint, Fraction(1), Fraction(0), e.is_revolute, name))  # type: ignore[arg-type]
        consts = []
    segments.append(Segment(f"{frame}_fixed", len(segments) - 1, frame, tuple(consts)))
    return tuple(segments), tuple(slots)
