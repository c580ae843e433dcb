"""``symkin bench kin``: kinematics per call and batched, for each backend and call path.

Per call (one configuration from Python): the C backend's extension module, the same C functions
through ctypes (pointers and output buffers cached) and cffi (when installed), the NumPy and
CasADi backends and the numeric reference; roboticstoolbox-python and Pinocchio when installed
(the ``compare`` extra), all measured in the same run, with ratios; Pinocchio's FK is that of one
frame (``forwardKinematics`` + ``updateFramePlacement``). Batched: throughput on N random
configurations on one core, through the extension (``c``, ``numpy``: validation and output arrays
included) and through the generated ``<f>_batch`` kernels alone, built as they are (four
configurations per step) and with ``-DSYMKIN_SCALAR`` (one per step), and the four-lane kernels
called on blocks of 1 000 configurations whose outputs stay in the cache (their arithmetic
throughput, without a large batch's memory traffic). Times are CPU times of the
calling thread (``time.thread_time``), so that other processes of a shared machine do not count.
"""

from __future__ import annotations

import ctypes
import functools
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from symkin.bench.common import best_of, cells, guarded, optional, rows_per_s, table, with_lanes

__all__ = ["run_kin", "format_kin", "per_call_us", "interleaved_us", "pinocchio_model", "rtb_ets"]

FUNCS = ("fkine", "jacob0", "hessian0")
BATCH_FUNCS = ("fkine", "jacob0", "fkine_jacob0", "hessian0")


def per_call_us(
    f: Callable[[], Any],
    budget: float = 0.25,
    repeats: int = 5,
    clock: Callable[[], float] = time.perf_counter,
) -> float:
    """Best-of-``repeats`` mean time of one call of ``f`` in microseconds, by ``clock`` (wall time;
    ``time.thread_time`` counts only the calling thread's CPU time, so that other processes of a
    shared machine do not)."""
    f()
    n, t = 1, 0.0
    while t < budget / repeats / 4:  # calls per timing: a quarter of the budget of one repeat
        n *= 4
        t = best_of(lambda n=n: _calls(f, n), 1, clock)
    return min(t, best_of(lambda: _calls(f, n), repeats - 1, clock)) / n * 1e6


def _calls(f: Callable[[], Any], n: int) -> None:
    for _ in range(n):
        f()


def interleaved_us(
    paths: dict[tuple[str, str], Callable[[], Any]],
    budget: float,
    rounds: int = 4,
    clock: Callable[[], float] = time.thread_time,
) -> dict[str, dict[str, float]]:
    """Microseconds per call of each path (:func:`per_call_us`), measured in turn for ``rounds``
    rounds (about ``budget`` seconds per path in all) and the best round kept: a burst of load on a
    shared machine then hits every path of a comparison, not just one. Keys (row, column) ->
    {row: {column: us}}."""
    best: dict[tuple[str, str], float] = {}
    for _ in range(rounds):
        for key, f in paths.items():
            best[key] = min(best.get(key, math.inf), per_call_us(f, budget=budget / rounds, clock=clock))
    out: dict[str, dict[str, float]] = {}
    for (row, col), us in best.items():
        out.setdefault(row, {})[col] = us
    return out


def _sizes(n: int) -> dict[str, int]:
    """The output size of each of FUNCS for n joints."""
    return {"fkine": 16, "jacob0": 6 * n, "hessian0": n * 6 * n}


def _ctypes_calls(kin: Any, q: np.ndarray) -> dict[str, Callable[[], Any]]:
    """The C entry points through ctypes with cached pointers and buffers (the best ctypes can do)."""
    lib, prefix = ctypes.CDLL(str(kin.path)), kin.c_prefix
    qbuf = np.ascontiguousarray(q, dtype=float)
    calls = {}
    for name, size in _sizes(kin.n).items():
        out = np.empty(size)
        fn = getattr(lib, f"{prefix}_{name}")
        fn.restype = None
        fn.argtypes = (ctypes.c_void_p, ctypes.c_void_p)
        qp, op = qbuf.ctypes.data, out.ctypes.data

        def call(fn: Any = fn, qp: int = qp, op: int = op, out: np.ndarray = out) -> np.ndarray:
            fn(qp, op)
            return out

        calls[name] = call
    return calls


