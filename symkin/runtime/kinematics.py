"""Compiled kinematics: the object :func:`symkin.compile` returns, for a chain or a tree (no sympy here).

One class for every model. Every method takes ``frame=`` (a frame name, or None when the model has
one frame: a chain's end effector, "ee"; on a chain also k, link frame k, the frame right after the
k-th joint along the chain) and has the numeric references' signatures and shapes: ``fkine``,
``jacob0``, ``jacobe``, ``fkine_jacob0``, ``hessian0``, ``hessiane``, ``jacob0_hessian0``,
``manipulability``, ``jacobm``, ``cond``, ``jacobs``, ``jacobb``, ``jacob0_dot``, ``ik``,
``fkine_all``, ``jacob0_all`` and ``fkine_jacob0_all`` (every frame, in ``frames`` order); a chain
adds ``link_poses``, ``ik_all`` and its closed form. On the C backend the generated methods are
the extension module's functions themselves, so a call costs one C function call.
"""

from __future__ import annotations

import contextlib
import sys
from collections.abc import Callable
from functools import cached_property
from pathlib import Path
from types import MethodType, ModuleType
from typing import Any

import numpy as np

from symkin.compiler.compile import OPTIONAL_BACKENDS, Artifact, build, cache_key, check_derivatives
from symkin.core.names import function_name
from symkin.errors import ConfigurationError, SymkinError
from symkin.model.derivatives import MAX_ORDER, check_order, derivative_kind
from symkin.model.differential import FrameMethods
from symkin.model.frames import resolve_frame
from symkin.model.tree import as_tree
from symkin.runtime.casadi_calls import casadi_methods
from symkin.runtime.ik import IK_OPTIONS, ik
from symkin.runtime.ik_qp_c import collision_qp_ik  # registers the QP step of the C IK solver
from symkin.runtime.memo import memoised
from symkin.runtime.model_attrs import ModelAttributes

__all__ = ["Kinematics", "KIN_METHODS", "load_kinematics", "kinematics_of"]

C_IK_MAX_JOINTS = 12  # SYMKIN_IK_NMAX of the C solver; longer chains use the NumPy solver
_FAST_KEYS = frozenset((*IK_OPTIONS, "q0", "seed", "backend"))  # what ik's memoised C solvers take

KIN_METHODS = (
    "fkine",
    "link_poses",
    "jacob0",
    "jacobe",
    "hessian0",
    "hessiane",
    "fkine_jacob0",
    "jacob0_hessian0",
)  # generated for a chain
# what a generated module may have besides: every frame's at once, and manipulability (C)
_MODULE_METHODS = (*KIN_METHODS, "fkine_all", "jacob0_all", "fkine_jacob0_all", "manipulability", "jacobm")


def _rebuild(model: Any, backend: str) -> Kinematics:
    """The kinematics of ``model`` on ``backend`` (the unpickler of :class:`Kinematics`)."""
    return load_kinematics(model, backend)


def _reduce_diff(kin: Any) -> tuple[Any, tuple[Any, str]]:
    """The pickle of a JAX or PyTorch :class:`~symkin.runtime.diff.kinematics.DiffKinematics`."""
    return (_rebuild, (kin.model, kin.backend))


# symkin 0.1.0 pickled compiled trees as symkin.runtime.tree_kinematics._rebuild: the same function
sys.modules.setdefault(f"{__package__}.tree_kinematics", sys.modules[__name__])


def load_kinematics(
    model: Any, backend: str = "c", cache: bool = True, strategy: str | None = None, derivatives: int = 0
) -> Kinematics:
    """The compiled kinematics of ``model`` (a Robot or a Tree) on ``backend`` (with the derivatives
    of orders 3..``derivatives``), memoised per cache key (see :mod:`symkin.compiler.compile`) and
    the model's own fingerprint: the object carries the model (a robot's configurations and source,
    a tree's) a controller reads."""
    derivatives = check_derivatives(derivatives)
    key = cache_key(model, backend, strategy, derivatives=derivatives)
    geometry = None if model.geometry is None else model.geometry.fingerprint()  # not in the code's key

    def make() -> Kinematics:
        kin = kinematics_of(model, build(model, backend, cache, strategy, key, derivatives), backend)
        kin._options = (cache, strategy)
        return kin

    return memoised((key, model.fingerprint, geometry), make, cache)


