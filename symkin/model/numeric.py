"""Numeric reference kinematics (numpy only), one kernel for chains and trees: the O(n) algorithm
of Haviland and Corke, Manipulator Differential Kinematics, Part 1, 2023, walked over a tree's
segments (a chain's are those of :func:`symkin.model.slots.chain_segments`: one per joint, then
the end effector's constants).

Everything is batched: ``Q`` (N, n) gives (N, ...) results. Segment k carries its link from its
parent's: ``L_k = L_parent A_k J_k(x) B_k`` (eqs 1, 5), with ``A_k``, ``B_k`` the constant
transforms before and after its joint and ``J_k`` the joint's elementary transform (Fig. 2) at
``x = sign (m q_j + c)`` (``m = 1, c = 0`` except for a mimic slot). Pre-reduced to
``w0 K0 + w1 K1 + K2`` with constant 4x4 ``K`` and weights (cos x, sin x) (revolute), (x, 0)
(prismatic) or (0, 0) (fixed), all segments are built by one ``einsum`` and chained by one matrix
product each.

Conventions:
- Base-frame Jacobian ``J0`` of the frame at segment f's link, rows (v, omega), v the velocity of
  its origin (eqs 14-16, 31-34): per slot a on f's path the column ``(w_a x (p_f - p_a) ; w_a)``
  (revolute) or ``(w_a ; 0)`` (prismatic), ``w_a`` the slot's signed axis and ``p_a`` its origin,
  added ``m_a`` times into joint ``j_a``'s column (the chain rule); joints off the path have zero
  columns. ``Je = blkdiag(R^T, R^T) J0``.
- Hessian ``H`` (n, 6, n), ``H[i] = dJ0/dq_i`` (Haviland and Corke, Maximising Manipulability
  During Resolved-Rate Motion Control, 2020, eq 20): :func:`symkin.model.differential.path_hessian`;
  higher orders: :func:`symkin.model.derivatives.path_derivative`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.model.derivatives import path_derivative
from symkin.model.differential import FrameMethods, path_hessian, rotate_rows
from symkin.model.kinematics import ROT_SLICES, const_matrix, cross
from symkin.model.slots import Segment, Slot

__all__ = ["NumericKinematics", "NumericFrames"]

_EYE = np.eye(4)


def _motion(joint: Any) -> np.ndarray:
    """(3, 4, 4) coefficients of a joint's transform on its weights (module docstring)."""
    a, b, d = np.zeros((4, 4)), np.zeros((4, 4)), np.eye(4)
    if joint is None:
        return np.stack((a, b, d))
    i = joint.axis.index
    if joint.axis.is_rotation:
        j, k = ROT_SLICES[i]
        a[j, j] = a[k, k] = 1.0
        b[j, k], b[k, j] = -1.0, 1.0
        d[j, j] = d[k, k] = 0.0
    else:
        a[i, 3] = 1.0
    return np.stack((a, b, d))


def _picks(W: np.ndarray) -> np.ndarray | None:
    """The joint each slot moves when weights ``W`` (m, n) only pick distinct joints with weight
    1 (no mimic slot), else None."""
    rows, cols = np.nonzero(W)
    if len(rows) == W.shape[0] and (W[rows, cols] == 1.0).all() and len(set(cols)) == len(cols):
        return cols
    return None


