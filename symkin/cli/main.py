"""The ``symkin`` command: :func:`build_parser` assembles the commands (one module each, in the
order of ``symkin --help``) and :func:`main` runs one, turning a user mistake into one line and
exit status 2."""

from __future__ import annotations

import contextlib
import os
import sys
import traceback
from collections.abc import Sequence
from typing import Any

from symkin.cli import (
    bench,
    check,
    collide,
    dataset,
    derive,
    generate,
    geometry,
    ik,
    list_frames,
    plot,
    reach,
    servo,
    srdf,
)
from symkin.cli import compile as compile_command
from symkin.cli import list as list_command
from symkin.cli import view as view_command
from symkin.cli.checks import UserError
from symkin.cli.common import ROBOT_HELP, Formatter, Parser

__all__ = ["build_parser", "main"]

#: the commands in the order of ``symkin --help``
COMMANDS = (
    list_command, compile_command, list_frames, generate, check, derive,
    ik, servo, collide, geometry, srdf, plot, view_command, bench, reach, dataset,
)  # fmt: skip


def build_parser() -> Parser:
    from symkin.core.version import __version__

    p = Parser(
        prog="symkin",
        description="symkin: a symbolic, code-generating kinematics compiler for robot manipulators.",
        epilog="ROBOT is " + ROBOT_HELP + ". Run `symkin COMMAND --help` for the options of a command. "
        "Exit status: 0 success; 1 the answer no (collide: in collision; ik: not solved; servo: not arrived; "
        "check: a failure; generate --check: out of date); 2 any error (one line; SYMKIN_TRACEBACK=1 adds "
        "the traceback of an unexpected one); 130 interrupted.",
        formatter_class=Formatter,
    )
    p.add_argument("--version", action="version", version=f"symkin {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for command in COMMANDS:
        command.add_parser(sub)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Run one symkin command; returns the exit status.

    Exit status 0 or 1 is the command's answer (1: in collision, not solved, did not arrive, a check
    failed, files out of date). Every error is one line ``symkin: error: ...`` and status 2: user
    mistakes, bad files, and also an unexpected exception (a bug; ``SYMKIN_TRACEBACK=1`` prints its
    traceback) or running out of memory, so an error never reads as an answer. Ctrl-C: status 130.
    When the reader of the output goes away (``symkin list | head -1``), symkin stops quietly with
    status 141 (128 + SIGPIPE), as a program killed by SIGPIPE would; an output that cannot be
    written (a full disk, ``> /dev/full``) is an error: ``symkin: error: cannot write the output:
    ...``, status 2.
    The output is flushed here, inside the guard, not by the interpreter at exit, so such an error
    is one line and status 2, not a success with nothing written or "Exception ignored".
    """
    stdout = sys.stdout
    if stdout is not None:
        sys.stdout = _Output(stdout)
    try:
        code = _run(argv)
        if sys.stdout is not None:
            sys.stdout.flush()
        return code
    except BrokenPipeError:  # `symkin ... | head`: the reader left; stop quietly like other tools
        _silence_stdout()
        return EXIT_PIPE  # 128 + SIGPIPE, what a shell reports for a command ended by a closed pipe
    except _OutputError as exc:
        _silence_stdout()
        _say(f"symkin: error: cannot write the output: {exc.cause.strerror or exc.cause}")
        return EXIT_ERROR
    finally:
        if isinstance(sys.stdout, _Output):
            sys.stdout = stdout


#: exit statuses: 0 and 1 are answers (1: in collision, not solved, not arrived, a check failed,
#: files out of date); every error is 2, whatever raised it; then interrupted and closed pipe
EXIT_OK, EXIT_NO, EXIT_ERROR, EXIT_INTERRUPTED, EXIT_PIPE = 0, 1, 2, 130, 141


def _run(argv: Sequence[str] | None) -> int:
    from symkin.errors import SymkinError

    try:
        try:
            args = build_parser().parse_args(argv)
        except SystemExit as exc:  # --help, --version, or a one-line usage error (exit 2)
            return exc.code if isinstance(exc.code, int) else EXIT_ERROR
        code = args.func(args)
    except (BrokenPipeError, _OutputError):
        raise
    except (UserError, SymkinError, ValueError, OSError) as exc:
        _say(f"symkin: error: {_first_line(exc)}")
        return EXIT_ERROR
    except KeyboardInterrupt:
        _say("symkin: interrupted")
        return EXIT_INTERRUPTED
    except MemoryError:
        _say("symkin: error: out of memory (ask for less: a smaller size, batch or resolution)")
        return EXIT_ERROR
    except Exception as exc:  # noqa: BLE001 - a bug: one line and status 2, never an answer's status
        _say(f"symkin: error: unexpected {type(exc).__name__}: {_first_line(exc)} (a bug in symkin: "
             f"please report it; {_TRACEBACK}=1 prints the traceback)")  # fmt: skip
        if os.environ.get(_TRACEBACK):
            traceback.print_exc()
        return EXIT_ERROR
    return code if code in (EXIT_OK, EXIT_NO) else EXIT_ERROR if code else EXIT_OK


_TRACEBACK = "SYMKIN_TRACEBACK"


def _first_line(exc: BaseException) -> str:
    text = str(exc).strip()
    return text.splitlines()[0] if text else type(exc).__name__


class _OutputError(Exception):
    """The output (stdout) could not be written; ``cause`` is the OSError."""

    def __init__(self, cause: OSError) -> None:
        super().__init__(str(cause))
        self.cause = cause


class _Output:
    """``sys.stdout`` while a command runs: a failed write raises _OutputError, told apart from the
    command's own OSErrors (a file it cannot write); a closed pipe stays a BrokenPipeError."""

    def __init__(self, stream: Any) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        return self._guard(self._stream.write, text)

    def writelines(self, lines: Any) -> None:
        self._guard(self._stream.writelines, lines)

    def flush(self) -> None:
        self._guard(self._stream.flush)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)

    @staticmethod
    def _guard(fn: Any, *args: Any) -> Any:
        try:
            return fn(*args)
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise _OutputError(exc) from exc


def _say(line: str) -> None:
    """One line on stderr; a stderr that cannot be written either is ignored (nowhere to report)."""
    with contextlib.suppress(OSError, ValueError, AttributeError):
        sys.stderr.write(line + "\n")
        sys.stderr.flush()


def _silence_stdout() -> None:
    """Point stdout at /dev/null so the interpreter's final flush does not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # stdout without a file descriptor (captured, None)
        pass


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
