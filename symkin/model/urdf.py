"""The one URDF reader (xml.etree only): :func:`read_graph` parses a URDF into its checked
link/joint graph for both :meth:`symkin.Robot.from_urdf` (:func:`urdf_args`, the serial chain from
``base_link`` to ``end_link`` as an exact ETS) and :meth:`symkin.Tree.from_urdf`
(:func:`urdf_tree_args`, every joint below ``base_link`` on the path to a frame).

Each joint contributes its origin ``tx ty tz Rz(yaw) Ry(pitch) Rx(roll)`` (the URDF
fixed-axis roll-pitch-yaw convention ``R = Rz(y) Ry(p) Rx(r)`` of the URDF specification)
followed by the joint itself (the elementary transforms of Haviland and Corke, Manipulator Differential
Kinematics, Part 1, 2023, Fig. 2):

- an axis along +-x, +-y or +-z is one ET (a negative axis gives a flipped joint, ``Rz(-q)``);
- an axis ``u`` in a coordinate plane is conjugated by one exact rotation, e.g. ``u`` in the
  xy-plane gives ``Rz(phi) Rx(q) Rz(-phi)`` with ``phi = atan2(uy, ux)``;
- any other axis gives ``Rz(phi) Ry(theta) Rz(q) Ry(-theta) Rz(-phi)`` with ``phi = atan2(uy, ux)``,
  ``theta = atan2(sqrt(ux^2 + uy^2), uz)``, kept exact as :class:`Const` atan2 terms of surds
  (an angle within ``snap_tol`` of a multiple of pi/12 snaps to it: ``0 0.5 0.8660254`` gives pi/3).

Numbers in the XML become exact rationals (the decimal as written). Angles within ``snap_tol`` of
a multiple of pi/4 snap to it exactly (``1.5707963267949`` becomes ``pi/2``), and axis components
within ``snap_tol * |u|`` of 0 become 0. Zero constants are dropped.

Numbers must be finite doubles; origin lengths and angles (and mimic multipliers and offsets)
within +-1e15, like joint values. xacro (ROS's XML macros: ``xacro:`` elements, the xacro namespace,
``${...}`` substitutions, a ``.xacro`` file name) is refused with the command that expands it, and
so is a DOCTYPE.

Limits come from ``<limit lower upper velocity>``; a continuous joint gets ``[-pi, pi]`` (every
angle once); a revolute or prismatic joint without lower/upper gets ``[-pi, pi]`` or
``[-1, 1]`` m. ``qd_max`` is set when every moving joint on the chain gives a velocity.

Trees: each joint is the same ETS fragment (:func:`joint_ets`), so the chain to one frame,
:meth:`symkin.Tree.chain`, is the chain :func:`urdf_args` imports, transform for transform. Joints
are numbered depth first from the base link, the children of a link in file order. Fixed joints
are folded into the constants, continuous joints are revolute. A mimic joint
(``<mimic joint="j" multiplier="m" offset="c"/>``) is no joint of its own: it moves by
``m q_j + c`` (exact rationals; a mimic of a mimic composes), and its Jacobian column adds ``m``
times its geometric column to joint j's column (the chain rule). Floating and planar joints on a
path are refused: name a ``base_link`` below them.
"""

from __future__ import annotations

import difflib
import math
import re
import shlex
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any
from xml.etree import ElementTree
from xml.parsers import expat

from symkin.core.sizes import read_bounded
from symkin.errors import URDFError
from symkin.model.ets import ET, ETS, Axis, Const, surd
from symkin.model.slots import Segment, Slot
from symkin.model.transform import rpy_ets

__all__ = [
    "URDFGraph",
    "URDFJoint",
    "read_graph",
    "joint_limits",
    "urdf_args",
    "axis_ets",
    "translation_ets",
    "atan2_const",
    "snap_angle",
    "snap_atan2",
    "joint_origin",
    "joint_axis",
    "load_xml",
    "xml_numbers",
    "MAX_URDF_VALUE",
    "joint_ets",
    "urdf_tree_args",
    "describe_urdf",
]