def _cffi_calls(kin: Any, q: np.ndarray) -> dict[str, Callable[[], Any]] | None:
    cffi = optional("cffi")
    if cffi is None:
        return None
    ffi, prefix = cffi.FFI(), kin.c_prefix
    ffi.cdef("".join(f"void {prefix}_{f}(const double *q, double *out);" for f in FUNCS))
    lib = ffi.dlopen(str(kin.path))
    calls = {}
    for name, size in _sizes(kin.n).items():
        fn = getattr(lib, f"{prefix}_{name}")

        def call(fn: Any = fn, size: int = size) -> np.ndarray:
            out = np.empty(size)
            fn(ffi.from_buffer("double[]", q), ffi.from_buffer("double[]", out))
            return out

        calls[name] = call
    return calls


def pinocchio_model(robot: Any) -> tuple[Any, Any, int] | None:
    """A Pinocchio model of an ETS robot (joints along +-x/y/z), its data and the end-effector frame id."""
    pin = optional("pinocchio")
    if pin is None:
        return None
    from symkin.model.kinematics import const_matrix

    model = pin.Model()
    parent = 0
    M = np.eye(4)
    for e in robot.ets:
        if not e.is_joint:
            M = M @ const_matrix(e.axis, e.const)
            continue
        axis = np.zeros(3)
        axis[e.axis.index] = e.sign
        if e.axis.is_rotation:
            joint = pin.JointModelRevoluteUnaligned(axis)
        else:
            joint = pin.JointModelPrismaticUnaligned(axis)
        parent = model.addJoint(parent, joint, pin.SE3(M[:3, :3], M[:3, 3]), f"j{e.joint}")
        M = np.eye(4)
    frame = model.addFrame(pin.Frame("ee", parent, pin.SE3(M[:3, :3], M[:3, 3]), pin.FrameType.OP_FRAME))
    return model, model.createData(), frame


def pinocchio_calls(robot: Any, q: np.ndarray) -> dict[str, Callable[[], Any]] | None:
    """One configuration ``q`` per call through Pinocchio (:func:`pinocchio_model`; None without it),
    the end-effector frame's: ``fkine`` (``forwardKinematics`` + ``updateFramePlacement``),
    ``fkine_all_frames`` (``framesForwardKinematics``), ``jacob0`` (``computeJointJacobians`` +
    ``getFrameJacobian``), ``frame_jacobian`` (``computeFrameJacobian``), ``manipulability``
    (sqrt(det(J J^T)) of that Jacobian through numpy) and ``hessian0``; LOCAL_WORLD_ALIGNED."""
    pm = pinocchio_model(robot)
    if pm is None:
        return None
    import pinocchio as pin

    model, data, fid = pm
    lwa = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
    pin.computeJointJacobians(model, data, q)

    def fk() -> Any:  # the pose of one frame: joint placements, then that frame's
        pin.forwardKinematics(model, data, q)
        return pin.updateFramePlacement(model, data, fid)

    def fk_all() -> Any:
        pin.framesForwardKinematics(model, data, q)
        return data.oMf[fid]

    def jac() -> Any:
        pin.computeJointJacobians(model, data, q)
        return pin.getFrameJacobian(model, data, fid, lwa)

    def manip() -> float:
        J = pin.computeFrameJacobian(model, data, q, fid, lwa)
        return math.sqrt(max(float(np.linalg.det(J @ J.T)), 0.0))

    def hess() -> Any:
        pin.computeJointKinematicHessians(model, data, q)
        return pin.getJointKinematicHessian(model, data, model.frames[fid].parentJoint, lwa)

    return {
        "fkine": fk,
        "fkine_all_frames": fk_all,
        "jacob0": jac,
        "frame_jacobian": lambda: pin.computeFrameJacobian(model, data, q, fid, lwa),
        "manipulability": manip,
        "hessian0": hess,
    }


def _peer_calls(robot: Any, q: np.ndarray) -> dict[str, dict[str, Callable[[], Any]]]:
    peers: dict[str, dict[str, Callable[[], Any]]] = {}
    pin = pinocchio_calls(robot, q)
    if pin is not None:
        peers["pinocchio"] = {f: pin[f] for f in FUNCS}
    rtb = optional("roboticstoolbox")
    if rtb is not None:
        ets = rtb_ets(rtb, robot)
        peers["rtb"] = {
            "fkine": lambda: ets.eval(q),
            "jacob0": lambda: ets.jacob0(q),
            "hessian0": lambda: ets.hessian0(q),
        }
    return peers


