"""Numerical IK in C (``csrc/symkin_ik.c``) through ctypes: the loop of :mod:`symkin.runtime.ik`.

One :class:`CIKSolver` holds a robot's kinematics and one set of options, with its C config built
once. A single target is one call of a small CPython extension compiled into the solver's library
(``csrc/symkin_ik_py.c``): it takes the ndarray directly, releases the GIL while it solves and
keeps its buffers per call, so several threads can share a solver, and it costs well under a
microsecond on top of the C work. A batch of targets is one ctypes call, which runs LM on 4
targets side by side with the same results as one by one.
Kinematics come from either

- the table-driven ETS interpreter in C (any object with ``n``, ``qlim`` and ``ets`` or
  ``robot.ets``, such as a :class:`symkin.Robot`), or
- a C function ``void fkjac(const double *q, double *T, double *J)`` (``symkin_fkjac_fn``: T
  row-major 4x4, J row-major (6, n) base frame, rows (v, omega)) passed as ``fkjac=`` (a ctypes
  function, or its address) or found as ``kin.c_fkjac``. Whoever passes it keeps its library
  loaded.
"""

from __future__ import annotations

import ctypes
import functools
import os
import weakref
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from symkin.core.arrays import as_config, as_rows, name_of
from symkin.core.pose import pose_array
from symkin.errors import ConfigurationError, PoseError
from symkin.runtime.cext import address, bind_functions, build_extension, csrc, layout
from symkin.runtime.ik_problem import IKOptions, IKResult, check_pose, ets_of, failure_reason, seed_of
from symkin.runtime.memo import per_object

__all__ = [
    "CIKSolver",
    "ik_sources",
    "ik_library",
    "ik_extension",
    "solver_for",
    "options_key",
    "ets_table",
    "register_qp_step",
]

_P = ctypes.c_void_p
_I32, _I64, _U64, _D = ctypes.c_int32, ctypes.c_int64, ctypes.c_uint64, ctypes.c_double
FKJAC = ctypes.CFUNCTYPE(None, _P, _P, _P)  # symkin_fkjac_fn
_METHOD = {"NR": 0, "GN": 1, "LM": 2, "QP": 3}
_DAMPING = {"wampler": 0, "chan": 1, "sugihara": 2}
_AXES = ("tx", "ty", "tz", "Rx", "Ry", "Rz")


class _Config(ctypes.Structure):
    _fields_ = [
        *((f, _I32) for f in ("n", "method", "damping", "pinv", "ilimit", "slimit", "tol_on_E")),
        *((f, _I32) for f in ("joint_limits", "nstarts", "pad_")),
        ("tol", _D),
        ("we", _D * 6),
        *((f, _P) for f in ("lam", "qlo", "qhi", "slo", "shi", "revolute", "starts", "fkjac", "ets")),
        *((f, _P) for f in ("fkjac_batch", "collides", "collision_env", "step", "step_ctx")),
    ]


_STATS = (
    *("success", "iterations", "searches", "limit_rejects", "singular", "status"),
    *("collision_rejects", "pad_"),
)


class _Stats(ctypes.Structure):
    _fields_ = [("residual", _D), *((f, _I32) for f in _STATS)]


STATS_DTYPE = np.dtype([("residual", "f8"), *((f, "i4") for f in _STATS)])


class _ET(ctypes.Structure):
    _fields_ = [("axis", _I32), ("joint", _I32), ("sign", _D), ("c", _D), ("s", _D), ("d", _D)]


class _ETS(ctypes.Structure):
    _fields_ = [("n", _I32), ("len", _I32), ("et", _P)]


def ik_sources() -> dict[str, str]:
    """The C solver's sources (file name -> text): ``symkin_ik.h``, ``symkin_pose.h``, ``symkin_ik.c``,
    ``symkin_ets.c``.

    Compile them together with generated kinematics to get one library exporting both (with
    :data:`IK_CFLAGS`).
    """
    return csrc("symkin_ik.h", "symkin_pose.h", "symkin_ik.c", "symkin_ets.c")


