"""Denavit-Hartenberg parameters to an ETS (Corke, Robotics, Vision and Control, 2017, chapter 7).

A standard DH link is ``Rz(theta) tz(d) tx(a) Rx(alpha)``; a modified (Craig) link is
``tx(a) Rx(alpha) Rz(theta) tz(d)`` (Craig's convention). For a revolute link the joint is
``theta = q + offset``; for a prismatic link ``theta`` is a constant angle and the joint is
``d = q + offset`` (a nonzero ``d`` of a prismatic link is added to ``offset``). A joint offset
becomes a constant ET just before the joint (``Rz(offset) Rz(q)`` or ``tz(offset) tz(q)``), and zero
constants are dropped.

Constants stay exact: numbers, or text such as ``"pi/2"`` or ``"90deg"`` (see :class:`Const`).
An angle given as a float within 1e-12 of ``k*pi/m`` (``m <= 12``) snaps to it exactly, so
``math.pi/2`` becomes ``pi/2``; any other float is kept as the exact decimal it prints as.

DH table files (:func:`symkin.load_dh_file`, :func:`dh_file_args`) are whitespace tables::

    # symkin dh: standard            <- required: 'standard' or 'modified'
    # name: puma560                  <- optional metadata: name, source, base, tool,
    # config qr: 0 90deg -90deg 0 0 0     qd_max, and 'config NAME' (one value per joint)
    type  d      a       alpha   offset  qmin     qmax       <- header: column names
    R     0      0       pi/2    0       -160deg  160deg
    P     0      0.0203  0       0       0.3048   1.27

Columns, in any order: ``type`` (required: ``R``/``P``, or ``revolute``/``prismatic``), ``d``,
``a``, ``alpha``, ``offset``, ``theta``, ``qmin``, ``qmax``, ``qdmax``, ``name``. A missing
column, or a cell ``-``, takes the default (0, or no limit). Lines starting ``#`` after the
header, and text after `` #`` in a row, are comments; so are ``#`` lines before the header that
are not metadata. The header may itself be written as a comment (``# type d a alpha ...``).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from fractions import Fraction
from pathlib import Path
from typing import Any, TypeAlias

import numpy as np

from symkin.errors import ETSParseError, RobotError
from symkin.model.ets import ET, ETS, Axis, Const
from symkin.model.transform import angle_const as float_angle
from symkin.model.transform import constant_ets

__all__ = ["DHLink", "dh_args", "dh_file_args", "dh_table_args", "angle_const", "length_const", "robot_args"]

Number: TypeAlias = float | int | Fraction | str | Const

_SNAP_TOL = 1e-12


@dataclass(frozen=True)
class DHLink:
    """One DH row. Lengths in m, angles in rad (numbers, or text like ``"pi/2"``, ``"90deg"``).

    ``prismatic=False``: the joint is ``theta = q + offset`` (``theta`` must stay 0).
    ``prismatic=True``: ``theta`` is a constant angle and the joint is ``d = q + offset + d``.
    ``qlim`` is the (lower, upper) joint limit; ``name`` the joint name.
    """

    d: Number = 0
    a: Number = 0
    alpha: Number = 0
    offset: Number = 0
    prismatic: bool = False
    theta: Number = 0
    qlim: tuple[float, float] | None = None
    name: str | None = None


_LINK_KEYS = tuple(f.name for f in fields(DHLink)) + ("type",)
_ANGLES = ("alpha", "theta")


def angle_const(value: Any, what: str = "angle", tol: float = _SNAP_TOL) -> Const:
    """An exact angle: text/Const as given, ints and Fractions exact, floats snapped to ``k*pi/m``.

    A float within ``tol`` of ``k*pi/m`` with ``m <= 12`` becomes exactly that multiple of pi,
    else the exact decimal it prints as. Raises RobotError naming ``what`` for bad values.
    """
    exact = isinstance(value, (bool, numbers.Rational)) or not isinstance(value, numbers.Real)
    if exact or not math.isfinite(value):  # text, Const, int, Fraction; or refused by Const.of
        return length_const(value, what)
    return float_angle(float(value), tol)


def length_const(value: Any, what: str = "length") -> Const:
    """An exact length: text/Const as given, ints and Fractions exact, floats as printed
    (:meth:`Const.of`); RobotError naming ``what`` for anything else."""
    try:
        return Const.of(value)
    except (ETSParseError, RobotError, TypeError) as exc:
        raise RobotError(f"{what}: {str(exc).splitlines()[0]}") from None


def _link_of(row: DHLink | Mapping[str, Any], j: int) -> DHLink:
    if isinstance(row, DHLink):
        return row
    if not isinstance(row, Mapping):
        raise RobotError(f"DH link {j} must be a DHLink or a dict, not {type(row).__name__}")
    bad = sorted(set(row) - set(_LINK_KEYS))
    if bad:
        raise RobotError(f"DH link {j}: unknown key(s) {bad}; valid keys: {list(_LINK_KEYS)}")
    kw = {k: v for k, v in row.items() if k != "type"}
    if "type" in row:
        kind = str(row["type"]).strip().lower()
        if kind not in ("r", "p", "revolute", "prismatic"):
            raise RobotError(f"DH link {j}: type {row['type']!r} must be 'R' (revolute) or 'P' (prismatic)")
        if "prismatic" in row and bool(row["prismatic"]) != (kind[0] == "p"):
            raise RobotError(f"DH link {j}: type {row['type']!r} contradicts prismatic={row['prismatic']!r}")
        kw["prismatic"] = kind[0] == "p"
    return DHLink(**kw)


def _add(a: Const, b: Const, what: str) -> Const:
    try:
        c = a + b
        if not math.isfinite(c.value):
            raise OverflowError
        return c
    except ValueError as exc:
        raise RobotError(f"{what}: {exc}") from None
    except OverflowError:
        raise RobotError(f"{what}: d + offset = {c} is beyond the range of a double") from None


def _link_ets(link: DHLink, j: int, modified: bool) -> list[ET]:
    """The ETs of one DH link: joint index ``j``."""
    where = f"DH link {j}"
    d = length_const(link.d, f"{where} d")
    a = length_const(link.a, f"{where} a")
    alpha = angle_const(link.alpha, f"{where} alpha")
    theta = angle_const(link.theta, f"{where} theta")
    if link.prismatic:
        offset = length_const(link.offset, f"{where} offset")
        rot = [ET(Axis.Rz, const=theta)]
        trans = [ET(Axis.tz, const=_add(d, offset, where)), ET(Axis.tz, joint=j)]
    else:
        if not theta.is_zero:
            raise RobotError(
                f"{where} is revolute, so theta is its joint variable; give the constant angle "
                f"{theta} as offset= instead (or set prismatic=True)"
            )
        offset = angle_const(link.offset, f"{where} offset")
        rot = [ET(Axis.Rz, const=offset), ET(Axis.Rz, joint=j)]
        trans = [ET(Axis.tz, const=d)]
    xa = [ET(Axis.tx, const=a), ET(Axis.Rx, const=alpha)]
    seq = xa + rot + trans if modified else rot + trans + xa
    return [e for e in seq if e.is_joint or not e.const.is_zero]


def robot_args(
    chain: Sequence[ET],
    name: str,
    qlim: Any,
    configs: Mapping[str, Any] | None,
    joint_names: Sequence[str] | None,
    qd_max: Any,
    source: str,
) -> dict[str, Any]:
    """The :class:`~symkin.Robot` arguments of an imported ``chain`` (the importers' own arguments,
    the configurations and joint names copied)."""
    return dict(
        ets=ETS(tuple(chain)),
        name=name,
        qlim=qlim,
        configs=dict(configs or {}),
        joint_names=tuple(joint_names or ()),
        qd_max=qd_max,
        source=source,
    )


def dh_args(
    links: Sequence[DHLink | Mapping[str, Any]],
    modified: bool = False,
    name: str = "robot",
    qlim: Any = None,
    base: Any = None,
    tool: Any = None,
    configs: Mapping[str, Any] | None = None,
    qd_max: Any = None,
    source: str = "",
    joint_names: Sequence[str] | None = None,
) -> dict[str, Any]:
    """The :class:`~symkin.Robot` arguments (``ets``, ``name``, limits, ...) of standard
    (``modified=False``) or modified (Craig) DH links (Corke, Robotics, Vision and Control, 2017,
    chapter 7).

    ``links``: DHLink or dicts with the same keys (plus ``type``: ``'R'``/``'P'``). ``qlim``
    (2, n) overrides the per-link limits; links without limits get the Robot defaults.
    ``base``/``tool``: constant transforms before the first and after the last link, in any form
    :meth:`symkin.Robot.with_tool` takes (ETS text, ``"x y z roll pitch yaw"``, a 4x4 matrix...).
    Joint names default to the links' ``name`` when every link has one.
    """
    if isinstance(links, (str, bytes, Mapping, DHLink)) or not isinstance(links, Sequence):
        raise RobotError("links must be a sequence of DHLink or dicts, one per joint")
    if not links:
        raise RobotError("a DH robot needs at least one link")
    rows = [_link_of(row, j) for j, row in enumerate(links)]
    chain = constant_ets(base, "base")
    for j, link in enumerate(rows):
        chain += _link_ets(link, j, modified)
    chain += constant_ets(tool, "tool")
    n = len(rows)
    if qlim is None and any(r.qlim is not None for r in rows):
        lim = []
        for j, r in enumerate(rows):
            if r.qlim is None:
                lim.append((-math.pi, math.pi) if not r.prismatic else (-1.0, 1.0))
            else:
                pair = tuple(r.qlim)
                if len(pair) != 2:
                    raise RobotError(f"DH link {j}: qlim must be (lower, upper), got {r.qlim!r}")
                lim.append(tuple(length_const(v, f"DH link {j} qlim").value for v in pair))
        qlim = np.array(lim, dtype=float).T
    if joint_names is None and all(r.name for r in rows):
        joint_names = [str(r.name) for r in rows]
    source = source or ("modified" if modified else "standard") + f" DH table, {n} links"
    return robot_args(chain, name, qlim, configs, joint_names, qd_max, source)


# ---------------------------------------------------------------------------------------------
# DH table files

_COLUMNS = ("type", "d", "a", "alpha", "offset", "theta", "qmin", "qmax", "qdmax", "name")
_META = ("name", "source", "base", "tool", "qd_max")


def dh_file_args(path: str | Path) -> dict[str, Any]:
    """The Robot arguments of a DH table file (format in the module docstring)."""
    from symkin.core.sizes import read_text

    text = read_text(path, DH_FILE_BYTES, f"DH table {str(path)!r}", RobotError)
    return dh_table_args(text, str(path))


DH_FILE_BYTES = 16 * 2**20  # a DH table file larger than this is refused before it is read


def dh_table_args(text: str, filename: str = "<dh table>") -> dict[str, Any]:
    """The Robot arguments of the text of a DH table file (see the module docstring)."""
    lines = text.splitlines()

    def fail(lineno: int, why: str) -> RobotError:
        return RobotError(f"{filename}:{lineno}: {why}")

    body = [(i + 1, ln.strip()) for i, ln in enumerate(lines) if ln.strip()]
    if not body or not body[0][1].startswith("#") or ":" not in body[0][1]:
        raise fail(
            body[0][0] if body else 1,
            "the first line must be '# symkin dh: standard' or '# symkin dh: modified'",
        )
    key, _, value = body[0][1][1:].partition(":")
    convention = value.strip().lower()
    if " ".join(key.split()).lower() != "symkin dh" or convention not in ("standard", "modified"):
        raise fail(
            body[0][0],
            f"the first line must be '# symkin dh: standard' or '# symkin dh: modified', not {body[0][1]!r}",
        )
    meta: dict[str, str] = {}
    meta_line: dict[str, int] = {}
    configs: dict[str, tuple[int, str]] = {}
    header: list[str] | None = None
    rows: list[tuple[int, list[str]]] = []
    for lineno, line in body[1:]:
        if line.startswith("#"):
            words = line[1:].lower().split()
            if header is None and words and words[0] == "type" and all(w in _COLUMNS for w in words):
                line = line[1:]  # the header written as a comment: '# type d a alpha ...'
            else:
                if header is None and ":" in line:  # metadata; other comments are ignored
                    k, _, v = line[1:].partition(":")
                    k = " ".join(k.split())
                    if k.lower().startswith("config "):
                        configs[k[7:].strip()] = (lineno, v.strip())
                    elif k.lower() in _META:
                        meta[k.lower()] = v.strip()
                        meta_line[k.lower()] = lineno
                continue
        cells = line.split(" #")[0].split()
        if header is None:
            header = [c.lower() for c in cells]
            bad = [c for c in header if c not in _COLUMNS]
            if bad:
                raise fail(lineno, f"unknown column(s) {bad} in the header; valid columns: {list(_COLUMNS)}")
            if "type" not in header:
                raise fail(lineno, f"the header must name the 'type' column; valid columns: {list(_COLUMNS)}")
            if len(set(header)) != len(header):
                raise fail(lineno, f"a column is named twice in the header {header}")
            continue
        if len(cells) != len(header):
            raise fail(
                lineno, f"{len(cells)} cells but the header has {len(header)} columns: {' '.join(header)}"
            )
        rows.append((lineno, cells))
    if header is None or not rows:
        raise RobotError(
            f"{filename}: no DH rows; after the header line (column names, e.g. "
            "'type d a alpha offset qmin qmax') give one row per joint"
        )
    links: list[DHLink] = []
    qd: list[float | None] = []
    for lineno, cells in rows:
        cell = dict(zip(header, cells))
        kw: dict[str, Any] = {}
        kind = cell["type"].lower()
        if kind not in ("r", "p", "revolute", "prismatic"):
            raise fail(lineno, f"type {cell['type']!r} must be R (revolute) or P (prismatic)")
        kw["prismatic"] = kind[0] == "p"
        for col in ("d", "a", "alpha", "offset", "theta"):
            if cell.get(col, "-") != "-":
                kw[col] = _cell_const(cell[col], col, lineno, fail)
        if not kw["prismatic"] and not kw.get("theta", Const()).is_zero:
            raise fail(
                lineno,
                "theta of a revolute row is its joint variable; put the constant angle in the "
                "offset column (or make the row P)",
            )
        lo, hi = cell.get("qmin", "-"), cell.get("qmax", "-")
        if (lo == "-") != (hi == "-"):
            raise fail(lineno, "give both qmin and qmax, or neither ('-')")
        if lo != "-":
            kw["qlim"] = (
                _cell_const(lo, "qmin", lineno, fail).value,
                _cell_const(hi, "qmax", lineno, fail).value,
            )
            if kw["qlim"][0] > kw["qlim"][1]:
                raise fail(lineno, f"qmin {lo} is greater than qmax {hi}")
        if cell.get("name", "-") != "-":
            kw["name"] = cell["name"]
        qd.append(
            _cell_const(cell["qdmax"], "qdmax", lineno, fail).value if cell.get("qdmax", "-") != "-" else None
        )
        links.append(DHLink(**kw))
    n = len(links)
    qd_max = None
    if "qd_max" in meta:
        qd_max = _values(meta["qd_max"], n, "qd_max", fail, meta_line["qd_max"])
    elif all(v is not None for v in qd):
        qd_max = qd
    cfg = {k: _values(v, n, f"config {k}", fail, ln) for k, (ln, v) in configs.items()}
    try:
        return dh_args(
            links,
            modified=convention == "modified",
            name=meta.get("name") or Path(filename).stem or "robot",
            base=meta.get("base") or None,
            tool=meta.get("tool") or None,
            configs=cfg,
            qd_max=qd_max,
            source=meta.get("source") or f"{convention} DH table {filename}",
        )
    except RobotError as exc:
        raise RobotError(f"{filename}: {exc}") from None


def _cell_const(text: str, col: str, lineno: int, fail: Any) -> Const:
    try:
        return Const.of(text)
    except ETSParseError as exc:
        raise fail(lineno, f"column {col!r}: {str(exc).splitlines()[0]}") from None


def _values(text: str, n: int, what: str, fail: Any, lineno: int) -> list[float]:
    cells = text.replace(",", " ").split()
    if len(cells) != n:
        raise fail(lineno, f"{what} needs {n} values (one per joint), got {len(cells)}")
    return [_cell_const(c, what, lineno, fail).value for c in cells]
