"""The one description every emitter takes: a kernel (named frames, functions with a
kind and a frame, aliases), made by the compiler from a model (:mod:`symkin.compiler.kernel`).

A chain is the kernel of one frame with link frames (``link_poses``, the ``*_link`` functions
and, under the chain's C names, the ``*_frame`` aliases of them); a tree of several frames has
every kind per frame (``fkine_3``), the functions of every frame (``fkine_all``) and the
``*_frame`` functions that take a frame index. Emitters never see a Robot or a Tree: what they
include follows from the kernel's data (how many frames, whether it has link frames, which
functions run Hessian loops).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from symkin.core.names import function_name
from symkin.model.derivatives import derivative_doc, derivative_kind

__all__ = ["Joint", "Frame", "Kernel", "link_text", "FRAMED", "FRAMED_DOCS", "LINKED"]

# the per-frame kinds every frame has (a model of several frames: also as <kind>_frame(q, k))
FRAMED = ("fkine", "jacob0", "jacobe", "fkine_jacob0", "hessian0", "hessiane", "jacob0_hessian0")
LINKED = ("fkine", "jacob0", "jacobe")  # the kinds with generated code for a chain's link frames
FRAMED_DOCS = {  # a model of several frames: the methods that take frame=
    "fkine": "Pose of the frame in the base frame, (4, 4) or (N, 4, 4).",
    "jacob0": "Base-frame Jacobian of the frame, (6, n) or (N, 6, n), rows (v, omega); 0 off its path.",
    "jacobe": "Jacobian of the frame in that frame, (6, n) or (N, 6, n), rows (v, omega) (eq 16).",
    "fkine_jacob0": "Pose and base-frame Jacobian of the frame together.",
    "hessian0": "Base-frame Hessian of the frame, (n, 6, n) or (N, n, 6, n), H[i] = dJ0/dq_i.",
    "hessiane": "Hessian of the frame in that frame, (n, 6, n) or (N, n, 6, n), H[i] = dJe/dq_i.",
    "jacob0_hessian0": "Base-frame Jacobian and Hessian of the frame together.",
}


@dataclass(frozen=True)
class Joint:
    """One joint of q: name, kind, limits (rad or m) and speed limit (inf when unknown)."""

    name: str
    revolute: bool
    lo: float
    hi: float
    qd: float = math.inf


@dataclass(frozen=True)
class Frame:
    """A frame of the kernel: its ``name`` and ``index`` (in the kernel's order; the Hessian loops
    carry the joints and multipliers of the slots on its path, :class:`symkin.symbolic.cse.HessianLoop`)."""

    name: str
    index: int


def link_text(links: Any) -> dict[str, list[str]]:
    """The link frames' tables (:class:`symkin.model.frames.ChainTables`: per joint along the chain
    its index, axis 0 x / 1 y / 2 z, sign -1 when flipped, kind) as C and Python literals."""
    return {
        "order": [str(int(j)) for j in links.order],
        "axis": [str(int(a)) for a in links.axis],
        "sign": [repr(float(x)) for x in links.sign],
        "revolute": [str(int(r)) for r in links.revolute],
    }


@dataclass(frozen=True)
class Kernel:
    """What an emitter renders.

    Attributes:
        name: the model's name (as given; quoted by each backend).
        code_name: its identifier in generated code (``symkin_<code_name>``, the C prefix and modules).
        joints: one per joint of q.
        frames: the named frames (a chain: its end effector, "ee").
        links: the link frames of a serial chain (:class:`symkin.model.frames.ChainTables`; link
            frame k is the frame right after the k-th joint along it), or None.
        functions: the generated functions (:class:`symkin.symbolic.functions.KinFunction`).
        aliases: exported name -> function name (a chain's ``fkine_frame`` is ``fkine_link``).
        ets: the ETS text of a serial chain, else "" (the headers then list the frames).
        command: the command that made it (for the headers).
    """

    name: str
    code_name: str
    joints: tuple[Joint, ...]
    frames: tuple[Frame, ...]
    links: Any
    functions: tuple[Any, ...]
    aliases: tuple[tuple[str, str], ...]
    ets: str
    command: str

    @property
    def n(self) -> int:
        return len(self.joints)

    @property
    def F(self) -> int:
        return len(self.frames)

    def name_of(self, kind: str, frame: int | None) -> str:
        """The function name of ``kind`` for ``frame`` (:func:`~symkin.core.names.function_name`)."""
        return function_name(kind, frame, self.F)

    @property
    def framed(self) -> tuple[str, ...]:
        """The per-frame kinds that also take a frame argument: :data:`FRAMED`, then the
        ``derivative<k>`` kinds the kernel has, by order."""
        orders = sorted({f.order for f in self.functions if f.order})
        return FRAMED + tuple(derivative_kind(k) for k in orders)

    def framed_doc(self, kind: str) -> str:
        """The docstring of the method ``kind(q, frame=None)`` of a model of several frames."""
        order = next((f.order for f in self.functions if f.kind == kind and f.order), 0)
        return derivative_doc(order, self.n, "the frame") if order else FRAMED_DOCS[kind]

    def table(self, kind: str) -> list[str]:
        """The function names of ``kind`` for every frame, in frame order."""
        return [self.name_of(kind, f.index) for f in self.frames]