_KNOWN = ("revolute", "continuous", "prismatic", "fixed", "floating", "planar")
_ROT = (Axis.Rx, Axis.Ry, Axis.Rz)
_TRANS = (Axis.tx, Axis.ty, Axis.tz)


# ---------------------------------------------------------------------------------------------
# exact geometry helpers (shared with the PoE importer)


def atan2_const(sy: Fraction, sx: Fraction) -> Const:
    """Exact ``atan2(y, x)`` for surds ``sy``, ``sx`` (see :func:`surd`): multiples of pi/12 when
    ``|y/x|`` is 0, 1, sqrt(3) or 1/sqrt(3), otherwise an atan2 term."""
    if sy == 0 and sx == 0:
        raise ValueError("atan2(0, 0) is undefined")
    if sy == 0:
        return Const() if sx > 0 else Const.pi_times(1)
    if sx == 0:
        return Const.pi_times(Fraction(1 if sy > 0 else -1, 2))
    ratio = abs(sy / sx)  # (y/x)^2
    base = {Fraction(1): Fraction(1, 4), Fraction(3): Fraction(1, 3), Fraction(1, 3): Fraction(1, 6)}.get(
        ratio
    )
    if base is None:
        return Const(atan2=(sy, sx))
    b = base if sx > 0 else 1 - base  # first or second quadrant
    return Const.pi_times(b if sy > 0 else -b)


def translation_ets(p: Sequence[Const | Fraction]) -> list[ET]:
    """``tx(px) ty(py) tz(pz)`` without the zero terms."""
    return rpy_ets([v if isinstance(v, Const) else Const(Fraction(v)) for v in p])


def axis_ets(u: Sequence[Fraction], joint: int, revolute: bool) -> list[ET]:
    """The ETs of a joint about (revolute) or along (prismatic) the direction ``u`` (rationals).

    One ET for a coordinate axis, three (one exact conjugating rotation) for an axis in a
    coordinate plane, five otherwise (module docstring). ``u`` need not be unit length.
    """
    ux, uy, uz = (Fraction(c) for c in u)
    kinds = _ROT if revolute else _TRANS
    nonzero = [i for i, c in enumerate((ux, uy, uz)) if c != 0]
    if not nonzero:
        raise ValueError("the joint axis is the zero vector")
    if len(nonzero) == 1:
        i = nonzero[0]
        return [ET(kinds[i], joint=joint, flip=(ux, uy, uz)[i] < 0)]
    if len(nonzero) == 2:
        if uz == 0:  # xy-plane: Rz(phi) maps x onto u
            g, j = ET(Axis.Rz, const=atan2_const(surd(uy), surd(ux))), kinds[0]
        elif ux == 0:  # yz-plane: Rx(alpha) maps y onto u
            g, j = ET(Axis.Rx, const=atan2_const(surd(uz), surd(uy))), kinds[1]
        else:  # zx-plane: Ry(beta) maps z onto u
            g, j = ET(Axis.Ry, const=atan2_const(surd(ux), surd(uz))), kinds[2]
        return [g, ET(j, joint=joint), ET(g.axis, const=-g.const)]
    phi = atan2_const(surd(uy), surd(ux))
    theta = atan2_const(ux * ux + uy * uy, surd(uz))
    return [
        ET(Axis.Rz, const=phi),
        ET(Axis.Ry, const=theta),
        ET(kinds[2], joint=joint),
        ET(Axis.Ry, const=-theta),
        ET(Axis.Rz, const=-phi),
    ]


def snap_atan2(e: ET, tol: float) -> ET:
    """A constant rotation by an atan2 term within ``tol`` of ``k*pi/12`` (decimal noise) becomes exact."""
    if e.is_joint or e.const.atan2 is None:
        return e
    v = e.const.value
    k = round(v * 12 / math.pi)
    return ET(e.axis, const=Const.pi_times(Fraction(k, 12))) if abs(v - k * math.pi / 12) <= tol else e


def snap_angle(value: Fraction, tol: float) -> Const:
    """``value`` (rad) as an exact Const, snapped to a multiple of pi/4 when within ``tol``."""
    x = float(value)
    k = round(x / (math.pi / 4))
    if abs(x - k * math.pi / 4) <= tol:
        return Const.pi_times(Fraction(k, 4))
    return Const(value)


