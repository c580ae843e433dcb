"""``symkin list``: the built-in robots."""

from __future__ import annotations

import argparse
import json
from typing import Any

from symkin.cli.common import add_command

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    s = add_command(sub, "list", "list the built-in robots")
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symkin.model.robots import list_robots, load

    rows = []
    for name in list_robots():
        r = load(name)
        rows.append((name, r.n, r.ets.structure, r.source.split(";")[0][:70]))
    if args.json:
        print(json.dumps([{"name": a, "n": b, "joints": c, "source": d} for a, b, c, d in rows], indent=2))
        return 0
    print(f"{'robot':10} {'n':>2}  {'joints':8} source")
    for name, n, s, src in rows:
        print(f"{name:10} {n:>2}  {s:8} {src}")
    return 0