def bind(lib: ctypes.CDLL) -> ctypes.CDLL:
    """Set the argument types of the ``symkin_ik_*`` functions of ``lib`` (and check the layout)."""
    bind_functions(lib, _SIGNATURES)
    layout(lib, "symkin_ik_layout", (ctypes.sizeof(_Stats), ctypes.sizeof(_Config)))
    return lib


_SIGNATURES = {
    "symkin_ik_nmax": (_I32, []),
    "symkin_ik_check_pose": (_I32, [_P, _P]),
    "symkin_ik_pose_error": (None, [_P, _P, _P]),
    "symkin_ik_solve": (_I32, [_P, _P, _P, _U64, _P, _P]),
    "symkin_ik_solve_batch": (_I64, [_P, _I64, _P, _P, _I64, _U64, _P, _P]),
    "symkin_ik_solve_each": (_I64, [_P, _I64, _P, _P, _I64, _U64, _P, _P]),
    "symkin_ik_kin_each": (None, [_P, _I64, _P, _P, _P]),
    "symkin_ik_trace": (_I32, [_P, _P, _P, _I32, _P]),
    "symkin_ik_random_q": (None, [_P, _U64, _I64, _I32, _P]),
    "symkin_ets_fkjac": (None, [_P, _P, _P, _P]),
}


# GCC 12 turns some a*b + c*d / a*b - c*d pairs into vfmaddsub when SLP-vectorising, even under
# -ffp-contract=off; the solver's hot loops are vectorised explicitly and lose nothing without it.
IK_CFLAGS: tuple[str, ...] = ("-fno-tree-slp-vectorize",)


@lru_cache(maxsize=2)
def _ik_build(profile: bool = False) -> tuple[Path, str]:
    """(path of the compiled solver library, name of the extension module inside it); ``profile``:
    the build whose extension times the parts of each call (``profile()``, for symkin bench calls)."""
    sources = {**ik_sources(), **csrc("symkin_ik_py.c", "symkin_pyarray.h")}
    flags = (*IK_CFLAGS, *(("-DSYMKIN_IK_PROFILE",) if profile else ()))
    stem = "symkin_ik_profile" if profile else "symkin_ik"
    return build_extension(sources, stem, "SYMKIN_IK_MODULE", f"_{stem}", flags)


@lru_cache(maxsize=1)
def ik_library() -> ctypes.CDLL:
    """The compiled C solver with the table-driven ETS kinematics (cached; see symkin.emit.c.build)."""
    from symkin.emit.c.build import load_library

    return bind(load_library(_ik_build()[0]))


@lru_cache(maxsize=1)
def ik_library_gil() -> ctypes.CDLL:
    """:func:`ik_library` through :class:`ctypes.PyDLL`: its calls hold the GIL (the QP step's
    embedded OSQP solvers are shared, see :mod:`symkin.runtime.ik_qp_c`)."""
    return bind(ctypes.PyDLL(str(_ik_build()[0])))


@lru_cache(maxsize=2)
def ik_extension(profile: bool = False) -> Any:
    """The extension module of :func:`ik_library`'s library: ``solve`` of one target (see
    ``csrc/symkin_ik_py.c``); ``profile``: that of the timing build (its ``profile()`` returns the
    nanoseconds of each part of the calls so far)."""
    from symkin.emit.c.build import load_extension

    module = load_extension(*reversed(_ik_build(profile)))

    def seed() -> None:  # fresh seeds (seed=None) differ between processes, forked ones included
        module.setup(IKResult, seed_of())

    seed()
    if hasattr(os, "register_at_fork"):
        os.register_at_fork(after_in_child=seed)
    return module


