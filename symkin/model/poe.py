"""Product of exponentials (Lynch and Park, Modern Robotics, 2017, chapter 4) to an exact ETS, and back
(numerically).

Space form ``T(q) = e^[S1]q1 ... e^[Sn]qn M``; body form ``T(q) = M e^[B1]q1 ... e^[Bn]qn`` with
``B_i = Ad_{M^-1} S_i``. Screws are rows ``(omega, v)`` (twist order of Modern
Robotics). A revolute screw has ``|omega| = 1`` and pitch 0 (``v = -omega x p`` for a point ``p``
on the axis); a prismatic screw has ``omega = 0`` and ``|v| = 1``. Helical screws are rejected.

Each ``e^[S]q`` becomes ``G E(q) G^-1`` (the ETS of Haviland and Corke, Manipulator Differential
Kinematics, Part 1, 2023, eq 1): ``G = tx ty tz(p)`` times an exact rotation
taking a coordinate axis onto ``omega`` (none when ``omega`` is +-x/y/z, so the joint is one ET),
``E(q)`` an elementary joint transform. ``M`` becomes ``tx ty tz`` and ZYX angles
``Rz Ry Rx`` (exact quarter turns when its rotation is a signed permutation). Adjacent constants
on the same axis are merged and runs of translations combined.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from fractions import Fraction
from typing import Any

import numpy as np

from symkin.core.arrays import as_config
from symkin.core.pose import as_pose
from symkin.errors import RobotError
from symkin.model.dh import robot_args
from symkin.model.ets import ET, Const
from symkin.model.kinematics import const_matrix, et_matrix
from symkin.model.transform import zyx_ets
from symkin.model.urdf import axis_ets, snap_atan2, translation_ets

__all__ = ["poe_args", "poe_of"]

_FRAMES = ("space", "body")
_CHECK = 1e-6  # tolerance of the unit-length, pitch and orthonormality checks


_LIMIT = 1e150


def _tidy(x: Fraction) -> Fraction:
    """Keep small exact rationals; a huge denominator (from float inputs) becomes the float's decimal."""
    return x if x.denominator <= 10**15 else Fraction(repr(float(x)))


