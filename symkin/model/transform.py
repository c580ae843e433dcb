"""Constant transforms as exact elementary transforms: tool and base offsets, SE(3) matrices.

:func:`constant_ets` turns what a user hands over as a fixed transform (ETS text, a symkin ETS
or ET, ``"x y z roll pitch yaw"``, a 4x4 matrix, a spatialmath ``SE3`` or a roboticstoolbox
ETS without joints) into a list of constant :class:`symkin.ET`. :func:`se3_ets` splits a 4x4
homogeneous matrix ``[R t; 0 1]`` into translations then rotations, ``tx ty tz`` then
``Rz(yaw) Ry(pitch) Rx(roll)`` (the fixed-axis roll-pitch-yaw convention of URDF,
``R = Rz(yaw) Ry(pitch) Rx(roll)``), or a single rotation when ``R`` turns about one coordinate
axis.

Exactness: a float matrix holds rounding noise, so its numbers are snapped the way the URDF
importer snaps (see :mod:`symkin.model.urdf`): an angle within ``snap_tol`` (default 1e-9 rad) of
``k pi / m`` with ``m <= 12`` becomes exactly that multiple of pi (``1.5707963267948966`` is
``pi/2``); a length within ``LENGTH_TOL`` (2e-15, about 8 units in the last place, relative to
max(1, |x|)) of a shorter decimal becomes that decimal (``0.6718299999999999`` is ``0.67183``), and
within it of 0 it becomes 0. Text stays exact as written (``"0 0 0.1 0 0 pi/2"``).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from fractions import Fraction
from typing import Any

import numpy as np

from symkin.core.pose import as_pose
from symkin.errors import ETSParseError, RobotError
from symkin.model.ets import ET, ETS, Axis, Const

__all__ = [
    "constant_ets",
    "se3_ets",
    "rpy_ets",
    "zyx_ets",
    "rpy_matrix",
    "length_const",
    "type_name",
    "SNAP_TOL",
    "LENGTH_TOL",
]

SNAP_TOL = 1e-9  # rad: angles this close to k pi / m (m <= 12) become exact
LENGTH_TOL = 2e-15  # lengths this close (relative to max(1, |x|)) to a shorter decimal become it
_ROT = (Axis.Rx, Axis.Ry, Axis.Rz)
_TRANS = (Axis.tx, Axis.ty, Axis.tz)


def type_name(obj: Any) -> str:
    """The full name of ``obj``'s type for error messages: ``roboticstoolbox.ets.ETS.ETS``, ``int``."""
    t = type(obj)
    module = getattr(t, "__module__", "")
    return t.__qualname__ if module in ("builtins", "") else f"{module}.{t.__qualname__}"


def length_const(x: float, tol: float = LENGTH_TOL) -> Const:
    """A float length as an exact constant: 0 or the shortest decimal within ``tol * max(1, |x|)``
    (rounding noise of float products removed), else the exact decimal the float prints as."""
    if not math.isfinite(x):
        raise RobotError(f"a length must be finite, not {x}")
    bound = tol * max(1.0, abs(x))
    if abs(x) <= bound:
        return Const()
    for places in range(16):
        r = round(x, places)
        if abs(x - r) <= bound:
            return Const(Fraction(repr(r)))
    return Const(Fraction(repr(x)))


def angle_const(x: float, tol: float = SNAP_TOL) -> Const:
    """A float angle (rad) as an exact constant: ``k pi / m`` (m <= 12) within ``tol``, else the
    exact decimal the float prints as."""
    if not math.isfinite(x):
        raise RobotError(f"an angle must be finite, not {x}")
    for m in range(1, 13):
        k = round(x * m / math.pi)
        if abs(x - k * math.pi / m) <= tol:
            return Const.pi_times(Fraction(k, m))
    return Const(Fraction(repr(x)))


def _rotation_ets(R: np.ndarray, tol: float) -> list[ET]:
    """Rotations equal to ``R``: one ET when R turns about a coordinate axis, else
    ``Rz(yaw) Ry(pitch) Rx(roll)``; zero angles dropped."""
    for i, axis in enumerate(_ROT):  # about axis i: column i and row i are e_i
        e = np.eye(3)[i]
        if np.abs(R[:, i] - e).max() <= tol and np.abs(R[i, :] - e).max() <= tol:
            j, k = ((1, 2), (2, 0), (0, 1))[i]
            c = angle_const(math.atan2(R[k, j], R[j, j]), tol)
            return [] if c.is_zero else [ET(axis, const=c)]
    return zyx_ets(R, tol)


