"""Collision queries at run time: the compiled FKCC kernel (C, loaded with ctypes) and the functions
compiled kinematics call (``kin.in_collision``, ``distances``, ``distance_jacobians``,
``collision_points``, ``motion_valid``).

The C kernel is generated per model and geometry (:mod:`symkin.emit.collision`), compiled once
into the cache (its key: the C source, which holds every constant of the model and geometry) and
kept loaded for the 16 models used last. Without the C backend the same queries run in the
generated NumPy module (:func:`symkin.emit.collision.render_collision_numpy`: straight-line link
poses vectorised over configurations, the pair math of :mod:`symkin.geometry.reference`); both give
the same answers (tested).
"""

from __future__ import annotations

import ctypes
from collections import OrderedDict
from typing import Any, NamedTuple

import numpy as np

from symkin.core.arrays import as_batch, finite_number
from symkin.core.names import identifier
from symkin.core.pose import as_poses
from symkin.core.sizes import count
from symkin.errors import ParameterError
from symkin.geometry.pairs import Layout, as_environment, layout_of
from symkin.model.geometry import Environment
from symkin.runtime.memo import lru

__all__ = [
    "Collision",
    "CollisionKernel",
    "collision_kernel",
    "collision_ik",
    "collision_solver",
    "collision_of",
    "collision_module",
    "motion_valid",
    "env_args",
    "Packed",
]

_KERNELS: OrderedDict[str, CollisionKernel] = OrderedDict()  # by the model's and the geometry's keys
_KEEP = 16
_P = ctypes.c_void_p  # arrays are passed by address (``ndarray.ctypes.data``)
_NO_ENV = Environment()


class Packed(NamedTuple):
    """An environment as the kernel takes it: the packed arrays (spheres, capsules, boxes; see
    :meth:`Environment.arrays`), the six obstacle arguments (address, count of each), the same as
    an int64 array and that array's address (the one-call path)."""

    arrays: tuple[np.ndarray, ...]
    args: list[int]
    table: np.ndarray
    address: int


def env_args(env: Environment) -> Packed:
    """The packed obstacles of ``env`` (:class:`Packed`), memoised on the Environment object
    (frozen: they never change)."""
    cached = env.__dict__.get("_packed")
    if cached is None:
        a = env.arrays()
        arrays = tuple(np.ascontiguousarray(a[k]) for k in ("spheres", "capsules", "boxes"))
        for x in arrays:
            x.setflags(write=False)
        args = [v for x in arrays for v in (x.ctypes.data, len(x))]
        packed = np.array(args, dtype=np.int64)
        cached = Packed(arrays, args, packed, packed.ctypes.data)
        object.__setattr__(env, "_packed", cached)
    return cached


