"""Kinematics methods that call ``casadi.Function`` objects of the CasADi backend: one
configuration through a ``Function.buffer()`` bound once to arrays where the function allows it,
a batch through ``Function.map``; every call takes and refuses q as the other backends do."""

from __future__ import annotations

import math
import threading
from collections.abc import Callable
from typing import Any

import numpy as np

from symkin.core.arrays import MAX_JOINT_VALUE, as_batch
from symkin.core.names import function_name
from symkin.emit.kernel import FRAMED, LINKED
from symkin.model.frames import ChainTables, LinkFrames, frame_jacobian, resolve_frame
from symkin.model.tree import as_tree

__all__ = ["casadi_call", "casadi_methods"]


def _mapped(f: Any, Q: np.ndarray, single: bool, shapes: dict[str, tuple[int, ...]]) -> list[np.ndarray]:
    """``f`` at the configurations ``Q`` (N, n), each output reshaped to (N, *shape) (or shape)."""
    names = f.name_out()
    if Q.shape[0] == 0:  # casadi cannot map over 0 items
        return [np.zeros((0, *shapes[k])) for k in names]
    if single:
        res = f(Q[0])
        res = res if isinstance(res, (list, tuple)) else [res]
        return [np.asarray(r).reshape(shapes[k]) for k, r in zip(names, res)]
    res = f.map(Q.shape[0])(Q.T)
    res = res if isinstance(res, (list, tuple)) else [res]
    outs = []
    for k, r in zip(names, res):
        a = np.asarray(r)  # (rows, cols*N), column blocks per configuration
        rows, cols = a.shape[0], a.shape[1] // Q.shape[0]
        outs.append(a.reshape(rows, Q.shape[0], cols).transpose(1, 0, 2).reshape((Q.shape[0], *shapes[k])))
    return outs


def casadi_call(f: Any, n: int, name: str, shapes: dict[str, tuple[int, ...]]) -> Callable[[Any], Any]:
    """A method calling the casadi.Function ``f`` of q (n,) or (N, n): the outputs named in
    ``shapes``, with a leading (N,) axis for a batch. One configuration goes through a buffer bound
    once to arrays (no DM conversion; a lock keeps it thread-safe) when ``f`` is dense."""
    names = f.name_out()
    dense = f.sparsity_in(0).is_dense() and all(f.sparsity_out(i).is_dense() for i in range(f.n_out()))
    evaluate = None
    if dense and hasattr(f, "buffer"):
        qbuf = np.zeros(n)
        outs = [np.zeros(f.nnz_out(i)) for i in range(f.n_out())]
        buf, evaluate = f.buffer()
        buf.set_arg(0, memoryview(qbuf))
        for i, out in enumerate(outs):
            buf.set_res(i, memoryview(out))
        sizes = [f.size_out(i) for i in range(f.n_out())]  # (rows, cols); nonzeros column-major
        lock = threading.Lock()
    f64 = np.dtype(float)

    def call(q: Any) -> Any:
        fast = evaluate is not None and type(q) is np.ndarray and q.dtype is f64 and q.shape == (n,)
        if fast and math.isfinite(sum(ql := q.tolist())) and max(map(abs, ql)) <= MAX_JOINT_VALUE:
            with lock:
                np.copyto(qbuf, q)
                evaluate()
                ok = buf.ret() == 0
                # copies: the buffers are reused by the next call (and by other threads)
                res = [
                    o.reshape(c, r).T.copy().reshape(shapes[k]) for o, (r, c), k in zip(outs, sizes, names)
                ]
            if ok:
                return res[0] if len(res) == 1 else tuple(res)
        Q, single = as_batch(q, n, name)  # raises the reference's error for invalid q
        out = _mapped(f, Q, single, shapes)
        return out[0] if len(out) == 1 else tuple(out)

    call.__name__ = f.name()
    call.__doc__ = f"{f.name()} through casadi.Function (see Kinematics.functions)."
    return call


def casadi_methods(model: Any, fns: dict[str, Any]) -> dict[str, Any]:
    """The methods of ``model``'s kinematics from its casadi functions, each kind of
    :data:`~symkin.emit.kernel.FRAMED` with ``frame=`` (a frame name, None for the only one; a
    chain's link frame k: ``fkine``, ``jacob0`` and ``jacobe`` from the link poses, the others
    through :class:`symkin.model.frames.LinkFrames`), ``link_poses`` and the ``*_all`` functions."""
    tree = as_tree(model)
    n, frames, name = tree.n, tree.frames, tree.name
    F, links = len(frames), n if "link_poses" in fns else 0
    shapes = {"T": (4, 4), "J": (6, n), "H": (n, 6, n), "links": (n, 4, 4)}
    every = {"T": (F, 4, 4), "J": (F, 6, n)}
    calls = {key: casadi_call(f, n, name, every if key.endswith("_all") else shapes) for key, f in fns.items()
             if not key.startswith("manipulability")}  # fmt: skip
    methods = {key: f for key, f in calls.items() if key == "link_poses" or key.endswith("_all")}

    def framed(kind: str) -> Any:
        plain = calls.get(kind)

        def call(q: Any, frame: Any = None) -> Any:
            if frame is None and plain is not None:
                return plain(q)
            k, link = resolve_frame(frame, frames, links, name)
            if link < 0:
                return calls[function_name(kind, k, F)](q)
            if kind not in LINKED:
                return getattr(link_frames, kind)(q, link)
            L = calls["link_poses"](q)
            if kind == "fkine":
                return L[..., link, :, :]
            Lb = L[None] if L.ndim == 3 else L
            J = frame_jacobian(Lb, link, tables, ee=kind == "jacobe")
            return J[0] if L.ndim == 3 else J

        call.__name__, call.__doc__ = kind, (plain or calls[function_name(kind, 0, F)]).__doc__
        return call

    methods.update({kind: framed(kind) for kind in FRAMED})
    tables = ChainTables.of(tree.chain().ets) if links else None
    link_frames = LinkFrames(n, name, methods["fkine"], methods["jacob0"], tables.order if tables else ())
    return methods
