"""``symkin generate``: the checked-in code of the built-in robots under ``generated/``."""

from __future__ import annotations

import argparse
from typing import Any

from symkin.cli.checks import output_dir
from symkin.cli.common import add_command

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    s = add_command(sub, "generate", "regenerate the checked-in code of the built-in robots under generated/")
    s.add_argument("-o", "--output", default="generated", metavar="DIR", help="folder to write")
    s.add_argument("--check", action="store_true", help="only report out-of-date files (exit 1 if any)")
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symkin.compiler.snapshot import compare_or_update

    output_dir(args.output)
    differ = compare_or_update(args.output, update=not args.check, progress=True)
    if args.check:
        if differ:
            print(f"{len(differ)} generated files are out of date in {args.output}/ (run `symkin generate`):")
            for d in differ:
                print(f"  {d}")
            return 1
        print(f"{args.output}/ is up to date")
        return 0
    print(f"updated {len(differ)} files in {args.output}/" if differ else f"{args.output}/ was up to date")
    return 0
