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
from symkin.model.frames import ChainTables, LinkFrames, frame_index, frame_jacobian

__all__ = ["casadi_call", "chain_functions", "tree_functions"]


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


def chain_functions(robot: Any, fns: dict[str, Any], methods: tuple[str, ...]) -> dict[str, Any]:
    """The methods of a chain's kinematics from its casadi functions, each with ``frame=`` (link
    frame k): ``fkine``, ``jacob0`` and ``jacobe`` from the link poses, the others from those
    (:class:`symkin.model.frames.LinkFrames`)."""
    n = robot.n
    shapes = {"T": (4, 4), "J": (6, n), "H": (n, 6, n), "links": (n, 4, 4)}
    functions = {name: casadi_call(fns[name], n, robot.name, shapes) for name in methods}
    link_poses = functions["link_poses"]
    chain = ChainTables.of(robot.ets)

    def framed(name: str) -> Any:
        plain = functions[name]

        def call(q: Any, frame: Any = None) -> Any:
            if frame is None:
                return plain(q)
            k = frame_index(frame, n, robot.name)
            L = link_poses(q)
            if name == "fkine":
                return L[..., k, :, :]
            Lb = L[None] if L.ndim == 3 else L
            J = frame_jacobian(Lb, k, chain, ee=name == "jacobe")
            return J[0] if L.ndim == 3 else J

        call.__name__, call.__doc__ = plain.__name__, plain.__doc__
        return call

    for name in ("fkine", "jacob0", "jacobe"):
        functions[name] = framed(name)
    links = LinkFrames(n, robot.name, functions["fkine"], functions["jacob0"], chain.order)

    def linked(name: str) -> Any:
        plain, of_link = functions[name], getattr(links, name)

        def call(q: Any, frame: Any = None) -> Any:
            return plain(q) if frame is None else of_link(q, frame)

        call.__name__, call.__doc__ = plain.__name__, plain.__doc__
        return call

    for name in ("fkine_jacob0", "jacob0_hessian0", "hessian0", "hessiane"):
        functions[name] = linked(name)
    return functions


def tree_functions(tree: Any, fns: dict[str, Any], methods: tuple[str, ...]) -> dict[str, Any]:
    """The methods of a tree's kinematics from its casadi functions (one per frame, ``<name>_<k>``,
    and the ``*_all`` ones over every frame), and ``jacob0_hessian0(q, frame)``."""
    n, F = tree.n, len(tree.frames)
    shapes = {"T": (4, 4), "J": (6, n), "H": (n, 6, n)}
    shapes_all = {"T": (F, 4, 4), "J": (F, 6, n)}

    def call(f: Any, q: Any, shape: dict[str, tuple[int, ...]]) -> Any:
        Q, single = as_batch(q, n, tree.name)
        outs = _mapped(f, Q, single, shape)
        return outs[0] if len(outs) == 1 else tuple(outs)

    def framed(base: str) -> Any:
        def method(q: Any, frame: Any = None) -> Any:
            return call(fns[f"{base}_{tree.frame_position(frame)}"], q, shapes)

        method.__name__ = base
        return method

    def every(name: str) -> Any:
        def method(q: Any) -> Any:
            return call(fns[name], q, shapes_all)

        method.__name__ = name
        return method

    return {
        name: every(name) if name.endswith("_all") else framed(name) for name in (*methods, "jacob0_hessian0")
    }
