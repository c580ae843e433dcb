"""The link pairs a MoveIt SRDF never checks: ``<disable_collisions link1= link2= reason=/>``, read
and written.

Reading. :func:`read_srdf` gives them as pairs of link names for
:meth:`symkin.geometry.Geometry.with_disabled`, translated to the model's link names with ``names``
(e.g. :func:`symkin.geometry.urdf.urdf_link_names` for a chain read with
:meth:`symkin.Robot.from_urdf`). Both it and :func:`srdf_disabled` (what the command line uses)
read conservatively: a pair of model links is disabled only when the SRDF disables every pair of
the links (with collision geometry, for :func:`srdf_disabled`) that the model merged into them
(fixed joints merge URDF links into one model link; an SRDF that disables the hand against link 5
but not the finger against link 5 leaves the pair checked). The file is parsed by the URDF
reader's safe loader (no DOCTYPE, no xacro).

Writing. :func:`disabled_pairs` lists a model's link pairs that need no check: ``"Adjacent"``
(links on one rigid body or on bodies one joint apart, which symkin never checks against each
other) and ``"Never"`` (every pair of their shapes proved apart over the joint limits by
:func:`symkin.geometry.proved_apart`: a proof, where MoveIt Setup Assistant's "Never" comes from
sampling). :func:`write_srdf` writes them as an SRDF MoveIt loads (srdfdom: a ``<robot name>``
root with ``<disable_collisions link1 link2 reason/>`` children, links named as in the URDF).
"Never" holds for symkin's collision model (spheres and capsules); for MoveIt's own geometry
(meshes) it holds where the spheres cover the meshes.
"""

from __future__ import annotations

import itertools
import warnings
from collections.abc import Callable, Collection, Mapping, Sequence
from pathlib import Path
from typing import Any
from xml.sax.saxutils import quoteattr

from symkin.core.names import listed
from symkin.errors import GeometryError, URDFError
from symkin.model.urdf import load_xml

__all__ = ["read_srdf", "srdf_disabled", "disabled_pairs", "write_srdf", "pairs_text"]


def _entries(path_or_xml: str | Path) -> tuple[list[tuple[str, str]], str]:
    """The ``disable_collisions`` (link1, link2) of an SRDF in file order, and where it is from."""
    try:
        root, where = load_xml(path_or_xml)
    except URDFError as exc:
        raise GeometryError(str(exc).replace("URDF", "SRDF")) from None
    where = where.replace("URDF", "SRDF")
    out = []
    for el in root.iter("disable_collisions"):
        a, b = el.get("link1"), el.get("link2")
        if not a or not b:
            raise GeometryError(f"{where}: a <disable_collisions> needs link1 and link2, got {el.attrib}")
        out.append((a.strip(), b.strip()))
    return out, where


def read_srdf(
    path_or_xml: str | Path, names: Mapping[str, str] | Callable[[str], str | None] | None = None
) -> tuple[tuple[str, str], ...]:
    """The ``disable_collisions`` pairs of an SRDF (file path or XML text), each sorted, sorted and
    without repeats.

    ``names`` (a mapping or a function, optional) translates SRDF link names to the model's, and the
    reading is then conservative, as :func:`srdf_disabled`'s: when several SRDF links fall on one
    model link (URDF links merged by fixed joints), a pair of model links is disabled only when the
    SRDF disables every pair of the SRDF links on them; pairs it disables only in part stay checked,
    with a warning. A mapping names every link it translates (e.g.
    :func:`symkin.geometry.urdf.urdf_link_names`); a function only sees the links the SRDF names, so
    pass a mapping when links merge. A pair with a link ``names`` does not know (a mapping without
    the key, a function returning None) is dropped with a warning, and so is a pair whose two links
    become one.
    """
    entries, where = _entries(path_or_xml)
    if names is None:
        return tuple(sorted({(a, b) if a <= b else (b, a) for a, b in entries if a != b}))
    get = names.get if isinstance(names, Mapping) else names
    dropped = [(a, b) for a, b in entries if get(a) is None or get(b) is None or get(a) == get(b)]
    _warn(
        where,
        dropped,
        "disable_collisions pairs name links the model does not have or that fall on one model link: dropped",
    )
    known = names.keys() if isinstance(names, Mapping) else {x for p in entries for x in p}
    carriers: dict[str, list[str]] = {}
    for x in sorted(known):
        m = get(x)
        if m is not None:
            carriers.setdefault(m, []).append(x)
    disabled, partial = _conservative({frozenset(p) for p in entries if p[0] != p[1]}, carriers)
    _warn(where, partial, "model link pairs stay checked, the SRDF disabling only some of the links on them:")
    return disabled


def pairs_text(pairs: Sequence[tuple[str, str]], most: int) -> str:
    """``(a, b), (c, d) ...``: the first ``most`` link pairs, as messages show them."""
    return listed([f"({a}, {b})" for a, b in pairs], most)


def _warn(where: str, pairs: Sequence[tuple[str, str]], what: str) -> None:
    """A warning (to the caller of :func:`read_srdf`) naming the first five ``pairs``, if any."""
    if pairs:
        warnings.warn(f"{where}: {len(pairs)} {what} {pairs_text(pairs, 5)}", stacklevel=3)


