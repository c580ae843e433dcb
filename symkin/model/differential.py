"""What every frame's kinematics derive from its pose T, Jacobian J0 and Hessian H0 (numpy only).

The numeric helpers (manipulability, its Jacobian, condition number, space Jacobian, dJ/dt,
the end-effector-frame Hessian, the Hessian of a serial path from its Jacobian's columns; the
orientation representations and analytic forms are in :mod:`symkin.model.orientation`) and
:class:`FrameMethods`, the methods every kinematics object has once it gives ``fkine``,
``jacob0``, ``jacobe``, ``fkine_jacob0`` and ``jacob0_hessian0`` of a frame: the numeric references
(:class:`symkin.Robot`, :class:`symkin.Tree`) and the compiled :class:`symkin.Kinematics` share them.

References: "eq N" are the equations of Haviland and Corke, Manipulator Differential Kinematics,
Part 1 (IEEE Robotics and Automation Magazine, 2023); "MMC paper eq N" those of Haviland and Corke,
Maximising Manipulability During Resolved-Rate Motion Control (arXiv, 2020).

For one configuration the batched helpers (``numpy.linalg.det`` and ``inv`` over a stack) cost
more than the kinematics: :func:`manipulability_one` takes ``m = sqrt(det(Jr Jr^T))`` from the
closed form for the 3 x 3 Gram matrix of ``axes="trans"``/``"rot"`` and, for the 6 x 6 one of
``axes="all"``, from symmetric Gaussian elimination written out as straight-line code (the product
of the pivots; a non-positive pivot means a singular Jacobian and m = 0).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from symkin.core.arrays import AXES_ROWS, as_batch, axes_rows, real_array
from symkin.errors import ConfigurationError, ParameterError
from symkin.model.derivatives import check_order
from symkin.model.kinematics import cross
from symkin.model.orientation import (  # noqa: F401 - NEAR_PI_L, angle_axis, REPRESENTATIONS re-exported
    NEAR_PI_L,
    REPRESENTATIONS,
    analytical_hessian_of,
    analytical_of,
    angle_axis,
    representation_of,
)
from symkin.model.spatial import velocity_transform, wrench_transform  # noqa: F401 - re-exported

__all__ = [
    "FrameMethods",
    "frame_and_rows",
    "path_hessian",
    "chain_hessian",
    "rotate_rows",
    "hessian_to_ee",
    "cond_of",
    "space_jacobian",
    "jacob_dot_of",
    "manipulability_of",
    "jacobm_of",
    "manipulability_one",
    "jacobm_one",
    "NEAR_PI_L",
    "angle_axis",
    "REPRESENTATIONS",
    "analytical_of",
    "analytical_hessian_of",
    "velocity_transform",
    "wrench_transform",
]


def path_hessian(
    Jv: np.ndarray, Jw: np.ndarray, A: np.ndarray, cols: Sequence[int] | None = None
) -> np.ndarray:
    """Hessian (N, n, 6, n) of a frame from the geometric columns Jv, Jw (N, s, 3) of the s joint
    slots on its path (base first; Jw = 0 for a prismatic slot): per pair of slots a, b, b at or
    before a: ``dJ_a/dq_b = (w_b x Jv_a ; w_b x w_a)``, b after a: ``(w_a x Jv_b ; 0)`` (MMC paper
    eq 20), contracted onto the joints by ``A`` (s, n): slot i moves joint j by ``A[i, j]``.
    ``cols``: the joint of each slot when that is all ``A`` says (no mimic slot), placed directly."""
    s = Jv.shape[1]
    X = cross(Jw[:, :, None, :], Jv[:, None, :, :])  # X[:, b, a] = w_b x v_a
    Y = cross(Jw[:, :, None, :], Jw[:, None, :, :])
    lower = np.triu(np.ones((s, s), dtype=bool))[None, :, :, None]  # b <= a
    Hv = np.where(lower, X, np.swapaxes(X, 1, 2))
    Hw = np.where(lower, Y, 0.0)
    Hs = np.concatenate((Hv, Hw), axis=-1)  # (N, b, a, 6)
    if cols is not None:  # slot i is joint cols[i]
        H = np.zeros((Hs.shape[0], A.shape[1], 6, A.shape[1]))
        H[np.ix_(range(Hs.shape[0]), cols, range(6), cols)] = np.swapaxes(Hs, 2, 3)
        return H
    return np.einsum("bk,Nbar,ai->Nkri", A, Hs, A)


def chain_hessian(J: np.ndarray, order: Sequence[int]) -> np.ndarray:
    """Base-frame Hessian (N, n, 6, n) of a frame of a serial chain from its J0 (N, 6, n):
    ``order[k]`` is the joint met k-th from the base (columns of joints after the frame are 0)."""
    o = list(order)
    A = np.zeros((len(o), J.shape[-1]))
    A[range(len(o)), o] = 1.0
    return path_hessian(np.swapaxes(J[:, :3, o], 1, 2), np.swapaxes(J[:, 3:, o], 1, 2), A, o)


def frame_and_rows(frame: Any, axes: Any, frames: Sequence[str] = ()) -> tuple[Any, slice]:
    """``(frame, rows of J0)`` of ``manipulability``/``jacobm``/``cond(q, frame, axes)``. A second
    positional argument that names axes ("all", "trans", "rot") and no frame of the model is the
    axes: a chain's ``manipulability(q, "trans")`` keeps working."""
    if isinstance(frame, str) and frame in AXES_ROWS and frame not in frames:
        if axes != "all":
            raise ParameterError(
                f"axes given twice ({frame!r} and {axes!r}): pass frame= and axes= by keyword"
            )
        return None, AXES_ROWS[frame]
    return frame, axes_rows(axes)


