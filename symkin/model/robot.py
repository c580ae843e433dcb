"""The robot model: an ETS with joint names, joint limits and named configurations.

Numeric reference kinematics (numpy only) are methods of :class:`Robot`. Every method takes ``q``
of shape (n,) or a batch (N, n); a batch gives results with a leading (N,) axis.

References: "eq N" and "Part 1 eq N" are the equations of Haviland and Corke, Manipulator
Differential Kinematics, Part 1 (IEEE Robotics and Automation Magazine, 2023); "MMC paper eq N"
those of Haviland and Corke, Maximising Manipulability During Resolved-Rate Motion Control
(arXiv, 2020).
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, fields
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from symkin.core.arrays import MAX_JOINT_VALUE, as_batch, axes_rows, real_array, sample_q  # noqa: F401 - generated C imports axes_rows here
from symkin.core.names import identifier
from symkin.errors import ConfigurationError, FrameError, RobotError
from symkin.model.differential import cond_of, jacob_dot_of, space_jacobian  # noqa: F401 - re-exported
from symkin.model.ets import ETS
from symkin.model.frames import frame_index
from symkin.model.geometry import Geometry, check_geometry, move_links
from symkin.model.kinematics import const_matrix
from symkin.model.numeric import NumericFrames, NumericKinematics
from symkin.model.slots import chain_segments

__all__ = [
    "Robot",
    "cond_of",
    "jacob_dot_of",
    "space_jacobian",
]


def _product(ets: Sequence[Any]) -> np.ndarray:
    """The 4x4 transform of constant elementary transforms."""
    T = np.eye(4)
    for e in ets:
        T = T @ const_matrix(e.axis, e.const)
    return T


def _not_ets(value: Any, expected: str, rtb_call: str) -> RobotError:
    """The error for an ``ets`` that is not ``expected``, pointing a roboticstoolbox one to ``rtb_call``."""
    from symkin.model.transform import type_name

    rtb = "roboticstoolbox" in type_name(value)
    hint = f"; for a roboticstoolbox robot or ETS use {rtb_call}" if rtb else ""
    return RobotError(f"ets must be {expected}, not {type_name(value)}{hint}")


def _readonly(a: np.ndarray) -> np.ndarray:
    a = np.array(a, dtype=float)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class Robot(NumericFrames):
    """A serial manipulator described by an ETS.

    Attributes:
        ets: the elementary transform sequence, base to end effector.
        name: a lowercase identifier-like name.
        qlim: joint limits, shape (2, n): row 0 lower, row 1 upper (rad or m).
        configs: named configurations (``qz``, ``qr``...), each shape (n,); also attributes.
        joint_names: one name per joint (by joint index).
        qd_max: joint speed limits, shape (n,), or None when unknown.
        source: where the parameters come from.
        geometry: collision shapes on the links ``base``, ``link1``..``link<n>`` (``link<k+1>``
            moves with the k-th joint along the chain: link frame k) and ``ee``
            (:class:`symkin.geometry.Geometry`), or None.
    """

    ets: ETS
    name: str = "robot"
    qlim: np.ndarray = field(default=None)  # type: ignore[assignment]
    configs: Mapping[str, np.ndarray] = field(default_factory=dict)
    joint_names: tuple[str, ...] = ()
    qd_max: np.ndarray | None = None
    source: str = ""
    geometry: Geometry | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.ets, ETS):
            raise _not_ets(self.ets, "a symkin.ETS", "Robot.from_rtb")
        n = self.ets.n
        if not isinstance(self.name, str) or not self.name:
            raise RobotError("a robot name must be a non-empty string")
        if "\0" in self.name or re.search("[\ud800-\udfff]", self.name):
            raise RobotError(f"a robot name must be text without NUL or lone surrogates, got {self.name!r}")
        if self.qlim is None:
            lo = [-math.pi if e.is_revolute else -1.0 for e in self.ets.joints]
            qlim = np.array([lo, [-v for v in lo]])
        else:
            qlim = real_array(self.qlim, "qlim", RobotError)
            if qlim.shape != (2, n):
                raise RobotError(f"qlim must have shape (2, {n}) (lower row, upper row), got {qlim.shape}")
            if np.isnan(qlim).any():
                raise RobotError("qlim contains NaN")
            bad = np.nonzero(qlim[0] > qlim[1])[0]
            if bad.size:
                raise RobotError(f"qlim lower > upper for joint {int(bad[0])}: {qlim[:, bad[0]].tolist()}")
        object.__setattr__(self, "qlim", _readonly(qlim))
        names = tuple(self.joint_names) or tuple(f"q{j}" for j in range(n))
        if not all(isinstance(x, str) and x for x in names) or re.search("[\0\ud800-\udfff]", "".join(names)):
            raise RobotError(f"joint names must be non-empty text without NUL or lone surrogates: {names!r}")
        if len(names) != n:
            raise RobotError(f"{len(names)} joint names given for {n} joints")
        if len(set(names)) != n:
            raise RobotError(f"joint names must be unique: {names}")
        object.__setattr__(self, "joint_names", names)
        configs = {"qz": np.zeros(n)}
        for key, value in dict(self.configs).items():
            if not key.isidentifier():
                raise RobotError(f"configuration name {key!r} is not an identifier")
            v = real_array(value, f"configuration {key!r}", RobotError)
            if v.shape != (n,) or not (np.abs(v) <= MAX_JOINT_VALUE).all():
                raise RobotError(f"configuration {key!r} must be {n} finite numbers, got {value!r}")
            configs[key] = v
        object.__setattr__(self, "configs", {k: _readonly(v) for k, v in configs.items()})
        if self.qd_max is not None:
            qd = real_array(self.qd_max, "qd_max", RobotError)
            if qd.shape != (n,) or not (qd > 0).all():
                raise RobotError(f"qd_max must be {n} positive numbers, got {self.qd_max!r}")
            object.__setattr__(self, "qd_max", _readonly(qd))
        check_geometry(self.geometry, self.link_names, self.name)

    # -- constructors ----------------------------------------------------------------------
    @classmethod
    def from_ets(
        cls,
        ets: ETS | str,
        qlim: Sequence[Sequence[float]] | np.ndarray | None = None,
        name: str | None = None,
        **kwargs: Any,
    ) -> Robot:
        """A robot from an ETS or its text form (see :class:`symkin.ETS`).

        A roboticstoolbox-python ETS is refused with a pointer to :meth:`from_rtb`, which also
        carries over its joint limits.
        """
        if isinstance(ets, str):
            ets = ETS.parse(ets)
        elif not isinstance(ets, ETS):
            raise _not_ets(ets, "a symkin.ETS or ETS text", "Robot.from_rtb(...)")
        return cls(ets, name=name or "robot", qlim=qlim, **kwargs)

    @classmethod
    def from_rtb(cls, robot_or_ets: Any, name: str | None = None, **kwargs: Any) -> Robot:
        """A robot from a roboticstoolbox-python robot (``rtb.models.Panda()``, a ``DHRobot``) or
        ETS, with exact constants, its joint limits, named configurations, base and tool; see
        :mod:`symkin.model.rtb`. roboticstoolbox itself is not needed to call this."""
        from symkin.model.rtb import rtb_args

        return cls(**rtb_args(robot_or_ets, name=name, **kwargs))

    @classmethod
    def from_dh(cls, *args: Any, **kwargs: Any) -> Robot:
        """A robot from standard or modified DH parameters; see :func:`symkin.model.dh.dh_args`."""
        from symkin.model.dh import dh_args

        return cls(**dh_args(*args, **kwargs))

    @classmethod
    def from_dh_file(cls, path: str | Path) -> Robot:
        """A robot from a DH table file (format in :mod:`symkin.model.dh`)."""
        from symkin.model.dh import dh_file_args

        return cls(**dh_file_args(path))

    @classmethod
    def from_urdf(
        cls, path_or_xml: str | Path, base_link: str | None = None, end_link: str | None = None, **kwargs: Any
    ) -> Robot:
        """The serial chain of a URDF from ``base_link`` to ``end_link``; see :mod:`symkin.model.urdf`."""
        from symkin.model.urdf import urdf_args

        return cls(**urdf_args(path_or_xml, base_link=base_link, end_link=end_link, **kwargs))

    @classmethod
    def from_poe(cls, M: Any, screws: Any, frame: str = "space", **kwargs: Any) -> Robot:
        """A robot from product-of-exponentials data (Lynch and Park, Modern Robotics, 2017); see
        :mod:`symkin.model.poe`."""
        from symkin.model.poe import poe_args

        return cls(**poe_args(M, screws, frame=frame, **kwargs))

    # -- tool and base ---------------------------------------------------------------------
    def with_tool(self, tool: Any, name: str | None = None) -> Robot:
        """A new robot with the constant transform ``tool`` appended after the end effector.

        ``tool``: constant ETS text (``"tz(0.1) Rx(pi/2)"``, exact), ``"x y z roll pitch yaw"``
        (m, rad; text stays exact), a symkin ETS or ET, a 4x4 homogeneous matrix or spatialmath
        ``SE3`` (split into ``tx ty tz`` and rotations, float noise snapped: see
        :mod:`symkin.model.transform`) or a roboticstoolbox ETS without joints. The new robot's
        ``fkine(q)`` is ``self.fkine(q) @ T_tool``; limits, names and configurations are kept.
        """
        return self._with("tool", tool, name)

    def with_base(self, base: Any, name: str | None = None) -> Robot:
        """A new robot with the constant transform ``base`` placed before the first link, so its
        ``fkine(q)`` is ``T_base @ self.fkine(q)``; ``base`` in any form :meth:`with_tool` takes."""
        return self._with("base", base, name)

    def _with(self, where: str, transform: Any, name: str | None) -> Robot:
        """The robot with the constant ``transform`` as its ``where`` ("tool" or "base")."""
        from symkin.model.transform import constant_ets

        extra = tuple(constant_ets(transform, where))
        if not extra and name is None:
            return self
        if where == "tool":  # the hand's shapes stay on the hand
            ets, moves = self.ets.ets + extra, {"ee": np.linalg.inv(_product(extra))}
        else:  # the base's shapes move with the arm
            ets, moves = extra + self.ets.ets, {"base": _product(extra)}
        configs = {k: v for k, v in self.configs.items() if k != "qz"}
        note = f"{where} {ETS(extra)}" if extra else ""
        source = "; ".join(s for s in (self.source, note) if s)
        return Robot(
            ETS(ets),
            name=name or self.name,
            qlim=self.qlim,
            configs=configs,
            joint_names=self.joint_names,
            qd_max=self.qd_max,
            source=source,
            geometry=move_links(self.geometry, moves),
        )

    # -- plain attributes ------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of joints."""
        return self.ets.n

    @property
    def link_names(self) -> tuple[str, ...]:
        """The links geometry attaches to: ``base``, ``link1``..``link<n>`` (``link<k+1>`` moves with
        the k-th joint along the chain; its frame is link frame k), ``ee`` (fixed to the last link)."""
        return ("base", *(f"link{k + 1}" for k in range(self.n)), "ee")

    def with_geometry(self, geometry: Geometry | None) -> Robot:
        """The same robot with collision ``geometry`` (or none)."""
        return dataclasses.replace(self, geometry=geometry)

    def __getattr__(self, key: str) -> np.ndarray:
        if key.startswith("_") or key == "configs":
            raise AttributeError(key)
        try:
            return self.configs[key]
        except KeyError:
            raise AttributeError(
                f"{type(self).__name__} {self.name!r} has no attribute or configuration {key!r}; "
                f"configurations: {sorted(self.configs)}"
            ) from None

    def __repr__(self) -> str:
        return f"Robot(name={self.name!r}, n={self.n}, ets={str(self.ets)!r})"

    def __getstate__(self) -> dict[str, Any]:
        """Pickle the fields only (not the cached numeric kinematics): small pickles for workers."""
        return {f.name: getattr(self, f.name) for f in fields(self)}

    def _repr_latex_(self) -> str:
        from symkin.model.latex import robot_latex

        return robot_latex(self)

    @property
    def key(self) -> str:
        """Structural hash (name and ETS text): what the derivation depends on. The compile caches
        use :attr:`fingerprint`."""
        return hashlib.sha256(f"{self.name}\n{self.ets}".encode()).hexdigest()

    @property
    def fingerprint(self) -> str:
        """Hash of every attribute (name, ETS, qlim, qd_max, configurations, joint names, source) but
        the collision geometry: two robots with equal fingerprints have identical kinematics. Part of
        the compile-cache keys (the geometry's own fingerprint keys the collision kernel, whose C
        source holds it, and the in-process memo of compiled kinematics)."""
        h = hashlib.sha256(f"{self.name}\0{self.ets}\0{self.source}\0".encode())
        h.update("\0".join(self.joint_names).encode() + b"\0\0")
        h.update(np.ascontiguousarray(self.qlim, dtype="<f8").tobytes())
        h.update(b"none" if self.qd_max is None else np.ascontiguousarray(self.qd_max, dtype="<f8").tobytes())
        for k in sorted(self.configs):
            h.update(f"\0{k}\0".encode() + np.ascontiguousarray(self.configs[k], dtype="<f8").tobytes())
        return h.hexdigest()

    @property
    def identifier(self) -> str:
        """``name`` reduced to a safe C/Python identifier."""
        return identifier(self.name)

    code_name = identifier  # the name in generated code (symbols ``symkin_<code_name>_*``)
    single_path = True  # one serial chain (see Tree.single_path)

    @cached_property
    def _num(self) -> NumericKinematics:
        """The numeric kernel (:mod:`symkin.model.numeric`) of the chain's segments."""
        return NumericKinematics.of(*chain_segments(self.ets, self.joint_names), self.n)

    def _segment(self, frame: Any) -> int:
        """Segment k is link frame k; segment n the end effector."""
        return self.n if frame is None else self.frame_name(frame)

    def check_q(self, q: Any, limits: bool = False) -> np.ndarray:
        """``q`` as a float array after validation; with ``limits``, reject values outside qlim."""
        Q, single = self._batch(q)
        if limits:
            lo, hi = self.qlim
            bad = np.argwhere((lo - 1e-12 > Q) | (hi + 1e-12 < Q))
            if bad.size:
                b, j = bad[0]
                raise ConfigurationError(
                    f"joint {j} ({self.joint_names[j]}) = {Q[b, j]:.6g} is outside its limits "
                    f"[{lo[j]:.6g}, {hi[j]:.6g}]"
                )
        return Q[0] if single else Q

    def within_limits(self, q: Any) -> np.ndarray | bool:
        """True where every joint of q lies within qlim."""
        Q, single = self._batch(q)
        ok = ((self.qlim[0] <= Q) & (self.qlim[1] >= Q)).all(axis=-1)
        return bool(ok[0]) if single else ok

    def random_q(self, N: int | None = None, seed: int | np.random.Generator | None = None) -> np.ndarray:
        """Uniform random configurations within qlim: (n,) or (N, n). An infinite bound (or one
        beyond +-MAX_JOINT_VALUE) is replaced by one turn (revolute) or 2 m (prismatic) beyond the
        other bound, or +-pi / +-1 m around 0 (:func:`sample_q`)."""
        return sample_q(self.qlim, self.revolute, N, seed)

    @property
    def revolute(self) -> np.ndarray:
        """(n,) bool: which joints are revolute (by joint index)."""
        return np.array([e.is_revolute for e in self.ets.joints], dtype=bool)

    def frame_name(self, frame: Any) -> int:
        """``frame`` as the index k of a link frame (FrameError naming the valid range)."""
        return frame_index(frame, self.n, self.name)

    # -- numeric reference kinematics (Part 1 eqs 1, 14-16, 31-34; NumericFrames) -----------
    def link_poses(self, q: Any) -> np.ndarray:
        """Base-frame pose of each link frame (right after its joint, eq 5), (n, 4, 4) or (N, n, 4, 4).

        Links are in chain order (the k-th joint met from the base); ``fkine(q, frame=k)`` is link k's.
        """
        Q, single = self._batch(q)
        T = self._num.poses(Q)[:, 1 : self.n + 1]
        return T[0] if single else T

    def ik(self, Tep: Any, frame: int | None = None, **kwargs: Any) -> Any:
        """Numerical IK on the numeric reference (slow; compile for speed): :func:`symkin.runtime.ik.ik`;
        ``frame=k`` solves for link frame k."""
        from symkin.runtime.ik import ik

        return ik(self, Tep, frame=frame, **kwargs)

    def to_data(self) -> tuple[str, dict[str, Any]]:
        """``("chain", fields)``: the robot as JSON data (its ETS as text, which round-trips exactly),
        for the manifests of :func:`symkin.write_generated`; :func:`symkin.model.tree.model_of_data`
        reads it back."""
        return "chain", {
            "name": self.name,
            "ets": str(self.ets),
            "joint_names": list(self.joint_names),
            "qlim": self.qlim.tolist(),
            "qd_max": None if self.qd_max is None else self.qd_max.tolist(),
            "configs": {k: v.tolist() for k, v in self.configs.items() if k != "qz"},
            "source": self.source,
        }

    def chain(self, frame: Any = None) -> Robot:
        """The serial chain to ``frame``: the robot itself (None or "ee", its end effector), as
        :meth:`symkin.Tree.chain` gives a tree's."""
        if frame is not None and frame != "ee":
            raise FrameError(
                f"the chain of robot {self.name!r} ends at its end effector (frame None or 'ee')"
            )
        return self

    def select(self, frame: int | None = None) -> Any:
        """The robot itself (``frame=None``: the end effector) or its link frame k as chain
        kinematics of all n joints, for IK, servo and MMC (:class:`symkin.model.frame_view.FrameView`)."""
        if frame is None:
            return self
        from symkin.model.frame_view import frame_view

        return frame_view(self, self, frame)

    # -- notebook and plot -----------------------------------------------------------------
    def _repr_markdown_(self) -> str:
        """The robot as a Markdown table (joints, kinds, limits, speeds) for Jupyter."""
        from symkin.model.describe import robot_markdown

        return robot_markdown(self)

    def plot(self, q: Any = None, **kwargs: Any) -> Any:
        """Draw the robot at ``q`` (default ``qz``) with matplotlib: links, joint frames and
        optionally the manipulability ellipsoid; ``path=`` saves a PNG. Returns the figure. See
        :func:`symkin.model.plot.plot_robot` (needs the ``plot`` extra)."""
        from symkin.model.plot import plot_robot

        return plot_robot(self, q, **kwargs)