class CollisionKernel:
    """The compiled FKCC kernel of one model's geometry (see :mod:`symkin.emit.collision`)."""

    def __init__(self, layout: Layout) -> None:
        from symkin.emit.c.build import compile_library, load_library
        from symkin.emit.collision import render_collision

        self.layout = layout
        self.n = layout.tree.n
        self.files = render_collision(layout)
        self.path = compile_library(self.files, f"skcoll_{identifier(layout.tree.name)}")
        lib = load_library(self.path)
        i, L = ctypes.c_int, ctypes.c_long
        lib.skcoll_points.argtypes = [_P, _P]
        lib.skcoll_in_collision.argtypes = [_P, _P, i, _P, i, _P, i]
        lib.skcoll_in_collision.restype = ctypes.c_int
        lib.skcoll_in_collision_packed.argtypes = [_P, _P]
        lib.skcoll_in_collision_packed.restype = ctypes.c_int
        self._one = lib.skcoll_in_collision_packed
        lib.skcoll_in_collision_batch.argtypes = [_P, L, _P, i, _P, i, _P, i, _P]
        lib.skcoll_distances.argtypes = [_P, _P, i, _P, i, _P, i, _P, _P]
        lib.skcoll_distances_batch.argtypes = [_P, L, _P, i, _P, i, _P, i, _P, _P]
        self.lib = lib

    def _q(self, q: Any) -> tuple[np.ndarray, bool]:
        Q, single = as_batch(q, self.n, self.layout.tree.name)
        return np.ascontiguousarray(Q, dtype=float), single

    def _env(self, env: Any) -> tuple[Environment, Packed]:
        """``env`` as an Environment and its packed arguments (:func:`env_args`)."""
        env = _NO_ENV if env is None else env if type(env) is Environment else as_environment(env)
        return env, env.__dict__.get("_packed") or env_args(env)

    def n_distances(self, env: Environment) -> int:
        return len(self.layout.self_pairs) + len(self.layout.shapes) * len(env)

    def points(self, q: Any) -> np.ndarray:
        """Base-frame shape points (P, 3) or (N, P, 3) (sphere centres, capsule ends)."""
        Q, single = self._q(q)
        X = np.empty((Q.shape[0], self.layout.n_points, 3))
        for k in range(Q.shape[0]):
            self.lib.skcoll_points(Q[k].ctypes.data, X[k].ctypes.data)
        return X[0] if single else X

    def in_collision(self, q: Any, env: Any = None) -> bool | np.ndarray:
        """Whether any active pair overlaps; (N,) bools for a batch (stops at the first overlap)."""
        if type(q) is np.ndarray and q.shape == (self.n,) and q.dtype == np.float64 and q.flags.c_contiguous:
            hit = self._one(
                q.ctypes.data, self._env(env)[1][3]
            )  # one C call; -1: a joint value NaN, inf or huge
            if hit >= 0:
                return hit == 1
        Q, single = self._q(q)
        args = self._env(env)[1].args
        if single:
            return bool(self.lib.skcoll_in_collision(Q.ctypes.data, *args))
        out = np.zeros(Q.shape[0], dtype=np.uint8)
        self.lib.skcoll_in_collision_batch(Q.ctypes.data, Q.shape[0], *args, out.ctypes.data)
        return out.astype(bool)

    def distances(self, q: Any, env: Any = None, jacobians: bool = False) -> Any:
        """Signed distances (M,) or (N, M); with ``jacobians`` also their gradients (M, n) or (N, M, n)."""
        Q, single = self._q(q)
        env, packed = self._env(env)
        args = packed.args
        M, N = self.n_distances(env), Q.shape[0]
        D = np.empty((N, M))
        J = np.empty((N, M, self.n)) if jacobians else None
        Jp = J.ctypes.data if J is not None else None
        self.lib.skcoll_distances_batch(Q.ctypes.data, N, *args, D.ctypes.data, Jp)
        if single:
            return (D[0], J[0]) if jacobians else D[0]  # type: ignore[index]
        return (D, J) if jacobians else D

    def distance_jacobians(self, q: Any, env: Any = None) -> tuple[np.ndarray, np.ndarray]:
        return self.distances(q, env, jacobians=True)


def collision_kernel(model: Any) -> CollisionKernel:
    """The compiled kernel of ``model``'s geometry (built and loaded once per geometry and model)."""
    layout = layout_of(model)
    key = f"{layout.tree.key}:{layout.tree.geometry.fingerprint()}"
    return lru(_KERNELS, key, lambda: CollisionKernel(layout), _KEEP)


def motion_valid(check: Any, q0: Any, q1: Any, n: int, resolution: float = 0.05) -> bool:
    """Whether the straight joint-space motion q0 -> q1 is free of collision, checked at steps of at
    most ``resolution`` (rad or m, the largest joint change between checks), both ends included.
    ``check(Q)`` returns (N,) collision verdicts."""
    res = finite_number(resolution, "resolution")
    a, _ = as_batch(q0, n, what="q0")
    b, _ = as_batch(q1, n, what="q1")
    if a.shape[0] != 1 or b.shape[0] != 1:
        raise ParameterError("motion_valid takes one configuration for q0 and one for q1")
    from symkin.core.sizes import room

    span = float(np.abs(b[0] - a[0]).max())
    room(8.0 * n * (span / res + 2), f"a motion checked at {span / res + 1:.6g} configurations")
    steps = max(1, int(np.ceil(span / res)))
    s = np.linspace(0.0, 1.0, steps + 1)[:, None]
    Q = a[0] + s * (b[0] - a[0])
    return not bool(np.asarray(check(Q)).any())


