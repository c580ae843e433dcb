"""Numeric reference kinematics of an ETS (numpy only): the O(n) algorithm of Haviland and Corke,
Manipulator Differential Kinematics, Part 1, 2023.

Everything is batched: a configuration array ``Q`` of shape (N, n) gives (N, ...) results. The
chain is pre-reduced to ``P0 * S_1(q) * ... * S_n(q)`` where each segment ``S_k`` is the joint's
elementary transform times the constant transforms up to the next joint, written as
``cos(q) A + sin(q) B + D`` (revolute) or ``q A + D`` (prismatic) with constant 4x4 ``A, B, D``,
so all segments are built by one ``einsum``.

Conventions:
- Base-frame Jacobian ``J0`` rows (v, omega), v the velocity of the end-effector origin (eq 14-16,
  31-34). End-effector-frame Jacobian ``Je = blkdiag(R^T, R^T) J0``.
- Hessian ``H`` of shape (n, 6, n), ``H[i] = dJ/dq_i`` (Haviland and Corke, Maximising Manipulability
  During Resolved-Rate Motion Control, 2020, eq 20 and Appendix I).
- Space / body Jacobians have rows (omega, v), the twist order of Lynch and Park, Modern Robotics,
  2017.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from symkin.model.ets import ETS, Axis, Const

__all__ = ["NumericKinematics", "et_matrix", "const_matrix", "cross"]

ROT_SLICES = {0: (1, 2), 1: (2, 0), 2: (0, 1)}  # rotation about i mixes columns (j, k)


def et_matrix(axis: Axis, value: float) -> np.ndarray:
    """The 4x4 matrix of one elementary transform (Fig. 2) at ``value``."""
    T = np.eye(4)
    i = axis.index
    if axis.is_rotation:
        j, k = ROT_SLICES[i]
        c, s = math.cos(value), math.sin(value)
        T[j, j], T[j, k], T[k, j], T[k, k] = c, -s, s, c
    else:
        T[i, 3] = value
    return T


def const_matrix(axis: Axis, const: Const) -> np.ndarray:
    """Like :func:`et_matrix`, exact (0, +-1 entries) for rotations by multiples of pi/2."""
    k = const.quarter_turns
    if axis.is_rotation and k is not None:
        T = np.eye(4)
        j, l_ = ROT_SLICES[axis.index]
        c, s = ((1, 0), (0, 1), (-1, 0), (0, -1))[k]
        T[j, j], T[j, l_], T[l_, j], T[l_, l_] = c, -s, s, c
        return T
    return et_matrix(axis, const.value)


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product along the last axis (faster than np.cross for small arrays)."""
    return np.stack(
        (
            a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
            a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
            a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0],
        ),
        axis=-1,
    )