def rtb_ets(rtb: Any, robot: Any) -> Any:
    """The same ETS in roboticstoolbox-python (flipped joints included)."""
    out = []
    for e in robot.ets:
        make = getattr(rtb.ET, e.axis.value)
        out.append(make(jindex=e.joint, flip=e.flip) if e.is_joint else make(e.const.value))
    return rtb.ETS(out)


def rtb_solve(
    solve: Callable[[np.ndarray], Any], Tep: Any
) -> tuple[float, np.ndarray, np.ndarray, np.ndarray]:
    """A roboticstoolbox-python IK ``solve(T)`` called once per target of ``Tep`` (N, 4, 4) after a
    warm-up call, by the CPU time of this thread: (seconds per solve, q (N, n), success (N,),
    iterations (N,))."""
    solve(Tep[0])
    t0 = time.thread_time()
    out = [solve(T) for T in Tep]
    seconds = (time.thread_time() - t0) / len(out)
    q = np.array([np.asarray(o.q, dtype=float) for o in out])
    return seconds, q, np.array([bool(o.success) for o in out]), np.array([int(o.iterations) for o in out])


def rtb_ik_lm(
    robot: Any, Tep: Any, tol: float, report: Callable[[float, np.ndarray, np.ndarray], Any], q0: Any = None
) -> Any:
    """roboticstoolbox-python's C++ ``ik_LM`` (Chan, lambda 0.1, 100 x 30; ``tol`` on E = |e|^2 / 2)
    on the same ETS, from ``q0`` (None: its random starts), on each target of ``Tep``
    (:func:`rtb_solve`): ``report(seconds per solve, success (N,), iterations (N,))``; None without
    roboticstoolbox-python, ``{"error": ...}`` when it fails (:func:`symkin.bench.common.guarded`)."""
    rtb = optional("roboticstoolbox")
    if rtb is None:
        return None

    def run() -> Any:
        lm = functools.partial(rtb_ets(rtb, robot).ik_LM, q0=q0, ilimit=30, slimit=100, tol=tol, k=0.1)
        seconds, _, success, iterations = rtb_solve(lm, Tep)
        return report(seconds, success, iterations)

    return guarded(run)


def run_kin(robot_spec: Any = "panda", batch: int = 100_000, seed: int = 0, progress: bool = True) -> dict:
    """Measure every backend and call path; returns a JSON-able dict (see :func:`format_kin`)."""
    import symkin
    from symkin.model.resolve import resolve_robot

    robot = resolve_robot(robot_spec)
    q = robot.random_q(seed=seed)
    kins = {b: with_lanes(symkin.compile(robot, backend=b)) for b in ("c", "numpy", "casadi")}
    paths: dict[str, dict[str, Callable[[], Any]]] = {
        "c (extension)": {f: (lambda f=f: getattr(kins["c"], f)(q)) for f in FUNCS},
        "c (ctypes, cached)": _ctypes_calls(kins["c"], q),
    }
    cffi_calls = _cffi_calls(kins["c"], q)
    if cffi_calls:
        paths["c (cffi)"] = cffi_calls
    for b in ("numpy", "casadi"):
        paths[b] = {f: (lambda f=f, b=b: getattr(kins[b], f)(q)) for f in FUNCS}
    paths["reference"] = {f: (lambda f=f: getattr(robot, f)(q)) for f in FUNCS}
    paths.update(_peer_calls(robot, q))
    from symkin.core.progress import bar

    items = [(p, f) for p in paths for f in FUNCS]
    per_call: dict[str, dict[str, float]] = {p: {} for p in paths}
    for p, f in bar(items, progress, desc="per call"):
        per_call[p][f] = per_call_us(paths[p][f], clock=time.thread_time)
    Q = robot.random_q(batch, seed=seed + 1)
    kernels = {b: {f: getattr(kins[b], f) for f in BATCH_FUNCS} for b in ("c", "numpy")}
    kernels.update(_c_builds(robot, kins["c"], Q))
    batched = {label: {f: rows_per_s(fn, Q) / 1e6 for f, fn in fns.items()} for label, fns in kernels.items()}
    ext = per_call["c (extension)"]
    ratios = {p: {f: per_call[p][f] / ext[f] for f in FUNCS} for p in ("pinocchio", "rtb") if p in per_call}
    return {
        "robot": robot.name,
        "n": robot.n,
        "batch": batch,
        "per_call_us": per_call,
        "batched_M_per_s": batched,
        "speedup_of_c_over": ratios,
    }