def _at(method: Any, q: Any, frame: Any) -> Any:
    """``method(q)`` for the default frame (a chain-like object's methods may take q alone), else
    ``method(q, frame)``."""
    return method(q) if frame is None else method(q, frame)


class FrameMethods:
    """The methods that follow from a frame's ``fkine``, ``jacob0``, ``jacobe``, ``fkine_jacob0``
    and ``jacob0_hessian0`` (each ``(q, frame=None)``): every kinematics object of symkin has them,
    with the same signatures, shapes and errors. ``frame=None`` is the end effector of a chain and
    the only frame of a one-frame tree."""

    n: int
    name: str

    def _batch(self, q: Any) -> tuple[np.ndarray, bool]:
        return as_batch(q, self.n, self.name)

    def hessian0(self, q: Any, frame: Any = None) -> np.ndarray:
        """Base-frame manipulator Hessian of ``frame`` (MMC paper eq 20): (n, 6, n) or (N, n, 6, n),
        ``H[i] = dJ0/dq_i``."""
        return _at(self.jacob0_hessian0, q, frame)[1]  # type: ignore[attr-defined]

    def derivative(self, q: Any, order: int = 1, frame: Any = None) -> np.ndarray:
        """Order-``order`` partial derivative of the pose of ``frame``: shape ``(n,) * (order - 1) +
        (6, n)``, or (N, ...) for a batch, ``D[i_{k-1}, ..., i_1, :, i_0] = d^{k-1} J0[:, i_0] /
        dq_{i_1} ... dq_{i_{k-1}}``, rows (v, omega) (Haviland and Corke, Manipulator Differential
        Kinematics, Part 2, 2023, section "Higher-Order Derivatives"; roboticstoolbox-python's
        ``partial_fkine0(q, order)`` layout). Order 1 is :meth:`jacob0` (6, n), order 2
        :meth:`hessian0` (n, 6, n). ParameterError for an order that is not 1..8 or whose tensor
        (6 n^order entries) is too large (:func:`symkin.model.derivatives.check_order`)."""
        k = check_order(order, self.n, self.name)
        if k == 1:
            return _at(self.jacob0, q, frame)  # type: ignore[attr-defined]
        if k == 2:
            return self.hessian0(q, frame)
        Q, single = self._batch(q)
        D = self._derivative(Q, k, frame)
        return D[0] if single else D

    def _derivative(self, Q: np.ndarray, order: int, frame: Any) -> np.ndarray:
        """The order-``order`` derivative (N, ...) at the checked configurations ``Q`` (N, n)."""
        raise NotImplementedError

    def hessiane(self, q: Any, frame: Any = None) -> np.ndarray:
        """Hessian of ``frame`` in that frame, ``He[i] = dJe/dq_i = blkdiag(R^T)(H0[i] -
        blkdiag([w_i]x) J0)``: (n, 6, n) or (N, n, 6, n)."""
        Q, single = self._batch(q)
        T = _at(self.fkine, Q, frame)  # type: ignore[attr-defined]
        J, H = _at(self.jacob0_hessian0, Q, frame)  # type: ignore[attr-defined]
        He = hessian_to_ee(T, J, H)
        return He[0] if single else He

    def manipulability(self, q: Any, frame: Any = None, axes: str = "all") -> np.ndarray | float:
        """Yoshikawa manipulability ``sqrt(det(J J^T))`` (eq 52) of the chosen rows of the J0 of
        ``frame``: float, or (N,) for a batch."""
        frame, rows = frame_and_rows(frame, axes, getattr(self, "frames", ()))
        if type(q) is np.ndarray and q.ndim == 1:  # one configuration: jacob0 checks q
            return manipulability_one(_at(self.jacob0, q, frame)[rows])  # type: ignore[attr-defined]
        Q, single = self._batch(q)
        if single:
            return manipulability_one(_at(self.jacob0, Q[0], frame)[rows])  # type: ignore[attr-defined]
        return manipulability_of(_at(self.jacob0, Q, frame)[:, rows])  # type: ignore[attr-defined]

    def jacobm(self, q: Any, frame: Any = None, axes: str = "all") -> np.ndarray:
        """Manipulability Jacobian dm/dq of ``frame`` (MMC paper eq 11): (n,) or (N, n)."""
        frame, rows = frame_and_rows(frame, axes, getattr(self, "frames", ()))
        Q, single = self._batch(q)
        if single:
            J, H = _at(self.jacob0_hessian0, Q[0], frame)  # type: ignore[attr-defined]
            return jacobm_one(J[rows], H[:, rows])
        J, H = _at(self.jacob0_hessian0, Q, frame)  # type: ignore[attr-defined]
        return jacobm_of(J[:, rows], H[:, :, rows])

    def cond(self, q: Any, frame: Any = None, axes: str = "all") -> np.ndarray | float:
        """Condition number sigma_max / sigma_min of the chosen rows of the J0 of ``frame`` (eq 53);
        inf when singular (see :func:`cond_of`)."""
        frame, rows = frame_and_rows(frame, axes, getattr(self, "frames", ()))
        Q, single = self._batch(q)
        c = cond_of(_at(self.jacob0, Q, frame)[:, rows])  # type: ignore[attr-defined]
        return float(c[0]) if single else c

    def jacobs(self, q: Any, frame: Any = None) -> np.ndarray:
        """Space Jacobian of Lynch and Park's Modern Robotics: (6, n) or (N, 6, n), rows
        (omega, v_s) with v_s = v - omega x p the velocity of the point at the base origin."""
        Q, single = self._batch(q)
        Js = space_jacobian(*_at(self.fkine_jacob0, Q, frame))  # type: ignore[attr-defined]
        return Js[0] if single else Js

    def jacobb(self, q: Any, frame: Any = None) -> np.ndarray:
        """Body Jacobian of Modern Robotics: (6, n) or (N, 6, n), rows (omega, v) in ``frame``
        (``jacobe`` with its row blocks swapped)."""
        Je = _at(self.jacobe, q, frame)  # type: ignore[attr-defined]
        return np.concatenate((Je[..., 3:, :], Je[..., :3, :]), axis=-2)

    def jacob0_dot(self, q: Any, qd: Any, frame: Any = None) -> np.ndarray:
        """dJ0/dt = sum_i H0[i] qd_i of ``frame`` at joint velocity ``qd`` (Haviland and Corke,
        Manipulator Differential Kinematics, Part 2, 2023; roboticstoolbox's ``jacob0_dot``): (6, n),
        or (N, 6, n) for q and qd of shape (N, n). Rows (v, omega), base frame."""
        Q, single = self._batch(q)
        Qd, _ = as_batch(qd, self.n, self.name, "qd")
        if Qd.shape[0] != Q.shape[0]:
            raise ConfigurationError(f"q and qd hold {Q.shape[0]} and {Qd.shape[0]} configurations")
        Jd = jacob_dot_of(_at(self.hessian0, Q, frame), Qd)
        return Jd[0] if single else Jd

    def jacob0_analytical(self, q: Any, representation: str = "rpy/xyz", frame: Any = None) -> np.ndarray:
        """Analytical Jacobian of ``frame``: (6, n) or (N, 6, n), mapping qd to (v, d gamma/dt).

        v (m/s per unit qd) is the velocity of the frame's origin in the base frame, as in
        :meth:`jacob0`; gamma (rad) is the orientation of ``fkine(q, frame)`` in ``representation``
        (roboticstoolbox-python's names and conventions, see :data:`REPRESENTATIONS`):
        ``J_a = blkdiag(I, A(gamma)^-1) J0`` with ``omega = A(gamma) d gamma/dt`` (Corke, Robotics,
        Vision and Control, 3rd ed., 2023, chap 8; Lynch and Park, Modern Robotics, 2017, for the
        exponential coordinates). ConfigurationError where A is singular (rpy pitch = +-90 deg, ZYZ
        theta = 0 or 180 deg); ParameterError for an unknown representation.
        """
        rep = representation_of(representation)
        Q, single = self._batch(q)
        T, J = _at(self.fkine_jacob0, Q, frame)  # type: ignore[attr-defined]
        Ja = analytical_of(T, J, rep)
        return Ja[0] if single else Ja

    def hessian0_analytical(self, q: Any, representation: str = "rpy/xyz", frame: Any = None) -> np.ndarray:
        """Analytical Hessian of ``frame``: (n, 6, n) or (N, n, 6, n), ``Ha[i] = dJ_a/dq_i``, the
        derivative of :meth:`jacob0_analytical` (rows (v, d gamma/dt), same ``representation``),
        laid out like :meth:`hessian0`.

        The translational rows are those of ``hessian0``; the rate rows are
        ``A^-1 H0_w[i] + (dA^-1/dq_i) J0_w`` (Haviland and Corke, Manipulator Differential
        Kinematics, Part 2: Acceleration and Advanced Applications, 2023, section "Analytic Forms";
        :func:`symkin.model.orientation.analytical_hessian_of`). ``sum_i Ha[i] qd_i`` is the rate
        of change of ``J_a`` along qd. ConfigurationError where A is singular (rpy pitch = +-90 deg,
        ZYZ theta = 0 or 180 deg), as :meth:`jacob0_analytical`; ParameterError for an unknown
        representation.
        """
        rep = representation_of(representation)
        Q, single = self._batch(q)
        T = _at(self.fkine, Q, frame)  # type: ignore[attr-defined]
        J, H = _at(self.jacob0_hessian0, Q, frame)  # type: ignore[attr-defined]
        Ha = analytical_hessian_of(T, J, H, rep)
        return Ha[0] if single else Ha

    def joint_torques(self, q: Any, wrench: Any, frame: Any = None, in_frame: str = "base") -> np.ndarray:
        """Joint forces/torques that balance ``wrench`` applied at ``frame``: ``tau = J^T w``, (n,) or (N, n).

        ``wrench`` (6,) or (N, 6) is (f, m), force in N and moment in N m about the origin of
        ``frame``, that the robot exerts on its environment at ``frame``; with ``in_frame="base"``
        both are expressed in the base frame and J = jacob0, with ``in_frame="ee"`` in ``frame``
        itself and J = jacobe. tau (N m for a revolute joint, N for a prismatic one) is what the
        joints must supply to hold it in static equilibrium, gravity aside (principle of virtual work:
        ``tau . dq = w . (J dq)``; Corke, Robotics, Vision and Control, 3rd ed., 2023, chap 8;
        Lynch and Park, Modern Robotics, 2017, sec 5.2). One wrench (6,) applies to every
        configuration of a batch, and one q to every wrench of a batch (N, 6).

        ``frame="base"`` or ``frame="ee"`` on a model without a frame of that name (a chain, compiled
        or not) means the end effector with the wrench in that frame: ``in_frame="base"|"ee"``; a
        tree's frame named "ee" is that frame, with the wrench in the base frame by default.
        """
        # the frames of the model (a compiled chain's frames are ("ee",), its Robot has none)
        frames = getattr(getattr(self, "model", self), "frames", ())
        if isinstance(frame, str) and frame in ("base", "ee") and frame not in frames:
            if in_frame not in ("base", frame):
                raise ParameterError(f"frame={frame!r} and in_frame={in_frame!r}: two frames for the wrench")
            in_frame, frame = frame, None
        if in_frame not in ("base", "ee"):
            raise ParameterError(f"in_frame must be 'base' or 'ee', not {in_frame!r}")
        W = real_array(wrench, "wrench", ParameterError, items="6 numbers")
        if W.ndim not in (1, 2) or W.shape[-1] != 6:
            raise ParameterError(f"wrench must have shape (6,) or (N, 6), got shape {W.shape}")
        if not np.isfinite(W).all():
            raise ParameterError("wrench holds NaN or infinite values")
        Q, single = self._batch(q)
        if W.ndim == 2 and not single and W.shape[0] != Q.shape[0]:
            raise ParameterError(
                f"q and wrench hold {Q.shape[0]} and {W.shape[0]} configurations; give one wrench "
                "(6,) or one per configuration"
            )
        J = _at(self.jacob0 if in_frame == "base" else self.jacobe, Q, frame)  # type: ignore[attr-defined]
        if W.ndim == 1:
            tau = np.einsum("Nrj,r->Nj", J, W)
        else:
            tau = np.einsum("Nrj,Nr->Nj", np.broadcast_to(J, (W.shape[0], *J.shape[1:])), W)
        return tau[0] if single and W.ndim == 1 else tau


