"""``symkin bench diff``: the JAX and PyTorch backends against pytorch_kinematics on the CPU, in one run.

The same robot on both sides: pytorch_kinematics builds its chain from the URDF symkin writes of
the robot (:func:`symkin.bench.urdf_text.chain_urdf`; the report gives the largest difference of
the two FKs). For each dtype (float64, float32) and batch size (1, 1024, 100000 by default) it
times forward kinematics (the end-effector pose) and the base-frame Jacobian of
pytorch_kinematics (``forward_kinematics(q, end_only=True)``, ``jacobian(q)``), of symkin's
PyTorch code as it is (eager) and under ``torch.compile``, and of symkin's JAX code under
``jax.jit``: the least wall time over ``rounds`` rounds, every path called once per round in turn
(so a burst of load on a shared machine hits all of them), after a first call whose time is
reported apart as the warm-up (``torch.compile`` and ``jax.jit`` compile then). The clock is the
process's CPU time (``time.process_time``: every thread of the process, XLA's included), so that
other processes on a shared machine do not count; the warm-ups are wall time.

IK: ``problems`` reachable targets (poses of random configurations within the limits), 10 starts x
30 iterations per target on every side: pytorch_kinematics' ``PseudoInverseIK`` as its README
configures it (``lr=0.2``, early stopping), symkin's LM (``slimit=10, ilimit=30``). A target counts
as solved when the returned q (its first converged start, else its best) is within the joint
limits and its pose, by symkin's numeric reference, is within 1 mm and 0.01 rad of the target
(pytorch_kinematics' default tolerances).

The libraries run on one thread each (``torch.set_num_threads(1)``; XLA's CPU client as it comes:
its elementwise loops run on one thread), so the figures compare code, not cores.

``device="cuda"`` runs every path on the GPU instead (``scripts/gpu_check.py``): the arrays and
pytorch_kinematics' chain on the first CUDA device, JAX on its first GPU device, and the clock
the wall time of a call that waits for the device (``torch.cuda.synchronize``,
``block_until_ready``).
"""

from __future__ import annotations

import functools
import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from symkin.bench.common import interleaved, optional
from symkin.errors import MissingExtraError

__all__ = [
    "DiffRow",
    "IKRow",
    "DiffReport",
    "run_diff",
    "format_diff",
    "pk_chain",
    "BATCHES",
    "POS_TOL",
    "ROT_TOL",
]

BATCHES = (1, 1024, 100_000)
POS_TOL, ROT_TOL = 1e-3, 1e-2  # a solved IK target: position (m) and rotation (rad) errors
_CLOCK = time.process_time  # CPU time of the whole process (XLA's threads too)
_WALL = time.perf_counter


@dataclass(frozen=True)
class DiffRow:
    """One measured path: ``what`` (fkine or jacob0), ``path`` (pk, torch, torch.compile, jax.jit),
    dtype, batch, the least time of a call (s) and the first call's (s)."""

    what: str
    path: str
    dtype: str
    batch: int
    seconds: float
    warmup: float


@dataclass(frozen=True)
class IKRow:
    path: str
    dtype: str
    problems: int
    seconds: float
    warmup: float
    solved: float  # fraction of targets solved (the module docstring's criterion)
    median_pos: float  # m
    median_rot: float  # rad


@dataclass(frozen=True)
class DiffReport:
    robot: str
    rows: tuple[DiffRow, ...]
    ik: tuple[IKRow, ...]
    agreement: float  # largest |T_pk - T_symkin| over the FK rows' configurations
    notes: tuple[str, ...] = field(default_factory=tuple)
    device: str = "cpu"

    def as_dict(self) -> dict[str, Any]:
        return {
            "robot": self.robot,
            "rows": [r.__dict__ for r in self.rows],
            "ik": [r.__dict__ for r in self.ik],
            "agreement": self.agreement,
            "notes": list(self.notes),
            "device": self.device,
        }


