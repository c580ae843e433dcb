"""Compiled kinematics on the JAX and PyTorch backends: the object :func:`symkin.compile` returns
for ``backend="jax"`` or ``"torch"``.

The generated functions (``fkine``, ``jacob0``, ``jacobe``, ``hessian0``, ``hessiane``,
``fkine_jacob0``, ``jacob0_hessian0``, ``link_poses`` of a chain, the ``*_all`` of a tree, and
any further kinds the kernel has) are the generated module's, taking q (..., n) of any batch shape
and returning arrays of q's dtype (and device): JAX arrays through ``jax.jit`` (``frame`` a static
argument), tensors as the module computes them. ``function(kind, frame)`` gives the plain function
to compose with ``jax.vmap``, ``jax.grad``, ``torch.compile`` or ``torch.func``. On top: the
batched, differentiable IK (:mod:`symkin.runtime.diff.ik`) and the collision distances and their
penalty (:mod:`symkin.runtime.diff.collision`).
"""

from __future__ import annotations

import inspect
from functools import partial
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from symkin.errors import FrameError, ParameterError
from symkin.model.derivatives import check_order, derivative_kind
from symkin.model.tree import as_tree
from symkin.runtime.diff.ops import ops_of
from symkin.runtime.model_attrs import ModelAttributes

__all__ = ["DiffKinematics"]


