"""URDF to a kinematic tree: every joint below a base link that lies on the path to a frame.

The tree is read with xml.etree like :mod:`symkin.model.urdf` and each joint becomes the same
exact ETS fragment (its origin ``tx ty tz Rz(yaw) Ry(pitch) Rx(roll)`` followed by the joint
about or along its axis), so the serial chain to one frame, :meth:`symkin.Tree.chain`, is the
chain :func:`symkin.model.urdf.urdf_args` imports, transform for transform.

Joints are numbered depth first from the base link, the children of a link in file order.
Fixed joints are folded into the constants, continuous joints are revolute. A mimic joint
(``<mimic joint="j" multiplier="m" offset="c"/>``) is no joint of its own: it moves by
``m q_j + c`` (exact rationals; a mimic of a mimic composes), and its Jacobian column adds ``m``
times its geometric column to joint j's column (the chain rule). Floating and planar joints on a
path are refused: name a ``base_link`` below them.
"""

from __future__ import annotations

from collections.abc import Sequence
from fractions import Fraction
from pathlib import Path
from typing import Any

from symkin.errors import URDFError
from symkin.model.ets import ET, Axis
from symkin.model.slots import Segment, Slot
from symkin.model.urdf import (
    MAX_URDF_VALUE,
    URDFGraph,
    URDFJoint,
    _suggest,
    axis_ets,
    joint_axis,
    joint_limits,
    joint_origin,
    read_graph,
    snap_angle,
    snap_atan2,
    translation_ets,
    xml_numbers,
)

__all__ = ["joint_ets", "urdf_tree_args", "describe_urdf"]


def joint_ets(graph: URDFGraph, j: URDFJoint, slot: int, snap_tol: float) -> list[ET]:
    """The exact ETs of joint ``j``: its origin, then (movable) the joint as joint index ``slot``.

    The same transforms :func:`symkin.model.urdf.urdf_args` writes for it.
    """
    what = f"joint {j.name!r}"
    xyz, rpy = joint_origin(j.el, what)
    out = translation_ets(xyz)
    for axis, ang in ((Axis.Rz, rpy[2]), (Axis.Ry, rpy[1]), (Axis.Rx, rpy[0])):
        c = snap_angle(ang, snap_tol)
        if not c.is_zero:
            out.append(ET(axis, const=c))
    if not j.movable:
        return out
    u = joint_axis(j.el, what, graph.where, snap_tol)
    return out + [snap_atan2(e, snap_tol) for e in axis_ets(u, slot, revolute=j.kind != "prismatic")]


def _mimic(graph: URDFGraph, j: URDFJoint) -> tuple[URDFJoint, Fraction, Fraction] | None:
    """(source joint, multiplier, offset) of a mimic joint, composed down to an independent joint."""
    el = j.el.find("mimic")
    if el is None:
        return None
    m, c = Fraction(1), Fraction(0)
    seen = [j.name]
    cur, src_el = j, el
    while src_el is not None:
        what = f"joint {cur.name!r}"
        src = src_el.get("joint")
        if src is None:
            raise URDFError(f"{graph.where}: {what} has <mimic> without a joint attribute")
        if src not in graph.joints:
            raise URDFError(
                f"{graph.where}: {what} mimics joint {src!r}, which does not exist"
                + _suggest(src, list(graph.joints)).replace("Links", "Joints")
            )
        mult = xml_numbers(src_el.get("multiplier"), 1, f"{what} mimic multiplier", "1", MAX_URDF_VALUE)[0]
        off = xml_numbers(src_el.get("offset"), 1, f"{what} mimic offset", "0", MAX_URDF_VALUE)[0]
        m, c = m * mult, m * off + c  # q_j = m q_cur + c and q_cur = mult q_src + off
        cur = graph.joints[src]
        if cur.name in seen:
            raise URDFError(f"{graph.where}: mimic joints form a cycle: {' -> '.join([*seen, cur.name])}")
        if not cur.movable:
            raise URDFError(
                f"{graph.where}: {what} mimics joint {cur.name!r}, which is {cur.kind}; a mimic source must "
                "be revolute, continuous or prismatic"
            )
        seen.append(cur.name)
        if max(abs(m), abs(c)) > MAX_URDF_VALUE:  # checked at each step, so m and c stay doubles
            raise URDFError(
                f"{graph.where}: mimic joint {j.name!r} follows {' -> '.join(seen)} with the composed "
                f"multiplier {float(m):.3g} and offset {float(c):.3g}; mimic multipliers and offsets, "
                f"composed too, must be within +-{MAX_URDF_VALUE:g}"
            )
        src_el = cur.el.find("mimic")
    return cur, m, c