# ---------------------------------------------------------------------------------------------
# the importer


def xml_numbers(
    text: str | None, count: int, what: str, default: str | None = None, bound: float | None = None
) -> list[Fraction]:
    """``count`` exact numbers from a space-separated attribute, each within +-``bound`` if given."""
    if text is None:
        if default is None:
            raise URDFError(f"{what} is missing")
        text = default
    cells = text.split()
    if len(cells) != count:
        raise URDFError(f"{what} must have {count} numbers, got {text!r}")
    values = [_number(c, what) for c in cells]
    for cell, v in zip(cells, values):
        if bound is not None and abs(v) > bound:
            shown = cell if len(cell) <= 40 else cell[:37] + "..."
            limit = f"{bound:g}".replace("e+", "e")
            raise URDFError(
                f"{what} contains {shown!r}; URDF lengths, angles and mimic factors must be within "
                f"+-{limit} (an angle beyond it has no meaningful double value)"
            )
    return values


#: The largest |value| of a URDF length or angle (origin xyz and rpy, mimic multiplier and offset),
#: the bound of joint values (:data:`symkin.core.arrays.MAX_JOINT_VALUE`): beyond it a double
#: resolves an angle to worse than 0.1 rad, and sums and squares of lengths along a chain head
#: for overflow (inf in the kinematics instead of an error here).
MAX_URDF_VALUE = 1e15
URDF_FILE_BYTES = 64 * 2**20  # a URDF (or SRDF) file larger than this is refused before it is read


def joint_origin(jel: ElementTree.Element, what: str) -> tuple[list[Fraction], list[Fraction]]:
    """``(xyz, rpy)`` of a joint's (or a collision element's) ``<origin>`` (zeros when absent),
    exact and within +-:data:`MAX_URDF_VALUE`; ``what`` names the element in messages. Shared by
    both readers and the collision readers (:mod:`symkin.geometry.urdf`, :mod:`symkin.geometry.meshes`)."""
    origin = jel.find("origin")
    attrs = {} if origin is None else origin.attrib
    xyz, rpy = (
        xml_numbers(attrs.get(k), 3, f"{what} origin {k}", "0 0 0", MAX_URDF_VALUE) for k in ("xyz", "rpy")
    )
    return xyz, rpy


def joint_axis(jel: ElementTree.Element, what: str, where: str, snap_tol: float) -> list[Fraction]:
    """The ``<axis xyz>`` of a movable joint (default ``1 0 0``) as exact rationals, components
    within ``snap_tol * |u|`` of 0 set to 0. Shared by both readers.

    Only the direction matters, so an axis whose largest component is beyond 1e+-100 is first
    scaled exactly by a power of ten (``1e200 0 0`` is ``1 0 0``, ``1e-300 1e-300 0`` is ``1 1 0``):
    the squares in its norm and atan2 terms neither overflow nor underflow. Other axes are used as
    written, so their ETS text does not change.
    """
    axis_el = jel.find("axis")
    u = xml_numbers(axis_el.get("xyz") if axis_el is not None else None, 3, f"{what} axis xyz", "1 0 0")
    big = max(abs(c) for c in u)
    if big == 0:
        raise URDFError(f"{where}: {what} has the zero vector as its axis; give a direction like '0 0 1'")
    if not Fraction(1, 10**100) <= big <= 10**100:
        shift = Fraction(10) ** round(math.log10(big.numerator) - math.log10(big.denominator))  # exact ints
        u = [c / shift for c in u]
    norm = math.sqrt(sum(float(c) ** 2 for c in u))
    return [c if abs(float(c)) > snap_tol * norm else Fraction(0) for c in u]


# a decimal number as XML Schema's xs:double writes it (no inf/nan, no fractions); unambiguous, so
# matching takes linear time
_DECIMAL = re.compile(r"[-+]?(?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?")
_MAX_NUMBER_CHARS = 1000