@dataclass(frozen=True, eq=False)
class NumericKinematics:
    """Pre-reduced numeric form of a tree's segments (build with :meth:`of`).

    Per segment k: ``up[k]`` its parent's place in :meth:`poses` (0 the base link), its slot
    ``slot_of[k]`` (-1 when fixed), the constants before (``A``) and after (``B``) its joint, the
    joint's axis index and sign (0 and 1 when fixed), its coefficients ``K`` (S, 3, 4, 4),
    ``paths[k]`` the slots on its path, base first, and ``weights[k]`` (m, n): slot i of the path
    moves joint j by ``[i, j]`` (``picks[k]``: the joint of each slot when that is all the weights
    say, else None). Per slot: its segment's coefficients (``moving``) and ``up``, its joint,
    ``scale`` and ``shift`` (``x = scale q_j + shift``), kind, and its signed axis and origin in
    its parent's link frame (``ut``, (s, 3, 2)).
    """

    n: int
    up: tuple[int, ...]
    slot_of: tuple[int, ...]
    A: np.ndarray
    B: np.ndarray
    K: np.ndarray
    moving: np.ndarray
    axis: tuple[int, ...]
    sign: tuple[float, ...]
    paths: tuple[np.ndarray, ...]
    weights: tuple[np.ndarray, ...]
    picks: tuple[np.ndarray | None, ...]
    segment: np.ndarray
    slot_up: np.ndarray
    joint: np.ndarray
    scale: np.ndarray
    shift: np.ndarray
    revolute: np.ndarray
    ut: np.ndarray

    @classmethod
    def of(cls, segments: Sequence[Segment], slots: Sequence[Slot], n: int) -> NumericKinematics:
        A, B, K, axis, sign, paths = [], [], [], [], [], []
        for seg in segments:
            before, after, joint = np.eye(4), np.eye(4), None
            for e in seg.ets:
                if e.is_joint:
                    joint = e
                elif joint is None:
                    before = before @ const_matrix(e.axis, e.const)
                else:
                    after = after @ const_matrix(e.axis, e.const)
            A.append(before)
            B.append(after)
            K.append(before @ _motion(joint) @ after)
            axis.append(0 if joint is None else joint.axis.index)
            sign.append(1.0 if joint is None else float(joint.sign))
            path = list(paths[seg.parent]) if seg.parent >= 0 else []
            paths.append(np.array(path + ([] if seg.slot is None else [seg.slot]), dtype=int))
        ut = np.zeros((len(slots), 3, 2))
        for i, s in enumerate(slots):
            ut[i, :, 0] = A[s.segment][:3, axis[s.segment]] * sign[s.segment]
            ut[i, :, 1] = A[s.segment][:3, 3]
        joint = np.array([s.joint for s in slots], dtype=int)
        multiplier = np.array([float(s.multiplier) for s in slots])
        weights = []
        for path in paths:
            W = np.zeros((len(path), n))
            np.add.at(W, (np.arange(len(path)), joint[path]), multiplier[path])
            weights.append(W)
        ssign = np.array([sign[s.segment] for s in slots])
        return cls(
            n=n,
            up=tuple(seg.parent + 1 for seg in segments),
            slot_of=tuple(-1 if seg.slot is None else seg.slot for seg in segments),
            A=np.array(A).reshape(-1, 4, 4),
            B=np.array(B).reshape(-1, 4, 4),
            K=np.array(K).reshape(-1, 3, 4, 4),
            moving=np.array([K[s.segment] for s in slots]).reshape(-1, 3, 4, 4),
            axis=tuple(axis),
            sign=tuple(sign),
            paths=tuple(paths),
            weights=tuple(weights),
            picks=tuple(_picks(W) for W in weights),
            segment=np.array([s.segment for s in slots], dtype=int),
            slot_up=np.array([segments[s.segment].parent + 1 for s in slots], dtype=int),
            joint=joint,
            scale=multiplier * ssign,
            shift=np.array([float(s.offset) for s in slots]) * ssign,
            revolute=np.array([s.revolute for s in slots], dtype=bool),
            ut=ut,
        )

    def poses(self, Q: np.ndarray) -> np.ndarray:
        """Link poses (N, S + 1, 4, 4) in the base frame: index 0 the base link, k + 1 segment k's."""
        x = Q[:, self.joint] * self.scale + self.shift
        W = np.empty((*x.shape, 3))
        W[..., 0] = np.where(self.revolute, np.cos(x), x)
        W[..., 1] = np.where(self.revolute, np.sin(x), 0.0)
        W[..., 2] = 1.0
        M = np.einsum("Nsk,skij->Nsij", W, self.moving)
        L = np.empty((Q.shape[0], len(self.up) + 1, 4, 4))
        L[:, 0] = _EYE
        for k, (p, i) in enumerate(zip(self.up, self.slot_of)):
            Sk = self.K[k, 2] if i < 0 else M[:, i]  # a fixed segment: its constants
            if p:
                np.matmul(L[:, p], Sk, out=L[:, k + 1])
            else:
                L[:, k + 1] = Sk
        return L

    def transform(self, Q: np.ndarray, k: int) -> np.ndarray:
        """Segment k's transform from its parent's link frame to its own, ``A_k J_k(x) B_k``
        (N, 4, 4)."""
        i = self.slot_of[k]
        if i < 0:
            return np.broadcast_to(self.K[k, 2], (Q.shape[0], 4, 4))
        x = Q[:, self.joint[i], None, None] * self.scale[i] + self.shift[i]
        if self.revolute[i]:
            return np.cos(x) * self.K[k, 0] + np.sin(x) * self.K[k, 1] + self.K[k, 2]
        return x * self.K[k, 0] + self.K[k, 2]

    def joint_frames(self, L: np.ndarray) -> np.ndarray:
        """Frames just before each segment's joint (N, S, 4, 4) from :meth:`poses` (a fixed
        segment's: its link frame)."""
        return L[:, list(self.up)] @ self.A

    def columns(self, L: np.ndarray, f: int) -> tuple[np.ndarray, np.ndarray]:
        """Geometric columns ``Jv, Jw`` (N, m, 3) of the m slots on segment f's path, base first,
        from :meth:`poses` (``Jw = 0`` for a prismatic slot; eqs 31-34)."""
        path = self.paths[f]
        parent = L[:, self.slot_up[path]]  # (N, m, 4, 4)
        wp = parent[..., :3, :3] @ self.ut[path]  # (N, m, 3, 2): axis, origin offset
        w, p = wp[..., 0], wp[..., 1] + parent[..., :3, 3]
        rev = self.revolute[path][:, None]
        Jv = np.where(rev, cross(w, L[:, f + 1, None, :3, 3] - p), w)
        return Jv, np.where(rev, w, 0.0)

    def jacobian(self, Jv: np.ndarray, Jw: np.ndarray, f: int) -> np.ndarray:
        """Base-frame Jacobian (N, 6, n) of segment f's link from its :meth:`columns`."""
        J6 = np.concatenate((Jv, Jw), axis=-1)
        cols = self.picks[f]
        if cols is None:
            return np.einsum("Nmr,mj->Nrj", J6, self.weights[f])
        J = np.zeros((J6.shape[0], 6, self.n))
        J[:, :, cols] = np.swapaxes(J6, 1, 2)
        return J