class DiffKinematics(ModelAttributes):
    """Generated JAX or PyTorch kinematics of ``model`` (a chain or a tree); see the module docstring.

    Attributes: ``model`` (also ``robot`` and ``tree``), ``backend`` ("jax" or "torch"), ``n``,
    ``name``, ``joint_names``, ``qlim`` (NumPy, (2, n)), ``revolute``, ``frames``, ``kinds`` (the
    generated functions), ``files`` (the generated sources), ``path``, ``module``, ``ops``.
    It pickles as (model, backend), unpickling compiles again (the reducer is registered by
    :func:`symkin.runtime.kinematics.kinematics_of`, which makes these objects).
    """

    def __init__(
        self, model: Any, backend: str, module: ModuleType, files: dict[str, str], path: Path | None = None
    ) -> None:
        self.model, self.backend, self.module, self.files, self.path = model, backend, module, files, path
        self.ops = ops_of(backend)
        self._n = int(model.n)
        self.frames: tuple[str, ...] = tuple(module.FRAMES)
        self.kinds: tuple[str, ...] = tuple(module.KINDS)
        self._jit: dict[Any, Any] = {}
        for kind in self.kinds:
            setattr(self, kind, self._bound(getattr(module, kind)))

    def _bound(self, fn: Any) -> Any:
        if self.backend != "jax":
            return fn
        framed = "frame" in inspect.signature(fn).parameters
        return self.ops.jax.jit(fn, static_argnames=("frame",) if framed else ())  # type: ignore[attr-defined]

    # -- what the model says (with ModelAttributes) -----------------------------------------
    @property
    def joint_names(self) -> tuple[str, ...]:
        return tuple(self.module.JOINT_NAMES)

    @property
    def revolute(self) -> np.ndarray:
        return np.array(self.module.REVOLUTE, dtype=bool)

    def __repr__(self) -> str:
        return (
            f"DiffKinematics(robot={self.name!r}, n={self.n}, frames={list(self.frames)}, "
            f"backend={self.backend!r})"
        )

    def check_q(self, q: Any) -> Any:
        """q as the generated functions take it (ConfigurationError for a wrong shape or dtype)."""
        return self.module._q(q)

    def function(self, kind: str, frame: Any = None) -> Any:
        """The generated function ``kind`` of ``frame`` as a plain function of q (not jitted), for
        ``jax.vmap``/``jax.grad``/``torch.func``/``torch.compile`` to transform."""
        if kind not in self.kinds:
            raise AttributeError(f"{self.name} has no generated {kind!r}; it has {list(self.kinds)}")
        fn = getattr(self.module, kind)
        if "frame" in inspect.signature(fn).parameters:
            return partial(fn, frame=frame)
        return fn

    def derivative(self, q: Any, order: int = 1, frame: Any = None) -> Any:
        """Order-``order`` partial derivative of the pose of ``frame``: ``(..., ) + (n,) * (order -
        1) + (6, n)`` (Haviland and Corke, Manipulator Differential Kinematics, Part 2, 2023;
        roboticstoolbox-python's ``partial_fkine0`` layout, as :meth:`symkin.Robot.derivative`).
        Order 1 is ``jacob0``, order 2 ``hessian0``; orders 3 and up are generated when the model
        is compiled with ``symkin.compile(model, backend, derivatives=k)`` (ParameterError
        otherwise: these modules are not compiled again on a call)."""
        k = check_order(order, self.n, self.name)
        kind = {1: "jacob0", 2: "hessian0"}.get(k, derivative_kind(k))
        if kind not in self.kinds:
            raise ParameterError(
                f"{self.name}: these {self.backend} kinematics have no order-{k} derivative; compile "
                f"them with symkin.compile(model, backend={self.backend!r}, derivatives={k})"
            )
        fn = getattr(self, kind)
        if "frame" in inspect.signature(getattr(self.module, kind)).parameters:
            return fn(q, frame=frame)
        if frame is not None and frame not in self.frames:
            raise FrameError(f"{self.name} has no frame {frame!r}; it has {list(self.frames)}")
        return fn(q)

    def random_q(self, N: int | None = None, seed: Any = None, dtype: Any = None) -> Any:
        """Uniform random configurations within qlim, (n,) or (N, n), as an array of this backend
        (float64 unless ``dtype``; JAX: float32 when x64 is off)."""
        Q = as_tree(self.model).random_q(N, seed)
        xp = self.ops.xp
        if self.backend == "jax":
            return xp.asarray(Q, dtype=dtype)
        return xp.as_tensor(Q, dtype=dtype or xp.float64)

    # -- every frame -------------------------------------------------------------------------
    def _all(self, kind: str, q: Any) -> Any:
        if f"{kind}_all" in self.kinds:
            return getattr(self, f"{kind}_all")(q)
        out = getattr(self, kind)(q)  # one frame: its own, with a frame axis
        return tuple(x[..., None, :, :] for x in out) if isinstance(out, tuple) else out[..., None, :, :]

    def fkine_all(self, q: Any) -> Any:
        """Poses of every frame, (..., F, 4, 4)."""
        return self._all("fkine", q)

    def jacob0_all(self, q: Any) -> Any:
        """Base-frame Jacobians of every frame, (..., F, 6, n)."""
        return self._all("jacob0", q)

    def fkine_jacob0_all(self, q: Any) -> tuple[Any, Any]:
        """:meth:`fkine_all` and :meth:`jacob0_all` together."""
        return self._all("fkine_jacob0", q)

    # -- inverse kinematics ------------------------------------------------------------------
    def ik(self, Tep: Any, q0: Any = None, **options: Any) -> Any:
        """Batched, differentiable IK of targets ``Tep`` (..., 4, 4): see
        :func:`symkin.runtime.diff.ik.solve` (options of :func:`symkin.ik`, ``slimit`` searches per
        target side by side, ``seed``, ``frame``)."""
        from symkin.runtime.diff.ik import solve

        return solve(self, Tep, q0, **options)

    def jitted_ik(self, plan: Any, fkjac: Any) -> Any:
        """The JAX IK core compiled for ``plan`` (memoised; :func:`symkin.runtime.diff.ik.jax_core`)."""
        key = ("ik", plan)
        if key not in self._jit:
            from symkin.runtime.diff.ik import jax_core

            self._jit[key] = jax_core(self.ops, plan, fkjac)
        return self._jit[key]

    # -- collision geometry ------------------------------------------------------------------
    def collision(self) -> Any:
        """The collision queries of the model's geometry
        (:class:`symkin.runtime.diff.collision.DiffCollision`)."""
        col = self.__dict__.get("_collision")
        if col is None:
            from symkin.runtime.diff.collision import DiffCollision

            col = self.__dict__["_collision"] = DiffCollision(self.model, self.backend)
        return col

    def _collision_fn(self, name: str, env: Any, **kw: Any) -> Any:
        """The collision query ``name`` with ``env`` bound (JAX: jitted, memoised per environment)."""
        from symkin.geometry.pairs import as_environment

        env = as_environment(env)
        fn = partial(getattr(self.collision(), name), env=env, **kw)
        if self.backend != "jax":
            return fn
        key = (name, env, tuple(sorted(kw.items())))
        if key not in self._jit:
            if len(self._jit) >= 64:
                self._jit.clear()
            self._jit[key] = self.ops.jax.jit(fn)  # type: ignore[attr-defined]
        return self._jit[key]

    def collision_points(self, q: Any) -> Any:
        """Base-frame points of the geometry (..., P, 3): each sphere's centre, each capsule's two
        segment ends, in the order of ``model.geometry.shapes``."""
        return self.collision().points(self.check_q(q))

    def distances(self, q: Any, env: Any = None) -> Any:
        """Signed distance (m) of every active pair, (..., M): self pairs, then every shape against
        each obstacle (:meth:`collision_pairs` says which is which); differentiable in q."""
        return self._collision_fn("distances", env)(self.check_q(q))

    def distance_jacobians(self, q: Any, env: Any = None) -> tuple[Any, Any]:
        """Signed distances (..., M) and their gradients d d/d q (..., M, n)."""
        return self._collision_fn("distance_jacobians", env)(self.check_q(q))

    def in_collision(self, q: Any, env: Any = None) -> Any:
        """Whether any active pair overlaps, (...) booleans."""
        return self._collision_fn("in_collision", env)(self.check_q(q))

    def collision_cost(self, q: Any, env: Any = None, margin: float = 0.0) -> Any:
        """sum over pairs of max(margin - d, 0)^2, (...): a smooth penalty for a loss (zero when
        every pair is ``margin`` m apart or more)."""
        return self._collision_fn("cost", env, margin=float(margin))(self.check_q(q))

    def collision_pairs(self, env: Any = None) -> list[tuple[str, int, int]]:
        """What each entry of :meth:`distances` is: ("self", i, j) or (obstacle kind, shape i, obstacle k)."""
        return self.collision().labels(env)
