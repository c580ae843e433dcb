"""The analytical Jacobian as exact sympy expressions: ``symkin.symbolic.jacob0_analytical(robot, rep)``.

``J_a = blkdiag(I, A(gamma)^-1) J0`` maps qd to (v, d gamma/dt), gamma the end effector's
orientation in one of roboticstoolbox-python's representations (:data:`REPRESENTATIONS`, the
same conventions as the numeric :meth:`symkin.Kinematics.jacob0_analytical`; Corke, Robotics,
Vision and Control, 3rd ed., 2023, chap 8; Lynch and Park, Modern Robotics, 2017, for the
exponential coordinates).

Keeping it short: A(gamma)^-1 is not written in the angles (``atan2`` of entries of R, whose
sines and cosines sympy would not simplify) but in the entries r_ij of the rotation R of the
pose, with ``cos(pitch) = sqrt(r_12^2 + r_22^2)`` and so on, then R's entries are substituted (the
rotation's subexpressions are shared with J0). Singularities: rpy where ``cos(pitch) = 0`` (pitch
= +-90 deg), ``eul`` where ``sin(theta) = sqrt(r_13^2 + r_23^2) = 0`` (theta = 0 or 180 deg): the
expressions divide by zero there. ``exp`` uses ``theta = atan2(|l|, tr R - 1)`` and ``r = theta l /
|l|`` with ``l = vee(R - R^T)`` (the principal rotation vector): 0/0 at theta = 0 (the limit is
``A^-1 = I``) and undefined at theta = 180 deg, where the principal vector jumps.

Size: the rpy and eul forms add a few operations per entry of J0's rotational rows; the exp form
is larger (the Panda's, written out as trees, about 185,000 operations against about 10,000 for
rpy), so print or lambdify it with common subexpressions (``sympy.lambdify(..., cse=True)``).
"""

from __future__ import annotations

from typing import Any

import sympy as sp

from symkin.errors import SymkinError
from symkin.model.differential import REPRESENTATIONS

__all__ = ["jacob0_analytical", "rates_from_omega", "REPRESENTATIONS"]


def rates_from_omega(R: sp.Matrix, representation: str) -> sp.Matrix:
    """A(gamma)^-1 (3 x 3) in the entries of the rotation matrix R: ``d gamma/dt = A^-1 omega`` with
    omega the angular velocity in the base frame (see the module docstring)."""
    if representation == "rpy/xyz":  # R = Rx(yaw) Ry(pitch) Rz(roll): R[:, 2] = (sp, -sy cp, cy cp)
        cp = sp.sqrt(R[1, 2] ** 2 + R[2, 2] ** 2)
        c3, s3, t2 = R[2, 2] / cp, -R[1, 2] / cp, R[0, 2] / cp
        return sp.Matrix([[0, -s3 / cp, c3 / cp], [0, c3, s3], [1, s3 * t2, -c3 * t2]])
    if representation == "rpy/zyx":  # R = Rz(yaw) Ry(pitch) Rx(roll): R[:, 0] = (cy cp, sy cp, -sp)
        cp = sp.sqrt(R[0, 0] ** 2 + R[1, 0] ** 2)
        c3, s3, t2 = R[0, 0] / cp, R[1, 0] / cp, -R[2, 0] / cp
        return sp.Matrix([[c3 / cp, s3 / cp, 0], [-s3, c3, 0], [c3 * t2, s3 * t2, 1]])
    if representation == "eul":  # R = Rz(phi) Ry(theta) Rz(psi): R[:, 2] = (cphi sth, sphi sth, cth)
        st = sp.sqrt(R[0, 2] ** 2 + R[1, 2] ** 2)
        c1, s1, c2 = R[0, 2] / st, R[1, 2] / st, R[2, 2]
        return sp.Matrix([[-c1 * c2 / st, -s1 * c2 / st, 1], [-s1, c1, 0], [c1 / st, s1 / st, 0]])
    if representation == "exp":  # A^-1 = J_l(r)^-1, the inverse left Jacobian of SO(3)
        l = sp.Matrix([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
        nl = sp.sqrt(l.dot(l))
        th = sp.atan2(nl, R.trace() - 1)
        r = th / nl * l
        K = sp.Matrix([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
        coef = (1 - (th / 2) / sp.tan(th / 2)) / th**2
        return sp.eye(3) - K / 2 + coef * K * K
    raise SymkinError(
        f"representation must be one of {', '.join(repr(r) for r in REPRESENTATIONS)}, not {representation!r}"
    )


def jacob0_analytical(robot: Any, representation: str = "rpy/xyz") -> sp.Matrix:
    """The analytical Jacobian (6 x n) of ``robot``'s end effector in the joint symbols q0 .. q{n-1}:
    rows (v, d gamma/dt), ``blkdiag(I, A(gamma)^-1) J0`` (see the module docstring).

    ``robot``: a Robot, an ETS or any ROBOT spec (``"ur5"``); the symbols are those of
    ``symkin.symbolic(robot).q``.
    """
    if representation not in REPRESENTATIONS:
        rates_from_omega(sp.eye(3), representation)  # raises, naming the valid ones
    from symkin.symbolic.expressions import symbolic

    k = symbolic(robot)
    r = sp.Matrix(3, 3, lambda i, j: sp.Symbol(f"zzr{i}{j}"))
    Ainv = rates_from_omega(r, representation).xreplace(
        {r[i, j]: k.T[i, j] for i in range(3) for j in range(3)}
    )
    return sp.Matrix.vstack(k.J0[:3, :], Ainv * k.J0[3:, :])