def pk_chain(robot: Any, dtype: Any, device: str = "cpu") -> Any:
    """pytorch_kinematics' serial chain of ``robot`` (from :func:`chain_urdf`) in ``dtype`` on ``device``."""
    import pytorch_kinematics as pk

    from symkin.bench.urdf_text import chain_urdf

    return pk.build_serial_chain_from_urdf(chain_urdf(robot).encode(), "ee").to(dtype=dtype, device=device)


def _timed(
    paths: dict[str, Callable[[], Any]], rounds: int, clock: Callable[[], float] = _CLOCK
) -> tuple[dict[str, float], dict[str, float]]:
    """(least ``clock`` time, first call's wall time) per path (:func:`symkin.bench.common.interleaved`)."""
    first = {}
    for key, f in paths.items():
        t0 = _WALL()
        f()
        first[key] = _WALL() - t0
    best, _ = interleaved(paths, rounds, clock)
    return best, first


def _kin_paths(
    what: str, kins: dict[str, Any], chain: Any, Q: dict[str, Any], sync: Callable[[], Any] = lambda: None
) -> dict[str, Callable[[], Any]]:
    """The calls of ``what`` for one batch: pk, symkin eager PyTorch, torch.compile, jax.jit (the
    PyTorch ones followed by ``sync``, which waits for the device)."""
    paths: dict[str, Callable[[], Any]] = {}
    if chain is not None:
        if what == "fkine":
            paths["pk"] = lambda: chain.forward_kinematics(Q["torch"], end_only=True).get_matrix()
        else:
            paths["pk"] = lambda: chain.jacobian(Q["torch"])
    if "torch" in kins:
        paths["torch"] = partial_call(getattr(kins["torch"], what), Q["torch"])
        if "torch.compile" in kins:
            paths["torch.compile"] = partial_call(kins["torch.compile"][what], Q["torch"])
    paths = {key: _then(f, sync) for key, f in paths.items()}
    if "jax" in kins:
        fn = getattr(kins["jax"], what)
        paths["jax.jit"] = lambda: fn(Q["jax"]).block_until_ready()
    return paths


def partial_call(fn: Callable[[Any], Any], q: Any) -> Callable[[], Any]:
    return lambda: fn(q)


def _then(f: Callable[[], Any], sync: Callable[[], Any]) -> Callable[[], Any]:
    """f, then ``sync()``; f's result."""

    def call() -> Any:
        out = f()
        sync()
        return out

    return call