class NumericFrames(FrameMethods):
    """``fkine``, ``jacob0``, ``jacobe``, ``fkine_jacob0``, ``jacob0_hessian0`` and the higher
    derivatives of a model's frames on its :class:`NumericKinematics` ``_num``: a Robot and a
    Tree differ only in which segment a ``frame`` names (:meth:`_segment`). Each takes ``q`` (n,)
    or a batch (N, n)."""

    _num: NumericKinematics

    def _segment(self, frame: Any) -> int:
        """The segment whose link is ``frame`` (FrameError when there is none)."""
        raise NotImplementedError

    def fkine(self, q: Any, frame: Any = None) -> np.ndarray:
        """Pose of ``frame`` in the base frame (eq 1): (4, 4) or (N, 4, 4). ``frame``: None for a
        chain's end effector or a one-frame tree's frame, a chain's link frame index k (the frame
        right after the k-th joint along it, as ``link_poses``), a tree's frame name."""
        f = self._segment(frame)
        Q, single = self._batch(q)
        T = self._num.poses(Q)[:, f + 1]
        return T[0] if single else T

    def jacob0(self, q: Any, frame: Any = None) -> np.ndarray:
        """Base-frame manipulator Jacobian of ``frame`` (eqs 31-34): (6, n) or (N, 6, n), rows
        (v, omega), v the velocity of the frame's origin in the base frame; zero columns for the
        joints off its path. For the space Jacobian of Lynch and Park's Modern Robotics (rows
        (omega, v), v of the point at the base origin) see :meth:`jacobs`."""
        return self.fkine_jacob0(q, frame)[1]

    def jacobe(self, q: Any, frame: Any = None) -> np.ndarray:
        """Jacobian of ``frame`` expressed in that frame (eq 16): ``blkdiag(R^T, R^T) J0``, rows
        (v, omega). For the body Jacobian of Modern Robotics (rows (omega, v)) see :meth:`jacobb`."""
        Q, single = self._batch(q)
        Je = rotate_rows(*self.fkine_jacob0(Q, frame))
        return Je[0] if single else Je

    def fkine_jacob0(self, q: Any, frame: Any = None) -> tuple[np.ndarray, np.ndarray]:
        """Pose and base-frame Jacobian of ``frame`` from one pass: ((4, 4), (6, n)) or batched."""
        f = self._segment(frame)
        Q, single = self._batch(q)
        L = self._num.poses(Q)
        T, J = L[:, f + 1], self._num.jacobian(*self._num.columns(L, f), f)
        return (T[0], J[0]) if single else (T, J)

    def jacob0_hessian0(self, q: Any, frame: Any = None) -> tuple[np.ndarray, np.ndarray]:
        """Base-frame Jacobian and Hessian of ``frame`` from one pass ((6, n), (n, 6, n)) or
        batched; ``H[i] = dJ0/dq_i``, per pair of slots a, b on its path (b at or before a:
        ``(w_b x Jv_a ; w_b x w_a)``; b after a: ``(w_a x Jv_b ; 0)``; MMC paper eq 20), weighted
        by both slots' multipliers."""
        f = self._segment(frame)
        Q, single = self._batch(q)
        Jv, Jw = self._num.columns(self._num.poses(Q), f)
        J, H = self._num.jacobian(Jv, Jw, f), path_hessian(Jv, Jw, self._num.weights[f], self._num.picks[f])
        return (J[0], H[0]) if single else (J, H)

    def _derivative(self, Q: np.ndarray, order: int, frame: Any) -> np.ndarray:
        """Order ``order`` >= 3 of :meth:`derivative` from the slot columns of ``frame``'s path,
        contracted onto the joints by the multipliers (Part 2's product rule and the chain rule of
        a mimic slot; :func:`symkin.model.derivatives.path_derivative`)."""
        f = self._segment(frame)
        Jv, Jw = self._num.columns(self._num.poses(Q), f)
        return path_derivative(Jv, Jw, self._num.weights[f], order)
