"""Quadratic-rate against resolved-rate control at singularities (Haviland and Corke, Manipulator
Differential Kinematics, Part 2, 2023, section "Quadratic-Rate Motion Control").

:func:`singular_tasks` gives servo tasks of a UR5 that start or end at a singularity;
:func:`run_singular` servos each with RRMC and with QRMC and reports, per controller, arrival, the
steps taken, the steps before the end effector first moved (a stall), the joint speeds each
controller asked for and applied against the limits, and manipulability; :func:`run_random` does
the same over random tasks (arrivals, runs whose requested speeds exceeded the limits).
:func:`plot_singular` draws one task: manipulability, the largest joint speed over its limit
(requested and applied) and the error against time. Run as ``python -m symkin.bench.qrmc`` or
``symkin bench qrmc [--plot PNG]``.
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from symkin.bench.common import figure
from symkin.core.progress import bar
from symkin.runtime.loop import ServoResult, servo
from symkin.runtime.qrmc import QRMC

__all__ = [
    "singular_tasks",
    "lost_direction_task",
    "run_singular",
    "run_random",
    "format_singular",
    "plot_singular",
    "speed_ratios",
    "stalled_steps",
    "PROTOCOL",
    "PLOTTED",
]

#: The servo protocol of the comparison: gain 1, dt 0.05 s, arrival at sum |e| < 0.01, 600 steps.
PROTOCOL: dict[str, Any] = {"dt": 0.05, "threshold": 0.01, "max_steps": 600}


def _rotation(r: np.ndarray) -> np.ndarray:
    """exp([r]x) (Rodrigues)."""
    th = float(np.linalg.norm(r))
    if th == 0.0:
        return np.eye(3)
    k = r / th
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(th) * K + (1.0 - math.cos(th)) * K @ K


def lost_direction_task(kin: Any, q0: Any, distance: float = 0.1) -> tuple[np.ndarray, np.ndarray]:
    """(q0, Tep): the target ``distance`` along the direction J0(q0) has lost, ``u`` the left singular
    vector of its smallest singular value (signed to point from the end effector toward the base
    origin): translated by ``distance u_v`` and rotated by ``exp([distance u_w]x)`` in the base frame,
    so that the pose error (Part 1 eq 37) is ``distance u`` and RRMC's velocity at q0 is J0^+ of a
    vector J0 cannot produce."""
    q0 = np.asarray(q0, dtype=float)
    T0 = np.asarray(kin.fkine(q0), dtype=float)
    U, _, _ = np.linalg.svd(np.asarray(kin.jacob0(q0), dtype=float))
    u = U[:, -1]
    if u[:3] @ T0[:3, 3] > 0:
        u = -u
    Tep = T0.copy()
    Tep[:3, 3] += distance * u[:3]
    Tep[:3, :3] = _rotation(distance * u[3:]) @ T0[:3, :3]
    return q0, Tep


def singular_tasks(kin: Any) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Named UR5 tasks, ``name -> (q0 (6,), Tep (4, 4))``:

    - ``"lost direction"``: from q0 = (0, -1, 0, -1, 1, 0.3) rad, the elbow stretched (J0 has rank 5),
      0.1 m (and 0.1 |u_w| rad) along the lost direction (:func:`lost_direction_task`);
    - ``"finish at a singularity"``: the article's notebook 7, section 7.4: from (0, -pi/2, pi/2, 0, 0,
      0) to the pose of (pi, 0, 0, 0, pi/2, 0), the elbow stretched;
    - ``"start and finish at singularities"``: section 7.5: from (0, 0, 0, 0, 0, 0), elbow and wrist
      singular, to the pose of (0, -pi/2, pi/2, 0, 0, 0), the wrist singular.
    """
    if int(kin.n) != 6:
        raise ValueError(f"the singular tasks are the UR5's (6 joints); {kin.name} has {kin.n}")
    half = math.pi / 2
    return {
        "lost direction": lost_direction_task(kin, [0.0, -1.0, 0.0, -1.0, 1.0, 0.3]),
        "finish at a singularity": (
            np.array([0.0, -half, half, 0.0, 0.0, 0.0]),
            np.asarray(kin.fkine(np.array([math.pi, 0.0, 0.0, 0.0, half, 0.0]))),
        ),
        "start and finish at singularities": (
            np.zeros(6),
            np.asarray(kin.fkine(np.array([0.0, -half, half, 0.0, 0.0, 0.0]))),
        ),
    }


def speed_ratios(res: ServoResult, qd_max: Any) -> tuple[np.ndarray, np.ndarray]:
    """(requested, applied) per step, (steps,) each: ``max_i |qd_i| / qd_max_i`` of the controller's
    answer before its speed scaling (``qd / info.scale``) and of the qd applied."""
    limit = np.asarray(qd_max, dtype=float)
    scale = np.array([i.scale for i in res.info]) if res.steps else np.zeros(0)
    applied = (np.abs(res.qd) / limit).max(axis=1) if res.steps else np.zeros(0)
    return applied / np.where(scale > 0, scale, 1.0), applied