def _number(cell: str, what: str) -> Fraction:
    """One exact, finite number from URDF text (the decimal as written)."""
    shown = cell if len(cell) <= 40 else cell[:37] + "..."
    if cell.lower().lstrip("+-") in ("nan", "inf", "infinity"):
        raise URDFError(f"{what} contains {shown!r}: numbers must be finite")
    if len(cell) > _MAX_NUMBER_CHARS or not _DECIMAL.fullmatch(cell):
        raise URDFError(f"{what} contains {shown!r}, which is not a number")
    mantissa, _, exponent = cell.lower().partition("e")
    if exponent and abs(int(exponent)) > 400:  # Fraction would build a 10**exponent integer
        if float(cell) != 0.0:
            raise URDFError(f"{what} contains {shown!r}, beyond the range of a double (about 1.8e308)")
        return Fraction(0)  # smaller than the smallest double
    value = Fraction(cell)
    if abs(value) > sys.float_info.max:
        raise URDFError(f"{what} contains {shown!r}, beyond the range of a double (about 1.8e308)")
    return value


def _suggest(name: str, options: Sequence[str]) -> str:
    close = difflib.get_close_matches(name, options, n=3)
    hint = f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
    return f"{hint} Links: {list(options)}"


class _RefusedError(Exception):
    pass


def _refuse(*args: object) -> None:
    raise _RefusedError


class _XacroError(Exception):
    """A xacro construct, described for the message."""


class _XacroScan:
    """The prescan's element handler: raise _XacroError for what only xacro gives meaning to, in
    names as written (no namespace processing): an element or attribute under the ``xacro:``
    prefix or a prefix bound to the xacro namespace (``http://www.ros.org/wiki/xacro``), a default
    namespace that is xacro's, or a ``${...}`` / ``$(...)`` substitution in an attribute. A
    declaration alone is not xacro: expanded files (example-robot-data's baxter.urdf) keep it."""

    def __init__(self) -> None:
        self.prefixes = {"xacro"}

    def __call__(self, name: str, attrs: dict[str, str]) -> None:
        for key, value in attrs.items():
            if key.startswith("xmlns") and "ros.org/wiki/xacro" in value:
                if key == "xmlns":
                    raise _XacroError(f"its default namespace is xacro's, xmlns={value!r}")
                self.prefixes.add(key.partition(":")[2])
        if name.partition(":")[0] in self.prefixes and ":" in name:
            raise _XacroError(f"it has the element <{name}>")
        for key, value in attrs.items():
            if key.partition(":")[0] in self.prefixes and ":" in key:
                raise _XacroError(f"it has the attribute {key!r} in <{name}>")
            for mark in ("${", "$("):
                if mark in value:
                    shown = value if len(value) <= 60 else value[:57] + "..."
                    raise _XacroError(f"it has the substitution {shown!r} in attribute {key!r} of <{name}>")


def _xacro_error(where: str, found: str, path: Path | None = None) -> URDFError:
    """The refusal of a xacro file, with the command that expands it."""
    src, out = "file.urdf.xacro", "file.urdf"
    if path is not None and path.name.lower().endswith(".xacro") and len(path.name) > len(".xacro"):
        src = path.name
        out = path.name[: -len(".xacro")]
        out = out if out.lower().endswith(".urdf") else out + ".urdf"
    return URDFError(
        f"{where} is xacro, not plain URDF: {found}. symkin does not expand xacro macros; expand them "
        f"first with `xacro {shlex.quote(src)} > {shlex.quote(out)}` (the xacro command comes with "
        f"`pip install xacro` or ROS) and read {out}"
    )


def _prescan(text: str, where: str, path: Path | None = None) -> None:
    """Refuse, before the real parse, what a URDF must not have: a document type declaration
    (DOCTYPE, entities) and xacro.

    A URDF never needs a DOCTYPE, and its entities are what "billion laughs" and external-entity
    attacks are made of; expat stops at the declaration, before expanding anything. A xacro file
    parses as XML too, but without its macros expanded it describes a different (smaller) robot,
    so it is refused with the command that expands it. The scan sees names as written (no
    namespace processing), so an undeclared ``xacro:`` prefix is caught too.
    """
    parser = expat.ParserCreate()
    parser.StartDoctypeDeclHandler = _refuse
    parser.EntityDeclHandler = _refuse
    parser.StartElementHandler = _XacroScan()
    try:
        parser.Parse(text, True)
    except _RefusedError:
        raise URDFError(
            f"{where} has a DOCTYPE (document type declaration); symkin refuses DOCTYPE and entity "
            "declarations in URDF, which never needs them: remove it"
        ) from None
    except _XacroError as found:
        raise _xacro_error(where, str(found), path) from None
    except expat.ExpatError:
        pass  # reported by the real parse below, with its position