def _ik_errors(robot: Any, q: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Position and rotation errors of the poses of q against the targets T, and whether q is
    within the joint limits (symkin's numeric reference)."""
    from symkin.model.orientation import angle_axis

    F = robot.fkine(q)
    pos = np.linalg.norm(F[:, :3, 3] - T[:, :3, 3], axis=1)
    rot = np.linalg.norm(angle_axis(T[:, :3, :3] @ np.swapaxes(F[:, :3, :3], 1, 2)), axis=1)
    lo, hi = robot.qlim
    return pos, rot, ((q >= lo - 1e-9) & (q <= hi + 1e-9)).all(axis=1)


def _ik_row(path: str, dtype: str, robot: Any, T: np.ndarray, solve: Callable[[], np.ndarray],
            rounds: int, clock: Callable[[], float] = _CLOCK) -> IKRow:  # fmt: skip
    best, first = _timed({path: solve}, rounds, clock)
    q = solve()
    pos, rot, inside = _ik_errors(robot, q, T)
    solved = float(np.mean((pos <= POS_TOL) & (rot <= ROT_TOL) & inside))
    return IKRow(
        path, dtype, len(T), best[path], first[path], solved, float(np.median(pos)), float(np.median(rot))
    )


def _ik_q(kin: Any, T: Any, seed: int, tol: float) -> np.ndarray:
    """q (N, n) of symkin's IK (PyTorch or JAX backend) on the targets T: 10 starts x 30 iterations."""
    q = kin.ik(T, slimit=10, ilimit=30, seed=seed, tol=tol).q
    return np.asarray(q.detach().cpu().numpy() if hasattr(q, "detach") else q, dtype=float)


def _pk_ik(chain: Any, robot: Any, torch: Any, Tt: Any, seed: int) -> Callable[[], np.ndarray]:
    import pytorch_kinematics as pk

    lim = torch.as_tensor(np.asarray(robot.qlim).T.copy(), dtype=Tt.dtype, device=Tt.device)
    ik = pk.PseudoInverseIK(
        chain, max_iterations=30, num_retries=10, joint_limits=lim, early_stopping_any_converged=True,
        early_stopping_no_improvement="all", debug=False, lr=0.2,
    )  # fmt: skip
    target = pk.Transform3d(matrix=Tt, dtype=Tt.dtype)

    def solve() -> np.ndarray:
        torch.manual_seed(seed)
        sol = ik.solve(target)
        err = sol.err_pos + sol.err_rot
        key = torch.where(sol.converged, -1.0, err)  # the first converged retry, else the best
        pick = torch.argmin(key, dim=1)
        return sol.solutions[torch.arange(len(pick)), pick].detach().cpu().numpy().astype(float)

    return solve


def run_diff(
    robot: Any = "panda",
    batches: tuple[int, ...] = BATCHES,
    dtypes: tuple[str, ...] = ("float64", "float32"),
    rounds: int = 5,
    libraries: tuple[str, ...] = ("torch", "jax"),
    problems: int = 1024,
    seed: int = 0,
    compile_torch: bool = True,
    progress: bool = False,
    device: str = "cpu",
) -> DiffReport:
    """The measurements of the module docstring, in one run (``robot`` a name or a Robot chain), on
    ``device`` ("cpu", or "cuda": the GPU, see the module docstring)."""
    import symkin
    from symkin.core.progress import bar
    from symkin.model.resolve import resolve_robot

    robot = resolve_robot(robot)
    torch = optional("torch")
    jax = optional("jax") if "jax" in libraries else None
    notes = []
    if torch is None:
        raise MissingExtraError("bench diff needs torch: pip install 'symkin[torch]'")
    torch.set_num_threads(1)
    gpu = device != "cpu"
    clock, sync = (_WALL, torch.cuda.synchronize) if gpu else (_CLOCK, lambda: None)
    if jax is not None:
        jax.config.update("jax_enable_x64", True)
    jax_device = None if jax is None else jax.devices("gpu" if gpu else "cpu")[0]
    have_pk = optional("pytorch_kinematics") is not None
    if not have_pk:
        notes.append("pytorch_kinematics is not installed (pip install 'symkin[compare-diff]'): no peer rows")
    kins: dict[str, Any] = {}
    if "torch" in libraries:
        kins["torch"] = symkin.compile(robot, backend="torch")
    if jax is not None:
        kins["jax"] = symkin.compile(robot, backend="jax")
    rows: list[DiffRow] = []
    agreement = 0.0
    rng = np.random.default_rng(seed)
    steps = [(d, N) for d in dtypes for N in batches]
    for dtype, N in bar(steps, progress, desc="bench diff"):
        tdt = getattr(torch, dtype)
        Qn = robot.random_q(N, seed=rng).reshape(N, robot.n).astype(dtype)
        Q = {"torch": torch.from_numpy(Qn).to(device)}
        if jax is not None:
            Q["jax"] = jax.device_put(Qn, jax_device)
        chain = pk_chain(robot, tdt, device) if have_pk else None
        if "torch" in kins and compile_torch:  # compiled per dtype and batch (dynamic=False)
            kins["torch.compile"] = {
                what: torch.compile(getattr(kins["torch"], what), dynamic=False)
                for what in ("fkine", "jacob0")
            }
        for what in ("fkine", "jacob0"):
            best, first = _timed(
                _kin_paths(what, kins, chain, Q, sync), rounds if N < 100_000 else max(2, rounds // 2), clock
            )
            rows += [DiffRow(what, p, dtype, N, best[p], first[p]) for p in best]
        if chain is not None and dtype == "float64":
            T_pk = chain.forward_kinematics(Q["torch"], end_only=True).get_matrix().cpu().numpy()
            agreement = max(agreement, float(np.abs(T_pk - robot.fkine(Qn)).max()))
    ik_rows = []
    T = robot.fkine(robot.random_q(problems, seed=rng).reshape(problems, robot.n))
    for dtype in dtypes:
        tdt = getattr(torch, dtype)
        Tt = torch.as_tensor(T, dtype=tdt, device=device)
        if have_pk:
            chain = pk_chain(robot, tdt, device)
            ik_rows.append(
                _ik_row("pk", dtype, robot, T, _pk_ik(chain, robot, torch, Tt, seed), rounds, clock)
            )
        tol = 1e-6 if dtype == "float64" else 1e-4
        for path, lib in (("torch", "torch"), ("jax.jit", "jax")):
            if lib in kins:
                Tx = Tt if lib == "torch" else jax.device_put(T.astype(dtype), jax_device)
                solve = functools.partial(_ik_q, kins[lib], Tx, seed=seed, tol=tol)
                ik_rows.append(_ik_row(path, dtype, robot, T, solve, rounds, clock))
    return DiffReport(robot.name, tuple(rows), tuple(ik_rows), agreement, tuple(notes), device)


def _ms(s: float) -> str:
    return f"{s * 1e3:9.3f}" if math.isfinite(s) else "        -"


def format_diff(report: DiffReport) -> str:
    """The tables: per function, dtype and batch each path's time, its ratio to pytorch_kinematics
    (how many times faster) and its warm-up; then the IK."""
    out = [
        f"symkin bench diff {report.robot}: "
        + (
            "CPU, one thread per library, least CPU time of a call (process time)"
            if report.device == "cpu"
            else f"GPU ({report.device}), least wall time of a call that waits for the device"
        )
        + "; warm-up: the first call's wall time",
        f"same robot: pytorch_kinematics' FK from symkin's URDF differs from symkin's by at most "
        f"{report.agreement:.1e}",
        f"{'function':8} {'dtype':8} {'batch':>7} {'path':14} {'ms':>9} {'x pk':>7} {'warm-up s':>10}",
    ]
    pk = {(r.what, r.dtype, r.batch): r.seconds for r in report.rows if r.path == "pk"}
    for r in report.rows:
        base = pk.get((r.what, r.dtype, r.batch))
        ratio = f"{base / r.seconds:7.1f}" if base and r.path != "pk" else "      -"
        out.append(
            f"{r.what:8} {r.dtype:8} {r.batch:7d} {r.path:14} {_ms(r.seconds)} {ratio} {r.warmup:10.2f}"
        )
    if report.ik:
        out.append("")
        out.append(
            f"IK: 10 starts x 30 iterations per target; solved: within {POS_TOL:g} m, {ROT_TOL:g} rad "
            "and the joint limits"
        )
        out.append(
            f"{'path':10} {'dtype':8} {'targets':>7} {'ms':>9} {'x pk':>7} {'solved':>7} "
            f"{'median pos m':>13} {'median rot':>11} {'warm-up s':>10}"
        )
        pk_ik = {r.dtype: r.seconds for r in report.ik if r.path == "pk"}
        for r in report.ik:
            base = pk_ik.get(r.dtype)
            ratio = f"{base / r.seconds:7.1f}" if base and r.path != "pk" else "      -"
            out.append(
                f"{r.path:10} {r.dtype:8} {r.problems:7d} {_ms(r.seconds)} {ratio} {r.solved:7.1%} "
                f"{r.median_pos:13.1e} {r.median_rot:11.1e} {r.warmup:10.2f}"
            )
    out += list(report.notes)
    return "\n".join(out)