def rotate_rows(T: np.ndarray, J: np.ndarray) -> np.ndarray:
    """blkdiag(R^T, R^T) @ J for batches: T (N, 4, 4), J (N, 6, k) or (N, m, 6, k)."""
    Rt = np.swapaxes(T[:, :3, :3], 1, 2)
    if J.ndim == 4:
        Rt = Rt[:, None]
    return np.concatenate((Rt @ J[..., :3, :], Rt @ J[..., 3:, :]), axis=-2)


def hessian_to_ee(T: np.ndarray, J: np.ndarray, H: np.ndarray) -> np.ndarray:
    """End-effector-frame Hessian from base-frame T (N,4,4), J (N,6,n), H (N,n,6,n)."""
    wi = np.swapaxes(J[:, 3:], 1, 2)[:, :, None, :]  # (N, i, 1, 3): omega_i
    Jv = np.swapaxes(J[:, :3], 1, 2)[:, None]  # (N, 1, a, 3)
    Jw = np.swapaxes(J[:, 3:], 1, 2)[:, None]
    cv = np.swapaxes(cross(wi, Jv), 2, 3)  # (N, i, 3, a): omega_i x Jv_a
    cw = np.swapaxes(cross(wi, Jw), 2, 3)
    D = H - np.concatenate((cv, cw), axis=2)
    return rotate_rows(T, D)