def load_xml(path_or_xml: str | Path) -> tuple[ElementTree.Element, str]:
    """Parse a URDF file path or XML text -> (root element, description for messages)."""
    if isinstance(path_or_xml, Path) or (
        isinstance(path_or_xml, str) and not path_or_xml.lstrip().lstrip("\ufeff").lstrip().startswith("<")
    ):
        path: Path | None = Path(path_or_xml)
        shown = repr(str(path)) if len(str(path)) <= 200 else repr(str(path)[:197] + "...")
        try:  # a byte-order mark is allowed; newlines as read_text reads them
            data = read_bounded(path, URDF_FILE_BYTES, "the file", OSError)  # named below
            text = data.decode("utf-8-sig").replace("\r\n", "\n").replace("\r", "\n")
        except UnicodeDecodeError as exc:
            raise URDFError(
                f"URDF file {shown} is not UTF-8 text: {exc.reason} at byte {exc.start}"
            ) from None
        except (OSError, ValueError) as exc:  # ValueError: a NUL in the path
            raise URDFError(
                f"cannot read URDF file {shown}: {getattr(exc, 'strerror', None) or exc}"
            ) from None
        where = f"URDF file {shown}"
        if path.name.lower().endswith(".xacro"):  # even one without macros: read the expanded file
            raise _xacro_error(where, "its name ends in .xacro", path)
    elif isinstance(path_or_xml, str):
        text, where = path_or_xml.lstrip().lstrip("\ufeff"), "URDF text"
        path = None
    else:
        raise URDFError(f"expected a URDF file path or XML text, not {type(path_or_xml).__name__}")
    _prescan(text, where, path)
    try:
        root = ElementTree.fromstring(text)
    except ElementTree.ParseError as exc:
        raise URDFError(
            f"malformed XML in {where}: {exc} (line, column as counted by the XML parser)"
        ) from None
    if root.tag != "robot":
        raise URDFError(f"{where}: the root element must be <robot>, not <{root.tag}>")
    return root, where


# -- the link/joint graph: the one reader of both Robot.from_urdf and Tree.from_urdf -----------


_MOVABLE = ("revolute", "continuous", "prismatic")


@dataclass(frozen=True, eq=False)
class URDFJoint:
    """One ``<joint>`` element: ``name``, ``kind`` (its type), ``parent`` and ``child`` links."""

    name: str
    kind: str
    parent: str
    child: str
    el: ElementTree.Element

    @property
    def movable(self) -> bool:
        return self.kind in _MOVABLE


@dataclass(frozen=True, eq=False)
class URDFGraph:
    """The link/joint graph of a URDF (checked to be a forest without cycles)."""

    where: str
    name: str
    links: tuple[str, ...]
    joints: dict[str, URDFJoint]  # by name, in file order
    parent_joint: dict[str, URDFJoint]  # by child link
    children: dict[str, list[URDFJoint]]  # by parent link, in file order

    @property
    def roots(self) -> list[str]:
        return [ln for ln in self.links if ln not in self.parent_joint]

    def check_link(self, link: str, what: str) -> None:
        if link not in self.children:
            raise URDFError(
                f"{self.where}: {what} {link!r} is not a link;" + _suggest(link, list(self.links))
            )

    def root(self) -> str:
        roots = self.roots
        if len(roots) != 1:
            raise URDFError(
                f"{self.where} has {len(roots)} root links {roots}; name base_link, one of the links: "
                f"{list(self.links)}"
            )
        return roots[0]

    def base(self, base_link: str | None) -> str:
        """``base_link`` checked to be a link, or the root link when None."""
        if base_link is None:
            return self.root()
        self.check_link(base_link, "base_link")
        return base_link

    def depth_first(self, base: str) -> list[URDFJoint]:
        """The joints below ``base``, depth first, the children of a link in file order."""
        out: list[URDFJoint] = []
        stack = list(reversed(self.children[base]))
        while stack:
            j = stack.pop()
            out.append(j)
            stack.extend(reversed(self.children[j.child]))
        return out

    def leaves(self, base: str) -> list[str]:
        """Links below ``base`` without children, depth first."""
        return [j.child for j in self.depth_first(base) if not self.children[j.child]]

    def path(self, base: str, link: str, what: str = "link") -> list[URDFJoint]:
        """The joints from ``base`` down to ``link`` (``what`` in the message when it is not below it),
        in order."""
        out: list[URDFJoint] = []
        ln = link
        while ln != base:
            j = self.parent_joint.get(ln)
            if j is None:
                raise URDFError(
                    f"{self.where}: {what} {link!r} is not below base_link {base!r} (no path down to it: "
                    f"walking up from {link!r} reached the root {ln!r})"
                )
            out.append(j)
            ln = j.parent
        out.reverse()
        return out


