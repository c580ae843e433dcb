"""``symkin geometry``: covering sphere models from collision meshes.

- ``symkin geometry fit ROBOT --max-excess 0.02``: cover a built-in arm's real collision meshes
  (the ``meshes`` extra) or a URDF's ``<collision>`` meshes and boxes, every surface point inside
  a sphere of its link, each sphere at most the excess out of the mesh; prints the sphere count,
  the coverage of mesh points drawn independently of the fit and the excess per link (``--json``,
  ``-o FILE`` for the spheres).
- ``symkin geometry builtins [ROBOT ...]``: the stored models' figures; ``--update`` refits and
  writes them, ``--check`` refits and compares (exit 1 when they differ).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from symkin.cli import common
from symkin.cli.checks import UserError, at_least_1, output_file, positive_float
from symkin.core.names import robot_key

__all__ = ["add_parser", "run_fit", "run_builtins"]


def add_parser(sub: Any) -> None:
    s = common.add_command(sub, "geometry", "covering sphere models fitted to collision meshes")
    inner = s.add_subparsers(dest="geometry_command", metavar="ACTION", required=True)
    f = common.add_command(
        inner, "fit", "cover a robot's collision meshes with spheres; report count, coverage, excess"
    )
    f.add_argument(
        "robot",
        metavar="ROBOT",
        help="a built-in robot with meshes (panda, ur3, ur5, ur10, lbr_iiwa14) or a URDF file",
    )
    f.add_argument(
        "--max-excess", type=positive_float, default=0.02, metavar="M",
        help="how far (m) a sphere may reach out of the mesh: smaller is tighter and takes more spheres",
    )  # fmt: skip
    f.add_argument(
        "--package", action="append", default=[], metavar="NAME=DIR",
        help="URDF: resolve package://NAME/... in DIR (repeatable; default: a folder NAME above the URDF)",
    )  # fmt: skip
    f.add_argument(
        "--samples",
        type=at_least_1,
        default=20_000,
        metavar="N",
        help="mesh points drawn per mesh for the coverage check",
    )
    f.add_argument("--json", action="store_true", help="print JSON (figures and spheres)")
    f.add_argument("-o", "--output", metavar="FILE", help="write the spheres and figures as JSON to FILE")
    f.set_defaults(func=run_fit)
    b = common.add_command(
        inner, "builtins", "the stored covering models of the built-in arms: figures, refit, check"
    )
    b.add_argument("robots", nargs="*", metavar="ROBOT", help="built-in robots (default: every stored one)")
    mode = b.add_mutually_exclusive_group()
    mode.add_argument("--update", action="store_true", help="refit from the meshes and write the store")
    mode.add_argument(
        "--check", action="store_true", help="refit and compare with the store (exit 1 if they differ)"
    )
    b.set_defaults(func=run_builtins)


def _packages(specs: list[str]) -> dict[str, str]:
    out = {}
    for spec in specs:
        name, sep, folder = spec.partition("=")
        if not sep or not name or not folder:
            raise UserError(f"--package must be NAME=DIR, got {spec!r}")
        out[name] = folder
    return out


def _table(fit: Any, cov: dict[str, tuple[float, float, int]]) -> list[str]:
    lines = [
        f"{'link':<14} {'spheres':>7} {'coverage':>9} {'points':>7} {'excess bound':>12} {'max':>6} "
        f"{'mean':>6}  meshes",
    ]
    for r in fit.rows:
        frac, worst, n = cov[r.link]
        lines.append(
            f"{r.link:<14} {r.spheres:>7} {100 * frac:>8.3f}% {n:>7} {1000 * r.excess_bound:>10.1f}mm "
            f"{1000 * r.excess_max:>4.1f}mm {1000 * r.excess_mean:>4.1f}mm  {', '.join(r.files)}"
        )
    return lines


def _json(fit: Any, cov: dict[str, tuple[float, float, int]]) -> dict[str, Any]:
    return {
        "source": fit.geometry.source,
        "max_excess": fit.max_excess,
        "spheres": len(fit.geometry),
        "links": [
            {
                "link": r.link,
                "spheres": r.spheres,
                "coverage": cov[r.link][0],
                "points": cov[r.link][2],
                "worst_outside": cov[r.link][1],
                "excess_bound": r.excess_bound,
                "excess_max_sampled": r.excess_max,
                "excess_mean_sampled": r.excess_mean,
                "slack": r.slack,
                "meshes": list(r.files),
            }
            for r in fit.rows
        ],  # fmt: skip
        "skipped": list(fit.skipped),
        "sphere_list": [[s.link, *s.center, s.radius] for s in fit.geometry.shapes],
    }


def run_fit(args: argparse.Namespace) -> int:
    from symkin.geometry.builtin_meshes import MESH_SOURCES
    from symkin.geometry.mesh_fit import coverage, fit_builtin, fit_urdf

    output_file(args.output, "--output")
    key = robot_key(args.robot)
    if key in MESH_SOURCES:
        fit = fit_builtin(key, args.max_excess)
    elif Path(args.robot).suffix.lower() in (".urdf", ".xml"):
        if not Path(args.robot).is_file():
            raise UserError(f"no such URDF file: {args.robot}")
        fit = fit_urdf(args.robot, None, args.max_excess, _packages(args.package))
    else:
        raise UserError(
            f"{args.robot!r} is neither a built-in robot with collision meshes "
            f"({', '.join(sorted(MESH_SOURCES))}) nor a URDF file"
        )
    cov = coverage(fit.geometry, fit.parts, args.samples)
    data = _json(fit, cov)
    if args.output:
        Path(args.output).write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    if args.json:
        print(json.dumps(data, indent=1))
    else:
        total = sum(c[2] for c in cov.values())
        inside = sum(c[0] * c[2] for c in cov.values())
        print(f"{fit.geometry.source}: {len(fit.geometry)} spheres")
        print("\n".join(_table(fit, cov)))
        print(
            f"coverage of {total} mesh points drawn apart from the fit: {100 * inside / total:.3f}% "
            "(exact by construction: every piece of every surface lies whole in one sphere)"
        )
        for line in fit.skipped:
            print(f"skipped: {line}")
    return 0 if all(c[0] == 1.0 for c in cov.values()) else 1


def run_builtins(args: argparse.Namespace) -> int:
    from symkin.geometry import builtin_store
    from symkin.model.builtin_geometry import COVERING, stored_models

    names = [robot_key(r) for r in args.robots] or list(COVERING)
    unknown = [n for n in names if n not in COVERING]
    if unknown:
        raise UserError(f"no covering model for {unknown}; built-ins with one: {', '.join(COVERING)}")
    if args.update:
        builtin_store.update(names)
        stored_models.cache_clear()
        print(f"refit and stored: {', '.join(names)}")
    if args.check:
        differ = builtin_store.compare(names)
        for line in differ:
            print(line)
        print(
            "the store matches a refit"
            if not differ
            else f"{len(differ)} differences: run `symkin geometry builtins --update`"
        )
        return 1 if differ else 0
    data = stored_models()
    print(f"stored covering models (outward excess <= {data['max_excess']:g} m):")
    for name in names:
        entry = data["robots"][name]
        rows = entry["links"]
        bound = max(r["excess_bound"] for r in rows)
        mean = sum(r["excess_mean_sampled"] * r["spheres"] for r in rows) / len(entry["spheres"])
        print(
            f"{name}: {len(entry['spheres'])} spheres, max excess bound {1000 * bound:.1f} mm, "
            f"mean sampled {1000 * mean:.1f} mm, "
            f"disabled {entry['disabled']}"
        )
    return 0
