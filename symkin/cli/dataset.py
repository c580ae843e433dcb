"""``symkin dataset``: a (q, pose) dataset for learning (Zarr, on Dask; the ``scale`` extra)."""

from __future__ import annotations

import argparse
import json
from typing import Any

from symkin.cli import common
from symkin.cli.checks import at_least_1

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    s = common.add_robot_command(sub, "dataset", "a (q, pose) dataset for learning (Zarr, on Dask)")
    s.add_argument("-n", type=at_least_1, required=True, help="number of samples (more than stored appends)")
    s.add_argument("-o", "--output", required=True, metavar="STORE", help="the Zarr store, e.g. data.zarr")
    s.add_argument("--chunk", type=at_least_1, default=65536, help="samples per block (default 65536)")
    common.add_scale_options(s)
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symkin.workspace import samples
    from symkin.workspace.run import require_scale

    require_scale(common.scheduler(args))
    robot = common.single_chain(args)
    ds = samples(
        robot, args.n, output=args.output, seed=args.seed, chunk=args.chunk, backend=args.backend,
        scheduler=common.scheduler(args), workers=args.workers, overwrite=args.overwrite,
    )  # fmt: skip
    st = ds.stats or {}
    summary = {"output": args.output, "samples": len(ds), "blocks": int(st.get("blocks", 0)),
               "computed": int(st.get("computed", 0)), "skipped": int(st.get("skipped", 0)),
               "damaged": int(st.get("damaged", 0)), "seconds": float(st.get("seconds", 0.0))}  # fmt: skip
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(f"{robot.name}: {len(ds)} (q, pose) samples -> {args.output} (arrays q {tuple(ds.q.shape)}, "
              f"pose {tuple(ds.pose.shape)})")  # fmt: skip
        computed = f"{summary['computed']} computed{common.damaged(summary)}"
        print(f"blocks: {computed}, {summary['skipped']} already written, in {summary['seconds']:.1f} s")
    return 0