def ets_table(ets: Any) -> tuple[ctypes.Array, _ETS]:
    """The ``symkin_et`` table of an ETS; constants of k*pi/2 rotations are exact (0, +-1)."""
    from symkin.model.kinematics import ROT_SLICES, const_matrix

    rows = []
    for e in ets:
        code = _AXES.index(e.axis.value)
        if e.is_joint:
            rows.append((code, int(e.joint), float(e.sign), 1.0, 0.0, 0.0))
        elif e.axis.is_rotation:
            M = const_matrix(e.axis, e.const)
            j, k = ROT_SLICES[e.axis.index]
            rows.append((code, -1, 1.0, float(M[j, j]), float(M[k, j]), 0.0))
        else:
            rows.append((code, -1, 1.0, 1.0, 0.0, float(e.const.value)))
    table = (_ET * max(len(rows), 1))(*(_ET(*r) for r in rows))
    return table, _ETS(int(ets.n), len(rows), ctypes.addressof(table))


def _addr(a: np.ndarray) -> int:
    return a.ctypes.data


_QP_STEP: Any = None  # QPStep of symkin.runtime.ik_qp_c, which registers it (it sits above this module)


def register_qp_step(make: Any) -> None:
    """Register the maker of method "QP"'s step: ``make(kin, options, environment, **collision)``
    returns an object with ``function`` and ``context`` (a ``symkin_ik_step_fn`` and its argument)
    that keeps them alive. :mod:`symkin.runtime.ik_qp_c` registers its :class:`QPStep` when it is
    imported: the step is the MMC library's (:mod:`symkin.runtime.mmc_c`), whose collision rows
    depend on modules that depend on this one."""
    global _QP_STEP
    _QP_STEP = make


