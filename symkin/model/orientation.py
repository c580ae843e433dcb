"""Orientation representations and the analytic forms of the Jacobian and the Hessian (numpy only).

The unit quaternion of a rotation and back (:func:`quaternion`, :func:`quaternion_matrix`), the
Euler vector of a rotation (the orientation part of the pose error, Haviland and Corke,
Manipulator Differential Kinematics, Part 1, IEEE Robotics and Automation Magazine, 2023, eqs
38-40), the orientation of a pose in roboticstoolbox-python's representations
(:data:`REPRESENTATIONS`), the rate matrix ``A(gamma)^-1`` mapping angular velocity to their rates
and its derivatives, and from them the analytical Jacobian ``J_a = blkdiag(I, A^-1) J0`` and its
derivative, the analytical Hessian (Haviland and Corke, Manipulator Differential Kinematics,
Part 2: Acceleration and Advanced Applications, 2023, section "Analytic Forms"). The methods
``jacob0_analytical`` and ``hessian0_analytical`` of every kinematics object
(:class:`symkin.model.differential.FrameMethods`) call :func:`analytical_of` and
:func:`analytical_hessian_of`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from symkin.errors import ConfigurationError, ParameterError

__all__ = [
    "NEAR_PI_L",
    "quaternion",
    "quaternion_matrix",
    "angle_axis",
    "REPRESENTATIONS",
    "representation_of",
    "gamma_of",
    "omega_to_rates",
    "rates_derivatives",
    "analytical_of",
    "analytical_hessian_of",
]


# -- unit quaternions (w, x, y, z) --------------------------------------------------------------------
def quaternion(R: Any) -> np.ndarray:
    """Unit quaternion (w, x, y, z), w >= 0, of a rotation matrix (3, 3) (Shepperd's method)."""
    R = np.asarray(R, dtype=float)
    tr = float(np.trace(R))
    i = int(np.argmax([tr, R[0, 0], R[1, 1], R[2, 2]]))
    if i == 0:
        r = 2.0 * math.sqrt(1.0 + tr)
        q = [r / 4, (R[2, 1] - R[1, 2]) / r, (R[0, 2] - R[2, 0]) / r, (R[1, 0] - R[0, 1]) / r]
    elif i == 1:
        r = 2.0 * math.sqrt(max(1.0 + R[0, 0] - R[1, 1] - R[2, 2], 1e-300))
        q = [(R[2, 1] - R[1, 2]) / r, r / 4, (R[0, 1] + R[1, 0]) / r, (R[0, 2] + R[2, 0]) / r]
    elif i == 2:
        r = 2.0 * math.sqrt(max(1.0 + R[1, 1] - R[0, 0] - R[2, 2], 1e-300))
        q = [(R[0, 2] - R[2, 0]) / r, (R[0, 1] + R[1, 0]) / r, r / 4, (R[1, 2] + R[2, 1]) / r]
    else:
        r = 2.0 * math.sqrt(max(1.0 + R[2, 2] - R[0, 0] - R[1, 1], 1e-300))
        q = [(R[1, 0] - R[0, 1]) / r, (R[0, 2] + R[2, 0]) / r, (R[1, 2] + R[2, 1]) / r, r / 4]
    out = np.array(q) / np.linalg.norm(q)
    return -out if out[0] < 0 else out


def quaternion_matrix(q: Any) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of unit quaternions (..., 4) (w, x, y, z), used as given."""
    w, x, y, z = np.moveaxis(np.asarray(q, dtype=float), -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )


# -- the Euler vector of a rotation (the orientation part of the pose error) ------------------------
#: |l| (eq 39) below which a rotation with trace < 0 counts as a half turn for :func:`angle_axis`
NEAR_PI_L = 1e-6


def angle_axis(R: Any) -> np.ndarray:
    """alpha(R) (eqs 38-40): the Euler vector of rotation matrices R (..., 3, 3) -> (..., 3).

    A diagonal R gives 0 for (1, 1, 1) and pi/2 (r11 + 1, r22 + 1, r33 + 1) otherwise (eq 40);
    other matrices use eq 38, except near pi (trace < 0 and |l| < 1e-6), where l of eq 39 is
    rounding noise and the axis comes from the symmetric part of R (its sign from l).
    """
    R = np.asarray(R, dtype=float)
    l = np.stack((R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]), -1)
    tr = np.trace(R, axis1=-2, axis2=-1)
    nl = np.sqrt((l * l).sum(-1))
    diag = (R[..., [0, 0, 1, 1, 2, 2], [1, 2, 0, 2, 0, 1]] == 0).all(-1)
    theta = np.arctan2(nl, tr - 1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        general = np.where((nl == 0)[..., None], 0.0, (theta / nl)[..., None] * l)
        ct = (tr - 1.0) / 2.0
        M = ((R + np.swapaxes(R, -1, -2)) / 2.0 - ct[..., None, None] * np.eye(3)) / (1.0 - ct)[
            ..., None, None
        ]
        d = np.diagonal(M, axis1=-2, axis2=-1)
        k = np.argmax(d, axis=-1)  # first maximum, like the C code
        ak = np.sqrt(np.maximum(np.take_along_axis(d, k[..., None], -1), 0.0))
        col = np.take_along_axis(M, k[..., None, None], -1)[..., 0]
        ax = col / ak
        ax = np.where(np.arange(3) == k[..., None], ak, ax)
        ax = np.where(((ax * l).sum(-1) < 0)[..., None], -ax, ax)
        near_pi = theta[..., None] * ax
    eq40 = np.where((tr > 0)[..., None], 0.0, math.pi / 2 * (np.diagonal(R, axis1=-2, axis2=-1) + 1.0))
    use_general = (tr >= 0) | (nl >= NEAR_PI_L)
    return np.where(diag[..., None], eq40, np.where(use_general[..., None], general, near_pi))


# -- orientation representations and their rates ---------------------------------------------------
#: The orientation representations of :meth:`FrameMethods.jacob0_analytical` and
#: :meth:`FrameMethods.hessian0_analytical` (roboticstoolbox-python's names), gamma = (gamma_1,
#: gamma_2, gamma_3) in rad:
#:
#: - ``"rpy/xyz"``: roll, pitch, yaw with ``R = Rx(yaw) Ry(pitch) Rz(roll)`` (spatialmath ``tr2rpy``
#:   order "xyz"); pitch in [-90, 90] deg, singular at pitch = +-90 deg.
#: - ``"rpy/zyx"``: roll, pitch, yaw with ``R = Rz(yaw) Ry(pitch) Rx(roll)`` (order "zyx");
#:   pitch in [-90, 90] deg, singular at pitch = +-90 deg.
#: - ``"eul"``: ZYZ Euler angles phi, theta, psi with ``R = Rz(phi) Ry(theta) Rz(psi)`` (``tr2eul``);
#:   theta in [0, 180] deg, singular at theta = 0 and 180 deg.
#: - ``"exp"``: exponential coordinates, the rotation vector r = theta n of ``R = exp([r]x)``
#:   (``trlog``), theta in [0, 180] deg. Its rate matrix is singular only at theta = 360 k deg,
#:   k != 0, which the principal rotation vector never reaches (it jumps from r to -r at 180 deg).
REPRESENTATIONS: tuple[str, ...] = ("rpy/xyz", "rpy/zyx", "eul", "exp")

#: Where A(gamma) counts as singular: |cos pitch| (rpy) or |sin theta| (eul) below this.
_SINGULAR_TOL = 1e-6


def representation_of(representation: Any) -> str:
    """``representation`` when it is one of :data:`REPRESENTATIONS`, else ParameterError."""
    if not isinstance(representation, str) or representation not in REPRESENTATIONS:
        raise ParameterError(
            f"representation must be one of {', '.join(repr(r) for r in REPRESENTATIONS)}, "
            f"not {representation!r}"
        )
    return representation


def gamma_of(R: np.ndarray, representation: str) -> np.ndarray:
    """Orientation (N, 3) in ``representation`` (see :data:`REPRESENTATIONS`) of rotations R (N, 3, 3)."""
    if representation == "rpy/xyz":  # R = Rx(y) Ry(p) Rz(r): R[0] = (cp cr, -cp sr, sp)
        roll = np.arctan2(-R[:, 0, 1], R[:, 0, 0])
        pitch = np.arctan2(R[:, 0, 2], np.hypot(R[:, 0, 0], R[:, 0, 1]))
        yaw = np.arctan2(-R[:, 1, 2], R[:, 2, 2])
        return np.stack((roll, pitch, yaw), axis=-1)
    if representation == "rpy/zyx":  # R = Rz(y) Ry(p) Rx(r): R[2] = (-sp, cp sr, cp cr)
        roll = np.arctan2(R[:, 2, 1], R[:, 2, 2])
        pitch = np.arctan2(-R[:, 2, 0], np.hypot(R[:, 0, 0], R[:, 1, 0]))
        yaw = np.arctan2(R[:, 1, 0], R[:, 0, 0])
        return np.stack((roll, pitch, yaw), axis=-1)
    if representation == "eul":  # R = Rz(phi) Ry(theta) Rz(psi): R[:, 2] = (cphi sth, sphi sth, cth)
        phi = np.arctan2(R[:, 1, 2], R[:, 0, 2])
        theta = np.arctan2(np.hypot(R[:, 0, 2], R[:, 1, 2]), R[:, 2, 2])
        psi = np.arctan2(R[:, 2, 1], -R[:, 2, 0])
        return np.stack((phi, theta, psi), axis=-1)
    return angle_axis(R)  # the principal rotation vector, theta in [0, pi]


def _skew_rows(g: np.ndarray) -> np.ndarray:
    """[g]x (N, 3, 3) of vectors g (N, 3)."""
    K = np.zeros((len(g), 3, 3))
    K[:, 0, 1], K[:, 0, 2], K[:, 1, 2] = -g[:, 2], g[:, 1], -g[:, 0]
    K[:, 1, 0], K[:, 2, 0], K[:, 2, 1] = g[:, 2], -g[:, 1], g[:, 0]
    return K


def _exp_coefficients(th: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(c, c'/theta) of the inverse left Jacobian ``I - K/2 + c(theta) K^2`` of SO(3): ``c = (1 -
    (theta/2) cot(theta/2)) / theta^2`` and ``c'(theta)/theta = (theta^2 / sin^2(theta/2) + 2 theta
    cot(theta/2) - 8) / (4 theta^4)``, each from its Taylor series near 0, where the closed form
    cancels (1/12 + theta^2/720 + ..., 1/360 + theta^2/7560 + ...)."""
    t2 = th * th
    with np.errstate(divide="ignore", invalid="ignore"):
        cot = 1.0 / np.tan(th / 2.0)
        c = (1.0 - (th / 2.0) * cot) / t2
        d = (t2 / np.sin(th / 2.0) ** 2 + 2.0 * th * cot - 8.0) / (4.0 * t2 * t2)
    c = np.where(th < 1e-2, 1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0, c)
    d = np.where(th < 0.2, 1.0 / 360.0 + t2 / 7560.0 + t2 * t2 / 201600.0 + t2**3 / 5987520.0, d)
    return c, d


def omega_to_rates(gamma: np.ndarray, representation: str, what: str = "Jacobian") -> np.ndarray:
    """A(gamma)^-1 (N, 3, 3), mapping base-frame angular velocity omega to d gamma/dt, in closed form
    (the inverse of ``omega = A(gamma) d gamma/dt``; Corke, Robotics, Vision and Control, 3rd ed.,
    2023, chap 8; spatialmath's ``rotvelxform(inverse=True)``). ConfigurationError where A is
    singular, naming the analytical ``what`` ("Jacobian" or "Hessian") and the angle."""
    g1, g2, g3 = gamma[:, 0], gamma[:, 1], gamma[:, 2]
    z, o = np.zeros_like(g1), np.ones_like(g1)
    if representation == "exp":
        # A^-1 = J_l(r)^-1, the inverse left Jacobian of SO(3): omega (base frame) = J_l(r) dr/dt, theta <= pi
        th = np.linalg.norm(gamma, axis=-1)
        bad = (np.abs(np.sin(th / 2.0)) < _SINGULAR_TOL) & (th > 1.0)
        _raise_singular(bad, representation, "rotation angle", th, what)
        K = _skew_rows(gamma)
        return np.eye(3) - K / 2.0 + _exp_coefficients(th)[0][:, None, None] * (K @ K)
    if representation == "eul":  # omega = (0, 0, 1) dphi + (-sphi, cphi, 0) dtheta + R[:, 2] dpsi
        s2 = np.sin(g2)
        _raise_singular(np.abs(s2) < _SINGULAR_TOL, representation, "theta", g2, what)
        c1, s1, c2 = np.cos(g1), np.sin(g1), np.cos(g2)
        rows = ((-c1 * c2 / s2, -s1 * c2 / s2, o), (-s1, c1, z), (c1 / s2, s1 / s2, z))
    else:
        c2 = np.cos(g2)
        _raise_singular(np.abs(c2) < _SINGULAR_TOL, representation, "pitch", g2, what)
        t2 = np.tan(g2)
        c3, s3 = np.cos(g3), np.sin(g3)
        if representation == "rpy/xyz":  # omega = R[:, 2] droll + Rx(yaw) y dpitch + x dyaw
            rows = ((z, -s3 / c2, c3 / c2), (z, c3, s3), (o, s3 * t2, -c3 * t2))
        else:  # rpy/zyx: omega = R[:, 0] droll + Rz(yaw) y dpitch + z dyaw
            rows = ((c3 / c2, s3 / c2, z), (-s3, c3, z), (c3 * t2, s3 * t2, o))
    return _matrices(rows)


def _matrices(rows: Any) -> np.ndarray:
    """(N, 3, 3) from three rows of three (N,) arrays."""
    return np.stack([np.stack(r, axis=-1) for r in rows], axis=-2)


def rates_derivatives(gamma: np.ndarray, representation: str) -> np.ndarray:
    """dA^-1/dgamma_k (N, 3, 3, 3), ``D[:, k] = d omega_to_rates(gamma) / d gamma_k``, in closed form;
    call it where :func:`omega_to_rates` did not raise (A regular)."""
    g1, g2, g3 = gamma[:, 0], gamma[:, 1], gamma[:, 2]
    z = np.zeros_like(g1)
    zero = ((z, z, z), (z, z, z), (z, z, z))
    if representation == "exp":  # d/dr_k (I - K/2 + c K^2) = -E_k/2 + c (E_k K + K E_k) + (c'/th) r_k K^2
        th = np.linalg.norm(gamma, axis=-1)
        c, d = _exp_coefficients(th)
        K = _skew_rows(gamma)
        E = _skew_rows(np.eye(3))  # E[k] = [e_k]x
        EK = np.einsum("kab,Nbc->Nkac", E, K)
        KE = np.einsum("Nab,kbc->Nkac", K, E)
        KK = K @ K
        dK2 = (d[:, None] * gamma)[:, :, None, None] * KK[:, None]
        return -E[None] / 2.0 + c[:, None, None, None] * (EK + KE) + dK2
    if representation == "eul":  # rows (-c1 cot2, -s1 cot2, 1), (-s1, c1, 0), (c1 / s2, s1 / s2, 0)
        c1, s1, s2, c2 = np.cos(g1), np.sin(g1), np.sin(g2), np.cos(g2)
        d1 = ((s1 * c2 / s2, -c1 * c2 / s2, z), (-c1, -s1, z), (-s1 / s2, c1 / s2, z))
        w = 1.0 / (s2 * s2)
        d2 = ((c1 * w, s1 * w, z), (z, z, z), (-c1 * c2 * w, -s1 * c2 * w, z))
        return np.stack((_matrices(d1), _matrices(d2), _matrices(zero)), axis=1)
    c2, s2 = np.cos(g2), np.sin(g2)
    c3, s3 = np.cos(g3), np.sin(g3)
    w, t2 = 1.0 / (c2 * c2), np.tan(g2)  # d(1/c2) = s2 w, d(t2) = w
    if representation == "rpy/xyz":  # rows (0, -s3/c2, c3/c2), (0, c3, s3), (1, s3 t2, -c3 t2)
        d2 = ((z, -s3 * s2 * w, c3 * s2 * w), (z, z, z), (z, s3 * w, -c3 * w))
        d3 = ((z, -c3 / c2, -s3 / c2), (z, -s3, c3), (z, c3 * t2, s3 * t2))
    else:  # rpy/zyx: rows (c3/c2, s3/c2, 0), (-s3, c3, 0), (c3 t2, s3 t2, 1)
        d2 = ((c3 * s2 * w, s3 * s2 * w, z), (z, z, z), (c3 * w, s3 * w, z))
        d3 = ((-s3 / c2, c3 / c2, z), (-c3, -s3, z), (-s3 * t2, c3 * t2, z))
    return np.stack((_matrices(zero), _matrices(d2), _matrices(d3)), axis=1)


def _raise_singular(
    bad: np.ndarray, representation: str, angle: str, values: np.ndarray, what: str = "Jacobian"
) -> None:
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        where = f" (configuration {i} of the batch)" if len(bad) > 1 else ""
        deg = round(math.degrees(float(values[i])), 4) + 0.0  # + 0.0: no -0
        raise ConfigurationError(
            f"the analytical {what} is singular for {representation} at {angle} = {deg:.6g} deg"
            f"{where}; use another representation"
        )


# -- the analytic forms ------------------------------------------------------------------------------
def analytical_of(T: np.ndarray, J: np.ndarray, representation: str = "rpy/xyz") -> np.ndarray:
    """Analytical Jacobian (N, 6, n), ``blkdiag(I, A(gamma)^-1) J``, from the base-frame pose T (N, 4, 4)
    and Jacobian J (N, 6, n) (rows (v, omega)) of a frame; gamma is the orientation of T in
    ``representation`` (:data:`REPRESENTATIONS`). ConfigurationError where A is singular."""
    rep = representation_of(representation)
    Ainv = omega_to_rates(gamma_of(T[:, :3, :3], rep), rep)
    return np.concatenate((J[:, :3], Ainv @ J[:, 3:]), axis=1)


def analytical_hessian_of(
    T: np.ndarray, J: np.ndarray, H: np.ndarray, representation: str = "rpy/xyz"
) -> np.ndarray:
    """Analytical Hessian (N, n, 6, n), ``Ha[:, i] = dJ_a/dq_i``, from the base-frame pose T (N, 4, 4),
    Jacobian J (N, 6, n) and Hessian H (N, n, 6, n) (``H[:, i] = dJ0/dq_i``) of a frame.

    With ``J_a = (Jv ; B Jw)``, ``B = A(gamma)^-1`` (:func:`omega_to_rates`) and ``dgamma/dq_i`` the
    column i of ``B Jw`` (the analytical Jacobian's rate rows), the product rule gives
    ``dJ_a/dq_i = (Hv_i ; B Hw_i + (sum_k dB/dgamma_k (B Jw)[k, i]) Jw)`` (Haviland and Corke,
    Manipulator Differential Kinematics, Part 2, 2023, section "Analytic Forms"; ``dB/dgamma``
    from :func:`rates_derivatives`). The translational rows are those of H. ConfigurationError
    where A is singular, as for the analytical Jacobian."""
    rep = representation_of(representation)
    gamma = gamma_of(T[:, :3, :3], rep)
    B = omega_to_rates(gamma, rep, "Hessian")
    D = rates_derivatives(gamma, rep)
    Jw = J[:, 3:]
    rates = B @ Jw  # (N, 3, n): dgamma/dq
    dB = np.einsum("Nkab,Nki->Niab", D, rates)  # (N, n, 3, 3): dB/dq_i
    Hw = np.einsum("Nab,Nibj->Niaj", B, H[:, :, 3:]) + dB @ Jw[:, None]
    return np.concatenate((H[:, :, :3], Hw), axis=2)
