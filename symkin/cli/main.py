"""The ``symkin`` command: :func:`build_parser` assembles the commands (one module each, in the
order of ``symkin --help``) and :func:`main` runs one, turning a user mistake into one line and
exit status 2."""

from __future__ import annotations

import sys
from collections.abc import Sequence

from symkin.cli import bench, check, dataset, derive, generate, ik, list_frames, plot, reach, servo
from symkin.cli import compile as compile_command
from symkin.cli import list as list_command
from symkin.cli.checks import UserError
from symkin.cli.common import ROBOT_HELP, Formatter, Parser

__all__ = ["build_parser", "main"]

#: the commands in the order of ``symkin --help``
COMMANDS = (
    list_command, compile_command, list_frames, generate, check, derive,
    ik, servo, plot, bench, reach, dataset,
)  # fmt: skip


def build_parser() -> Parser:
    from symkin.core.version import __version__

    p = Parser(
        prog="symkin",
        description="symkin: a symbolic, code-generating kinematics compiler for robot manipulators.",
        epilog="ROBOT is " + ROBOT_HELP + ". Run `symkin COMMAND --help` for the options of a command.",
        formatter_class=Formatter,
    )
    p.add_argument("--version", action="version", version=f"symkin {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for command in COMMANDS:
        command.add_parser(sub)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    from symkin.errors import SymkinError

    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, or a one-line usage error (exit 2)
        return exc.code if isinstance(exc.code, int) else 2
    try:
        return int(args.func(args) or 0)
    except BrokenPipeError:  # `symkin ... | head`: the reader left; stop quietly like other tools
        _silence_stdout()
        return 141  # 128 + SIGPIPE, what a shell reports for a command ended by a closed pipe
    except (UserError, SymkinError, ValueError, OSError) as exc:
        message = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        print(f"symkin: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("symkin: interrupted", file=sys.stderr)
        return 130


def _silence_stdout() -> None:
    """Point stdout at /dev/null so the interpreter's final flush does not fail again."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # stdout without a file descriptor (captured)
        pass


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
