"""Table I of Haviland and Corke, "Maximising Manipulability During Resolved-Rate Motion Control" (2020).

``run_table1`` servos each robot over random tasks with RRMC and with MMC and reports mean and final
manipulability, arrivals, tasks leaving the joint limits and step times beside the paper's numbers.
``format_table1`` prints it; ``plot_task`` draws one task in the style of the paper's Fig. 3.

Run as ``python -m symkin.bench.mmc --tasks 100``.
"""

from __future__ import annotations

import argparse
import json
import math
import time
import warnings
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from symkin.bench.common import cell, figure, optional, table
from symkin.core.progress import bar
from symkin.runtime.control import MMC, joint_velocity_bounds, rrmc
from symkin.runtime.loop import ServoResult, servo

__all__ = [
    "run_table1",
    "format_table1",
    "plot_task",
    "step_timing",
    "format_step_timing",
    "rtb_mmc",
    "table1_tasks",
    "PAPER_TABLE1",
]

#: Table I of the MMC paper: mean and mean final manipulability, RRMC and MMC (lambda = 0.005, 1000 tasks)
PAPER_TABLE1: dict[str, dict[str, float]] = {
    "panda": {"mean_rrmc": 0.0742, "mean_mmc": 0.0880, "final_rrmc": 0.0782, "final_mmc": 0.0934},
    "lbr_iiwa7": {"mean_rrmc": 0.0667, "mean_mmc": 0.0776, "final_rrmc": 0.0643, "final_mmc": 0.0761},
    "sawyer": {"mean_rrmc": 0.2721, "mean_mmc": 0.3206, "final_rrmc": 0.2572, "final_mmc": 0.3263},
}
PROTOCOL_NOTE = (
    "Protocol of eq 14 of Haviland and Corke's MMC paper (2020): start and target configurations uniform "
    "in [qmin + 50 deg, qmax - 50 deg], target pose = FK of the target configuration; angle-axis "
    "base-frame error (Manipulator Differential Kinematics, Part 1, eq 37), gain 1, "
    "dt 0.05 s, arrival at sum|e| < 0.1, at most 500 steps. The paper discards self-colliding "
    "configurations; symkin has no collision model, so none are discarded here. Joint limits are not "
    "enforced except in the 'mmc_jl' run (velocity dampers)."
)
_MARGIN = math.radians(50.0)


def _robot(robot: Any, backend: str | None = None) -> Any:
    """A robot object as is; a built-in name loaded, and compiled on ``backend`` unless None (the
    NumPy reference is used when C compilation is impossible)."""
    if not isinstance(robot, str):
        return robot
    from symkin.model.robots import load

    model = load(robot)
    if backend is None:
        return model
    import symkin
    from symkin.errors import CompileError

    try:
        return symkin.compile(model, backend=backend)
    except CompileError as exc:  # pragma: no cover - no C compiler
        warnings.warn(f"{robot}: {exc}; using the NumPy reference kinematics", stacklevel=3)
        return model


