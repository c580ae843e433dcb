"""Kept for pickles of compiled trees written by symkin 0.1.0 (they name this module's
``_rebuild``) and for code importing ``TreeKinematics``: a tree compiles into the one
:class:`symkin.Kinematics` (:mod:`symkin.runtime.kinematics`)."""

from __future__ import annotations

from typing import Any

from symkin.runtime.kinematics import Kinematics, load_kinematics

__all__ = ["TreeKinematics"]

TreeKinematics = Kinematics


def _rebuild(tree: Any, backend: str) -> Kinematics:
    """The compiled kinematics of ``tree`` on ``backend`` (the unpickler of 0.1.0's tree kinematics)."""
    return load_kinematics(tree, backend)