def _conservative(
    off: Collection[frozenset[str]], carriers: Mapping[str, Collection[str]]
) -> tuple[tuple[tuple[str, str], ...], tuple[tuple[str, str], ...]]:
    """(model link pairs all of whose carrier pairs are in ``off``, pairs with only some of them)."""
    disabled, partial = [], []
    for x, y in itertools.combinations(sorted(carriers), 2):
        wanted = [frozenset((a, b)) for a in carriers[x] for b in carriers[y] if a != b]
        hits = sum(p in off for p in wanted)
        if wanted and hits == len(wanted):
            disabled.append((x, y))
        elif hits:
            partial.append((x, y))
    return tuple(disabled), tuple(partial)


def srdf_disabled(
    path_or_xml: str | Path, carriers: Mapping[str, Collection[str]]
) -> tuple[tuple[tuple[str, str], ...], tuple[tuple[str, str], ...], int]:
    """The model link pairs an SRDF disables, conservatively: ``carriers`` maps each model link
    with shapes to the SRDF (URDF) links whose collision geometry it carries; a pair of model links
    is disabled when the SRDF disables every pair of their carriers. Returns (disabled pairs,
    pairs the SRDF disables only in part, which stay checked; how many of the SRDF's pairs name
    a carrier at all), pairs sorted."""
    entries, _ = _entries(path_or_xml)
    off = {frozenset(p) for p in entries if p[0] != p[1]}
    known = {x for links in carriers.values() for x in links}
    used = sum(1 for p in off if p <= known)
    return (*_conservative(off, carriers), used)


def disabled_pairs(model: Any) -> tuple[tuple[str, str, str], ...]:
    """The pairs of links of ``model``'s geometry (a Robot, a Tree or compiled kinematics) that
    need no check, ``(link1, link2, reason)`` with link1 < link2, sorted: ``"Adjacent"`` for
    links on one body or on bodies one joint apart, ``"Never"`` for links every pair of whose
    shapes is proved apart within the joint limits (:func:`symkin.geometry.proved_apart`). The
    geometry's own disabled pairs are ignored: every pair is judged."""
    from symkin.geometry.clearance import proved_apart
    from symkin.geometry.pairs import as_tree, layout_of
    from symkin.model.geometry import Geometry

    tree = as_tree(model)
    geometry = tree.geometry
    if geometry is None or not geometry.shapes:
        raise GeometryError(f"{tree.name} has no collision geometry to write an SRDF of")
    layout = layout_of(tree.with_geometry(Geometry(geometry.shapes, (), geometry.source)))
    proved = proved_apart(layout)
    by_links: dict[tuple[str, str], list[bool]] = {}
    for i, j in layout.self_pairs:
        a, b = sorted((layout.shapes[i].link, layout.shapes[j].link))
        by_links.setdefault((a, b), []).append((i, j) in proved)
    out = []
    for a, b in itertools.combinations(sorted(geometry.links), 2):
        apart = by_links.get((a, b))
        if apart is None:  # no shape pair between them is checked: one body or adjacent bodies
            out.append((a, b, "Adjacent"))
        elif all(apart):
            out.append((a, b, "Never"))
    return tuple(out)


def write_srdf(
    name: str,
    pairs: Collection[tuple[str, str, str]],
    carriers: Mapping[str, Collection[str]] | None = None,
    note: str = "",
) -> str:
    """An SRDF (text) for robot ``name`` disabling ``pairs`` ((link1, link2, reason) of model
    links, :func:`disabled_pairs`). ``carriers`` maps each model link to the URDF links it carries
    (the names MoveIt knows): a pair of model links becomes every pair of their URDF links, and
    URDF links carried by one model link are "Adjacent"; without it the model's names are written.
    ``note`` goes into the file's comment."""
    rows: dict[tuple[str, str], str] = {}

    def add(a: str, b: str, reason: str) -> None:
        if a != b:
            rows.setdefault((min(a, b), max(a, b)), reason)

    links = {x for p in pairs for x in p[:2]} | set(carriers or ())
    urdf = {x: sorted(carriers.get(x, ())) if carriers is not None else [x] for x in links}
    for x in sorted(links):
        for a, b in itertools.combinations(urdf[x], 2):
            add(a, b, "Adjacent")
    for x, y, reason in pairs:
        for a in urdf[x]:
            for b in urdf[y]:
                add(a, b, reason)
    text = _comment(
        "Written by symkin: the link pairs its collision model never needs to check. Adjacent: "
        "links on one rigid body or on bodies one joint apart. Never: every pair of their shapes "
        "is proved apart within the joint limits (branch and bound, symkin.geometry.clearance), "
        "for symkin's spheres and capsules; it holds for other geometry where those cover it. " + note
    )
    lines = ['<?xml version="1.0" encoding="UTF-8"?>', text, f"<robot name={quoteattr(name)}>"]
    lines += [
        f"    <disable_collisions link1={quoteattr(a)} link2={quoteattr(b)} reason={quoteattr(r)}/>"
        for (a, b), r in sorted(rows.items())
    ]
    lines.append("</robot>")
    return "\n".join(lines) + "\n"


def _comment(text: str) -> str:
    """An XML comment of ``text`` (no ``--`` inside, wrapped at 100 columns)."""
    words = " ".join(text.replace("--", "- -").split()).split(" ")
    lines, line = [], ""
    for w in words:
        if line and len(line) + len(w) > 95:
            lines.append(line)
            line = ""
        line += ("" if not line else " ") + w
    lines.append(line)
    return "<!--\n" + "\n".join(f"  {x}" for x in lines) + "\n-->"