def stalled_steps(res: ServoResult, tol: float = 1e-9) -> int:
    """Steps at the start of a run before the error sum |e| first fell by more than ``tol`` (relative)."""
    err = np.abs(res.e).sum(axis=1)
    moved = np.flatnonzero(err < err[0] * (1.0 - tol))
    return int(moved[0]) - 1 if len(moved) else res.steps


def _row(res: ServoResult, qd_max: np.ndarray) -> dict[str, Any]:
    requested, applied = speed_ratios(res, qd_max)
    return {
        "arrived": bool(res.arrived),
        "steps": res.steps,
        "stalled_steps": stalled_steps(res),
        "final_error": float(np.abs(res.e[-1]).sum()),
        "max_requested_over_limit": float(requested.max(initial=0.0)),
        "max_applied_over_limit": float(applied.max(initial=0.0)),
        "scaled_steps": int((requested > 1.0 + 1e-12).sum()),
        "min_manipulability": float(res.manipulability.min()),
        "final_manipulability": float(res.manipulability[-1]),
        "limit_violations": res.limit_violations,
        "median_step_us": float(np.median(res.step_time) * 1e6) if res.steps else 0.0,
        "status": {s: res.status.count(s) for s in sorted(set(res.status))},
    }


def _controllers(kin: Any, horizon: float) -> dict[str, Any]:
    return {"rrmc": "rrmc", "qrmc": QRMC(kin, horizon=horizon)}


def run_singular(
    kin: Any, tasks: dict[str, tuple[np.ndarray, np.ndarray]] | None = None, horizon: float = 1.0,
    progress: bool = True, keep: bool = False, **protocol: Any,
) -> dict[str, Any]:  # fmt: skip
    """Servo each task with RRMC and QRMC (``horizon``) under :data:`PROTOCOL` (``protocol`` overrides
    it): ``{"protocol", "horizon", "qd_max", "tasks": {name: {"rrmc": row, "qrmc": row}}}``, a row
    as :func:`format_singular` prints it; with ``keep`` also ``"runs"``: the ServoResults."""
    options = {**PROTOCOL, **protocol}
    tasks = singular_tasks(kin) if tasks is None else tasks
    qd_max = np.broadcast_to(np.asarray(kin.qd_max, dtype=float), (int(kin.n),))
    out: dict[str, Any] = {"protocol": options, "horizon": horizon, "qd_max": qd_max.tolist(), "tasks": {}}
    runs: dict[str, dict[str, ServoResult]] = {}
    with bar(total=2 * len(tasks), progress=progress, desc="qrmc bench") as b:
        for name, (q0, Tep) in tasks.items():
            runs[name] = {}
            for label, ctrl in _controllers(kin, horizon).items():
                runs[name][label] = servo(kin, q0, Tep, controller=ctrl, **options)
                b.update(1)
            out["tasks"][name] = {label: _row(r, qd_max) for label, r in runs[name].items()}
    if keep:
        out["runs"] = runs
    return out


def run_random(
    kin: Any, n_tasks: int = 60, seed: int = 0, horizon: float = 1.0, progress: bool = True, **protocol: Any
) -> dict[str, Any]:
    """RRMC and QRMC over random tasks: start q0 and target configuration halfway between q0 and a
    second random configuration (``kin.random_q``), target pose its FK. Per controller: arrivals, the
    median steps of the arrived runs, runs whose requested joint speeds exceeded the limits and the
    largest requested speed over its limit."""
    options = {**PROTOCOL, **protocol}
    Q0 = kin.random_q(n_tasks, seed=seed)
    Q1 = Q0 + 0.5 * (kin.random_q(n_tasks, seed=seed + 1) - Q0)
    qd_max = np.broadcast_to(np.asarray(kin.qd_max, dtype=float), (int(kin.n),))
    rows: dict[str, dict[str, Any]] = {}
    with bar(total=2 * n_tasks, progress=progress, desc=f"qrmc bench ({kin.name})") as b:
        for label in ("rrmc", "qrmc"):
            arrived, steps, over, worst = 0, [], 0, 0.0
            for q0, q1 in zip(Q0, Q1, strict=True):
                ctrl = _controllers(kin, horizon)[label]
                res = servo(kin, q0, kin.fkine(q1), controller=ctrl, **options)
                requested = speed_ratios(res, qd_max)[0]
                arrived += res.arrived
                steps += [res.steps] if res.arrived else []
                over += bool((requested > 1.0 + 1e-12).any())
                worst = max(worst, float(requested.max(initial=0.0)))
                b.update(1)
            rows[label] = {
                "arrived": arrived,
                "median_steps": float(np.median(steps)) if steps else math.nan,
                "runs_over_limit": over,
                "max_requested_over_limit": worst,
            }
    return {"robot": kin.name, "tasks": n_tasks, "seed": seed, "protocol": options, "rows": rows}