def read_graph(path_or_xml: str | Path) -> URDFGraph:
    """Parse a URDF (file path or XML text) into its link/joint graph, with clear errors."""
    root, where = load_xml(path_or_xml)
    links = [el.get("name") for el in root.findall("link")]
    if any(n is None for n in links):
        raise URDFError(f"{where}: a <link> has no name attribute")
    if len(set(links)) != len(links):
        dup = sorted({n for n in links if links.count(n) > 1})
        raise URDFError(f"{where}: link names must be unique; {dup} appear more than once")
    joints: dict[str, URDFJoint] = {}
    parent_joint: dict[str, URDFJoint] = {}
    children: dict[str, list[URDFJoint]] = {n: [] for n in links}
    for el in root.findall("joint"):
        jname = el.get("name")
        if not jname:
            raise URDFError(f"{where}: a <joint> has no name attribute")
        if jname in joints:
            raise URDFError(f"{where}: joint names must be unique; {jname!r} appears more than once")
        kind = el.get("type")
        if kind not in _KNOWN:
            raise URDFError(
                f"{where}: joint {jname!r} has unknown type {kind!r}; valid types: {list(_KNOWN)}"
            )
        ends = []
        for tag in ("parent", "child"):
            sub = el.find(tag)
            lname = sub.get("link") if sub is not None else None
            if lname is None:
                raise URDFError(f"{where}: joint {jname!r} has no <{tag} link=...>")
            if lname not in children:
                raise URDFError(
                    f"{where}: joint {jname!r} names {tag} link {lname!r}, which is not declared"
                    + _suggest(lname, links)
                )
            ends.append(lname)
        j = URDFJoint(jname, kind, ends[0], ends[1], el)
        if j.child in parent_joint:
            raise URDFError(
                f"{where}: link {j.child!r} is the child of two joints, {parent_joint[j.child].name!r} and "
                f"{jname!r}; a URDF must be a tree"
            )
        joints[jname] = j
        parent_joint[j.child] = j
        children[j.parent].append(j)
    graph = URDFGraph(where, root.get("name") or "robot", tuple(links), joints, parent_joint, children)
    rooted: set[str] = set()  # links whose walk up ends at a root: each link is walked from once
    for link in links:  # a cycle has no root: walking up from any of its links comes back
        seen, ln = {link}, link
        while ln in parent_joint and ln not in rooted:
            ln = parent_joint[ln].parent
            if ln in seen:
                raise URDFError(f"{where}: the joints form a cycle through link {ln!r}")
            seen.add(ln)
        rooted |= seen
    return graph


def joint_limits(j: URDFJoint, where: str) -> tuple[float, float, float]:
    """(lower, upper, velocity) of a movable joint: +-pi (revolute) or +-1 m without limits, the
    velocity NaN when not given or not positive."""
    what = f"joint {j.name!r}"
    lim = j.el.find("limit")
    default = math.pi if j.kind != "prismatic" else 1.0
    lo, hi = -default, default
    if lim is not None and j.kind != "continuous":
        if lim.get("lower") is not None:
            lo = float(xml_numbers(lim.get("lower"), 1, f"{what} limit lower")[0])
        if lim.get("upper") is not None:
            hi = float(xml_numbers(lim.get("upper"), 1, f"{what} limit upper")[0])
        if lo > hi:
            raise URDFError(f"{where}: {what} has limit lower {lo} > upper {hi}")
    vel = lim.get("velocity") if lim is not None else None
    v = float(xml_numbers(vel, 1, f"{what} limit velocity")[0]) if vel is not None else math.nan
    return lo, hi, v if v > 0 else math.nan