def collision_module(layout: Layout, backend: str = "numpy") -> Any:
    """The generated collision module of ``layout`` for ``backend`` ("numpy":
    :func:`symkin.emit.collision.render_collision_numpy`; "casadi":
    :func:`~symkin.emit.collision.render_collision_casadi`; "jax", "torch":
    :func:`~symkin.emit.collision.render_collision_tensor`), imported once per layout (its bytecode
    cached by content)."""
    memo = layout.__dict__.get("_modules")
    if memo is None:
        memo = {}
        object.__setattr__(layout, "_modules", memo)
    module = memo.get(backend)
    if module is None:
        from symkin.core.cache import cache_dir
        from symkin.emit import collision as emit
        from symkin.emit.numpy.backend import load_numpy

        if backend in ("jax", "torch"):
            files = emit.render_collision_tensor(layout, backend)
        else:
            render = emit.render_collision_casadi if backend == "casadi" else emit.render_collision_numpy
            files = render(layout)
        module = memo[backend] = load_numpy(files, cache_dir() / backend)
    return module


class Collision:
    """Collision queries of one model on one backend: the compiled C kernel on ``"c"``, the
    generated NumPy module otherwise (same answers, tested). Made by :meth:`symkin.Kinematics.collision`."""

    def __init__(self, model: Any, backend: str = "c") -> None:
        self.layout = layout_of(model)
        self.backend = backend
        self.kernel = collision_kernel(model) if backend == "c" else None
        self.module = None if self.kernel is not None else collision_module(self.layout)
        self._queries: Any = self.kernel if self.kernel is not None else self.module  # the same methods
        self.n = self.layout.tree.n

    def points(self, q: Any) -> np.ndarray:
        return self._queries.points(q)

    def in_collision(self, q: Any, env: Any = None) -> bool | np.ndarray:
        return self._queries.in_collision(q, env)

    def distances(self, q: Any, env: Any = None) -> np.ndarray:
        return self._queries.distances(q, env)

    def distance_jacobians(self, q: Any, env: Any = None) -> tuple[np.ndarray, np.ndarray]:
        return self._queries.distance_jacobians(q, env)

    def labels(self, env: Any = None) -> list[tuple[str, int, int]]:
        return self.layout.pair_labels(as_environment(env))

    def motion_valid(self, q0: Any, q1: Any, env: Any = None, resolution: float = 0.05) -> bool:
        env = as_environment(env)
        return motion_valid(lambda Q: self.in_collision(Q, env), q0, q1, self.n, resolution)


def collision_ik(kin: Any, Tep: Any, env: Any, attempts: int = 20, **kwargs: Any) -> Any:
    """``kin.ik(Tep, **kwargs)`` keeping only collision-free solutions (with the robot itself and
    ``env``; ``True``: self-collision only).

    On compiled C kinematics of a chain with a compiled collision kernel, the C solver checks each
    converged solution with the kernel inside its search loop: one that collides is rejected and
    the next search starts (from ``starts``, then random), as for joint limits, within ``slimit``
    searches; the reason of a failure counts the rejected solutions ("... rejected: in
    collision"). Elsewhere the targets whose solution collides are solved again, all together,
    from new random starts (seeded from ``seed``), in at most ``attempts - 1`` more rounds; a
    target without a collision-free solution gets ``success=False``, reason "in collision", and
    its last solution; iterations and searches count every round."""
    from symkin.runtime.ik_problem import IKResult

    attempts = count(attempts, "collision_attempts")
    solver = collision_solver(kin, env, kwargs)
    if solver is not None:
        return solver.solve(Tep, q0=kwargs.get("q0"), seed=kwargs.get("seed"))
    env = Environment() if env is True else as_environment(env)
    check = kin.collision()
    first = kin.ik(Tep, **kwargs)
    batch = first.batch
    seed = kwargs.pop("seed", None)
    kwargs.pop("q0", None)
    T = as_poses(Tep)[0]  # (N, 4, 4) by the one pose rule (kin.ik has checked it)
    q = np.array(first.q, dtype=float).reshape(len(T), -1)
    success = np.atleast_1d(np.array(first.success, dtype=bool))
    iters = np.atleast_1d(np.array(first.iterations, dtype=int))
    searches = np.atleast_1d(np.array(first.searches, dtype=int))
    residual = np.atleast_1d(np.array(first.residual, dtype=float))
    reason = list(first.reason) if batch else [first.reason]
    # unreachable targets stay as the plain solver says; colliding solutions are solved again
    todo = np.flatnonzero(success & np.atleast_1d(check.in_collision(q, env)))
    rng = np.random.default_rng(None if seed is None else [int(seed), 7919])
    for _ in range(attempts - 1):
        if not len(todo):
            break
        res = kin.ik(T[todo], q0=kin.random_q(len(todo), seed=rng), seed=int(rng.integers(2**63)), **kwargs)
        rq = np.asarray(res.q, dtype=float).reshape(len(todo), -1)
        iters[todo] += np.asarray(res.iterations, dtype=int)
        searches[todo] += np.asarray(res.searches, dtype=int)
        q[todo], residual[todo] = rq, np.asarray(res.residual, dtype=float)
        free = np.asarray(res.success, dtype=bool) & ~np.atleast_1d(check.in_collision(rq, env))
        for j in np.flatnonzero(free):
            reason[todo[j]] = "success"
        todo = todo[~free]
    success[todo] = False
    for i in todo:
        reason[i] = "in collision"
    result = IKResult(q, success, iters, searches, residual, tuple(reason))
    return result if batch else result[0]