def _c_builds(robot: Any, kin: Any, Q: np.ndarray) -> dict[str, dict[str, Callable[[np.ndarray], Any]]]:
    """The generated ``<f>_batch`` entry points through ctypes (outputs preallocated: the kernels
    alone), of the default build (four configurations per step where the compiler has vector
    extensions) and of the same sources built with ``-DSYMKIN_SCALAR`` (one per step)."""
    import symkin
    from symkin.emit.c.build import compile_library, load_library

    files = symkin.generate(robot, "c")
    sources = {k: v for k, v in files.items() if not k.endswith("_pymodule.c")}
    prefix, n = kin.c_prefix, robot.n
    sizes = {"fkine": (16,), "jacob0": (6 * n,), "fkine_jacob0": (16, 6 * n), "hessian0": (6 * n * n,)}
    builds = {}
    for label, flags in (("c kernels, 4 lanes", ()), ("c kernels, scalar", ("-DSYMKIN_SCALAR",))):
        lib = load_library(compile_library(sources, f"{prefix}_bench{len(flags)}", extra_cflags=flags))
        fns = {}
        for f, shape in sizes.items():
            fn = getattr(lib, f"{prefix}_{f}_batch")
            fn.restype = None
            fn.argtypes = [ctypes.c_void_p] * (1 + len(shape)) + [ctypes.c_ssize_t]
            outs = [np.empty(len(Q) * size) for size in shape]
            fns[f] = _KernelCall(fn, outs, n)
        builds[label] = fns
        if not flags:  # the same kernels on blocks whose outputs stay in the cache
            builds[f"4 lanes, {BLOCK} per call"] = {f: fn.blocks for f, fn in fns.items()}
    return builds


BLOCK = 1000  # configurations per call of the cache-resident rows of bench kin


class _KernelCall:
    """One ``<f>_batch`` kernel with its preallocated output arrays ``outs``: called on Q,
    all rows in one call; ``blocks(Q)``: BLOCK rows per call, every block's outputs in the first
    rows of the output arrays (the kernels' throughput without a large batch's memory traffic)."""

    def __init__(self, fn: Any, outs: list[np.ndarray], n: int) -> None:
        self.fn, self.arrays, self.row = fn, outs, 8 * n  # the arrays stay alive with the call
        self.outs = [o.ctypes.data for o in outs]

    def __call__(self, Q: np.ndarray) -> None:
        Q = np.ascontiguousarray(Q, dtype=float)
        self.fn(Q.ctypes.data, *self.outs, len(Q))

    def blocks(self, Q: np.ndarray) -> None:
        Q = np.ascontiguousarray(Q, dtype=float)
        fn, outs, base = self.fn, self.outs, Q.ctypes.data
        for i in range(0, len(Q), BLOCK):
            fn(base + i * self.row, *outs, min(BLOCK, len(Q) - i))


def format_kin(r: dict) -> str:
    rows = [cells(path, row, FUNCS, "{:.3f}") for path, row in r["per_call_us"].items()]
    rows += [
        cells(f"c speed-up vs {peer}", row, FUNCS, "{:.1f}x") for peer, row in r["speedup_of_c_over"].items()
    ]
    lines = [f"symkin bench kin: {r['robot']} ({r['n']} joints), one configuration per call from Python", ""]
    lines += table(["path", *(f"{f} (us)" for f in FUNCS)], rows)
    if not r["speedup_of_c_over"]:
        lines.append(
            "(install the compare extra, pip install 'symkin[compare]', to measure RTB and Pinocchio)"
        )
    batched = r["batched_M_per_s"]
    rows = [cells(b, row, BATCH_FUNCS, "{:.2f}") for b, row in batched.items()]
    four, one = batched.get("c kernels, 4 lanes"), batched.get("c kernels, scalar")
    if four and one:
        rows.append(
            cells("4 lanes vs scalar", {f: four[f] / one[f] for f in BATCH_FUNCS}, BATCH_FUNCS, "{:.2f}x")
        )
    lines += ["", f"batched, {r['batch']} configurations, one core (million per second)"]
    return "\n".join(lines + table(["backend", *BATCH_FUNCS], rows))
