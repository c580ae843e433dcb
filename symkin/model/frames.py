"""Frames at run time (NumPy only): validating a ``frame`` argument (a model's named frames, a
chain's link frames), the Jacobian of a link frame from the link poses, and :class:`LinkFrames`,
every method of a link frame from the generated ``fkine(q, frame=k)`` and ``jacob0(q, frame=k)``.

Link frame ``k`` is the frame right after the k-th joint along the chain, ``link_poses(q)[k]``
(chain order; for every built-in and imported robot the k-th joint along the chain is joint k).
"""

from __future__ import annotations

import operator
from collections.abc import Sequence
from typing import Any

import numpy as np

from symkin.errors import FrameError
from symkin.model.differential import FrameMethods, chain_hessian, rotate_rows
from symkin.model.kinematics import cross

__all__ = ["frame_index", "frame_position", "resolve_frame", "ChainTables", "frame_jacobian", "LinkFrames"]


def frame_position(frame: Any, frames: Sequence[str], name: str = "tree", links: int = 0) -> int:
    """The position of frame ``frame`` (a name; None when there is one frame) in ``frames``;
    FrameError listing the valid ones (and the link frames 0..links-1 of a chain)."""
    if isinstance(frame, str):
        try:
            return frames.index(frame)
        except ValueError:
            import difflib

            close = difflib.get_close_matches(frame, frames, n=3)
            hint = f" (did you mean {' or '.join(repr(c) for c in close)}?)" if close else ""
            tail = f" or a link frame index 0..{links - 1} (chain order, as link_poses)" if links else ""
            raise FrameError(
                f"{name} has no frame {frame!r}{hint}; its frames: {list(frames)}{tail}"
            ) from None
    if frame is None:
        if len(frames) == 1:
            return 0
        raise FrameError(f"{name} has {len(frames)} frames: name one with frame=, one of {list(frames)}")
    raise FrameError(
        f"a frame of {name} is a link name, one of {list(frames)}, not {type(frame).__name__} {frame!r}"
    )


def resolve_frame(frame: Any, frames: Sequence[str], links: int, name: str) -> tuple[int, int]:
    """``frame`` of a compiled model as ``(k, -1)`` for its named frame k (None: the only one) or
    ``(-1, k)`` for link frame k of a chain (an integer, when the model has ``links`` link frames);
    FrameError naming what is valid."""
    if links and frame is not None and not isinstance(frame, str):
        return -1, frame_index(frame, links, name)
    return frame_position(frame, frames, name, links), -1


def frame_index(frame: Any, n: int, name: str = "robot") -> int:
    """``frame`` as a link frame index in [0, n); raises FrameError naming the valid range."""
    if isinstance(frame, (bool, np.bool_)):
        raise FrameError(f"frame must be a link frame index 0..{n - 1} or None, not {frame!r}")
    try:
        k = operator.index(frame)
    except TypeError:
        raise FrameError(
            f"frame must be a link frame index 0..{n - 1} (chain order, as link_poses) or None "
            f"(the end effector) for {name}, not {type(frame).__name__} {frame!r}"
        ) from None
    if not 0 <= k < n:
        raise FrameError(f"{name} has link frames 0..{n - 1} (one after each joint), not frame {k}")
    return k


class ChainTables:
    """Per joint along the chain: joint index, axis index (0 x, 1 y, 2 z), sign, revolute."""

    def __init__(self, order: Any, axis: Any, sign: Any, revolute: Any) -> None:
        self.order = np.asarray(order, dtype=int)
        self.axis = np.asarray(axis, dtype=int)
        self.sign = np.asarray(sign, dtype=float)
        self.revolute = np.asarray(revolute, dtype=bool)

    @classmethod
    def of(cls, ets: Any) -> ChainTables:
        joints = [e for e in ets if e.is_joint]
        return cls(
            [e.joint for e in joints], [e.axis.index for e in joints], [e.sign for e in joints],
            [e.is_revolute for e in joints],
        )  # fmt: skip


def frame_jacobian(L: np.ndarray, k: int, chain: ChainTables, ee: bool = False) -> np.ndarray:
    """Jacobian (N, 6, n) of link frame ``k`` from the link poses ``L`` (N, n, 4, 4), rows (v, omega).

    Column a (a joint at or before the frame along the chain) is ``(w_a x (p_k - p_a) ; w_a)``
    for a revolute and ``(w_a ; 0)`` for a prismatic joint, with ``w_a`` the joint's signed axis
    (a column of ``L[a]``) and ``p_a`` its origin (eqs 31-34 of Haviland and Corke, Manipulator
    Differential Kinematics, Part 1, 2023, with frame k in place of the end effector); later
    joints' columns are 0. ``ee``: both row blocks expressed in frame k (eq 16).
    """
    N, n = L.shape[0], L.shape[1]
    a = np.arange(k + 1)
    columns = np.swapaxes(L[:, : k + 1, :3, :3], -1, -2)  # (N, k+1, column, row)
    w = columns[:, a, chain.axis[a], :] * chain.sign[a][:, None]  # (N, k+1, 3) signed joint axes
    r = L[:, k, None, :3, 3] - L[:, : k + 1, :3, 3]
    rev = chain.revolute[a][:, None]
    v = np.where(rev, cross(w, r), w)
    o = np.where(rev, w, 0.0)
    if ee:
        R = L[:, k, :3, :3]
        v = np.einsum("Nji,Naj->Nai", R, v)
        o = np.einsum("Nji,Naj->Nai", R, o)
    J = np.zeros((N, 6, n))
    cols = chain.order[a]
    J[:, :3, cols] = np.swapaxes(v, 1, 2)
    J[:, 3:, cols] = np.swapaxes(o, 1, 2)
    return J


class LinkFrames(FrameMethods):
    """The methods of the link frames of a compiled chain (``hessian0(q, frame=k)``, ``jacobm``...)
    from its generated ``fkine(q, frame)`` and ``jacob0(q, frame)``: what the generated functions
    without code of their own for ``frame=k`` call. ``order[k]``: the joint met k-th from the base."""

    def __init__(self, n: int, name: str, fkine: Any, jacob0: Any, order: Any) -> None:
        self.n, self.name = n, name
        self._fkine, self._jacob0, self._order = fkine, jacob0, tuple(order)

    def fkine(self, q: Any, frame: Any = None) -> np.ndarray:
        return self._fkine(q, frame)

    def jacob0(self, q: Any, frame: Any = None) -> np.ndarray:
        return self._jacob0(q, frame)

    def fkine_jacob0(self, q: Any, frame: Any = None) -> tuple[np.ndarray, np.ndarray]:
        return self._fkine(q, frame), self._jacob0(q, frame)

    def jacobe(self, q: Any, frame: Any = None) -> np.ndarray:
        Q, single = self._batch(q)
        Je = rotate_rows(self._fkine(Q, frame), self._jacob0(Q, frame))
        return Je[0] if single else Je

    def jacob0_hessian0(self, q: Any, frame: Any = None) -> tuple[np.ndarray, np.ndarray]:
        Q, single = self._batch(q)
        J = self._jacob0(Q, frame)
        H = chain_hessian(J, self._order)
        return (J[0], H[0]) if single else (J, H)
