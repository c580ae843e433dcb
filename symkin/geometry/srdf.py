"""The link pairs a MoveIt SRDF never checks: ``<disable_collisions link1= link2= reason=/>``.

:func:`read_srdf` gives them as pairs of link names for :meth:`symkin.geometry.Geometry.with_disabled`,
translated to the model's link names with ``names`` (e.g.
:func:`symkin.geometry.urdf.urdf_link_names` for a chain read with :meth:`symkin.Robot.from_urdf`).
The file is parsed by the URDF reader's safe loader (no DOCTYPE, no xacro).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable, Mapping
from pathlib import Path

from symkin.errors import GeometryError, URDFError
from symkin.model.urdf import load_xml

__all__ = ["read_srdf"]


def read_srdf(
    path_or_xml: str | Path, names: Mapping[str, str] | Callable[[str], str | None] | None = None
) -> tuple[tuple[str, str], ...]:
    """The ``disable_collisions`` pairs of an SRDF (file path or XML text), each sorted, sorted and
    without repeats.

    ``names`` (a mapping or a function, optional) translates SRDF link names to the model's: a
    pair with a link it does not know (a mapping without the key, a function returning None) is
    dropped with a warning, and so is a pair whose two links become one.
    """
    try:
        root, where = load_xml(path_or_xml)
    except URDFError as exc:
        raise GeometryError(str(exc).replace("URDF", "SRDF")) from None
    where = where.replace("URDF", "SRDF")
    out: set[tuple[str, str]] = set()
    dropped: list[tuple[str, str]] = []
    for el in root.iter("disable_collisions"):
        a, b = el.get("link1"), el.get("link2")
        if not a or not b:
            raise GeometryError(f"{where}: a <disable_collisions> needs link1 and link2, got {el.attrib}")
        if names is not None:
            get = names.get if isinstance(names, Mapping) else names
            ma, mb = get(a), get(b)
            if ma is None or mb is None or ma == mb:
                dropped.append((a, b))
                continue
            a, b = ma, mb
        if a != b:
            out.add((a, b) if a <= b else (b, a))
    if dropped:
        shown = ", ".join(f"({a}, {b})" for a, b in dropped[:5]) + (" ..." if len(dropped) > 5 else "")
        warnings.warn(
            f"{where}: {len(dropped)} disable_collisions pairs name links the model does not have or "
            f"that fall on one model link: dropped {shown}",
            stacklevel=2,
        )
    return tuple(sorted(out))