def cond_of(J: np.ndarray) -> np.ndarray:
    """sigma_max / sigma_min per batch item of J (N, r, n) (eq 53), inf where J is rank-deficient:
    fewer columns than rows, or sigma_min <= sigma_max * max(r, n) * eps (NumPy's matrix_rank
    tolerance: below it sigma_min is rounding noise, e.g. 1e-17 at a singular configuration)."""
    r, n = J.shape[-2:]
    if J.shape[0] == 0:
        return np.zeros(0)
    s = np.linalg.svd(J, compute_uv=False)
    if n < r:
        return np.full(J.shape[0], np.inf)
    singular = s[:, -1] <= s[:, 0] * max(r, n) * np.finfo(float).eps
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(singular, np.inf, s[:, 0] / np.where(singular, 1.0, s[:, -1]))


def space_jacobian(T: np.ndarray, J: np.ndarray) -> np.ndarray:
    """Space Jacobian (rows (omega, v_s), v_s = v_e - omega x p_e) from T (N, 4, 4), J0 (N, 6, n)."""
    p = T[:, None, :3, 3]
    Jv, Jw = np.swapaxes(J[:, :3], 1, 2), np.swapaxes(J[:, 3:], 1, 2)
    vs = Jv - cross(Jw, p)
    return np.concatenate((J[:, 3:], np.swapaxes(vs, 1, 2)), axis=1)