def zyx_ets(R: np.ndarray, tol: float = SNAP_TOL) -> list[ET]:
    """``Rz(yaw) Ry(pitch) Rx(roll)`` (ZYX Euler angles, each snapped by :func:`angle_const`) equal
    to the rotation ``R``; zero angles dropped."""
    cp = math.hypot(R[0, 0], R[1, 0])
    pitch = math.atan2(-R[2, 0], cp)
    if cp > 1e-9:
        yaw, roll = math.atan2(R[1, 0], R[0, 0]), math.atan2(R[2, 1], R[2, 2])
    else:  # gimbal lock: pitch = +-pi/2, the rotation about z goes into yaw
        yaw, roll = math.atan2(-R[0, 1], R[1, 1]), 0.0
    return rpy_ets((), [angle_const(a, tol) for a in (roll, pitch, yaw)])


def se3_ets(T: Any, what: str = "transform", snap_tol: float = SNAP_TOL) -> list[ET]:
    """A 4x4 homogeneous matrix ``[R t; 0 1]`` as ``tx ty tz`` then rotations (module docstring).

    Raises RobotError when ``T`` breaks the one pose rule (:func:`symkin.core.pose.as_pose`: 4x4,
    finite, bottom row (0, 0, 0, 1), R orthonormal to 1e-6 with det R > 0).
    """
    M = as_pose(T, what, RobotError)  # the one pose rule
    R = M[:3, :3]
    return rpy_ets([length_const(float(v)) for v in M[:3, 3]]) + _rotation_ets(R, snap_tol)


def rpy_ets(xyz: Sequence[Const], rpy: Sequence[Const] = ()) -> list[ET]:
    """``tx ty tz Rz(yaw) Ry(pitch) Rx(roll)`` from exact constants, zeros dropped."""
    out = [ET(a, const=c) for a, c in zip(_TRANS, xyz) if not c.is_zero]
    if rpy:
        roll, pitch, yaw = rpy
        out += [
            ET(a, const=c) for a, c in ((Axis.Rz, yaw), (Axis.Ry, pitch), (Axis.Rx, roll)) if not c.is_zero
        ]
    return out


def rpy_matrix(xyz: Any, rpy: Any) -> np.ndarray:
    """The 4x4 homogeneous transform (floats) of translation ``xyz`` and fixed-axis roll, pitch,
    yaw ``rpy`` (rad): rotation ``Rz(yaw) Ry(pitch) Rx(roll)``, as a URDF ``<origin>``."""
    r, p, y = (float(v) for v in rpy)
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    T = np.eye(4)
    T[:3, :3] = [
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ]
    T[:3, 3] = [float(v) for v in xyz]
    return T


def _text_ets(text: str, what: str, snap_tol: float) -> list[ET]:
    """ETS text of constants, or 3 (x y z), 6 (x y z roll pitch yaw) or 16 (row-major matrix) numbers."""
    if "(" in text:
        try:
            return list(ETS.parse(text))
        except ETSParseError as exc:
            raise RobotError(f"{what}: {str(exc).splitlines()[0]}") from None
    cells = text.replace(",", " ").split()
    if len(cells) == 16:
        try:
            values = [float(c) for c in cells]
        except ValueError:
            raise RobotError(f"{what}: the 16 matrix entries must be plain numbers, got {text!r}") from None
        return se3_ets(np.array(values).reshape(4, 4), what, snap_tol)
    if len(cells) not in (3, 6):
        raise RobotError(
            f"{what} must be constant ETS text like 'tz(0.1) Rx(pi/2)', or 'x y z', 'x y z roll pitch yaw' "
            f"(m, rad) or 16 numbers of a 4x4 matrix; got {len(cells)} numbers in {text!r}"
        )
    try:
        consts = [Const.of(c) for c in cells]
    except ETSParseError as exc:
        raise RobotError(f"{what}: {str(exc).splitlines()[0]}") from None
    return rpy_ets(consts[:3], consts[3:])


def is_rtb(obj: Any) -> bool:
    """A roboticstoolbox ET or ETS (duck-typed: no import of roboticstoolbox)."""
    first = obj
    if not hasattr(obj, "isjoint"):
        try:
            first = next(iter(obj))
        except (TypeError, StopIteration):
            return False
    return hasattr(first, "isjoint") and (hasattr(first, "kind") or hasattr(first, "axis"))


