"""The ``symkin`` command line: :mod:`symkin.cli.main` (the parser and the entry point), one module
per command (``symkin.cli.compile`` for ``symkin compile``, ``symkin.cli.list_frames`` for ``symkin
list-frames``, ...; each with ``add_parser(subparsers)`` and ``run(args) -> int``),
:mod:`symkin.cli.common` (the ROBOT argument and its resolution into a chain or a tree, the parser
classes, output helpers) and :mod:`symkin.cli.checks` (argument checks made before any long work).

Every command that takes a ROBOT accepts a built-in name (``panda``), an ETS string in quotes
(``"Rz(q) tx(1) Rz(q) tx(1)"``), a DH table file, a URDF file or ``path.urdf:FRAME`` for the
chain to one link (also ``--base-link/--end-link``), and ``--tool``/``--base`` to add a constant
transform after the end effector / before the first link. ``compile``, ``check`` and ``derive``
take a whole tree with ``--frames a,b,c`` (a branching URDF without a frame is a tree of its
leaves). Exit status 0 and 1 are answers (1: in collision, not solved, not arrived, a failed
check, files out of date); every error is one line ``symkin: error: ...`` and status 2 (user
mistakes, checked before any long work starts where they can be; bad input files; running out
of memory; an unexpected exception, whose traceback ``SYMKIN_TRACEBACK=1`` prints). When the
reader of the output goes away (``symkin list | head -1``), symkin stops quietly with status 141
(128 + SIGPIPE), as a program killed by SIGPIPE would; an output that cannot be written (a full
disk, ``> /dev/full``) is an error: ``symkin: error: cannot write the output: ...``, status 2.
Progress bars appear only when stderr is a terminal (:mod:`symkin.core.progress`).
"""

from symkin.cli.main import build_parser, main

__all__ = ["build_parser", "main"]
