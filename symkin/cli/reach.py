"""``symkin reach``: the reachability and manipulability map of the workspace (Zarr, on Dask; the
``scale`` extra)."""

from __future__ import annotations

import argparse
import json
from typing import Any

import numpy as np

from symkin.cli import common
from symkin.cli.checks import UserError, at_least_1, positive_float

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    s = common.add_robot_command(
        sub, "reach", "reachability and manipulability map of the workspace (Zarr, on Dask)"
    )
    s.add_argument(
        "--resolution", type=positive_float, default=0.05, help="voxel edge in metres (default 0.05)"
    )
    s.add_argument("--orientations", type=at_least_1, default=50, help="orientations per voxel (default 50)")
    s.add_argument("-o", "--output", required=True, metavar="STORE", help="the Zarr store, e.g. map.zarr")
    s.add_argument("--chunk", type=at_least_1, help="voxels per block edge (default: 16..4, >= 64 blocks)")
    s.add_argument("--solutions", action="store_true", help="also store one solution per orientation")
    s.add_argument("--axes", default="all", help="manipulability rows: all, trans, rot or indices '0 1 5'")
    s.add_argument("--bounds", metavar="'XMIN XMAX YMIN YMAX ZMIN ZMAX'", help="only voxels in this box (m)")
    s.add_argument(
        "--radius", type=positive_float, help="radius of the mapped ball (default: sum of link lengths)"
    )
    s.add_argument("--slimit", type=at_least_1, default=10, help="IK searches per target (default 10)")
    s.add_argument("--ilimit", type=at_least_1, default=30, help="IK iterations per search (default 30)")
    s.add_argument("--plot", metavar="PNG", help="write a slice of the map (reachability, manipulability)")
    s.add_argument("--slice-axis", choices=("x", "y", "z"), default="z", help="plot: axis of the slice")
    s.add_argument("--slice-at", type=float, help="plot: coordinate of the slice (default: the centre)")
    common.add_collision_options(
        s, "count only collision-free solutions (self-collisions, and the obstacles given)"
    )
    common.add_scale_options(s)
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symkin.workspace import reachability
    from symkin.workspace.run import require_scale

    require_scale(common.scheduler(args))  # before compiling: say which extra is missing at once
    robot, _, collision = common.collision_model(args)
    bounds = None if args.bounds is None else common.floats(args.bounds, "--bounds", 6).reshape(3, 2)
    axes: Any = args.axes if args.axes in ("all", "trans", "rot") else _rows(args.axes)
    ik_options = {"slimit": args.slimit, "ilimit": args.ilimit}
    rmap = reachability(
        robot, args.resolution, args.orientations, output=args.output, seed=args.seed,
        solutions=args.solutions, axes=axes, bounds=bounds, radius=args.radius, chunk=args.chunk,
        backend=args.backend, ik_options=ik_options, scheduler=common.scheduler(args), workers=args.workers,
        overwrite=args.overwrite, collision=collision,
    )  # fmt: skip
    inside = rmap.reach > 0
    st = rmap.stats or {}
    summary = {
        "output": args.output,
        "shape": list(rmap.reach.shape),
        "orientations": len(rmap.rotations),
        "reachable_voxels": int(inside.sum()),
        "mean_reach_of_reachable": float(rmap.reach[inside].mean()) if inside.any() else 0.0,
        "max_manipulability": float(np.nanmax(rmap.manipulability)) if inside.any() else None,
        "blocks": int(st.get("blocks", 0)), "computed": int(st.get("computed", 0)),
        "skipped": int(st.get("skipped", 0)), "damaged": int(st.get("damaged", 0)),
        "seconds": float(st.get("seconds", 0.0)),
        "problems": int(st.get("problems", 0)),
    }  # fmt: skip
    if args.plot:
        rmap.plot(args.plot, axis=args.slice_axis, at=args.slice_at)
        summary["plot"] = args.plot
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    x, y, z = rmap.reach.shape
    K = len(rmap.rotations)
    print(f"{robot.name}: {x}x{y}x{z} voxels of {rmap.resolution:g} m, {K} orientations -> {args.output}")
    done, skipped = summary["computed"], summary["skipped"]
    print(
        f"blocks: {done} computed{common.damaged(summary)}, {skipped} already written, of {summary['blocks']}"
    )
    if summary["computed"]:
        rate = summary["problems"] / max(summary["seconds"], 1e-9)
        print(f"{summary['problems']} IK problems in {summary['seconds']:.1f} s ({rate:,.0f} per second)")
    best = summary["max_manipulability"] or 0.0
    print(
        f"reachable voxels: {summary['reachable_voxels']} (mean reachability index "
        f"{summary['mean_reach_of_reachable']:.3f}); best manipulability {best:.4g}"
    )
    if args.plot:
        print(f"plot written to {args.plot}")
    return 0


def _rows(text: str) -> list[int]:
    try:
        return [int(x) for x in text.replace(",", " ").split()]
    except ValueError:
        raise UserError(
            f"--axes must be all, trans, rot or row indices 0-5 such as '0 1 5', not {text!r}"
        ) from None
