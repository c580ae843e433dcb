"""``symkin srdf``: a MoveIt SRDF of the link pairs the robot's collision model never needs to check:
adjacent links, and links every pair of whose shapes is proved apart over the joint limits
(:func:`symkin.geometry.srdf.disabled_pairs`, :func:`~symkin.geometry.srdf.write_srdf`)."""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from pathlib import Path
from typing import Any

from symkin.cli import common
from symkin.cli.checks import UserError, int_at_least

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    s = common.add_robot_command(
        sub,
        "srdf",
        "write a MoveIt SRDF disabling adjacent link pairs and pairs proved apart over the joint limits",
    )
    common.add_link_options(s, frames=True)
    s.add_argument("-o", "--output", metavar="FILE", help="file to write (default: print it)")
    s.add_argument(
        "--mesh-spheres",
        type=int_at_least(0),
        default=0,
        metavar="N",
        help="URDF: fit N spheres to each <mesh> (trimesh) and write pairs of those links too; their "
        "'Never' then holds for the fitted spheres, not proved for the meshes (default 0: links with a "
        "mesh are left out, MoveIt checks them)",
    )
    s.set_defaults(func=run)


def _model(args: argparse.Namespace) -> tuple[Any, str, dict[str, tuple[str, ...]] | None, str]:
    """(model with its geometry, the robot's name in the SRDF, the URDF links each model link
    carries (None: a built-in robot, named as symkin names it), a note on what was left out)."""
    file = common.urdf_of(args)
    model = common.chain_or_tree(args)
    if file is None:
        if args.mesh_spheres:
            raise UserError("--mesh-spheres applies to a URDF ROBOT")
        return model, model.name, None, ""
    from symkin.geometry.urdf import urdf_carriers, urdf_geometry
    from symkin.model.urdf import read_graph

    geometry, skipped = urdf_geometry(file, model, mesh_spheres=args.mesh_spheres)
    if not geometry.shapes:
        raise UserError(f"{file} has no <collision> shapes symkin reads (sphere, cylinder, capsule, box)")
    model = model.with_geometry(geometry)
    carriers = {k: tuple(x for x in v if x not in skipped) for k, v in urdf_carriers(file, model).items()}
    note = f"Left out (collision elements symkin did not read): {', '.join(skipped)}." if skipped else ""
    if args.mesh_spheres:
        note += f" Meshes fitted with {args.mesh_spheres} spheres each (not proved to cover them)."
    return model, read_graph(file).name, carriers, note


def run(args: argparse.Namespace) -> int:
    from symkin.geometry.srdf import disabled_pairs, write_srdf

    model, name, carriers, note = _model(args)
    pairs = disabled_pairs(model)
    text = write_srdf(name, pairs, carriers, note)
    reasons = Counter(r for _, _, r in pairs)
    links = len(model.geometry.links)
    summary = (
        f"{model.name}: {reasons['Adjacent']} adjacent and {reasons['Never']} never-touching link pairs "
        f"of {links * (links - 1) // 2} ({len(model.geometry.shapes)} shapes on {links} links)"
    )
    if args.output is None:
        print(text, end="")
        print(summary, file=sys.stderr)
        return 0
    out = Path(args.output).expanduser()
    try:
        out.write_text(text)
    except OSError as exc:
        raise UserError(f"cannot write {out}: {exc.strerror or exc}") from None
    print(f"wrote {out}: {summary}")
    return 0