def _exact(value: Any, what: str, tol: float) -> Fraction:
    """An exact rational from a number; floats within ``tol`` of 0 or +-1 snap to them."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise RobotError(f"{what} must be a number, not {type(value).__name__} {value!r}")
    if isinstance(value, (numbers.Integral, Fraction)):
        if abs(value) > _LIMIT:
            raise RobotError(f"{what} is too large: PoE data must be within +-{_LIMIT:g}")
        return Fraction(value)
    x = float(value)
    if not math.isfinite(x):
        raise RobotError(f"{what} is {x}: PoE data must be finite")
    if abs(x) > _LIMIT:  # squares in norms must not overflow
        raise RobotError(f"{what} is {x:.3g}: PoE data must be within +-{_LIMIT:g}")
    for target in (0, 1, -1):
        if abs(x - target) <= tol:
            return Fraction(target)
    return Fraction(repr(x))


def _matrix(a: Any, shape: tuple[int, ...] | None, what: str, tol: float) -> list[list[Fraction]]:
    arr = np.asarray(a, dtype=object)
    if arr.ndim != 2 or (shape is not None and arr.shape != shape):
        want = "x".join(map(str, shape)) if shape else "2-D"
        raise RobotError(f"{what} must be a {want} array, got shape {arr.shape}")
    return [
        [_exact(x, f"{what}[{i}, {j}]", tol) for j, x in enumerate(row)] for i, row in enumerate(arr.tolist())
    ]


def _merge(a: Const, b: Const) -> Const | None:
    """a + b, or None when not representable (two different atan2 terms)."""
    if a.atan2 is not None and b.atan2 is not None:
        return Const() if -b == a else None
    return a + b


def simplify_constants(chain: list[ET], tol: float = 0.0) -> list[ET]:
    """Merge runs of constant translations and adjacent same-axis constants; drop zeros.

    Exact, except that a merged translation within ``tol`` of 0 (float noise) is dropped.
    """
    changed = True
    while changed:
        changed = False
        out: list[ET] = []
        i = 0
        while i < len(chain):
            e = chain[i]
            if e.is_joint:
                out.append(e)
                i += 1
                continue
            if not e.axis.is_rotation:  # a run of constant translations commutes: sum per axis
                j = i
                total = [Const(), Const(), Const()]
                while j < len(chain) and not chain[j].is_joint and not chain[j].axis.is_rotation:
                    total[chain[j].axis.index] = total[chain[j].axis.index] + chain[j].const
                    j += 1
                merged = translation_ets([Const() if abs(t.value) <= tol else t for t in total])
                changed |= [str(x) for x in merged] != [str(x) for x in chain[i:j]]
                out += merged
                i = j
                continue
            if e.const.is_zero:
                changed = True
            elif out and not out[-1].is_joint and out[-1].axis == e.axis:
                s = _merge(out[-1].const, e.const)
                if s is None:
                    out.append(e)
                else:
                    changed = True
                    out.pop()
                    if not s.is_zero:
                        out.append(ET(e.axis, const=s))
            else:
                out.append(e)
            i += 1
        chain = out
    return chain


def _screw_ets(S: list[Fraction], j: int, tol: float) -> list[ET]:
    """``e^[S]q`` of joint ``j`` as ETs (Modern Robotics): ``G E(q) G^-1``."""
    w, v = S[:3], S[3:]
    wn = math.sqrt(sum(float(c) ** 2 for c in w))
    vn = math.sqrt(sum(float(c) ** 2 for c in v))
    if wn <= tol:
        if abs(vn - 1) > _CHECK:
            raise RobotError(
                f"screw {j} (omega = 0, prismatic) has |v| = {vn:.6g}; a prismatic screw needs a unit v"
            )
        return [snap_atan2(e, tol) for e in axis_ets(v, j, revolute=False)]
    if abs(wn - 1) > _CHECK:
        raise RobotError(
            f"screw {j} has |omega| = {wn:.6g}; a revolute screw needs a unit omega "
            "(and a prismatic one omega = 0)"
        )
    w2 = sum(c * c for c in w)
    pitch = float(sum(a * b for a, b in zip(w, v)) / w2)
    if abs(pitch) > _CHECK:
        raise RobotError(
            f"screw {j} is helical (pitch omega.v = {pitch:.6g}); only revolute screws (pitch 0, "
            "v = -omega x p) and prismatic screws (omega = 0) are supported"
        )
    p = [(w[1] * v[2] - w[2] * v[1]) / w2, (w[2] * v[0] - w[0] * v[2]) / w2, (w[0] * v[1] - w[1] * v[0]) / w2]
    p = [Fraction(0) if abs(c) <= tol else _tidy(c) for c in p]
    rot = [snap_atan2(e, tol) for e in axis_ets(w, j, revolute=True)]
    return translation_ets(p) + rot + translation_ets([-c for c in p])


def poe_args(
    M: Any,
    screws: Any,
    frame: str = "space",
    name: str = "robot",
    qlim: Any = None,
    configs: Mapping[str, Any] | None = None,
    qd_max: Any = None,
    source: str = "",
    joint_names: Sequence[str] | None = None,
    tol: float = 1e-9,
) -> dict[str, Any]:
    """A robot from the home pose ``M`` (4x4) and screws (n, 6) rows ``(omega, v)`` (Modern Robotics).

    ``frame="space"``: ``T = e^[S1]q1 ... e^[Sn]qn M``; ``frame="body"``: ``T = M e^[B1]q1 ... e^[Bn]qn``.
    Entries within ``tol`` of 0 or +-1 are snapped to them.
    """
    if frame not in _FRAMES:
        raise RobotError(f"frame must be one of {list(_FRAMES)}, not {frame!r}")
    checked = as_pose(M, "M", RobotError)  # the one pose rule first, then PoE's exact numbers
    Mx = _matrix(M if isinstance(M, (np.ndarray, list, tuple)) else checked, (4, 4), "M", tol)
    Mf = np.array([[float(x) for x in row] for row in Mx])
    as_pose(Mf, "M", RobotError)  # and on the snapped entries
    R = Mf[:3, :3]
    arr = np.asarray(screws, dtype=object)
    if arr.ndim == 1 and arr.shape == (6,):
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != 6 or arr.shape[0] == 0:
        raise RobotError(f"screws must have shape (n, 6), rows (omega, v), got shape {arr.shape}")
    Sx = _matrix(arr, None, "screws", tol)
    home = translation_ets([Mx[0][3], Mx[1][3], Mx[2][3]]) + zyx_ets(R, tol)
    joints: list[ET] = []
    for j, S in enumerate(Sx):
        joints += _screw_ets(S, j, tol)
    chain = joints + home if frame == "space" else home + joints
    chain = simplify_constants(chain, tol)
    source = source or f"product of exponentials ({frame} form), {len(Sx)} screws"
    args = robot_args(chain, name, qlim, configs, joint_names, qd_max, source)
    T0 = np.eye(4)
    for e in args["ets"]:  # the pose at q = 0
        T0 = T0 @ (et_matrix(e.axis, 0.0) if e.is_joint else const_matrix(e.axis, e.const))
    if np.abs(T0 - Mf).max() > _CHECK:  # guard against a decomposition bug: T(0) must be M
        raise RobotError(
            f"internal error: the ETS of M does not reproduce M (max error {np.abs(T0 - Mf).max():.3g})"
        )
    return args


def poe_of(robot: Any, q: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """Space-form PoE data of ``robot`` about ``q`` (default zeros): ``(M (4, 4), S (n, 6))``.

    ``M = T(q)`` and ``S`` the space Jacobian's columns at ``q`` (Modern Robotics, ``J_s1 = S_1``...),
    so ``T(q + dq) = e^[S1]dq1 ... e^[Sn]dqn M``.
    """
    q = np.zeros(robot.n) if q is None else as_config(q, robot.n, robot.name)
    return robot.fkine(q), robot.jacobs(q).T.copy()