class CIKSolver:
    """The C solver for one kinematics and one set of options (see :func:`symkin.runtime.ik.ik`).

    Args:
        kin: ``n``, ``qlim`` and either ``ets`` (table-driven kinematics) or ``c_fkjac`` (and
            ``c_fkjac_batch``, the generated ``fkine_jacob0_batch``: a batch of LM solves then
            evaluates its four lanes' poses in one four-lane call, the same numbers).
        options: an :class:`IKOptions`, or keyword options of :func:`ik` (method, damping, lam...).
        fkjac: a ``symkin_fkjac_fn`` (ctypes function or address) overriding ``kin``'s kinematics.
        collides: ``(function, env)``: a ``symkin_collides_fn`` (a compiled collision kernel's
            ``skcoll_in_collision_packed``) and the :class:`~symkin.runtime.collision.Packed`
            obstacles it checks against; a converged solution that collides is rejected and the next
            search starts, as for joint limits (the reason counts them).
        lib: a library exporting the ``symkin_ik_*`` functions (default: :func:`ik_library`).
        environment: method ``"QP"``: obstacles whose collision rows the QP step keeps (with
            ``collision`` the MMC's row options: :class:`~symkin.runtime.ik_qp_c.QPStep`).

    Method ``"QP"`` needs compiled C kinematics (its step is the MMC's, :mod:`symkin.runtime.ik_qp_c`)
    and solves with the GIL held (the embedded OSQP solvers of its step are shared).
    """

    def __init__(
        self,
        kin: Any,
        options: IKOptions | None = None,
        *,
        fkjac: Any = None,
        lib: ctypes.CDLL | None = None,
        collides: Any = None,
        environment: Any = None,
        collision: dict[str, Any] | None = None,
        **kwargs: Any,
    ) -> None:
        opt = options if options is not None else IKOptions.of(kin, **kwargs)
        if options is not None and kwargs:
            raise TypeError("pass either options or keyword options, not both")
        self._qp = None
        own = lib is None  # the default library, with the extension's one-target entry point
        if opt.method == "QP":  # the QP step: an MMC controller's, with the GIL held
            if _QP_STEP is None:  # pragma: no cover - registered when symkin.runtime.kinematics loads
                raise ConfigurationError("method='QP' in C needs symkin.runtime.ik_qp_c (import symkin)")
            self._qp = _QP_STEP(kin, opt, environment, **(collision or {}))
            lib = lib if lib is not None else ik_library_gil()
        self.lib = bind(lib) if lib is not None else ik_library()
        nmax = self.lib.symkin_ik_nmax()
        if opt.n > nmax or opt.n < 1:
            raise ConfigurationError(
                f"the C IK solver handles 1..{nmax} joints, not {opt.n}; use backend='numpy'"
            )
        self.options, self.n, self.kin = opt, opt.n, kin
        self._name = name_of(kin)
        batch = None
        if fkjac is None:
            fkjac = getattr(kin, "c_fkjac", None)
            batch = getattr(kin, "c_fkjac_batch", None) if fkjac is not None else None
        self._fkjac_ref, self._batch_ref = fkjac, batch
        self._fkjac_addr = address(fkjac)
        self._table = self._ets = None
        if not self._fkjac_addr:
            ets = ets_of(kin)
            if ets is None:
                raise TypeError("CIKSolver needs kinematics: kin.ets (a Robot), kin.c_fkjac or fkjac=")
            self._table, self._ets = ets_table(ets)
        (qlo, qhi), (slo, shi) = opt.qlim, opt.sample
        arrays = {"lam": opt.lam, "qlo": qlo, "qhi": qhi, "slo": slo, "shi": shi, "starts": opt.starts}
        self._keep = {name: np.ascontiguousarray(a, dtype=float) for name, a in arrays.items()}
        self._keep["revolute"] = np.ascontiguousarray(opt.revolute, dtype=np.int32)
        cfg = _Config()
        cfg.n, cfg.method, cfg.damping = opt.n, _METHOD[opt.method], _DAMPING[opt.damping]
        cfg.pinv, cfg.ilimit, cfg.slimit = int(opt.pinv), opt.ilimit, opt.slimit
        cfg.tol_on_E, cfg.joint_limits, cfg.tol = int(opt.tol_on == "E"), int(opt.joint_limits), opt.tol
        cfg.nstarts = len(opt.starts)
        cfg.we[:] = [float(w) for w in opt.we]
        for name, arr in self._keep.items():
            setattr(cfg, name, _addr(arr) if arr.size else None)
        cfg.fkjac = self._fkjac_addr or None
        cfg.fkjac_batch = address(batch) or None
        self._collides = collides  # kept alive: the function's library and the packed obstacles
        if collides is not None:
            fn, env = collides
            cfg.collides, cfg.collision_env = address(fn), env.address
        cfg.ets = ctypes.addressof(self._ets) if self._ets is not None else None
        if self._qp is not None:
            cfg.step, cfg.step_ctx = self._qp.function, self._qp.context
        self._cfg = cfg
        self._cfg_addr = ctypes.addressof(cfg)
        # one target: the extension's solve when the library is the default one (it has it), else
        # a batch of one through ctypes; either way with buffers per call (thread-safe)
        # fast(Tep, q0=None, seed=None): an IKResult, or None when an argument needs checking
        self.fast = functools.partial(ik_extension().solve, self._cfg_addr, self._reason) if own else None

    def bind(self, fallback: Any, by_options: dict[tuple, Any] | None = None) -> Any:
        """A callable ``ik(Tep, *args, **kwargs)`` for a kinematics object's ``ik``: one target
        alone solves in one C call (as :attr:`fast`, no Python frame); so does one target with
        keyword options (``q0``, ``seed`` and options whose tuple of ``(name, value)`` pairs, in
        call order, is a key of ``by_options``, whose values are callables this method returned).
        Any other call, or a target that needs checking, goes to ``fallback`` with the same
        arguments. None when this solver uses another library than the default one."""
        if self.fast is None:
            return None
        return ik_extension().bind(self._cfg_addr, self._reason, fallback, self, by_options)

    def __repr__(self) -> str:
        o = self.options
        kin = "fkjac" if self._fkjac_addr else "ets table"
        return f"CIKSolver(n={o.n}, method={o.method}, damping={o.damping}, lam={o.lam[0]:g}, kin={kin})"

    # -- solving --------------------------------------------------------------------------
    def solve(self, Tep: Any, q0: Any = None, seed: int | None = None) -> IKResult:
        """Solve one target (4, 4) or a batch (N, 4, 4); same arguments and result as :func:`ik`.

        Thread-safe: one target is solved without the GIL (with it for method "QP"), with buffers of
        its own.
        """
        if self.fast is not None:
            res = self.fast(Tep, q0, seed)
            if res is not None:
                return res
        return self._solve_checked(Tep, q0, seed)

    def _reason(self, residual: float, limit_rejects: int, singular: int, collisions: int = 0) -> str:
        o = self.options
        return failure_reason(False, residual, limit_rejects, singular, o.ilimit, o.slimit, collisions)

    def _solve_checked(self, Tep: Any, q0: Any, seed: Any) -> IKResult:
        """:meth:`solve` with every argument validated first (detailed errors) and batches."""
        seed = seed_of(seed)
        T = np.ascontiguousarray(pose_array(Tep))  # the pose rule's conversion: no complex, strings...
        if T.shape != (4, 4):
            return self._solve_batch(T, q0, seed)
        check_pose(T)  # the detailed PoseError
        Q0 = None if q0 is None else np.ascontiguousarray(self._check_q0(q0))
        if self.fast is not None:
            res = self.fast(T, Q0, seed)
            if res is not None:
                return res
        return self._solve_batch(T[None], None if Q0 is None else Q0[None], seed)[0]  # another library

    def _check_q0(self, q0: Any) -> np.ndarray:
        """q0 of one target: the joint-value rule of q (as_config), as the NumPy solver's."""
        return as_config(q0, self.n, self._name, "q0")

    def _solve_batch(self, T: np.ndarray, q0: Any, seed: int) -> IKResult:
        if T.ndim != 3 or T.shape[1:] != (4, 4):
            check_pose(T)  # the rule's PoseError for the shape
        T = np.ascontiguousarray(T, dtype=float)
        Q0 = None  # the rule of the NumPy solver: (n,) for all targets or (N, n)
        if q0 is not None:
            Q0 = np.ascontiguousarray(as_rows(q0, self.n, len(T), False, self._name, "q0"))
        q, st = self._call(self.lib.symkin_ik_solve_batch, T, Q0, seed)
        success = st["success"].astype(bool)
        columns = ("success", "residual", "limit_rejects", "singular", "collision_rejects")
        reason = tuple(
            "success" if ok else self._reason(r, lr, sg, cr)
            for ok, r, lr, sg, cr in zip(*(st[c].tolist() for c in columns))
        )
        return IKResult(
            q, success, st["iterations"].copy(), st["searches"].copy(), st["residual"].copy(), reason
        )

    # -- inspection -----------------------------------------------------------------------
    def trace(self, Tep: Any, q0: Any, steps: int) -> np.ndarray:
        """Iterates q_0 .. q_steps of one search from q0 (like :func:`symkin.runtime.ik.ik_trace`)."""
        T, single = check_pose(Tep)
        if not single:
            raise PoseError("trace takes one target pose (4, 4)")
        T = np.ascontiguousarray(T[0])
        q0 = np.ascontiguousarray(self._check_q0(q0))
        out = np.zeros((int(steps) + 1, self.n))
        k = self.lib.symkin_ik_trace(self._cfg_addr, _addr(T), _addr(q0), int(steps), _addr(out))
        return out[:k]

    def fkine_jacob0(self, q: Any) -> tuple[np.ndarray, np.ndarray]:
        """The C kinematics the solver uses: T (4, 4) and J0 (6, n) at q (n,)."""
        q = np.ascontiguousarray(self._check_q0(q))
        T, J = np.zeros((4, 4)), np.zeros((6, self.n))
        if self._fkjac_addr:
            FKJAC(self._fkjac_addr)(_addr(q), _addr(T), _addr(J))
        else:
            self.lib.symkin_ets_fkjac(ctypes.addressof(self._ets), _addr(q), _addr(T), _addr(J))
        return T, J

    def pose_error(self, Te: Any, Tep: Any) -> np.ndarray:
        """e of eq 37 computed by the C code, (6,)."""
        a, b = (np.ascontiguousarray(np.asarray(x, dtype=float).reshape(4, 4)) for x in (Te, Tep))
        e = np.zeros(6)
        self.lib.symkin_ik_pose_error(_addr(a), _addr(b), _addr(e))
        return e

    # -- benchmarks (symkin bench calls) ---------------------------------------------------
    def solve_each(self, Tep: np.ndarray, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """The scalar batch: targets ``Tep`` (N, 4, 4) solved one at a time in one C call, as
        ``solve(Tep[i], seed=seed + i)`` (no lanes, no Python per target); (q (N, n), success (N,))."""
        q, st = self._call(
            self.lib.symkin_ik_solve_each, np.ascontiguousarray(Tep, dtype=float), None, seed_of(seed)
        )
        return q, st["success"].astype(bool)

    def _call(
        self, fn: Any, T: np.ndarray, Q0: np.ndarray | None, seed: int
    ) -> tuple[np.ndarray, np.ndarray]:
        """(q (N, n), stats (N,)) of ``fn`` (``symkin_ik_solve_batch`` or ``_each``) on the targets ``T``
        (N, 4, 4) from ``Q0`` (N, n) or None; PoseError for the first target that is not a pose."""
        q, st = np.empty((len(T), self.n)), np.zeros(len(T), dtype=STATS_DTYPE)
        stride = 0 if Q0 is None else self.n
        bad = fn(
            self._cfg_addr,
            len(T),
            _addr(T),
            None if Q0 is None else _addr(Q0),
            stride,
            seed,
            _addr(q),
            _addr(st),
        )
        if bad >= 0:
            check_pose(T)  # the detailed PoseError
            raise PoseError(f"target [{bad}] is not a valid pose (code {st['status'][bad]})")
        return q, st

    def kin_each(self, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The solver's kinematics at each row of ``Q`` (N, n), one at a time in one C call (for
        timing one evaluation); T (4, 4) and J0 (6, n) of the last row."""
        Q = np.ascontiguousarray(Q, dtype=float).reshape(-1, self.n)
        T, J = np.zeros((4, 4)), np.zeros((6, self.n))
        self.lib.symkin_ik_kin_each(self._cfg_addr, len(Q), _addr(Q), _addr(T), _addr(J))
        return T, J

    def profiled(self) -> tuple[Any, Any] | None:
        """``(solve, parts)``: ``solve(Tep, q0=None, seed=None)`` as :attr:`fast`, from the build of
        the extension that times each part of a call, and ``parts()``: the calls since the last
        ``parts()`` and their nanoseconds in arguments, GIL release and retake, the solver and the
        result, summed (``(calls, args, gil, solver, result)``). None with another library."""
        if self.fast is None:
            return None
        ext = ik_extension(True)
        return functools.partial(ext.solve, self._cfg_addr, self._reason), ext.profile

    def random_q(self, seed: int, count: int, stream: int = 0) -> np.ndarray:
        """The first ``count`` random restarts of the stream (seed, stream), (count, n)."""
        out = np.zeros((int(count), self.n))
        self.lib.symkin_ik_random_q(self._cfg_addr, seed_of(seed), int(stream), int(count),
                                    _addr(out))  # fmt: skip
        return out


_SOLVERS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def options_key(opt: IKOptions) -> tuple:
    arrays = (opt.lam, opt.we, opt.qlim, opt.starts, opt.rho_i, opt.rho_s)
    return (opt.method, opt.damping, opt.pinv, opt.ilimit, opt.slimit, opt.tol, opt.tol_on, opt.joint_limits,
            *(a.tobytes() for a in arrays), opt.starts.shape, opt.slack_gain, opt.manipulability,
            opt.xi)  # fmt: skip


def solver_for(kin: Any, opt: IKOptions) -> CIKSolver:
    """A :class:`CIKSolver` for ``kin`` and ``opt``, memoised per kinematics object and options."""
    return per_object(_SOLVERS, kin, options_key(opt), lambda: CIKSolver(kin, opt))
