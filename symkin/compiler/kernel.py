"""A model and its derived functions -> the :class:`~symkin.emit.kernel.Kernel` the emitters render."""

from __future__ import annotations

import math
from typing import Any

from symkin.emit.kernel import LINKED, Frame, Joint, Kernel
from symkin.model.frames import ChainTables
from symkin.model.tree import Tree

__all__ = ["kernel_of"]


def _joints(tree: Tree) -> tuple[Joint, ...]:
    prismatic = {s.joint for s in tree.slots if not s.revolute}
    return tuple(
        Joint(
            name,
            j not in prismatic,
            float(tree.qlim[0, j]),
            float(tree.qlim[1, j]),
            math.inf if math.isnan(tree.velocity[j]) else float(tree.velocity[j]),
        )
        for j, name in enumerate(tree.joint_names)
    )


def kernel_of(model: Any, tree: Tree, functions: list, command: str) -> Kernel:
    """The kernel of ``model`` (a Robot or a Tree; ``tree`` its tree) with the derived ``functions``."""
    frames = tuple(Frame(name, f) for f, name in enumerate(tree.frames))
    links = ChainTables.of(tree.chain().ets) if any(fn.kind == "link_poses" for fn in functions) else None
    aliases = (
        tuple((f"{kind}_frame", f"{kind}_link") for kind in LINKED) if links and len(frames) == 1 else ()
    )
    return Kernel(
        name=model.name,
        code_name=model.code_name,
        joints=_joints(tree),
        frames=frames,
        links=links,
        functions=tuple(functions),
        aliases=aliases,
        ets=str(tree.chain().ets) if tree.single_path else "",
        command=command,
    )