def constant_ets(value: Any, what: str = "transform", snap_tol: float = SNAP_TOL) -> list[ET]:
    """The constant ETs of a tool or base transform given in any of the module's forms.

    Accepts None (none), ETS text or numbers (see :func:`_text_ets`), a symkin ETS, ET or list of
    ET, a 4x4 matrix, an object with a 4x4 ``.A`` (spatialmath ``SE3``), or a roboticstoolbox ET
    or ETS. Joints are refused; zero constants are dropped.
    """
    if value is None:
        return []
    if isinstance(value, str):
        out = _text_ets(value, what, snap_tol)
    elif isinstance(value, ETS):
        out = list(value)
    elif isinstance(value, ET):
        out = [value]
    elif isinstance(value, (list, tuple)) and all(isinstance(e, ET) for e in value):  # [] too
        out = list(value)
    elif isinstance(value, np.ndarray) or (
        isinstance(value, (list, tuple))
        and len(value) == 4
        and all(isinstance(r, (list, tuple)) for r in value)
    ):
        out = se3_ets(value, what, snap_tol)
    elif is_rtb(value):
        chain, _ = rtb_ets(value, snap_tol)
        out = chain
    elif isinstance(getattr(value, "A", None), (np.ndarray, list)):  # spatialmath SE3: the pose rule
        out = se3_ets(value, what, snap_tol)
    else:
        raise RobotError(
            f"{what} must be constant ETS text, 'x y z roll pitch yaw', a symkin ETS or ET, a 4x4 matrix, a "
            f"spatialmath SE3 or a roboticstoolbox ETS; not {type_name(value)}"
        )
    for e in out:
        if e.is_joint:
            raise RobotError(f"{what} must be constant, but contains the joint {e}")
    return [e for e in out if not e.const.is_zero]


# -- roboticstoolbox ETS ----------------------------------------------------------------------
RTB_KINDS = {
    "tx": Axis.tx,
    "ty": Axis.ty,
    "tz": Axis.tz,
    "Rx": Axis.Rx,
    "Ry": Axis.Ry,
    "Rz": Axis.Rz,
    "R": Axis.Rz,
}


def rtb_kind(et: Any) -> str:
    kind = getattr(et, "kind", None)
    if kind is None:
        kind = getattr(et, "axis", None)
    return str(kind)


def _param(et: Any) -> Any:
    return et.param if hasattr(et, "param") else getattr(et, "eta", None)


def _matrix_4x4(et: Any, kind: str) -> np.ndarray:
    A = np.asarray(et.A(), dtype=float)
    if kind == "SE2":  # (3, 3) planar transform: rotation about z and a translation in xy
        M = np.eye(4)
        M[:2, :2], M[:2, 3] = A[:2, :2], A[:2, 2]
        return M
    return A


def rtb_ets(ets: Any, snap_tol: float = SNAP_TOL) -> tuple[list[ET], list[tuple[int, Any]]]:
    """symkin ETs of a roboticstoolbox ET or ETS, and (roboticstoolbox jindex, ET) per joint in
    chain order. Joints are numbered 0..n-1 by their ``jindex`` (in chain order when unset)."""
    items = [ets] if hasattr(ets, "isjoint") else list(ets)
    joints = [(getattr(et, "jindex", None), k) for k, et in enumerate(items) if getattr(et, "isjoint", False)]
    if any(j is None for j, _ in joints):
        joints = [(k, pos) for k, (_, pos) in enumerate(joints)]
    indices = [int(j) for j, _ in joints]
    if len(set(indices)) != len(indices):
        raise RobotError(f"the roboticstoolbox ETS uses a joint index twice: jindex {sorted(indices)}")
    number = {j: i for i, j in enumerate(sorted(indices))}
    joint_at = dict((pos, j) for j, pos in zip(indices, (p for _, p in joints)))
    out: list[ET] = []
    info: list[tuple[int, Any]] = []
    for pos, et in enumerate(items):
        kind = rtb_kind(et)
        where = f"element {pos} ({kind}) of the roboticstoolbox ETS"
        if pos in joint_at:
            if kind not in RTB_KINDS:
                raise RobotError(f"{where} is a joint of kind {kind!r}; symkin joints are tx ty tz Rx Ry Rz")
            out.append(
                ET(RTB_KINDS[kind], joint=number[joint_at[pos]], flip=bool(getattr(et, "isflip", False)))
            )
            info.append((joint_at[pos], et))
        elif kind in ("SE3", "SE2"):
            out += se3_ets(_matrix_4x4(et, kind), where, snap_tol)
        elif kind in RTB_KINDS:
            try:
                value = float(_param(et))
            except (TypeError, ValueError):
                raise RobotError(f"{where} has the constant {_param(et)!r}, which is not a number") from None
            axis = RTB_KINDS[kind]
            c = angle_const(value, snap_tol) if axis.is_rotation else length_const(value)
            if not c.is_zero:
                out.append(ET(axis, const=c))
        else:
            raise RobotError(
                f"{where}: unknown kind {kind!r} (expected tx ty tz Rx Ry Rz SE3, or R SE2 in 2-D)"
            )
    return out, info
