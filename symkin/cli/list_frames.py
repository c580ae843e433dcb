"""``symkin list-frames``: the link tree of a URDF (joints, links, leaves)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from symkin.cli.common import add_command

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    s = add_command(sub, "list-frames", "print the link tree of a URDF (joints, links, leaves)")
    s.add_argument("urdf", metavar="URDF", help="a URDF file")
    s.add_argument("--base-link", metavar="LINK", help="start at this link (default the root)")
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """``symkin list-frames path.urdf``: the tree with joint and link names, leaves marked."""
    from symkin.model.urdf import describe_urdf

    rows = describe_urdf(Path(args.urdf).expanduser(), base_link=args.base_link)
    if args.json:
        print(json.dumps([{"depth": d, "link": ln, "joint": j, "kind": k} for d, ln, j, k in rows], indent=2))
        return 0
    leaves = [ln for _, ln, _, k in rows if k.endswith("leaf")]
    movable = sum(1 for *_, k in rows if ", q" in k)
    print(f"{args.urdf}: {len(rows)} links, {movable} independent joints, {len(leaves)} leaf links")
    for depth, link, joint, kind in rows:
        via = f"  <- {joint} ({kind})" if joint else "  (base)"
        print(f"{'  ' * depth}{link}{via}")
    print(f"\nleaf links (the default frames): {','.join(leaves)}")
    return 0
