"""The JAX and PyTorch backends: generated Python modules of ``jax.numpy`` or ``torch`` code.

The same lowered functions as the NumPy backend (:func:`symkin.emit.lowering.lower`), printed by
:class:`~symkin.emit.printers.JaxPrinter` or :class:`~symkin.emit.printers.TorchPrinter` into one
template per backend (``jax/module.py.j2``, ``torch/module.py.j2``; the functions' bodies are
shared, ``python/_tensor_body.py.j2``). Every function takes q of shape (..., n), any batch shape,
batch first, and returns arrays of shape (..., *out): each joint column ``q[..., j]`` goes through
the straight-line code and each output is stacked from its entries (JAX arrays are immutable), so
``jax.jit``, ``jax.vmap``, ``jax.grad``, ``torch.compile`` and ``torch.func`` see plain array code.
Numbers are Python floats, so float32 and float64 inputs keep their dtype (and torch its device).

XLA on the CPU fuses each output entry with every intermediate it depends on, recomputing what the
entries share (the CSE undone: the Panda's FK evaluated its 7 sines 148 times, 4x slower than
PyTorch's eager code at batch 1024). The JAX module therefore materialises the intermediates level
by level (an intermediate's level is one more than the highest of those it uses) through
``_keep``, an identity matrix product XLA does not fuse, in groups of at most :data:`KEEP_GROUP`;
on other platforms ``_keep`` returns its arguments.
"""

from __future__ import annotations

from typing import Any

import sympy as sp

from symkin.emit.templates import python_module
from symkin.errors import CompileError

__all__ = ["render_tensor", "TENSOR_BACKENDS", "KEEP_GROUP"]

# backend -> (template, module suffix)
TENSOR_BACKENDS = {"jax": ("jax/module.py.j2", "_jax"), "torch": ("torch/module.py.j2", "_torch")}
# what the module docstring says of each library
_NOTES = {
    "jax": {
        "library": "JAX",
        "array_kind": "JAX arrays",
        "dtype_note": "float64 needs ``jax.config.update('jax_enable_x64', True)``",
        "device_note": "",
        "transforms": "``jax.jit``, ``jax.vmap``, ``jax.grad`` and ``jax.jacfwd``",
    },
    "torch": {
        "library": "PyTorch",
        "array_kind": "tensors",
        "dtype_note": "a torch.Tensor",
        "device_note": " on q's device",
        "transforms": "autograd, ``torch.compile`` and ``torch.func`` (``vmap``, ``jacrev``)",
    },
}
# the largest group of intermediates one _keep materialises (its product costs KEEP_GROUP
# multiply-adds per value)
KEEP_GROUP = 4


def _levels(intermediates: list[tuple[sp.Symbol, sp.Expr]]) -> list[int]:
    """Per intermediate, 1 + the highest level of the intermediates it uses (joints: level 0)."""
    level: dict[sp.Symbol, int] = {}
    out = []
    for s, e in intermediates:
        lv = 1 + max((level[x] for x in e.free_symbols if x in level), default=0)
        level[s] = lv
        out.append(lv)
    return out


def _groups(lines: tuple[tuple[str, str], ...], levels: list[int], keep: bool) -> list[dict[str, Any]]:
    """The lines in groups: by level, each followed by ``_keep`` of its names in chunks of at most
    :data:`KEEP_GROUP` (``keep``), or one group without (PyTorch)."""
    if not keep or not lines:
        return [{"lines": list(lines), "keep": []}]
    groups = []
    for lv in sorted(set(levels)):
        group = [line for line, x in zip(lines, levels) if x == lv]
        names = [name for name, _ in group]
        chunks = [names[i : i + KEEP_GROUP] for i in range(0, len(names), KEEP_GROUP)]
        groups.append({"lines": group, "keep": [c for c in chunks if len(c) > 1]})
    return groups


def _entries(o: Any, exprs: tuple[sp.Expr, ...]) -> list[str]:
    """The printed entries of output ``o``, constants as ``_z`` (the batch's zeros) plus the number."""
    printed = dict(o.values)
    out = []
    for i, e in enumerate(exprs):
        if e.is_Number:
            out.append("_z" if e == 0 else f"(_z + {printed[i]})")
        else:
            out.append(printed[i])
    return out


def tensor_function(f: Any, printer: Any, keep: bool) -> dict[str, Any]:
    """Function ``f`` lowered for the tensor templates: its joints, lines (in groups), outputs and
    scratch arrays with their entries, Hessian loops and delegate."""
    from symkin.emit.lowering import lower

    p = lower(f, printer)
    code = f.code

    def table(outs: tuple) -> list[dict[str, Any]]:
        return [
            {"name": o.name, "shape": o.shape, "entries": _entries(o, code.outputs[o.name][1])}
            for o in outs
            if o.values
        ]

    return {
        **p.__dict__,
        "groups": _groups(p.lines, _levels(list(code.intermediates)) if p.lines else [], keep),
        "outs": table(p.outs),
        "scratch": table(p.scratch),
        "out_names": [o.name for o in p.outs],
    }


def render_tensor(kernel: Any, backend: str) -> dict[str, str]:
    """The generated module ``symkin_<code_name>_<backend>.py`` of ``kernel`` (backend "jax" or "torch")."""
    from symkin.emit.printers import JaxPrinter, TorchPrinter

    template, suffix = TENSOR_BACKENDS[backend]
    printer = JaxPrinter() if backend == "jax" else TorchPrinter()
    printed = [tensor_function(f, printer, keep=backend == "jax") for f in kernel.functions]
    kinds = list(dict.fromkeys(f["kind"] for f in printed))
    for kind in kinds:
        frames = [f["frame"] for f in printed if f["kind"] == kind]
        if frames != [None] and frames != list(range(kernel.F)):  # pragma: no cover - a kernel's invariant
            raise CompileError(f"{kind}: functions for frames {frames}, not one for each of {kernel.F}")
    return python_module(
        template,
        kernel,
        printed,
        suffix,
        joint_names=[ascii(j.name) for j in kernel.joints],
        revolute=[j.revolute for j in kernel.joints],
        kinds=kinds,
        **_NOTES[backend],
    )
