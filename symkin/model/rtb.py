"""roboticstoolbox-python robots and ETS to an exact symkin Robot (Corke's Robotics Toolbox for Python).

roboticstoolbox is never imported here: its objects are read through their attributes, so this
module works wherever the caller got them from. What is read:

- each ET's kind (``kind``, formerly ``axis``: ``tx ty tz Rx Ry Rz``, ``SE3`` for a constant 4x4
  transform; in 2-D ``ETS2``: ``R`` (about z), ``tx``, ``ty``, ``SE2``), its constant (``param``,
  formerly ``eta``), ``isjoint``, ``isflip`` and ``jindex``;
- a robot's ``ets()`` (base to its default end effector, or ``start``/``end``), its ``base`` and
  ``tool`` transforms (which its ``fkine`` includes), ``qlim``, ``configs`` (``qr``, ``qz``...),
  ``qdlim`` when it holds a positive speed per joint, the names of its joint links, and ``name``;
- an ETS's per-joint ``qlim`` where set (other joints get symkin's defaults).

Constants become exact the way :mod:`symkin.model.transform` snaps floats: angles within 1e-9 of
``k pi / m`` (m <= 12) are that multiple of pi, lengths within a few units in the last place of a
shorter decimal are that decimal, and ``SE3`` constants are split into translations and rotations.
Joint indices are renumbered 0..n-1 in the order of their ``jindex`` (a sub-chain of a
branched robot keeps the robot's order).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from symkin.errors import RobotError
from symkin.model.ets import ETS
from symkin.model.transform import RTB_KINDS, SNAP_TOL, is_rtb, rtb_ets, rtb_kind, se3_ets, type_name

__all__ = ["rtb_args", "rtb_ets"]


def _is_identity(T: Any) -> bool:
    A = getattr(T, "A", T)
    try:
        return bool(np.allclose(np.asarray(A, dtype=float), np.eye(4), rtol=0, atol=1e-15))
    except (TypeError, ValueError):
        return False


def _limits(qlim: Any, n: int) -> np.ndarray | None:
    try:
        a = np.asarray(qlim, dtype=float)
    except (TypeError, ValueError):
        return None
    return a if a.shape == (2, n) and np.isfinite(a).all() and (a[0] <= a[1]).all() else None


def rtb_args(
    obj: Any,
    name: str | None = None,
    start: Any = None,
    end: Any = None,
    snap_tol: float = SNAP_TOL,
) -> dict[str, Any]:
    """The :class:`~symkin.Robot` arguments (``ets``, ``name``, limits, ...) of a roboticstoolbox
    robot (``rtb.models.Panda()``, a ``DHRobot``...) or an
    ``ETS``/``ETS2``/``ET`` (see the module docstring for what is carried over).

    ``start``/``end`` choose the links of a branched robot (passed to its ``ets()``); ``name``
    replaces the robot's name. The result's ``fkine`` equals the robot's ``fkine`` (base and tool
    included).
    """
    if hasattr(obj, "ets") and callable(obj.ets) and hasattr(obj, "qlim"):
        return _from_robot(obj, name, start, end, snap_tol)
    if start is not None or end is not None:
        raise RobotError("start/end choose links of a roboticstoolbox robot; an ETS has no links")
    if not is_rtb(obj):
        raise RobotError(
            f"from_rtb needs a roboticstoolbox robot, ETS or ET, not {type_name(obj)}; for symkin's own "
            "ETS use Robot.from_ets"
        )
    chain, info = rtb_ets(obj, snap_tol)
    if not info:
        raise RobotError("the roboticstoolbox ETS has no joints")
    lo, hi = [], []
    for _, et in sorted(info, key=lambda t: t[0]):
        default = math.pi if RTB_KINDS[rtb_kind(et)].is_rotation else 1.0
        raw = getattr(et, "qlim", None)
        lim = None if raw is None or np.size(raw) != 2 else _limits(np.reshape(raw, (2, 1)), 1)
        lo.append(float(lim[0, 0]) if lim is not None else -default)
        hi.append(float(lim[1, 0]) if lim is not None else default)
    return dict(
        ets=ETS(tuple(chain)),
        name=name or "rtb_ets",
        qlim=[lo, hi],
        source=f"imported from a roboticstoolbox-python {type(obj).__name__}",
    )


def _from_robot(robot: Any, name: str | None, start: Any, end: Any, snap_tol: float) -> dict[str, Any]:
    kwargs = {k: v for k, v in (("start", start), ("end", end)) if v is not None}
    try:
        ets = robot.ets(**kwargs)
    except Exception as exc:  # roboticstoolbox raises ValueError/TypeError for branched robots
        raise RobotError(
            f"cannot take the chain of the roboticstoolbox robot {getattr(robot, 'name', '')!r}: {exc} "
            "(name the links with start=/end=)"
        ) from None
    chain, info = rtb_ets(ets, snap_tol)
    if not info:
        raise RobotError(
            f"the roboticstoolbox robot {getattr(robot, 'name', '')!r} has no joints on this chain"
        )
    base = getattr(robot, "base", None)
    tool = getattr(robot, "tool", None)
    if base is not None and not _is_identity(base):
        chain = se3_ets(getattr(base, "A", base), "the robot's base", snap_tol) + chain
    if tool is not None and not _is_identity(tool):
        chain = chain + se3_ets(getattr(tool, "A", tool), "the robot's tool", snap_tol)
    order = sorted(j for j, _ in info)  # roboticstoolbox joint index of symkin joint 0..n-1
    n = len(order)
    try:  # the robot's limits of these joints, if it has a usable (2, >= n) table
        qlim = _limits(np.asarray(robot.qlim, dtype=float)[:, order], n)
    except IndexError:  # no table, or fewer columns than joints
        qlim = None
    configs = {}
    for key, value in dict(getattr(robot, "configs", None) or {}).items():
        v = np.asarray(value, dtype=float).ravel()
        if key != "qz" and key.isidentifier() and v.size > max(order) and np.isfinite(v[order]).all():
            configs[key] = v[order]
    qd_max = None
    qd = getattr(robot, "qdlim", None)
    if qd is not None:
        qd = np.asarray(qd, dtype=float).ravel()
        if qd.size > max(order) and np.isfinite(qd[order]).all() and (qd[order] > 0).all():
            qd_max = qd[order]
    links = {getattr(link, "jindex", None): getattr(link, "name", "") for link in getattr(robot, "links", ())}
    names = tuple(str(links.get(j) or "") for j in order)
    if not all(names) or len(set(names)) != n:
        names = ()
    maker = getattr(robot, "manufacturer", "") or ""
    rname = str(getattr(robot, "name", "") or "rtb_robot")
    return dict(
        ets=ETS(tuple(chain)),
        name=name or rname.lower().replace(" ", "_"),
        qlim=qlim,
        configs=configs,
        joint_names=names,
        qd_max=qd_max,
        source=f"imported from roboticstoolbox-python {type(robot).__name__} {rname!r}"
        + (f" ({maker})" if maker else "")
        + ("; joint names are its joint links' names" if names else ""),
    )