_AVOIDING: OrderedDict[tuple, tuple] = OrderedDict()  # (kin id, options, env id) -> (kin, env, solver)


def collision_solver(
    kin: Any, env: Any, kwargs: dict[str, Any], attempts: Any = 20, rows: dict[str, Any] | None = None
) -> Any:
    """The C IK solver of ``kin.ik(**kwargs)`` that rejects converged solutions colliding with
    ``env`` (an Environment or obstacles; ``True``: self-collision only), the kernel's
    ``skcoll_in_collision_packed`` in its search loop, memoised for the last 16 kinematics,
    options and environments; None when the C path does not apply (another backend, a tree or a
    frame off the end effector, options the C solver does not take). ``attempts``: the
    ``collision_attempts`` of the other paths, checked here too. ``rows`` (method ``"QP"``): the
    MMC's collision-row options; the QP step then also keeps the rows of ``env``
    (:class:`~symkin.runtime.ik_qp_c.QPStep`)."""
    from symkin.runtime.ik import IK_OPTIONS, _ik_defaults, _options
    from symkin.runtime.ik_c import CIKSolver, options_key

    count(attempts, "collision_attempts")
    if getattr(kin, "backend", None) != "c" or len(getattr(kin, "frames", ())) != 1:  # one frame's kinematics
        return None
    if set(kwargs) - set(IK_OPTIONS) - {"q0", "seed"} or (rows is None and getattr(kin, "n", 99) > 12):
        return None  # frame=, backend=...: the general path
    env = Environment() if env is True else as_environment(env)
    check = kin.collision()
    if check.kernel is None:
        return None
    defaults = _ik_defaults()  # the options, validated once per values (ik's memo)
    options = _options(kin, *(kwargs.get(k, defaults[k]) for k in IK_OPTIONS))
    fn = check.kernel.lib.skcoll_in_collision_packed

    def make() -> tuple:
        qp = {} if rows is None else {"environment": env, "collision": rows}
        return kin, env, CIKSolver(kin, options, collides=(fn, env_args(env)), **qp)

    qp_key = None if rows is None else tuple(sorted((k, repr(v)) for k, v in rows.items()))
    key = (id(kin), options_key(options), id(env), qp_key)
    hit = lru(_AVOIDING, key, make, _KEEP)
    if hit[0] is not kin or hit[1] is not env:  # another object under a reused id
        hit = _AVOIDING[key] = make()
    return hit[2]


def collision_of(kin: Any) -> Collision:
    """The collision queries of ``kin``: compiled kinematics' own (:meth:`Kinematics.collision`), else
    the generated NumPy module of a Robot or Tree (or of a frame view's model)."""
    method = getattr(kin, "collision", None)
    if callable(method):
        return method()
    source = getattr(kin, "source", None)
    if source is not None and callable(getattr(source, "collision", None)):
        return source.collision()
    return Collision(source if source is not None else kin, "numpy")