def _limit_lists(limits: Sequence[tuple[float, float, float]]) -> list[list[float]]:
    """The lower limits, upper limits and velocities of :func:`joint_limits` rows, as three lists."""
    return [[row[i] for row in limits] for i in range(3)]


def joint_ets(graph: URDFGraph, j: URDFJoint, slot: int, snap_tol: float) -> list[ET]:
    """The exact ETs of joint ``j`` in a chain or a tree: its origin, then (movable) the joint as
    joint index ``slot``."""
    what = f"joint {j.name!r}"
    xyz, rpy = joint_origin(j.el, what)
    out = rpy_ets([Const(v) for v in xyz], [snap_angle(a, snap_tol) for a in rpy])
    if not j.movable:
        return out
    u = joint_axis(j.el, what, graph.where, snap_tol)
    return out + [snap_atan2(e, snap_tol) for e in axis_ets(u, slot, revolute=j.kind != "prismatic")]


def urdf_args(
    path_or_xml: str | Path,
    base_link: str | None = None,
    end_link: str | None = None,
    name: str | None = None,
    snap_tol: float = 1e-9,
) -> dict[str, Any]:
    """The serial chain of a URDF (file path or XML text) from ``base_link`` to ``end_link``: the
    tree of that one frame (:func:`urdf_tree_args`), its joints' ETs in order.

    ``base_link`` defaults to the root link, ``end_link`` to the only leaf below ``base_link``
    (a branching tree needs ``end_link``). Joints: revolute, continuous, prismatic, fixed.
    """
    graph = read_graph(path_or_xml)
    where, base_link = graph.where, graph.base(base_link)
    if end_link is None:
        leaves = graph.leaves(base_link) or [base_link]
        if len(leaves) != 1:
            raise URDFError(
                f"{where}: the tree below {base_link!r} branches; name end_link, one of the leaf "
                f"links {leaves}"
            )
        end_link = leaves[0]
    graph.check_link(end_link, "end_link")
    one = [end_link] if end_link != base_link else []  # a path without joints: refused below
    tree = urdf_tree_args(graph, one, base_link, snap_tol, name) if one else {"slots": ()}
    mimic = next((s for s in tree["slots"] if s.is_mimic), None)
    if mimic is not None:
        raise URDFError(
            f"{where}: joint {mimic.name!r} mimics joint {mimic.mimics!r}; mimic joints are not supported "
            "(each joint must be independent): choose another end_link or edit the URDF"
        )
    if not tree["slots"]:
        raise URDFError(
            f"{where}: no revolute, continuous or prismatic joint between {base_link!r} and {end_link!r}"
        )
    qd = tree["velocity"]
    return dict(
        ets=ETS(tuple(e for seg in tree["segments"] for e in seg.ets)),
        name=tree["name"],
        qlim=tree["qlim"],
        joint_names=tree["joint_names"],
        qd_max=None if any(math.isnan(v) for v in qd) else qd,
        source=f"{where}, chain {base_link} -> {end_link}",
    )


# ---------------------------------------------------------------------------------------------
# trees


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
    path_or_xml: str | Path | URDFGraph,
    frames: Sequence[str] | str | None = None,
    base_link: str | None = None,
    snap_tol: float = 1e-9,
    name: str | None = None,
) -> dict[str, Any]:
    """The :class:`symkin.Tree` arguments of a URDF (or of its read graph): see
    :meth:`symkin.Tree.from_urdf`."""
    graph = path_or_xml if isinstance(path_or_xml, URDFGraph) else read_graph(path_or_xml)
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
    lower, upper, vel = _limit_lists([joint_limits(graph.joints[n], where) for n in names])
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
    return dict(
        name=name or graph.name,
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
    base_link = graph.base(base_link)
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