@dataclass(frozen=True, eq=False)
class NumericKinematics:
    """Pre-reduced numeric form of an ETS. Build with :meth:`of`."""

    n: int
    P0: np.ndarray  # (4, 4) constants before the first joint
    K: np.ndarray  # (n, 3, 4, 4) segment coefficients (A, B, D), chain order
    revolute: np.ndarray  # (n,) bool, chain order
    axis: np.ndarray  # (n,) int axis index, chain order
    sign: np.ndarray  # (n,) +-1, chain order
    order: np.ndarray  # (n,) joint index of the k-th joint along the chain
    Kjoint: np.ndarray  # (n, 3, 4, 4) like K without the trailing constants (link frames)

    @classmethod
    def of(cls, ets: ETS) -> NumericKinematics:
        chain = list(ets)
        P = np.eye(4)
        pos = [i for i, e in enumerate(chain) if e.is_joint]
        for e in chain[: pos[0] if pos else len(chain)]:
            P = P @ const_matrix(e.axis, e.const)
        if not pos:
            z = np.zeros((0, 3, 4, 4))
            e_ = np.zeros(0, dtype=int)
            return cls(0, P, z, e_.astype(bool), e_, e_, e_, z)
        K, Kj, rev, ax, sg, order = [], [], [], [], [], []
        for k, p in enumerate(pos):
            e = chain[p]
            C = np.eye(4)
            for c in chain[p + 1 : pos[k + 1] if k + 1 < len(pos) else len(chain)]:
                C = C @ const_matrix(c.axis, c.const)
            i = e.axis.index
            A, B, D = np.zeros((4, 4)), np.zeros((4, 4)), np.eye(4)
            if e.axis.is_rotation:
                j, l_ = ROT_SLICES[i]
                A[j, j] = A[l_, l_] = 1.0
                B[j, l_], B[l_, j] = -1.0, 1.0
                D[j, j] = D[l_, l_] = 0.0
            else:
                A[i, 3] = 1.0
            Kj.append(np.stack((A, B, D)))
            K.append(np.stack((A @ C, B @ C, D @ C)))
            rev.append(e.axis.is_rotation)
            ax.append(i)
            sg.append(e.sign)
            order.append(e.joint)
        return cls(
            len(pos),
            P,
            np.array(K),
            np.array(rev),
            np.array(ax),
            np.array(sg, dtype=float),
            np.array(order),
            np.array(Kj),
        )

    # -- core ------------------------------------------------------------------------------
    @cached_property
    def axvec(self) -> np.ndarray:
        """(n, 3) signed unit joint axes in each joint's own frame, chain order."""
        v = np.zeros((self.n, 3))
        v[np.arange(self.n), self.axis] = self.sign
        return v

    @cached_property
    def _axcol(self) -> np.ndarray:
        return self.axvec[:, :, None]

    def _weights(self, Q: np.ndarray) -> np.ndarray:
        """(N, n, 3) segment weights (cos, sin, 1) or (q, 0, 1), chain order."""
        x = Q[:, self.order] * self.sign  # (N, n)
        W = np.empty((*x.shape, 3))
        W[..., 0] = np.where(self.revolute, np.cos(x), x)
        W[..., 1] = np.where(self.revolute, np.sin(x), 0.0)
        W[..., 2] = 1.0
        return W

    def prefixes(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Frames just before each joint (N, n, 4, 4), chain order, and the end pose (N, 4, 4)."""
        N = Q.shape[0]
        S = np.einsum("Nnk,nkij->Nnij", self._weights(Q), self.K)
        P = np.empty((N, self.n + 1, 4, 4))
        P[:, 0] = self.P0
        for k in range(self.n):
            np.matmul(P[:, k], S[:, k], out=P[:, k + 1])
        return P[:, : self.n], P[:, self.n]

    def fkine(self, Q: np.ndarray) -> np.ndarray:
        """End-effector pose 0T_e, (N, 4, 4) (eq 1)."""
        return self.prefixes(Q)[1]

    def link_poses(self, Q: np.ndarray) -> np.ndarray:
        """Pose of each link frame right after its joint's transform (eq 5), (N, n, 4, 4), chain order."""
        P, _ = self.prefixes(Q)
        Sj = np.einsum("Nnk,nkij->Nnij", self._weights(Q), self.Kjoint)
        return P @ Sj

    def _columns(self, P: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Base-frame (Jv, Jw), each (N, n, 3), chain order (eqs 31-34)."""
        w = (P[..., :3, :3] @ self._axcol)[..., 0]  # (N, n, 3) signed joint axes
        r = T[:, None, :3, 3] - P[:, :, :3, 3]
        rev = self.revolute[:, None]
        Jv = np.where(rev, cross(w, r), w)
        Jw = np.where(rev, w, 0.0)
        return Jv, Jw

    def jacob0(self, Q: np.ndarray) -> np.ndarray:
        """Base-frame manipulator Jacobian, (N, 6, n), rows (v, omega)."""
        P, T = self.prefixes(Q)
        return self._assemble(*self._columns(P, T))

    def _assemble(self, Jv: np.ndarray, Jw: np.ndarray) -> np.ndarray:
        J = np.empty((Jv.shape[0], 6, self.n))
        J[:, :3, self.order] = np.swapaxes(Jv, 1, 2)
        J[:, 3:, self.order] = np.swapaxes(Jw, 1, 2)
        return J

    def fkine_jacob0(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        P, T = self.prefixes(Q)
        return T, self._assemble(*self._columns(P, T))

    def hessian0(self, Q: np.ndarray) -> np.ndarray:
        """Base-frame manipulator Hessian, (N, n, 6, n), ``H[:, i] = dJ0/dq_i``.

        For joints a (column) and b (derivative), in chain order, revolute b before or at a:
        dJ_a/dq_b = (w_b x Jv_a ; w_b x Jw_a); b after a with a revolute: (w_a x Jv_b ; 0);
        a prismatic joint b before a, or a prismatic a before b, contributes nothing.
        """
        P, T = self.prefixes(Q)
        Jv, Jw = self._columns(P, T)
        return self._hessian(Jv, Jw)

    def _hessian(self, Jv: np.ndarray, Jw: np.ndarray) -> np.ndarray:
        n = self.n
        N = Jv.shape[0]
        # pairwise crosses: X[:, b, a] = w_b x Jv_a, Y[:, b, a] = w_b x w_a (w = Jw for revolute)
        wb = Jw[:, :, None, :]
        X = cross(wb, Jv[:, None, :, :])  # (N, b, a, 3)
        Y = cross(wb, Jw[:, None, :, :])
        lower = np.triu(np.ones((n, n), dtype=bool))[None, :, :, None]  # b <= a
        # b > a: (w_a x Jv_b ; 0) = -(Jv_b x w_a) -> use X transposed: X[:, a, b] = w_a x Jv_b
        Xt = np.swapaxes(X, 1, 2)
        Hv = np.where(lower, X, Xt)
        Hw = np.where(lower, Y, 0.0)
        H = np.empty((N, n, 6, n))
        # H[:, joint(b), rows, joint(a)]
        Hv_t = np.swapaxes(Hv, 2, 3)  # (N, b, 3, a)
        Hw_t = np.swapaxes(Hw, 2, 3)
        o = self.order
        H[np.ix_(np.arange(N), o, np.arange(3), o)] = Hv_t
        H[np.ix_(np.arange(N), o, np.arange(3, 6), o)] = Hw_t
        return H

    def jacob0_hessian0(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(T, J0, H0) sharing one pass."""
        P, T = self.prefixes(Q)
        Jv, Jw = self._columns(P, T)
        return T, self._assemble(Jv, Jw), self._hessian(Jv, Jw)
