"""A kinematic tree: many frames of one robot (a quadruped's feet, a humanoid's hands and feet).

A :class:`Tree` is a set of :class:`Segment` s (one per URDF joint on a path to a frame), each
an exact ETS fragment from its parent link to its child link, walked depth first. Movable
segments are :class:`Slot` s; each is driven by one joint of ``q`` as ``theta = m q_j + c``
(``m = 1, c = 0`` except for mimic joints). Numeric reference kinematics (numpy only) are methods
of :class:`Tree`, on the kernel a chain uses too (:mod:`symkin.model.numeric`); every method takes
``q`` of shape (n,) or a batch (N, n).
"""

from __future__ import annotations

import dataclasses
import hashlib
import math
import re
from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np

from symkin.core.names import identifier
from symkin.errors import RobotError, URDFError
from symkin.model.ets import ET, ETS
from symkin.model.frames import frame_position
from symkin.model.geometry import Geometry, check_geometry, rename_links
from symkin.model.numeric import NumericFrames, NumericKinematics
from symkin.model.robot import Robot
from symkin.model.slots import Segment, Slot, chain_segments

__all__ = ["Tree", "Segment", "Slot", "frame_position", "as_tree", "robot_of"]

_SURROGATE = re.compile("[\ud800-\udfff]")


