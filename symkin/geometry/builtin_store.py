"""The stored covering models of the built-in arms (:data:`symkin.model.builtin_geometry.STORE`):
refit from the meshes, write, compare.

:func:`refit` fits one built-in robot (:func:`symkin.geometry.mesh_fit.fit_builtin`) and decides
its disabled link pairs: the pairs of links, not adjacent, whose spheres overlap at the robot's
zero configuration or at one of its named configurations within the joint limits (they touch by
construction, as the "Default" pairs of MoveIt's setup assistant). :func:`update` writes the store,
:func:`compare` lists how a refit differs from it. The fit is deterministic, so a store written on one machine
is refit to the same numbers on another (NumPy's floating point permitting: compared to 1e-9).
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from symkin.geometry.mesh_fit import MeshFit, fit_builtin
from symkin.geometry.pairs import layout_of
from symkin.geometry.reference import distances
from symkin.model.builtin_geometry import COVERING, DEFAULT_EXCESS, STORE
from symkin.model.geometry import Geometry

__all__ = ["refit", "touching_pairs", "entry", "update", "compare"]


def touching_pairs(robot: Any, geometry: Geometry) -> list[tuple[str, str]]:
    """Link pairs (sorted) whose checked spheres overlap at ``robot``'s zero or named configurations
    (those within its joint limits: the Panda's zero configuration is outside them)."""
    model = robot.with_geometry(Geometry(geometry.shapes, (), geometry.source))
    layout = layout_of(model)
    shapes = layout.shapes
    out: set[tuple[str, str]] = set()
    for q in [np.zeros(robot.n), *robot.configs.values()]:
        if not robot.within_limits(q):
            continue
        d = distances(model, np.asarray(q, dtype=float))
        for k in np.flatnonzero(d[: len(layout.self_pairs)] < 0):
            i, j = layout.self_pairs[k]
            a, b = shapes[i].link, shapes[j].link
            out.add((a, b) if a <= b else (b, a))
    return sorted(out)


def refit(name: str, max_excess: float = DEFAULT_EXCESS, progress: bool = True) -> tuple[MeshFit, Geometry]:
    """The covering fit of built-in robot ``name`` and its Geometry with the touching pairs disabled."""
    from symkin.model.robots import load

    fit = fit_builtin(name, max_excess, progress=progress)
    robot = load(name)
    disabled = touching_pairs(robot, fit.geometry)
    return fit, Geometry(fit.geometry.shapes, tuple(disabled), fit.geometry.source)


def entry(fit: MeshFit, geometry: Geometry) -> dict[str, Any]:
    """The store's record of one robot."""
    return {
        "source": geometry.source,
        "disabled": [list(p) for p in geometry.disabled],
        "links": [
            {
                "link": r.link,
                "spheres": r.spheres,
                "pieces": r.pieces,
                "excess_bound": round(r.excess_bound, 6),
                "excess_max_sampled": round(r.excess_max, 6),
                "excess_mean_sampled": round(r.excess_mean, 6),
                "slack": round(r.slack, 9),
                "meshes": list(r.files),
            }
            for r in fit.rows
        ],
        "spheres": [[s.link, *s.center, s.radius] for s in geometry.shapes],
    }


def _dump(data: dict[str, Any]) -> str:
    return json.dumps(data, indent=1) + "\n"


def update(
    names: Sequence[str] = COVERING,
    max_excess: float = DEFAULT_EXCESS,
    path: Path = STORE,
    progress: bool = True,
) -> dict[str, Any]:
    """Refit ``names`` and write them into the store at ``path`` (other robots kept)."""
    data: dict[str, Any] = {"format": 1, "max_excess": max_excess, "robots": {}}
    if path.is_file():
        old = json.loads(path.read_text(encoding="utf-8"))
        if old.get("max_excess") == max_excess:
            data["robots"].update(old.get("robots", {}))
    data["note"] = (
        "covering sphere models of the built-in arms: written by `symkin geometry builtins --update`"
    )
    for name in names:
        fit, geometry = refit(name, max_excess, progress)
        data["robots"][name] = entry(fit, geometry)
    data["robots"] = dict(sorted(data["robots"].items()))
    path.write_text(_dump(data), encoding="utf-8")
    return data


def compare(names: Sequence[str] = COVERING, path: Path = STORE, progress: bool = True) -> list[str]:
    """How a refit of ``names`` differs from the store (empty when it matches to 1e-9 m)."""
    stored = json.loads(path.read_text(encoding="utf-8"))
    out: list[str] = []
    for name in names:
        old = stored["robots"].get(name)
        if old is None:
            out.append(f"{name}: not in the store")
            continue
        fit, geometry = refit(name, stored["max_excess"], progress)
        new = entry(fit, geometry)
        if len(new["spheres"]) != len(old["spheres"]):
            out.append(f"{name}: {len(new['spheres'])} spheres refit, {len(old['spheres'])} stored")
            continue
        A = np.array([row[1:] for row in new["spheres"]], dtype=float)
        B = np.array([row[1:] for row in old["spheres"]], dtype=float)
        links_differ = [a[0] for a, b in zip(new["spheres"], old["spheres"]) if a[0] != b[0]]
        if links_differ or np.abs(A - B).max() > 1e-9:
            out.append(f"{name}: spheres differ by up to {np.abs(A - B).max():.3g} m")
        if new["disabled"] != old["disabled"]:
            out.append(f"{name}: disabled pairs {new['disabled']} refit, {old['disabled']} stored")
    return out