def urdf_tree_args(
    path_or_xml: str | Path,
    frames: Sequence[str] | str | None = None,
    base_link: str | None = None,
    snap_tol: float = 1e-9,
    name: str | None = None,
) -> dict[str, Any]:
    """The :class:`symkin.Tree` arguments of a URDF: see :meth:`symkin.Tree.from_urdf`."""
    graph = read_graph(path_or_xml)
    where, base_link = graph.where, graph.base(base_link)
    if isinstance(frames, str):
        frames = [f.strip() for f in frames.split(",") if f.strip()]
    if frames is None:
        frames = graph.leaves(base_link)
        if not frames:
            raise URDFError(f"{where}: base_link {base_link!r} has no links below it")
    frames = tuple(frames)
    if not frames:
        raise URDFError(f"{where}: frames is empty; name at least one link")
    if len(set(frames)) != len(frames):
        dup = sorted({f for f in frames if frames.count(f) > 1})
        raise URDFError(f"{where}: frames must be distinct; {dup} appear more than once")
    needed: set[str] = set()
    for f in frames:
        if not isinstance(f, str):
            raise URDFError(f"{where}: frames are link names, not {type(f).__name__} {f!r}")
        graph.check_link(f, "frame")
        if f == base_link:
            raise URDFError(f"{where}: frame {f!r} is the base link; frames are links below it")
        for j in graph.path(base_link, f):
            if j.kind in ("floating", "planar"):
                raise URDFError(
                    f"{where}: joint {j.name!r} on the path from {base_link!r} to {f!r} is {j.kind}; symkin "
                    f"supports revolute, continuous, prismatic and fixed joints (name base_link "
                    f"{j.child!r} or a link below it)"
                )
            needed.add(j.name)
    # independent joints: the movable joints on the paths that mimic nothing, and the joints the
    # mimic joints on the paths follow; numbered depth first from the URDF root (base_link's
    # subtree keeps that order)
    mimics = {n: _mimic(graph, graph.joints[n]) for n in needed if graph.joints[n].movable}
    independent = {n for n, mm in mimics.items() if mm is None}
    independent |= {mm[0].name for mm in mimics.values() if mm is not None}
    rank = {j.name: i for r in graph.roots for i, j in enumerate(graph.depth_first(r))}
    names = sorted(independent, key=lambda n: rank[n])
    index = {n: i for i, n in enumerate(names)}
    lower, upper, vel = [], [], []
    for n in names:
        lo, hi, v = joint_limits(graph.joints[n], where)
        lower.append(lo)
        upper.append(hi)
        vel.append(v)
    segments: list[Segment] = []
    slots: list[Slot] = []
    seg_of: dict[str, int] = {}  # by child link
    for j in graph.depth_first(base_link):
        if j.name not in needed:
            continue
        slot = len(slots) if j.movable else None
        ets = tuple(joint_ets(graph, j, slot or 0, snap_tol))
        parent = seg_of.get(j.parent, -1)
        seg_of[j.child] = len(segments)
        segments.append(Segment(j.name, parent, j.child, ets, slot))
        if slot is not None:
            mm = mimics[j.name]
            src, m, c = (j, Fraction(1), Fraction(0)) if mm is None else mm
            slots.append(
                Slot(j.name, len(segments) - 1, index[src.name], m, c, j.kind != "prismatic", src.name)
            )
    robot_name = name or graph.name
    return dict(
        name=robot_name,
        base_link=base_link,
        segments=tuple(segments),
        slots=tuple(slots),
        frames=frames,
        frame_segments=tuple(seg_of[f] for f in frames),
        joint_names=tuple(names),
        qlim=[lower, upper],
        velocity=vel,
        source=f"{where}, tree below {base_link}",
    )


def describe_urdf(path_or_xml: str | Path, base_link: str | None = None) -> list[tuple[int, str, str, str]]:
    """The tree below ``base_link`` as rows (depth, link, joint, text) for ``symkin list-frames``:
    each link with the joint that leads to it (type, axis kind, mimic), depth first."""
    graph = read_graph(path_or_xml)
    if base_link is None:
        base_link = graph.root()
    else:
        graph.check_link(base_link, "base_link")
    depth = {base_link: 0}
    rows = [(0, base_link, "", "base")]
    movable = 0
    for j in graph.depth_first(base_link):
        depth[j.child] = depth[j.parent] + 1
        text = j.kind
        if j.movable:
            mm = j.el.find("mimic")
            if mm is not None:
                text += f", mimics {mm.get('joint')!r}"
            else:
                text += f", q{movable}"
                movable += 1
        if not graph.children[j.child]:
            text += ", leaf"
        rows.append((depth[j.child], j.child, j.name, text))
    return rows