def table1_tasks(kin: Any, n_tasks: int, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Start configurations (n_tasks, n) and target poses (n_tasks, 4, 4) by eq 14 of the MMC paper."""
    lo, hi = np.asarray(kin.qlim, dtype=float)
    margin = np.minimum(_MARGIN, 0.45 * (hi - lo))
    lo, hi = lo + margin, hi - margin
    q0 = rng.uniform(lo, hi, size=(n_tasks, kin.n))
    qt = rng.uniform(lo, hi, size=(n_tasks, kin.n))
    Tep = np.array([kin.fkine(q) for q in qt])
    return q0, Tep


def _summary(runs: list[ServoResult]) -> dict[str, Any]:
    times = np.concatenate([r.step_time for r in runs]) if runs else np.zeros(0)
    infos = [i for r in runs for i in r.info]
    return {
        "mean_manipulability": float(np.mean([r.mean_manipulability for r in runs])),
        "final_manipulability": float(np.mean([r.final_manipulability for r in runs])),
        "arrived": int(sum(r.arrived for r in runs)),
        "left_limits": int(sum(r.left_limits for r in runs)),
        "mean_steps": float(np.mean([r.steps for r in runs])),
        "step_us_median": float(np.median(times) * 1e6) if times.size else float("nan"),
        "step_methods": _methods(infos),
        "step_status": dict(Counter(i.status for i in infos)),
        "max_slack": float(max((i.slack for i in infos), default=0.0)),
    }


def _methods(infos: Any) -> dict[str, int]:
    """How many steps each method settled (``fallback_<reason>`` for a fallback step)."""
    return dict(Counter(i.method if i.fallback is None else f"fallback_{i.fallback}" for i in infos))


def _pct(new: float, old: float) -> float:
    return 100.0 * (new - old) / old if old else float("nan")


def run_table1(
    robots: tuple[Any, ...] | list[Any] = ("panda", "lbr_iiwa7", "sawyer"),
    n_tasks: int = 1000,
    seed: int = 0,
    progress: bool = True,
    joint_limits: bool = True,
    lam: float = 0.005,
    gain: float = 1.0,
    dt: float = 0.05,
    threshold: float = 0.1,
    max_steps: int = 500,
    qd_max: Any = np.inf,
    backend: str | None = "c",
    timing: bool = True,
    timing_tasks: int = 50,
) -> dict[str, Any]:
    """Reproduce Table I of the MMC paper (protocol in :data:`PROTOCOL_NOTE`); returns a JSON-able dict.

    ``robots`` are built-in names (``symkin.model.robots.load``, compiled with ``symkin.compile``
    on ``backend``, or the NumPy reference with ``backend=None``) or robot objects. With ``timing``
    each robot also gets :func:`step_timing` on its first ``timing_tasks`` tasks (C and Python
    paths of :class:`MMC`, and RTB + qpsolvers when installed). Each robot gets
    ``n_tasks`` tasks from ``np.random.default_rng([seed, index])``; the same tasks go to RRMC, MMC
    and, with ``joint_limits``, MMC with velocity dampers (``"mmc_jl"``). ``qd_max=np.inf`` (the
    paper's setting) leaves joint speeds unbounded; ``None`` uses each robot's speed limits.
    Step times are the controllers' (kinematics and solve) with whatever kinematics the robot
    object provides.
    """
    loop = {"gain": gain, "dt": dt, "threshold": threshold, "max_steps": max_steps}  # of every servo run
    out: dict[str, Any] = {
        "protocol": {
            "n_tasks": n_tasks,
            "seed": seed,
            "lam": lam,
            **loop,
            "qd_max": None if qd_max is None else np.broadcast_to(qd_max, (1,)).tolist()[0],
            "note": PROTOCOL_NOTE,
        },
        "robots": {},
    }
    for index, spec in enumerate(robots):
        kin = _robot(spec, backend)
        name = getattr(kin, "name", str(spec))
        rng = np.random.default_rng([seed, index])
        q0s, Teps = table1_tasks(kin, n_tasks, rng)
        controllers: dict[str, Any] = {
            "rrmc": lambda q, nu, kin=kin: rrmc(kin, q, nu, qd_max=qd_max),
            "mmc": MMC(kin, lam=lam, qd_max=qd_max),
        }
        if joint_limits:
            controllers["mmc_jl"] = MMC(kin, lam=lam, qd_max=qd_max, joint_limits=True, dt=dt)
        runs: dict[str, list[ServoResult]] = {k: [] for k in controllers}
        t0 = time.perf_counter()
        for t in bar(range(n_tasks), progress, desc=f"Table I {name}", unit="task", leave=True):
            for key, ctrl in controllers.items():
                runs[key].append(servo(kin, q0s[t], Teps[t], ctrl, **loop))
        res = {key: _summary(r) for key, r in runs.items()}
        for which in ("mean", "final"):
            m = f"{which}_manipulability"
            res[f"improvement_{which}_pct"] = _pct(res["mmc"][m], res["rrmc"][m])
        res["mmc_not_below_rrmc_final"] = int(
            sum(
                m.final_manipulability >= r.final_manipulability - 1e-9
                for m, r in zip(runs["mmc"], runs["rrmc"])
            )
        )
        res["wall_s"] = time.perf_counter() - t0
        if name in PAPER_TABLE1:
            p = PAPER_TABLE1[name]
            res["paper"] = {
                **p,
                "improvement_mean_pct": _pct(p["mean_mmc"], p["mean_rrmc"]),
                "improvement_final_pct": _pct(p["final_mmc"], p["final_rrmc"]),
            }
        res["source"] = getattr(kin, "source", "")
        if timing:
            res["step_timing"] = step_timing(
                kin, min(n_tasks, timing_tasks), seed=seed, index=index, lam=lam, **loop
            )
        out["robots"][name] = res
    return out


def format_table1(result: dict[str, Any]) -> str:
    """Plain-text table of a :func:`run_table1` result, with the paper's numbers beside ours."""
    pr = result["protocol"]
    lines = [
        f"Table I of Haviland and Corke 2020 (MMC), {pr['n_tasks']} tasks per robot, lambda = {pr['lam']}, "
        f"random seed {pr['seed']}",
        "",
        f"{'robot':<10} {'':<6} {'mean m RRMC':>11} {'MMC':>8} {'impr.':>7}   "
        f"{'final m RRMC':>12} {'MMC':>8} {'impr.':>7}",
    ]
    for name, r in result["robots"].items():
        lines.append(
            f"{name:<10} {'symkin':<6} {r['rrmc']['mean_manipulability']:>11.4f} "
            f"{r['mmc']['mean_manipulability']:>8.4f} {r['improvement_mean_pct']:>+6.1f}%   "
            f"{r['rrmc']['final_manipulability']:>12.4f} {r['mmc']['final_manipulability']:>8.4f} "
            f"{r['improvement_final_pct']:>+6.1f}%"
        )
        if "paper" in r:
            p = r["paper"]
            lines.append(
                f"{'':<10} {'paper':<6} {p['mean_rrmc']:>11.4f} {p['mean_mmc']:>8.4f} "
                f"{p['improvement_mean_pct']:>+6.1f}%   {p['final_rrmc']:>12.4f} {p['final_mmc']:>8.4f} "
                f"{p['improvement_final_pct']:>+6.1f}%"
            )
    lines += [
        "",
        f"{'robot':<10} {'controller':<8} {'arrived':>8} {'left limits':>12} {'mean steps':>10} "
        f"{'step us (median)':>17}  steps by method",
    ]
    n = pr["n_tasks"]
    for name, r in result["robots"].items():
        for key in ("rrmc", "mmc", "mmc_jl"):
            if key not in r:
                continue
            s = r[key]
            methods = ", ".join(f"{k} {v}" for k, v in sorted(s["step_methods"].items()))
            left = f"{s['left_limits']} ({100 * s['left_limits'] / n:.0f}%)"
            lines.append(
                f"{name:<10} {key:<8} {s['arrived']:>4}/{n:<3} {left:>12} "
                f"{s['mean_steps']:>10.1f} {s['step_us_median']:>17.1f}  {methods}"
            )
        lines.append(
            f"{'':<10} MMC final manipulability >= RRMC's in {r['mmc_not_below_rrmc_final']}/{n} tasks"
            + (f"; max slack (mmc_jl) {r['mmc_jl']['max_slack']:.3g}" if "mmc_jl" in r else "")
        )
    for r in result["robots"].values():
        if "step_timing" in r:
            lines += ["", format_step_timing(r["step_timing"])]
    lines += ["", pr["note"]]
    return "\n".join(lines)


#: configurations of :func:`step_timing`: MMC options (lam and dt added) beside the Table I protocol
TIMING_CONFIGS: dict[str, dict[str, Any]] = {
    "mmc": {"qd_max": np.inf},  # Table I: no bounds (the closed form settles every regular step)
    "mmc_jl": {"qd_max": np.inf, "joint_limits": True},  # velocity dampers, slack
    "mmc_jl_osqp": {"qd_max": np.inf, "joint_limits": True, "closed_form": False},  # OSQP every step
}


def rtb_mmc(rtb: Any, qpsolvers: Any, robot: Any, mmc: MMC) -> Any:
    """The controller of ``mmc`` written with roboticstoolbox-python and qpsolvers (OSQP): RTB's
    ``jacob0`` and ``jacobm`` (which computes J and H itself) on the robot's ETS, the same bounds,
    ``qpsolvers.solve_qp(..., solver="osqp")`` with MMC's OSQP tolerances. Returns ``step(q, nu) ->
    qd or None`` (None when OSQP finds no solution); ``step.kinematics(q, nu)`` is its RTB part alone."""
    from symkin.bench.kin import rtb_ets

    ets = rtb_ets(rtb, robot)
    n, lam, w = mmc.n, mmc.lam, mmc.slack_weight
    qlim, qd_max = np.asarray(mmc.qlim, dtype=float), mmc.qd_max
    opts = {k: mmc.settings[k] for k in ("eps_abs", "eps_rel", "max_iter", "polishing") if k in mmc.settings}
    ns = 6 if mmc.slack else 0
    P = np.diag(np.r_[np.full(n, lam), np.full(ns, w)])
    Aslack = np.eye(6)[:, :ns]
    free = np.full(ns, np.inf)

    def kinematics(q: np.ndarray, nu: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        try:
            return ets.jacob0(q), ets.jacobm(q)
        except np.linalg.LinAlgError:  # RTB's jacobm inverts J J^T, singular for a planar arm
            return None

    def step(q: np.ndarray, nu: np.ndarray) -> np.ndarray | None:
        JJm = kinematics(q, nu)
        if JJm is None:
            return None
        J, Jm = JJm[0], JJm[1].ravel()
        lb = ub = None
        if mmc._bounded:
            lower, upper = joint_velocity_bounds(
                q, qlim, qd_max, mmc.joint_limits, mmc.rho_i, mmc.rho_s, mmc.xi, mmc.dt
            )
            lb, ub = np.r_[lower, -free], np.r_[upper, free]
        c = np.r_[-Jm, np.zeros(ns)]
        x = qpsolvers.solve_qp(P, c, A=np.c_[J, Aslack], b=nu, lb=lb, ub=ub, solver="osqp", **opts)
        return None if x is None else x[:n]

    step.kinematics = kinematics  # type: ignore[attr-defined]
    return step


def step_timing(
    robot: Any = "panda",
    n_tasks: int = 50,
    seed: int = 0,
    index: int = 0,
    lam: float = 0.005,
    dt: float = 0.05,
    gain: float = 1.0,
    threshold: float = 0.1,
    max_steps: int = 500,
    configs: tuple[str, ...] = ("mmc", "mmc_jl", "mmc_jl_osqp"),
    rtb: bool = True,
    max_states: int = 1500,
    rounds: int = 2,
) -> dict[str, Any]:
    """Median microseconds of one MMC step on the C path, the Python path and, when
    roboticstoolbox-python and qpsolvers import, the same controller in RTB + qpsolvers (OSQP).

    ``robot`` is compiled with the C backend. For each configuration of :data:`TIMING_CONFIGS`
    the states (q, nu) of the Table I tasks (``n_tasks``; rng ``[seed, index]`` as in
    :func:`run_table1`) servoed by the C path (the first ``max_states``) are replayed in order
    through a fresh controller of each kind, ``rounds`` times (the order of the kinds reversed
    every other round), each call timed from Python. Also reports the steps' methods on the C
    path and the largest difference of qd between the C path and the others (the first round).
    """
    import symkin

    kin = _robot(robot)
    if getattr(kin, "backend", None) != "c":
        kin = symkin.compile(getattr(kin, "robot", kin), "c")
    peers = (optional("roboticstoolbox"), optional("qpsolvers")) if rtb else (None, None)
    rng = np.random.default_rng([seed, index])
    q0s, Teps = table1_tasks(kin, n_tasks, rng)
    out: dict[str, Any] = {"robot": kin.name, "n_tasks": n_tasks, "lam": lam, "configs": {}}
    for name in configs:
        options = {**TIMING_CONFIGS[name], "lam": lam, "dt": dt}
        ctrl = MMC(kin, **options)
        if ctrl.backend != "c":  # pragma: no cover - C path unavailable for this robot
            raise RuntimeError(f"no C path for {kin.name}")
        states: list[tuple[np.ndarray, np.ndarray]] = []

        def record(q: np.ndarray, nu: np.ndarray, ctrl: MMC = ctrl, states: list = states) -> Any:
            states.append((q.copy(), nu.copy()))
            return ctrl.step(q, nu)

        for q0, Tep in zip(q0s, Teps):
            servo(kin, q0, Tep, record, dt=dt, gain=gain, threshold=threshold, max_steps=max_steps)
        states = states[:max_states]
        makers: dict[str, Any] = {
            "c": lambda o=options: MMC(kin, **o).step,
            "python": lambda o=options: MMC(kin, backend="python", **o).step,
        }
        if all(peers):
            makers["rtb_qpsolvers"] = lambda c=ctrl: rtb_mmc(*peers, kin.robot, c)
            makers["rtb_kinematics"] = lambda c=ctrl: rtb_mmc(*peers, kin.robot, c).kinematics
        times: dict[str, list[float]] = {k: [] for k in makers}
        answers: dict[str, list[Any]] = {}
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # qpsolvers warns on every unsolved QP
            for r in range(rounds):
                for key in makers if r % 2 == 0 else reversed(makers):
                    fn, ts, got = makers[key](), times[key], []
                    for q, nu in states:
                        t0 = time.perf_counter()
                        got.append(fn(q, nu))
                        ts.append(time.perf_counter() - t0)
                    answers.setdefault(key, got)
        methods = _methods(info for _, info in answers["c"])
        med = {k: float(np.median(v) * 1e6) for k, v in times.items()}
        res_c = {
            "steps": len(states),
            "median_us": med,
            "p90_us": {k: float(np.percentile(v, 90) * 1e6) for k, v in times.items()},
            "c_methods": methods,
            "speedup_vs_python": med["python"] / med["c"],
            "max_abs_qd": float(max(np.abs(a[0]).max() for a in answers["c"])),
        }
        qd_c = [a[0] for a in answers["c"]]
        res_c["max_diff_python"] = _max_diff(qd_c, [a[0] for a in answers["python"]])
        if "rtb_qpsolvers" in answers:
            res_c["speedup_vs_rtb"] = med["rtb_qpsolvers"] / med["c"]
            pairs = [
                (a, b) for a, b in zip(answers["c"], answers["rtb_qpsolvers"]) if b is not None and a[1].ok
            ]
            res_c["max_diff_rtb"] = _max_diff([a[0] for a, _ in pairs], [b for _, b in pairs])
        out["configs"][name] = res_c
    return out


_TIMED = ("c", "python", "rtb_qpsolvers", "rtb_kinematics")  # the step timing's paths, in its table's order


def _max_diff(a: list[np.ndarray], b: list[np.ndarray]) -> float:
    return max((float(np.abs(x - y).max()) for x, y in zip(a, b)), default=float("nan"))


def format_step_timing(timing: dict[str, Any]) -> str:
    """Plain-text table of a :func:`step_timing` result."""
    rows = []
    for name, r in timing["configs"].items():
        med, p90 = r["median_us"], r["p90_us"]
        us = [f"{med[k]:.1f} ({p90[k]:.0f})" if k in med else "-" for k in _TIMED]
        methods = ", ".join(f"{k} {v}" for k, v in sorted(r["c_methods"].items()))
        ratios = [cell(r.get("speedup_vs_rtb"), "{:.1f}x"), f"{r['speedup_vs_python']:.1f}x"]
        rows.append([name, r["steps"], *us, *ratios, methods])
    head = ["config", "steps", "C", "Python", "RTB+qpsolvers", "(RTB J, Jm)", "C vs RTB", "C vs Py"]
    lines = [
        f"MMC step, {timing['robot']} ({timing['n_tasks']} Table I tasks replayed; median (p90) us per step "
        "from Python, same states for each)",
        *table([*head, "C path methods"], rows, "lrrrrrrrl"),
    ]
    diffs = [
        f"{name} {r['max_diff_python']:.1e}"
        + (f" / {r['max_diff_rtb']:.1e}" if "max_diff_rtb" in r else "")
        + f" (|qd| <= {r['max_abs_qd']:.2g})"
        for name, r in timing["configs"].items()
    ]
    lines.append("max |qd_C - qd| (rad/s) vs Python / vs RTB: " + "; ".join(diffs))
    return "\n".join(lines)


def plot_task(
    robot: Any, q0: Any, Tep: Any, path: str | Path, title: str | None = None, **servo_options: Any
) -> dict[str, ServoResult]:
    """Servo one task with RRMC and MMC and write manipulability against time as a PNG (Fig. 3 of the MMC
    paper).

    ``servo_options`` go to :func:`symkin.runtime.loop.servo` (``lam``, ``dt``, ``qd_max``...).
    Needs matplotlib (``pip install symkin[plot]``). Returns the two :class:`ServoResult`.
    """
    kin = _robot(robot)
    results = {c: servo(kin, q0, Tep, c, **servo_options) for c in ("rrmc", "mmc")}
    with figure(path, "plot_task", figsize=(6.0, 3.2), dpi=150) as (_, ax):
        for key, label, style in (("rrmc", "RRMC", "--"), ("mmc", "MMC", "-")):
            ax.plot(results[key].t, results[key].manipulability, style, label=label, linewidth=1.6)
        ax.set_xlabel("Time (s)")
        ax.set_ylabel("Manipulability")
        ax.set_title(
            title or f"{getattr(kin, 'name', 'robot')}: manipulability during position-based servoing"
        )
        ax.grid(True, alpha=0.3)
        ax.legend()
    return results


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description="Reproduce Table I of Haviland and Corke 2020 (MMC vs RRMC).")
    ap.add_argument("--robots", nargs="+", default=["panda", "lbr_iiwa7", "sawyer"])
    ap.add_argument("--tasks", type=int, default=1000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-joint-limits", action="store_true", help="skip the MMC run with velocity dampers")
    ap.add_argument("--json", type=Path, help="also write the result as JSON here")
    ap.add_argument("--backend", default="c", help="kinematics backend ('c', 'numpy'; 'reference': none)")
    ap.add_argument("--no-timing", action="store_true", help="skip the step timing (C, Python, RTB)")
    ap.add_argument("--timing-tasks", type=int, default=50, help="tasks replayed by the step timing")
    args = ap.parse_args(argv)
    res = run_table1(
        tuple(args.robots),
        args.tasks,
        args.seed,
        joint_limits=not args.no_joint_limits,
        backend=None if args.backend == "reference" else args.backend,
        timing=not args.no_timing,
        timing_tasks=args.timing_tasks,
    )
    print(format_table1(res))
    if args.json:
        args.json.write_text(json.dumps(res, indent=1))


if __name__ == "__main__":
    main()