def format_singular(result: dict[str, Any], random: list[dict[str, Any]] = ()) -> str:  # type: ignore[assignment]
    """The tables of :func:`run_singular` (and of :func:`run_random` results)."""
    p = result["protocol"]
    lines = [
        f"RRMC vs QRMC (horizon {result['horizon']} s) on the UR5: gain 1, dt {p['dt']} s, arrival at "
        f"sum|e| < {p['threshold']}, at most {p['max_steps']} steps; speeds as max_i |qd_i| / qd_max_i "
        "(requested: before the speed scaling)",
        f"{'task':36s} {'ctrl':5s} {'arrived':>7s} {'steps':>5s} {'stalled':>7s} {'requested':>10s} "
        f"{'applied':>7s} {'scaled':>6s} {'min m':>8s} {'final m':>8s} {'us/step':>7s}",
    ]
    for name, rows in result["tasks"].items():
        for label, r in rows.items():
            lines.append(
                f"{name:36s} {label:5s} {'yes' if r['arrived'] else 'no':>7s} {r['steps']:5d} "
                f"{r['stalled_steps']:7d} {r['max_requested_over_limit']:10.3g} "
                f"{r['max_applied_over_limit']:7.3g} {r['scaled_steps']:6d} {r['min_manipulability']:8.2g} "
                f"{r['final_manipulability']:8.3g} {r['median_step_us']:7.1f}"
            )
    for res in random:
        lines.append(
            f"random tasks, {res['robot']} ({res['tasks']}, seed {res['seed']}): "
            + "; ".join(
                f"{label}: arrived {r['arrived']}, median steps {r['median_steps']:.0f}, requested speeds "
                f"over the limits in {r['runs_over_limit']} runs (worst {r['max_requested_over_limit']:.3g}x)"
                for label, r in res["rows"].items()
            )
        )
    return "\n".join(lines)


def plot_singular(runs: dict[str, dict[str, ServoResult]], qd_max: Any, path: str | Path) -> None:
    """One column per task (``runs``: task -> controller label -> ServoResult): manipulability, the
    largest joint speed over its limit (requested: dashed; applied: solid) and the error sum |e|
    against time, one line per controller, as a PNG. Needs matplotlib (``pip install symkin[plot]``)."""
    size = {"figsize": (5.5 * len(runs), 7.5), "sharex": "col", "squeeze": False}
    with figure(path, "plot_singular", 110, nrows=3, ncols=len(runs), **size) as (_, grid):
        for col, (task, by_label) in enumerate(runs.items()):
            axes = grid[:, col]
            for (label, res), color in zip(
                by_label.items(), ("tab:red", "tab:blue", "tab:green"), strict=False
            ):
                requested, applied = speed_ratios(res, qd_max)
                t, name = res.t, label.upper()
                axes[0].plot(t, res.manipulability, color=color, label=name)
                floor = np.maximum(requested, 1e-6)
                axes[1].semilogy(t[:-1], floor, "--", color=color, label=f"{name} requested")
                axes[1].semilogy(t[:-1], np.maximum(applied, 1e-6), color=color, label=f"{name} applied")
                axes[2].semilogy(t, np.abs(res.e).sum(axis=1), color=color, label=name)
            axes[1].axhline(1.0, color="k", linewidth=0.8, linestyle=":", label="joint speed limit")
            axes[0].set_title(f"UR5: {task}")
            axes[2].set_xlabel("time (s)")
            for ax in axes:
                ax.grid(True, alpha=0.3)
                ax.legend(fontsize="small", loc="best")
        grid[0, 0].set_ylabel("manipulability")
        grid[1, 0].set_ylabel("max |qd_i| / qd_max_i")
        grid[2, 0].set_ylabel("sum |e|")


#: The tasks :func:`main` and ``symkin bench qrmc --plot`` draw.
PLOTTED = ("lost direction", "finish at a singularity")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description="QRMC vs RRMC at singularities (Haviland and Corke, Part 2).")
    ap.add_argument("--horizon", type=float, default=1.0, help="QRMC horizon (s)")
    ap.add_argument("--random", type=int, default=0, help="also N random tasks on the UR5 and the Panda")
    ap.add_argument("--plot", type=Path, help="plot the 'lost direction' and 'finish' tasks here (PNG)")
    ap.add_argument("--json", type=Path, help="also write the result as JSON here")
    args = ap.parse_args(argv)
    from symkin.runtime.load import compile as compile_robot

    ur5 = compile_robot("ur5", backend="c")
    res = run_singular(ur5, horizon=args.horizon, keep=bool(args.plot))
    random = [run_random(compile_robot(r, backend="c"), args.random, horizon=args.horizon) for r in
              (("ur5", "panda") if args.random else ())]  # fmt: skip
    print(format_singular(res, random))
    if args.plot:
        runs = res.pop("runs")
        plot_singular({k: runs[k] for k in PLOTTED}, ur5.qd_max, args.plot)
    if args.json:
        args.json.write_text(json.dumps({"singular": res, "random": random}, indent=2))


if __name__ == "__main__":  # pragma: no cover
    main()
