"""Emit a tree kernel: the functions of :func:`symkin.symbolic.functions.tree_functions` as C
(a ``.c``/``.h`` pair and a CPython extension), a NumPy module or a CasADi module.

One generated function per entry point, each the straight-line code its outputs need: the
``*_all`` functions walk the whole tree once, the per-frame functions only the path to their
frame. Frame names enter generated code only as escaped string literals (C, or ``ascii`` in Python)
and as :func:`~symkin.core.names.comment_safe` text in comments.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from symkin.core.names import c_string, comment_safe, identifier
from symkin.emit.templates import render
from symkin.symbolic.program import PER_FRAME

__all__ = ["render_tree", "tree_prefix", "TreeHeader", "FRAMED_DOCS"]

FRAMED_DOCS = {
    "fkine": "Pose of the frame in the base frame, (4, 4) or (N, 4, 4).",
    "jacob0": "Base-frame Jacobian of the frame, (6, n) or (N, 6, n), rows (v, omega); 0 off its path.",
    "jacobe": "Jacobian of the frame in that frame, (6, n) or (N, 6, n), rows (v, omega) (eq 16).",
    "fkine_jacob0": "Pose and base-frame Jacobian of the frame together.",
}
STRATEGY = (
    "straight-line program over the tree, walked depth first: the parts frames share are computed "
    "once (named link frames and Jacobian columns)"
)


def tree_prefix(tree: Any) -> str:
    """The C symbol prefix of a tree kernel: ``symkin_<identifier>_tree``."""
    return f"symkin_{identifier(tree.name)}_tree"


@dataclass(frozen=True)
class TreeHeader:
    """What every generated tree file says about itself."""

    robot: str
    name_literal: str
    frames: str
    version: str
    command: str
    counts: str
    strategy: str

    @classmethod
    def of(cls, tree: Any, functions: list, command: str, literal: str) -> TreeHeader:
        from symkin.core.version import __version__
        from symkin.symbolic.program import total_ops

        return cls(
            robot=identifier(tree.name),
            name_literal=literal,
            frames=comment_safe(", ".join(tree.frames), limit=2000),
            version=__version__,
            command=comment_safe(command),
            counts=f"{total_ops(functions)} over {len(functions)} functions",
            strategy=STRATEGY,
        )


def _frame_fn_base(name: str) -> str | None:
    """``"fkine_jacob0"`` of ``"fkine_jacob0_3"`` (a per-frame function's base), else None."""
    base, _, k = name.rpartition("_")
    return base if k.isdigit() and base in PER_FRAME else None


def _frame_fns(tree: Any) -> dict[str, list[str]]:
    return {base: [f"{base}_{k}" for k in range(len(tree.frames))] for base in PER_FRAME}


def _paths(tree: Any) -> list[list[int] | None]:
    """Per frame: the joints on its path, base first, or None when a mimic joint is on it."""
    plain = dict(plain_paths(tree))
    return [plain.get(k) for k in range(len(tree.frames))]


def plain_paths(tree: Any) -> list[tuple[int, list[int]]]:
    """(frame index, joint indices on its path, base first) of every frame whose path has no mimic
    joint: its Jacobian columns are the joints' own, so H follows from J (the C controllers' case)."""
    out = []
    for k, frame in enumerate(tree.frames):
        slots = [tree.slots[i] for i in tree.path_slots(frame)]
        if not any(s.is_mimic for s in slots):
            out.append((k, [s.joint for s in slots]))
    return out


def render_tree(
    tree: Any,
    functions: list,
    backend: str,
    command: str,
    prefix: str | None = None,
    precision: str = "double",
    libm: bool = False,
) -> dict[str, str]:
    """The generated files of ``tree`` for ``backend`` (filename -> text). C only, as for a chain
    (:func:`symkin.emit.c.backend.render_c`): ``prefix`` of every exported symbol and file name
    (default ``symkin_<tree>_tree``), ``precision="float"`` for single-precision code without the
    Python module, ``libm`` for the C library's sin and cos."""
    from symkin.emit.lowering import lower

    n, F = tree.n, len(tree.frames)
    if backend == "c":
        from symkin.emit.c.backend import c_variant, four_lane_bodies, module_name

        printer, variant = c_variant(tree_prefix(tree), prefix, precision, libm)
        printed = [lower(f, printer) for f in functions]
        prefix = variant["prefix"]
        outs = {f.name: f.outs for f in printed}
        # batch entry points with four-lane bodies: the *_all functions and each frame's fkine,
        # jacob0, jacobe and fkine_jacob0 (the per-frame batches of maps, datasets and IK)
        laned = [f for f in printed if f.name.endswith("_all") or _frame_fn_base(f.name) is not None]
        context = {
            **variant,
            "n": n,
            "F": F,
            "functions": printed,
            "header": TreeHeader.of(tree, functions, command, c_string(tree.name)),
            "frame_literals": [c_string(f) for f in tree.frames],
            "frame_fns": {base: [f"{name}_" for name in names] for base, names in _frame_fns(tree).items()},
            "framed": [(base, outs[f"{base}_0"]) for base in PER_FRAME],
            "framed_docs": FRAMED_DOCS,
            "plain_paths": plain_paths(tree),
            "lanes": four_lane_bodies(laned if precision == "double" else []),
        }
        files = {
            f"{prefix}.h": render("c/tree.h.j2", **context),
            f"{prefix}.c": render("c/tree.c.j2", **context),
        }
        if precision == "float":
            return files
        ext = render("c/tree_module.c.j2", module=module_name(files), **context)
        return {**files, f"{prefix}_pymodule.c": ext}
    if backend == "numpy":
        from symkin.emit.printers import MathModulePrinter, NumPyPrinter

        printed_py = []
        for f in functions:
            vec, one = lower(f, NumPyPrinter()), lower(f, MathModulePrinter())
            printed_py.append({**vec.__dict__, "scalar_lines": one.lines, "scalar_outs": one.outs})
        module = f"symkin_{identifier(tree.name)}_tree"
        text = render(
            "numpy/tree.py.j2",
            **_python_context(tree, functions, command, module, printed_py),
            frame_fns=_frame_fns(tree),
            framed_docs=FRAMED_DOCS,
            paths=_paths(tree),
        )
        return {f"{module}.py": text}
    from symkin.emit.casadi.backend import casadi_function

    printed_ca = [casadi_function(f) for f in functions]
    module = f"symkin_{identifier(tree.name)}_tree_casadi"
    text = render("casadi/tree.py.j2", **_python_context(tree, functions, command, module, printed_ca))
    return {f"{module}.py": text}


def _python_context(tree: Any, functions: list, command: str, module: str, printed: list) -> dict[str, Any]:
    """The template variables the NumPy and CasADi trees share (``printed``: the functions as
    each template takes them)."""
    return {
        "module": module,
        "n": tree.n,
        "F": len(tree.frames),
        "functions": printed,
        "header": TreeHeader.of(tree, functions, command, ascii(tree.name)),
        "name_literal": ascii(tree.name),
        "frame_literals": [ascii(f) for f in tree.frames],
    }