@dataclass(frozen=True, eq=False)
class Tree(NumericFrames):
    """A kinematic tree with named frames (build with :meth:`from_urdf`).

    Attributes:
        name: the robot's name.
        base_link: the link every pose is expressed in.
        segments: the joints on the paths to the frames, depth first (parents before children).
        slots: the movable segments, depth first.
        frames: the frame (link) names, in the order given; ``*_all`` results follow it.
        frame_segments: per frame, the segment ending at its link.
        joint_names: the n independent joints, depth first (children in file order).
        qlim: joint limits (2, n); qd_max: joint speed limits (n,) when every joint gives one.
    """

    name: str
    base_link: str
    segments: tuple[Segment, ...]
    slots: tuple[Slot, ...]
    frames: tuple[str, ...]
    frame_segments: tuple[int, ...]
    joint_names: tuple[str, ...]
    qlim: np.ndarray = field(default=None)  # type: ignore[assignment]
    velocity: Any = None  # per joint, NaN when unknown
    source: str = ""
    geometry: Geometry | None = None  # collision shapes on the tree's links (base_link, segment links)

    def __post_init__(self) -> None:
        n = len(self.joint_names)
        if not isinstance(self.name, str) or not self.name:
            raise RobotError("a tree name must be a non-empty string")
        # names reach generated C as string literals: text a C string carries whole (as Robot's)
        for what, names in (
            ("the tree name", [self.name]),
            ("frame names", self.frames),
            ("joint names", [*self.joint_names, *(s.name for s in self.segments)]),
        ):
            bad = [x for x in names if not isinstance(x, str) or "\0" in x or _SURROGATE.search(x)]
            if bad:
                raise RobotError(f"{what} must be text without NUL or lone surrogates, got {bad[0]!r}")
        if len(set(self.joint_names)) != n:
            raise RobotError(f"joint names must be unique: {self.joint_names}")
        if len(self.frames) != len(self.frame_segments) or not self.frames:
            raise RobotError("a tree needs at least one frame, each with its segment")
        for k, seg in enumerate(self.segments):
            if not -1 <= seg.parent < k:
                raise RobotError(f"segment {seg.name!r}: its parent must come before it (depth first)")
        qlim = np.asarray(
            self.qlim if self.qlim is not None else [[-math.pi] * n, [math.pi] * n], dtype=float
        )
        if qlim.shape != (2, n) or np.isnan(qlim).any() or (qlim[0] > qlim[1]).any():
            raise RobotError(f"qlim must be (2, {n}) with lower <= upper, got {qlim.tolist()}")
        qlim.setflags(write=False)
        object.__setattr__(self, "qlim", qlim)
        vel = np.full(n, np.nan) if self.velocity is None else np.asarray(self.velocity, dtype=float)
        vel.setflags(write=False)
        object.__setattr__(self, "velocity", vel)
        check_geometry(self.geometry, self.link_names, self.name)

    # -- constructors ----------------------------------------------------------------------
    @classmethod
    def from_urdf(
        cls,
        path_or_xml: str | Path,
        frames: Sequence[str] | str | None = None,
        base_link: str | None = None,
        snap_tol: float = 1e-9,
        name: str | None = None,
    ) -> Tree:
        """The tree of a URDF (file path or XML text): the movable joints below ``base_link``
        (default the root link) on the path to at least one of ``frames`` (link names, default
        every leaf link below ``base_link``, depth first). Fixed joints are folded, continuous
        joints are revolute, mimic joints follow their joint exactly; see
        :mod:`symkin.model.urdf`. ``snap_tol`` as in :func:`symkin.model.urdf.urdf_args`."""
        from symkin.model.urdf import urdf_tree_args

        return cls(**urdf_tree_args(path_or_xml, frames, base_link, snap_tol, name))

    @classmethod
    def from_robot(cls, robot: Robot, frame: str = "ee", base_link: str = "base") -> Tree:
        """The serial chain ``robot`` as a tree with one frame, ``frame``, at its end effector: a
        chain is a tree with one end frame. One segment per joint (the constant transforms before
        it, then the joint; its link ``link<k>``, k along the chain from 1), then a fixed one to
        ``frame``. Same joints, names, limits and kinematics; :meth:`chain` gives the ETS back."""
        segments, slots = chain_segments(robot.ets, robot.joint_names, frame)
        links = {base_link, *(seg.link for seg in segments[:-1])}
        if not isinstance(frame, str) or frame in links:
            raise RobotError(
                f"the end frame must be a name other than the links {sorted(links)}, not {frame!r}"
            )
        qd = robot.qd_max
        return cls(
            name=robot.name,
            base_link=base_link,
            segments=segments,
            slots=slots,
            frames=(frame,),
            frame_segments=(len(segments) - 1,),
            joint_names=robot.joint_names,
            qlim=robot.qlim,
            velocity=None if qd is None else qd,
            source=f"{robot.source or robot.name}, as a tree",
            geometry=rename_links(robot.geometry, {"base": base_link, "ee": frame}),
        )

    def to_data(self) -> tuple[str, dict[str, Any]]:
        """``("tree", fields)``: every field of the tree (as :meth:`__getstate__` pickles it, but the
        geometry) as JSON data: the segments' ETS as text with their joints numbered in order, the
        slots' multipliers and offsets as exact fractions; :func:`model_of_data` reads it back."""
        segments = []
        for seg in self.segments:
            local = iter(range(len(seg.ets)))
            text = " ".join(
                str(ET(e.axis, joint=next(local), flip=e.flip) if e.is_joint else e) for e in seg.ets
            )
            joints = [e.joint for e in seg.ets if e.is_joint]
            segments.append(
                {
                    "name": seg.name,
                    "parent": seg.parent,
                    "link": seg.link,
                    "slot": seg.slot,
                    "ets": text,
                    "joints": joints,
                }
            )
        slots = [
            {**dataclasses.asdict(s), "multiplier": str(s.multiplier), "offset": str(s.offset)}
            for s in self.slots
        ]
        return "tree", {
            "name": self.name,
            "base_link": self.base_link,
            "frames": list(self.frames),
            "frame_segments": list(self.frame_segments),
            "joint_names": list(self.joint_names),
            "qlim": self.qlim.tolist(),
            "velocity": [None if np.isnan(v) else float(v) for v in self.velocity],
            "source": self.source,
            "segments": segments,
            "slots": slots,
        }

    def __getstate__(self) -> dict[str, Any]:
        """Pickle the fields (and cached values) without the memoised frame views, collision layout
        and numeric kernel (rebuilt on first use)."""
        state = dict(self.__dict__)
        for key in ("_frame_views", "_collision_layout", "_num"):
            state.pop(key, None)
        return state

    # -- plain attributes ------------------------------------------------------------------
    @property
    def n(self) -> int:
        """Number of independent joints."""
        return len(self.joint_names)

    @property
    def qd_max(self) -> np.ndarray | None:
        return None if np.isnan(self.velocity).any() else self.velocity

    @property
    def configs(self) -> dict[str, np.ndarray]:
        return {"qz": np.zeros(self.n)}

    @property
    def qz(self) -> np.ndarray:
        return np.zeros(self.n)

    @property
    def identifier(self) -> str:
        return identifier(self.name)

    @cached_property
    def key(self) -> str:
        """Structural hash (name, segments, slots, frames): the compile-cache key."""
        lines = [self.name, self.base_link, ",".join(self.frames), ",".join(self.joint_names)]
        for seg in self.segments:
            lines.append(f"{seg.name}|{seg.parent}|{seg.link}|{seg.slot}|{' '.join(map(str, seg.ets))}")
        for s in self.slots:
            lines.append(f"{s.name}|{s.segment}|{s.joint}|{s.multiplier}|{s.offset}|{s.revolute}")
        return hashlib.sha256("\n".join(lines).encode()).hexdigest()

    @property
    def fingerprint(self) -> str:
        """:attr:`key` and the limits, speeds and source: two trees with equal fingerprints have
        identical kinematics and generated code (the compile caches' part of a model)."""
        h = hashlib.sha256(f"{self.key}\0{self.source}\0".encode())
        h.update(np.ascontiguousarray(self.qlim, dtype="<f8").tobytes())
        h.update(np.ascontiguousarray(self.velocity, dtype="<f8").tobytes())
        return h.hexdigest()

    @property
    def code_name(self) -> str:
        """The name in generated code: ``<identifier>_tree`` (symbols ``symkin_<code_name>_*``)."""
        return f"{self.identifier}_tree"

    @property
    def single_path(self) -> bool:
        """Whether the tree is one serial chain: one frame and no mimic joint on its path (what
        the expanded derivation, closed-form IK and the live view need: :meth:`chain` gives it)."""
        return len(self.frames) == 1 and not any(self.slots[k].is_mimic for k in self.path_slots(None))

    def __repr__(self) -> str:
        return f"Tree(name={self.name!r}, n={self.n}, frames={list(self.frames)})"

    @property
    def link_names(self) -> tuple[str, ...]:
        """The base link and every segment's link (what geometry attaches to), depth first."""
        return (self.base_link, *(seg.link for seg in self.segments))

    def with_geometry(self, geometry: Geometry | None) -> Tree:
        """The same tree with collision ``geometry`` (or none)."""
        return dataclasses.replace(self, geometry=geometry)

    def frame_position(self, frame: Any) -> int:
        """The position of ``frame`` in :attr:`frames` (FrameError listing them when unknown)."""
        return frame_position(frame, self.frames, self.name)

    def frame_name(self, frame: Any) -> str:
        """The name of ``frame`` (a name, or None for a one-frame tree; FrameError when unknown)."""
        return self.frames[self.frame_position(frame)]

    def path(self, frame: Any) -> list[int]:
        """Segment indices from the base link to ``frame``, in order."""
        out = []
        s = self.frame_segments[self.frame_position(frame)]
        while s >= 0:
            out.append(s)
            s = self.segments[s].parent
        return out[::-1]

    def path_slots(self, frame: Any) -> list[int]:
        """Slot indices on the path to ``frame``, base first."""
        return [self.segments[s].slot for s in self.path(frame) if self.segments[s].slot is not None]  # type: ignore[misc]

    @property
    def revolute(self) -> np.ndarray:
        """(n,) bool: joints whose every slot turns by an integer multiple of them (so q wraps by 2 pi)."""
        rev = np.ones(self.n, dtype=bool)
        for s in self.slots:
            if not s.revolute or s.multiplier.denominator != 1:
                rev[s.joint] = False
        return rev

    def chain(self, frame: Any = None) -> Robot:
        """The serial chain from the base link to ``frame`` (None: the only frame) as a
        :class:`Robot` (the same ETS as ``Robot.from_urdf(..., end_link=frame)``). Its joints keep
        their order in the tree (the joints of a chain's own tree, :meth:`from_robot`, their indices;
        a URDF tree's, numbered depth first, the order along the path): the chain's q is
        ``q[sorted(joints on the path)]`` of the tree's. A chain through a mimic joint
        cannot be a Robot (its joints are independent): URDFError naming the joint."""
        frame = self.frame_name(frame)
        on = self.path_slots(frame)
        slots = [self.slots[k] for k in on]
        for s in slots:
            if s.is_mimic:
                raise URDFError(
                    f"the chain to frame {frame!r} passes mimic joint {s.name!r} (it follows {s.mimics!r}); "
                    "a Robot has independent joints only: use the Tree (symkin.compile(tree), "
                    f"frame={frame!r})"
                )
        if not slots:
            raise URDFError(
                f"no revolute, continuous or prismatic joint between {self.base_link!r} and {frame!r}"
            )
        cols = sorted(s.joint for s in slots)  # the chain's joints, in the tree's order
        joint = {k: cols.index(s.joint) for k, s in zip(on, slots)}  # slot -> joint of the chain
        ets = [
            ET(e.axis, joint=joint[e.joint], flip=e.flip) if e.is_joint else e
            for si in self.path(frame)
            for e in self.segments[si].ets
        ]
        vel = self.velocity[cols]
        return Robot(
            ETS(tuple(ets)),
            name=self.name,
            qlim=self.qlim[:, cols],
            joint_names=tuple(self.joint_names[j] for j in cols),
            qd_max=None if np.isnan(vel).any() else vel,
            source=f"{self.source.split(', tree below')[0]}, chain {self.base_link} -> {frame}",
        )

    def select(self, frame: Any = None) -> Any:
        """This tree's kinematics of one frame, as a chain-like object for IK, servo and MMC
        (:class:`symkin.model.frame_view.FrameView`; the joints off its path are free)."""
        from symkin.model.frame_view import frame_view

        return frame_view(self, self, frame)

    def ik(self, Tep: Any, frame: Any = None, **kwargs: Any) -> Any:
        """Numerical IK of one frame on the numeric reference (the other joints are free), as
        :meth:`symkin.Robot.ik` for a chain: see :func:`symkin.runtime.ik.ik`."""
        return self.select(frame).ik(Tep, **kwargs)

    # -- configurations --------------------------------------------------------------------
    def random_q(self, N: int | None = None, seed: int | np.random.Generator | None = None) -> np.ndarray:
        """Uniform random configurations within qlim: (n,) or (N, n); bounds beyond +-1e15 or
        infinite as in :meth:`symkin.Robot.random_q`."""
        from symkin.core.arrays import sample_q

        prismatic = {s.joint for s in self.slots if not s.revolute}
        revolute = np.array([k not in prismatic for k in range(self.n)], dtype=bool)
        return sample_q(self.qlim, revolute, N, seed)

    within_limits = Robot.within_limits

    # -- numeric reference kinematics (symkin.model.numeric) --------------------------------
    @cached_property
    def _num(self) -> NumericKinematics:
        return NumericKinematics.of(self.segments, self.slots, self.n)

    def _segment(self, frame: Any) -> int:
        return self.frame_segments[self.frame_position(frame)]

    def _walk(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Link poses L (N, S, 4, 4) after each segment and joint frames P (N, S, 4, 4) just
        before each segment's joint, depth first."""
        L = self._num.poses(Q)
        return L[:, 1:], self._num.joint_frames(L)

    def segment_poses(self, q: Any) -> tuple[np.ndarray, np.ndarray]:
        """Base-frame poses of every segment, in :attr:`segments` order (Part 1 eqs 1-5, walked
        depth first): its link's frame, after the joint and the constants that follow it, and its
        joint frame, just before the joint (the link's frame for a fixed segment). Two (S, 4, 4)
        arrays, or (N, S, 4, 4) for a batch."""
        Q, single = self._batch(q)
        L, P = self._walk(Q)
        return (L[0], P[0]) if single else (L, P)

    def fkine_all(self, q: Any) -> np.ndarray:
        """Poses of every frame, in :attr:`frames` order: (F, 4, 4) or (N, F, 4, 4)."""
        Q, single = self._batch(q)
        T = self._num.poses(Q)[:, [f + 1 for f in self.frame_segments]]
        return T[0] if single else T

    def jacob0_all(self, q: Any) -> np.ndarray:
        """Base-frame Jacobians of every frame: (F, 6, n) or (N, F, 6, n)."""
        return self.fkine_jacob0_all(q)[1]

    def fkine_jacob0_all(self, q: Any) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`fkine_all` and :meth:`jacob0_all` from one pass."""
        Q, single = self._batch(q)
        L = self._num.poses(Q)
        T = L[:, [f + 1 for f in self.frame_segments]]
        J = np.stack([self._num.jacobian(*self._num.columns(L, f), f) for f in self.frame_segments], axis=1)
        return (T[0], J[0]) if single else (T, J)


def as_tree(model: Any) -> Tree:
    """``model`` (a Robot, a Tree, or what holds one as ``model``: compiled kinematics) as a Tree:
    a chain through :meth:`Tree.from_robot`, memoised on the Robot. Where symkin asks whether a
    model is a tree; everything below a model works on the tree."""
    model = getattr(model, "model", model)
    if isinstance(model, Tree):
        return model
    if not isinstance(model, Robot):
        raise TypeError(f"a symkin model is a Robot or a Tree, not {type(model).__name__}")
    tree = model.__dict__.get("_tree")
    if tree is None:
        tree = Tree.from_robot(model)
        object.__setattr__(model, "_tree", tree)
    return tree


def robot_of(model: Any) -> Robot | None:
    """``model`` (or what holds one as ``model``: compiled kinematics) when it is a Robot, a chain
    whose links are named by their place along it (``base``, ``link1``.., ``ee``), else None (a
    Tree: its links by their own names)."""
    model = getattr(model, "model", model)
    return None if as_tree(model) is model else model