def jacob_dot_of(H: np.ndarray, qd: np.ndarray) -> np.ndarray:
    """``sum_i H[:, i] qd[:, i]`` for batches: H (N, n, 6, n), qd (N, n) -> (N, 6, n)."""
    return np.einsum("Nirj,Ni->Nrj", H, qd)


def manipulability_of(J: np.ndarray) -> np.ndarray:
    """sqrt(det(J J^T)) per batch item of J (N, r, n); 0 where J J^T is singular (eq 52), exactly 0
    with fewer joints than rows (det would be rounding noise)."""
    if J.shape[-1] < J.shape[-2]:
        return np.zeros(J.shape[0])
    with np.errstate(divide="ignore", invalid="ignore"):  # LAPACK's LU of an exactly singular J J^T
        d = np.linalg.det(J @ np.swapaxes(J, 1, 2))
    return np.sqrt(np.maximum(np.nan_to_num(d, nan=0.0), 0.0))


def jacobm_of(J: np.ndarray, H: np.ndarray) -> np.ndarray:
    """Manipulability Jacobian (MMC paper eq 11): J (N, r, n), H (N, n, r, n) -> (N, n).

    ``Jm_i = m vec(J H_i^T)^T vec((J J^T)^-1)``; at a singular configuration (m = 0) the
    pseudo-inverse keeps the result finite.
    """
    if J.shape[-1] < J.shape[-2]:  # m = 0 for every q: so is its gradient
        return np.zeros((J.shape[0], J.shape[-1]))
    A = J @ np.swapaxes(J, 1, 2)
    m = manipulability_of(J)
    try:
        Ainv = np.linalg.inv(A)
        if not np.isfinite(Ainv).all():
            raise np.linalg.LinAlgError
    except np.linalg.LinAlgError:
        Ainv = np.linalg.pinv(A, hermitian=True)
    JH = np.einsum("Nrk,Nisk->Nirs", J, H)  # J H_i^T
    return m[:, None] * np.einsum("Nirs,Nrs->Ni", JH, Ainv)