def kinematics_of(model: Any, art: Artifact, backend: str) -> Kinematics:
    """The :class:`Kinematics` of ``model`` around its built code ``art`` (JAX and PyTorch: a
    :class:`symkin.runtime.diff.kinematics.DiffKinematics`)."""
    if backend in OPTIONAL_BACKENDS:
        import copyreg

        from symkin.runtime.diff.kinematics import DiffKinematics

        copyreg.pickle(DiffKinematics, _reduce_diff)  # pickled as (model, backend), as Kinematics
        return DiffKinematics(model, backend, art.module, art.files, art.path)  # type: ignore[return-value]
    if backend == "casadi":
        fns = art.module.functions()
        kin = Kinematics(model, backend, casadi_methods(model, fns), art.files, art.path, art.module)
        kin.functions = fns  # type: ignore[attr-defined]
        return kin
    names = (*_MODULE_METHODS, *(derivative_kind(k) for k in range(3, MAX_ORDER + 1)))
    functions = {name: getattr(art.module, name) for name in names if hasattr(art.module, name)}
    return Kinematics(model, backend, functions, art.files, art.path, art.module)


class Kinematics(ModelAttributes, FrameMethods):
    """Generated kinematics of ``model`` (a :class:`symkin.Robot` chain or a :class:`symkin.Tree`)
    on one backend ("c", "numpy" or "casadi"); the generated functions are bound as attributes (on
    the C backend, the extension module's functions themselves).

    Attributes: ``model`` (also ``robot`` and ``tree``), ``backend``, ``n``, ``name``,
    ``joint_names``, ``qlim``, ``qd_max``, ``configs`` and each named configuration (``kin.qr``, as
    on the model), ``frames`` (a chain: "ee"), ``files`` (the generated sources), ``path`` (the
    compiled library or module), ``module``.
    """

    fkine: Callable[..., np.ndarray]
    jacob0: Callable[..., np.ndarray]
    jacobe: Callable[..., np.ndarray]
    fkine_jacob0: Callable[..., tuple[np.ndarray, np.ndarray]]

    def __init__(
        self,
        model: Any,
        backend: str,
        functions: dict[str, Callable[..., Any]],
        files: dict[str, str],
        path: Path | None = None,
        module: ModuleType | None = None,
    ) -> None:
        self.model = model
        self._n = int(model.n)  # kept: a Robot counts the joints of its ETS on every call
        self.backend, self.files, self.path, self.module = backend, files, path, module
        self.frames: tuple[str, ...] = as_tree(model).frames
        self._links = self._n if "link_poses" in functions else 0  # a chain's link frames
        for name, fn in functions.items():
            setattr(self, name, fn)
        self._ik_solver: Any = None  # the C IK solver with the default options, after a first call
        self._ik_by_options: dict[tuple, Any] = {}  # C IK solvers by keyword options (see ik)
        self._ik_bound: dict[tuple, Any] = {}  # their bound C entry points, looked up by kin.ik in C
        self._c_rrmc: dict[tuple, Any] = {}  # C RRMC controllers by options (symkin.runtime.control.rrmc)
        self._options: tuple[bool, str | None] = (True, None)  # cache and strategy of the compile

    # -- what the model says (with ModelAttributes) -----------------------------------------
    @property
    def qd_max(self) -> np.ndarray | None:
        return self.model.qd_max

    @property
    def configs(self) -> Any:
        """The model's named configurations (``qz``, ``qr``...; each (n,)), as on the Robot; also
        attributes: ``kin.qr``."""
        return self.model.configs

    def __getattr__(self, key: str) -> np.ndarray:
        """A named configuration of the model as an attribute (``kin.qr``), as the Robot has it."""
        model = self.__dict__.get("model")
        if model is None or key.startswith("_"):
            raise AttributeError(key)
        try:
            return model.configs[key]
        except KeyError:
            raise AttributeError(
                f"Kinematics {model.name!r} has no attribute or configuration {key!r}; "
                f"configurations: {sorted(model.configs)}"
            ) from None

    @property
    def c_prefix(self) -> str:
        """The prefix of the exported C symbols (``symkin_<name>`` unless generated with another)."""
        headers = sorted(f for f in self.files if f.endswith(".h"))
        if self.backend != "c" or not headers:
            raise AttributeError("c_prefix exists only on the C backend")
        return headers[0][:-2]

    def random_q(self, N: int | None = None, seed: Any = None) -> np.ndarray:
        """Uniform random configurations within qlim: (n,) or (N, n)."""
        return self.model.random_q(N, seed)

    def __repr__(self) -> str:
        frames = list(self.frames)
        return f"Kinematics(robot={self.name!r}, n={self.n}, frames={frames}, backend={self.backend!r})"

    def __reduce__(self) -> tuple[Any, tuple[Any, str]]:
        """Pickle as (model, backend): unpickling compiles again, which loads the generated code
        from the compile cache of the process that unpickles (a Dask worker, say) when it is there."""
        return (_rebuild, (self.model, self.backend))

    def _repr_markdown_(self) -> str:
        """Notebook view: the backend, the generated files and the robot's joint table."""
        from symkin.model.describe import md_text, robot_markdown

        files = ", ".join(f"`{md_text(f)}`" for f in sorted(self.files))
        head = f"**{md_text(self.name)}** compiled for the **{self.backend}** backend ({files})"
        try:
            chain = self.model.chain()
        except SymkinError:  # several frames, or a mimic joint on the path
            return f"{head}: frames {', '.join(f'`{md_text(f)}`' for f in self.frames)}, {self.n} joints.\n"
        methods = (
            "fkine, link_poses, jacob0, jacobe, jacobs, jacobb, jacob0_dot, hessian0, hessiane, "
            "manipulability, jacobm, cond, ik"
        )
        return robot_markdown(chain, head) + f"Methods: {methods}.\n"

    # -- derivatives of any order ------------------------------------------------------------
    def derivative(self, q: Any, order: int = 1, frame: Any = None) -> np.ndarray:
        """Order-``order`` partial derivative of the pose of ``frame``: ``(n,) * (order - 1) + (6,
        n)``, or (N, ...) for a batch, ``D[i_{k-1}, ..., i_1, :, i_0] = d^{k-1} J0[:, i_0] /
        dq_{i_1} ... dq_{i_{k-1}}`` (roboticstoolbox-python's ``partial_fkine0`` layout; see
        :meth:`symkin.Robot.derivative`). Order 1 is :meth:`jacob0`, order 2 :meth:`hessian0`.

        Orders 3 and up are generated code (:mod:`symkin.symbolic.derivatives`): compiled with
        ``symkin.compile(model, derivatives=k)``, or on the first call of an order the kinematics
        lack (the model compiled again with the derivatives up to that order, from the compile
        cache when it is there; a cold Panda order 4 takes seconds, see the performance guide).
        A chain's link frame k takes them from its Jacobian (numeric, Part 2's recursion)."""
        k = check_order(order, self.n, self.name)
        if k < 3:
            return super().derivative(q, k, frame)
        fn = self.__dict__.get(derivative_kind(k))
        if fn is None:
            fn = self._compile_derivatives(k)
        return fn(q) if frame is None else fn(q, frame)

    def _compile_derivatives(self, order: int) -> Callable[..., np.ndarray]:
        """The generated ``derivative<order>`` of this model on this backend: these kinematics
        compiled again with the derivatives up to ``order``; every order it has is kept here."""
        cache, strategy = self._options
        other = load_kinematics(self.model, self.backend, cache, strategy, derivatives=order)
        for k in range(3, order + 1):
            self.__dict__[derivative_kind(k)] = other.__dict__[derivative_kind(k)]
        return self.__dict__[derivative_kind(order)]

    # -- frames ------------------------------------------------------------------------------
    def fkine_all(self, q: Any) -> np.ndarray:
        """Poses of every frame, (F, 4, 4) or (N, F, 4, 4) (a model of one frame: its pose)."""
        return np.expand_dims(self.fkine(q), -3)

    def jacob0_all(self, q: Any) -> np.ndarray:
        """Base-frame Jacobians of every frame, (F, 6, n) or (N, F, 6, n)."""
        return np.expand_dims(self.jacob0(q), -3)

    def fkine_jacob0_all(self, q: Any) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`fkine_all` and :meth:`jacob0_all` together."""
        T, J = self.fkine_jacob0(q)
        return np.expand_dims(T, -3), np.expand_dims(J, -3)

    def _frame(self, frame: Any) -> tuple[int, int]:
        """(frame index, -1) or (-1, link frame index) of a frame argument."""
        return resolve_frame(frame, self.frames, self._links, self.name)

    def select(self, frame: Any = None) -> Any:
        """One frame as chain kinematics of all n joints, for :func:`symkin.ik`, :func:`symkin.servo`
        and :class:`symkin.MMC`: these kinematics themselves for the only frame (``frame=None``),
        else a :class:`symkin.model.frame_view.FrameView`."""
        if frame is None and len(self.frames) == 1:
            return self
        from symkin.model.frame_view import frame_view

        return frame_view(self.model, self, frame)

    def _c_functions(self, frame: Any, kinds: tuple[str, ...]) -> dict[str, Any] | None:
        """The generated C functions ``kinds`` of ``frame`` (a named frame) as ctypes functions;
        None for another backend or a chain's link frame."""
        if self.backend != "c" or self.path is None:
            return None
        k, link = self._frame(frame)
        if link >= 0:
            return None
        from symkin.emit.c.build import load_library

        self._lib = load_library(self.path)
        F = len(self.frames)
        return {kind: getattr(self._lib, f"{self.c_prefix}_{function_name(kind, k, F)}") for kind in kinds}

    def c_controller_functions(self, frame: Any) -> dict[str, Any] | None:
        """The C functions the C controllers (MMC, RRMC, the servo loop) call for ``frame``, as
        ctypes functions (``jacob0_hessian0``, ``jacob0``, ``fkine``, ``manipulability``), or None
        when the backend is not C or ``frame`` is a chain's link frame (the controllers then run
        in Python)."""
        return self._c_functions(frame, ("jacob0_hessian0", "jacob0", "fkine", "manipulability"))

    def c_fkjac_of(self, frame: Any) -> Any:
        """The C entry point ``fkine_jacob0`` of ``frame`` as a ctypes function (C backend), for the
        C IK solver; None for other backends and a chain's link frames."""
        fns = self._c_functions(frame, ("fkine_jacob0",))
        return None if fns is None else fns["fkine_jacob0"]

    @cached_property
    def c_fkjac(self) -> Any:
        """The C entry point ``fkine_jacob0(q, T, J)`` of the only frame as a ctypes function (C
        backend), for the C IK solver."""
        return self._c_entry("fkine_jacob0")

    @cached_property
    def c_fkjac_batch(self) -> Any:
        """The C entry point ``fkine_jacob0_batch(q, T, J, N)`` of the only frame as a ctypes
        function (C backend), four configurations per step: a batch of LM solves evaluates its
        lanes with it."""
        return self._c_entry("fkine_jacob0_batch")

    def _c_entry(self, name: str) -> Any:
        if self.backend != "c" or self.path is None or len(self.frames) != 1:
            raise AttributeError(
                f"{name} of the only frame exists on the C backend only (several frames: c_fkjac_of)"
            )
        from symkin.emit.c.build import load_library

        return getattr(load_library(self.path), f"{self.c_prefix}_{name}")

    def ik(self, Tep: Any, frame: Any = None, **kwargs: Any) -> Any:
        """Numerical inverse kinematics of ``frame`` (eqs 37-51); see :func:`symkin.runtime.ik.ik`
        for the options. Off the end effector of a chain (a tree's frame, a chain's link frame) the
        other joints are free: see :class:`symkin.model.frame_view.FrameView`.

        On the C backend the whole solver loop runs in C on the generated kinematics; on the
        NumPy and CasADi backends the NumPy solver calls the generated functions. A call with the
        default options goes straight to the C solver; after the first one, ``kin.ik`` is the C
        solver's entry point itself, which solves one target without a Python frame (one target
        costs little more than the solve itself), also with ``q0=``, ``seed=`` and keyword options
        seen before (in the same order: their solver, made and validated the first time, is found
        by its options in C), and passes any other call on to this method. It is thread-safe.

        ``method="analytic"``: the closed form (:meth:`ik_all`), returning the solution nearest
        ``q0`` (options ``q0``, ``weights``, ``joint_limits``, ``tol``); ``success=False`` with a
        reason when the pose is out of reach or every solution is outside the joint limits. For a
        redundant arm ``free_joint=j`` sweeps joint ``j`` (64 values over its limits, or one turn,
        plus ``q0[j]``) and ``free_joint=(j, values)`` tries the given values; see :meth:`ik_all`.

        ``collision=env`` (an Environment or obstacles; ``True``: self-collision only) rejects
        solutions in collision: on the C backend inside the C solver's search loop (the next
        search starts, within ``slimit``; its solver is made once and found by its options, an
        equal environment included, so one target is one C call like the plain solve), elsewhere
        by solving again from new random starts, at most ``collision_attempts`` (20) times; see
        :func:`symkin.runtime.collision.collision_ik`. With ``method="QP"`` on a chain's C
        kinematics each step also keeps the MMC's collision rows
        (:func:`symkin.runtime.ik_qp_c.collision_qp_ik`).
        """
        q0, seed = kwargs.get("q0"), kwargs.get("seed")
        options = {k: v for k, v in kwargs.items() if k not in ("q0", "seed")}  # what a C solver is made of
        if frame is None and self._ik_by_options:  # options seen before: straight to their C solver
            try:
                solver = self._ik_by_options[tuple(options.items())]
            except (KeyError, TypeError):  # new or unhashable options: made and checked below
                pass
            else:
                return solver.solve(Tep, q0, seed)
        if "collision" in kwargs or "collision_attempts" in kwargs:
            env = kwargs.pop("collision", None)
            attempts = kwargs.pop("collision_attempts", 20)
            if env is not None and env is not False:
                qp = str(kwargs.get("method", "")).upper() == "QP"
                if qp and frame is None and self.backend == "c" and len(self.frames) == 1:
                    return collision_qp_ik(self, Tep, env, attempts, **kwargs)  # the QP keeps the MMC's rows
                from symkin.runtime.collision import collision_ik, collision_solver

                if frame is not None:
                    kwargs["frame"] = frame
                solver = collision_solver(self, env, kwargs, attempts)
                if solver is None:
                    return collision_ik(self, Tep, env, attempts, **kwargs)
                with contextlib.suppress(TypeError):  # later calls of these options: one C call
                    self._c_ik_solver({})
                    self._remember_ik(
                        tuple(options.items()), solver, solver.bind(MethodType(Kinematics.ik, self))
                    )
                return solver.solve(Tep, q0, seed)
            options = {k: v for k, v in kwargs.items() if k not in ("q0", "seed")}
        view = self.select(frame)
        if view is not self:
            return view.ik(Tep, **kwargs)
        c_loop = self.backend == "c" and self.n <= C_IK_MAX_JOINTS
        fast = kwargs.keys() <= _FAST_KEYS and kwargs.get("method") != "analytic"
        if c_loop and fast and kwargs.get("backend", "c") == "c":
            options.pop("backend", None)
            solver = self._c_ik_solver(options)
            if solver is not None:  # None: an unhashable option
                return solver.solve(Tep, q0, seed)
        if kwargs.get("method") == "analytic":
            options = {k: v for k, v in kwargs.items() if k != "method"}
            unknown = sorted(set(options) - {"q0", "weights", "joint_limits", "tol", "free_joint"})
            if unknown:
                raise TypeError(
                    f"method='analytic' takes q0, weights, joint_limits, tol, free_joint; not {unknown}"
                )
            free = options.pop("free_joint", None)
            if free is not None:
                from symkin.runtime.free_joint import free_joint_solver, parse_free_joint

                j, values = parse_free_joint(free)
                return free_joint_solver(self.model.chain(), j, self.backend).ik(Tep, values, **options)
            return self.analytic.ik(Tep, fkine=self.fkine, **options)
        kwargs.setdefault("backend", "c" if c_loop else "numpy")
        return ik(self, Tep, **kwargs)

    def _c_ik_solver(self, options: dict[str, Any]) -> Any:
        """The C IK solver of these keyword options of :meth:`ik`, made and validated once per
        options (None when one is unhashable, an array say). The defaults' solver also becomes
        ``kin.ik`` itself, which finds every solver made here by its options: a later call of one
        target, with no options or options seen before (plus ``q0``, ``seed``), is one C call."""
        if not options:
            if self._ik_solver is None:
                from symkin.runtime.ik import default_c_solver

                self._ik_solver = solver = default_c_solver(self)
                bound = solver.bind(MethodType(Kinematics.ik, self), self._ik_bound)
                self._remember_ik((), solver, bound)
                if bound is not None:  # later calls of one target: one C call, no Python frame
                    self.__dict__["ik"] = bound
            return self._ik_solver
        key = tuple(options.items())
        try:
            solver = self._ik_by_options.get(key)
        except TypeError:
            return None
        if solver is None:
            from symkin.runtime.ik import c_solver_with

            solver = c_solver_with(self, options)
            self._c_ik_solver({})  # kin.ik: the C entry point that finds this solver by its options
            self._remember_ik(key, solver, solver.bind(MethodType(Kinematics.ik, self)))
        return solver

    def _remember_ik(self, key: tuple, solver: Any, bound: Any) -> None:
        """Memoise ``solver`` and its bound entry point (None: it has none) under ``key`` and
        ``key + (("backend", "c"),)``; at most 64 keys (then all but the defaults are dropped)."""
        if len(self._ik_by_options) >= 64:
            self._ik_by_options.clear()
            self._ik_bound.clear()
            self._remember_ik((), self._ik_solver, self.__dict__.get("ik"))
        for k in (key, (*key, ("backend", "c"))):
            self._ik_by_options[k] = solver
            if bound is not None:
                self._ik_bound[k] = bound

    # -- collision geometry (symkin.runtime.collision) -----------------------------------------------
    def collision(self) -> Any:
        """The collision queries of the model's geometry: the compiled FKCC kernel on the C backend,
        the generated NumPy module on the others (built once; GeometryError when the model has none)."""
        checker = self.__dict__.get("_collision")
        if checker is None:
            from symkin.runtime.collision import Collision

            checker = Collision(self.model, "c" if self.backend == "c" else "numpy")
            self.__dict__["_collision"] = checker
        return checker

    def collision_points(self, q: Any) -> np.ndarray:
        """Base-frame points of the geometry, (P, 3) or (N, P, 3): each sphere's centre, each
        capsule's two segment ends, in the order of ``model.geometry.shapes``."""
        return self.collision().points(q)

    def in_collision(self, q: Any, env: Any = None) -> bool | np.ndarray:
        """Whether the robot at ``q`` collides with itself (active pairs: not on one body, not on
        adjacent bodies, not disabled) or with ``env`` (obstacles in the base frame); (N,) for a batch."""
        return self.collision().in_collision(q, env)

    def distances(self, q: Any, env: Any = None) -> np.ndarray:
        """Signed distance (m) of every active pair, (M,) or (N, M): self pairs, then every shape
        against each obstacle (spheres, capsules, boxes); :meth:`collision_pairs` says which is which."""
        return self.collision().distances(q, env)

    def distance_jacobians(self, q: Any, env: Any = None) -> tuple[np.ndarray, np.ndarray]:
        """Signed distances (M,) and their gradients d d/d q (M, n) (from the point Jacobians of the
        closest points); batched (N, M), (N, M, n)."""
        return self.collision().distance_jacobians(q, env)

    def collision_pairs(self, env: Any = None) -> list[tuple[str, int, int]]:
        """What each entry of :meth:`distances` is: ("self", i, j) or (obstacle kind, shape i, obstacle k)."""
        return self.collision().labels(env)

    def collision_function(self, env: Any = None) -> Any:
        """The distances of :meth:`distances` as a ``casadi.Function`` ``q -> d`` (SX, closed forms;
        a capsule against a box is refused): constraints ``d >= margin`` for ``casadi.Opti``
        problems, CasADi's derivatives; built by the generated CasADi collision module, once per
        environment (any backend)."""
        from symkin.geometry.pairs import as_environment, layout_of
        from symkin.runtime.collision import collision_module

        env = as_environment(env)
        memo = self.__dict__.setdefault("_collision_functions", {})
        if env not in memo:
            if len(memo) >= 8:
                memo.clear()
            memo[env] = collision_module(layout_of(self.model), "casadi").function(env)
        return memo[env]

    def motion_valid(self, q0: Any, q1: Any, env: Any = None, resolution: float = 0.05) -> bool:
        """Whether the straight joint-space motion q0 -> q1 stays free of collision (checked every
        ``resolution`` rad or m of the largest joint change, ends included)."""
        return self.collision().motion_valid(q0, q1, env, resolution)

    # -- closed-form inverse kinematics (symkin.compiler.analytic_ik) -------------------------------------
    @cached_property
    def analytic(self) -> Any:
        """The closed-form solver of this robot on this backend (compiled on first use); raises
        NoAnalyticIKError naming what the arm lacks."""
        from symkin.runtime.analytic_ik import compile_analytic

        return compile_analytic(self.model.chain(), self.backend)

    @property
    def has_analytic_ik(self) -> bool:
        """Whether symkin derives a closed-form IK for this arm (cached; see :meth:`ik_all`)."""
        from symkin.compiler.analytic_ik import analytic_refusal

        try:
            chain = self.model.chain()
        except SymkinError:  # several frames, or a mimic joint on the path: no one chain
            return False
        return analytic_refusal(chain, self.backend) is None

    def ik_all(
        self, T: Any, q0: Any = None, joint_limits: bool = True, weights: Any = None, free_joint: Any = None
    ) -> np.ndarray:
        """Every distinct closed-form solution of the pose ``T`` (base frame).

        ``T`` (4, 4) -> (k, n), ordered by ``sum_j weights_j (q_j - q0_j)^2`` when ``q0`` is given;
        ``T`` (N, 4, 4) -> (N, S, n) with NaN rows after each pose's solutions (S: the arm's
        maximum, 8 for a 6R arm). Revolute joints are wrapped by 2 pi into the joint limits where a
        shift allows; with ``joint_limits`` rows outside them are dropped. See
        :mod:`symkin.runtime.analytic_ik`. On the C backend later calls go straight to the compiled
        solver (the same signature, plus ``tol``): no Python frame per pose.

        ``free_joint=(j, values)`` (redundant arms): joint ``j``, the first or the last of the chain,
        takes each of ``values`` (a number or a 1-D array) and the other joints are solved in closed
        form; (N, 4, 4) -> (N, V * S, n). See :mod:`symkin.runtime.free_joint`.
        """
        if free_joint is not None:
            from symkin.runtime.free_joint import free_joint_solver, parse_free_joint

            j, values = parse_free_joint(free_joint)
            if values is None:
                raise ConfigurationError("ik_all needs the values of the free joint: free_joint=(j, values)")
            return free_joint_solver(self.model.chain(), j, self.backend).ik_all(
                T, values, q0, joint_limits, weights
            )
        solver = self.analytic
        if self.backend == "c":
            self.__dict__["ik_all"] = solver.ik_all
        return solver.ik_all(T, q0, joint_limits, weights)