def manipulability_one(Jr: np.ndarray) -> float:
    """sqrt(det(Jr Jr^T)) (eq 52) of one (r, n) Jacobian, r = 3 or 6 (other r: numpy's det);
    0 where Jr Jr^T is singular, exactly 0 with fewer joints than rows."""
    if Jr.shape[1] < Jr.shape[0]:
        return 0.0
    G = (Jr @ Jr.T).tolist()
    r = len(G)
    if r == 6:
        d = _det6_spd(G)
    elif r == 3:
        (a, b, c), (_, e, f), (_, _, i) = G
        d = a * (e * i - f * f) - b * (b * i - f * c) + c * (b * f - e * c)
    else:
        d = float(np.linalg.det(np.array(G))) if r else 1.0
    return math.sqrt(d) if d > 0.0 else 0.0


def jacobm_one(Jr: np.ndarray, Hr: np.ndarray) -> np.ndarray:
    """Manipulability Jacobian (MMC paper eq 11) of one configuration: Jr (r, n), Hr (n, r, n) -> (n,),
    ``Jm_i = m sum(H_i * (Jr Jr^T)^-1 Jr)``; zeros where Jr Jr^T is singular (m = 0)."""
    m = manipulability_one(Jr)
    if m == 0.0:
        return np.zeros(Hr.shape[0])
    return m * np.einsum("irk,rk->i", Hr, np.linalg.solve(Jr @ Jr.T, Jr))


def _det6_spd(G: list[list[float]]) -> float:
    """det G of a symmetric 6 x 6 G (nested lists) by Gaussian elimination on its upper triangle,
    written out; 0 at a non-positive pivot (G singular or not positive definite)."""
    a00, a01, a02, a03, a04, a05 = G[0]
    _, a11, a12, a13, a14, a15 = G[1]
    _, _, a22, a23, a24, a25 = G[2]
    _, _, _, a33, a34, a35 = G[3]
    _, _, _, _, a44, a45 = G[4]
    _, _, _, _, _, a55 = G[5]
    det = 1.0
    if not a00 > 0.0:
        return 0.0
    det *= a00
    f = a01 / a00
    a11 -= f * a01
    a12 -= f * a02
    a13 -= f * a03
    a14 -= f * a04
    a15 -= f * a05
    f = a02 / a00
    a22 -= f * a02
    a23 -= f * a03
    a24 -= f * a04
    a25 -= f * a05
    f = a03 / a00
    a33 -= f * a03
    a34 -= f * a04
    a35 -= f * a05
    f = a04 / a00
    a44 -= f * a04
    a45 -= f * a05
    f = a05 / a00
    a55 -= f * a05
    if not a11 > 0.0:
        return 0.0
    det *= a11
    f = a12 / a11
    a22 -= f * a12
    a23 -= f * a13
    a24 -= f * a14
    a25 -= f * a15
    f = a13 / a11
    a33 -= f * a13
    a34 -= f * a14
    a35 -= f * a15
    f = a14 / a11
    a44 -= f * a14
    a45 -= f * a15
    f = a15 / a11
    a55 -= f * a15
    if not a22 > 0.0:
        return 0.0
    det *= a22
    f = a23 / a22
    a33 -= f * a23
    a34 -= f * a24
    a35 -= f * a25
    f = a24 / a22
    a44 -= f * a24
    a45 -= f * a25
    f = a25 / a22
    a55 -= f * a25
    if not a33 > 0.0:
        return 0.0
    det *= a33
    f = a34 / a33
    a44 -= f * a34
    a45 -= f * a35
    f = a35 / a33
    a55 -= f * a35
    if not a44 > 0.0:
        return 0.0
    det *= a44
    f = a45 / a44
    a55 -= f * a45
    if not a55 > 0.0:
        return 0.0
    det *= a55
    return det
