"""Table 1 of Haviland and Corke, Manipulator Differential Kinematics, Part 1, 2023: numerical IK methods
compared over random reachable UR5 targets.

The authors' protocol: ``np.random.seed(seed)``; ``n_problems`` target configurations uniform
within the joint limits (targets are their poses), then one shared set of 100 start points;
search s of every problem starts from ``starts[s]``. Settings (a) 1 search x 500 iterations and
(b) 100 searches x 30 iterations; a problem is solved when ``E = 1/2 e^T e < 1e-6`` (the paper's
criterion; ``tol_on="e"`` uses symkin's ``|e| < tol`` instead). Iterations count pose
evaluations, failed searches included; their mean and median are over the solved problems (the
paper's setting (a) figures are too: failures would add 500 each). The largest ``|e|`` among
solved problems shows what ``E < 1e-6`` allows (up to 1.4e-3). Times are CPU times of the calling
thread (``time.thread_time``), so that other processes of a shared machine do not count.
"""

from __future__ import annotations

import functools
import time
from collections.abc import Iterable
from typing import Any

import numpy as np

from symkin.bench.common import guarded, interleaved, table, with_lanes

__all__ = ["run_table1", "format_table1", "table1_problems", "TABLE1_METHODS", "PAPER_TABLE1", "SETTINGS"]

SETTINGS: dict[str, tuple[int, int]] = {"a": (1, 500), "b": (100, 30)}  # (searches, iterations)

TABLE1_METHODS: dict[str, dict[str, Any]] = {
    "NR": {"method": "NR"},
    "GN": {"method": "GN"},
    "NR Pseudoinverse": {"method": "NR", "pinv": True},
    "GN Pseudoinverse": {"method": "GN", "pinv": True},
    "LM (Wampler lambda=1e-4)": {"method": "LM", "damping": "wampler", "lam": 1e-4},
    "LM (Wampler lambda=1e-6)": {"method": "LM", "damping": "wampler", "lam": 1e-6},
    "LM (Chan lambda=1.0)": {"method": "LM", "damping": "chan", "lam": 1.0},
    "LM (Chan lambda=0.1)": {"method": "LM", "damping": "chan", "lam": 0.1},
    "LM (Sugihara w_n=1e-3)": {"method": "LM", "damping": "sugihara", "lam": 1e-3},
    "LM (Sugihara w_n=1e-4)": {"method": "LM", "damping": "sugihara", "lam": 1e-4},
    # Manipulator Differential Kinematics, Part 2's QP (symkin.runtime.ik_qp): lambda_q = 0.01, lambda_delta
    # = 1, joint-limit dampers; with the manipulability term of Part 2's UR5 experiment (1 / lambda_m)
    "QP (lambda_q=0.01)": {"method": "QP"},
    "QP + Jm (w_m=0.01)": {"method": "QP", "manipulability": 0.01},
}

# Table 1 of Part 1: (mean iterations, median iterations, infeasible count, infeasible %, mean
# searches, max searches) per method and setting, 10 000 problems.
PAPER_TABLE1: dict[tuple[str, str], tuple[float, float, int, float, float, float]] = {
    ("NR", "a"): (21.34, 16.0, 1093, 10.93, 1.0, 1.0),
    ("GN", "a"): (21.6, 16.0, 1078, 10.78, 1.0, 1.0),
    ("NR Pseudoinverse", "a"): (21.24, 16.0, 1100, 11.0, 1.0, 1.0),
    ("GN Pseudoinverse", "a"): (21.72, 16.0, 1090, 10.9, 1.0, 1.0),
    ("LM (Wampler lambda=1e-4)", "a"): (20.1, 14.0, 934, 9.34, 1.0, 1.0),
    ("LM (Wampler lambda=1e-6)", "a"): (29.84, 17.0, 529, 5.29, 1.0, 1.0),
    ("LM (Chan lambda=1.0)", "a"): (16.58, 14.0, 1011, 10.11, 1.0, 1.0),
    ("LM (Chan lambda=0.1)", "a"): (9.43, 9.0, 963, 9.63, 1.0, 1.0),
    ("LM (Sugihara w_n=1e-3)", "a"): (20.54, 15.0, 1024, 10.24, 1.0, 1.0),
    ("LM (Sugihara w_n=1e-4)", "a"): (17.01, 14.0, 1011, 10.11, 1.0, 1.0),
    ("NR", "b"): (30.16, 18.0, 0, 0.0, 1.47, 25.0),
    ("GN", "b"): (30.33, 18.0, 0, 0.0, 1.48, 23.0),
    ("NR Pseudoinverse", "b"): (30.27, 18.0, 0, 0.0, 1.47, 20.0),
    ("GN Pseudoinverse", "b"): (30.65, 18.0, 0, 0.0, 1.49, 20.0),
    ("LM (Wampler lambda=1e-4)", "b"): (25.23, 15.0, 0, 0.0, 1.35, 17.0),
    ("LM (Wampler lambda=1e-6)", "b"): (29.3, 18.0, 0, 0.0, 1.45, 24.0),
    ("LM (Chan lambda=1.0)", "b"): (22.6, 15.0, 0, 0.0, 1.25, 18.0),
    ("LM (Chan lambda=0.1)", "b"): (15.33, 9.0, 0, 0.0, 1.2, 18.0),
    ("LM (Sugihara w_n=1e-3)", "b"): (26.49, 16.0, 0, 0.0, 1.35, 18.0),
    ("LM (Sugihara w_n=1e-4)", "b"): (23.04, 15.0, 0, 0.0, 1.26, 18.0),
}
_PAPER_KEYS = (
    "mean_iterations",
    "median_iterations",
    "infeasible",
    "infeasible_pct",
    "mean_searches",
    "max_searches",
)


def table1_problems(
    robot: Any, n_problems: int = 10000, seed: int = 0
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The authors' problems: (q_targets (N, n), Tep (N, 4, 4), starts (100, n)) from
    ``np.random.seed(seed)`` (a private RandomState, same numbers)."""
    rs = np.random.RandomState(seed)
    lo, hi = np.asarray(robot.qlim, dtype=float)
    q = rs.uniform(lo, hi, size=(int(n_problems), robot.n))
    starts = rs.uniform(lo, hi, size=(100, robot.n))
    return q, np.asarray(robot.fkine(q)), starts


def run_table1(
    robot: Any = "ur5",
    n_problems: int = 10000,
    seed: int = 0,
    methods: Iterable[str] | None = None,
    progress: bool = True,
    settings: Iterable[str] = ("a", "b"),
    backend: str = "c",
    tol: float = 1e-6,
    tol_on: str = "E",
    chunk: int = 1000,
    rtb: bool = True,
    rtb_qp_problems: int = 1000,
) -> dict[str, Any]:
    """Reproduce Table 1 of Part 1 (module docstring) -> a dict with one entry per row.

    Args:
        robot: a Robot or built-in name (the paper uses the UR5).
        methods: row labels of :data:`TABLE1_METHODS` (default all).
        settings: ``"a"`` (1 x 500) and/or ``"b"`` (100 x 30).
        backend: ``"c"`` (fast) or ``"numpy"`` (slow: use a few hundred problems).
        tol, tol_on: the convergence test; the paper's is ``E < 1e-6`` (``tol_on="E"``).
        rtb: also time roboticstoolbox-python's C++ ``ik_LM`` (Chan 0.1, setting b) if installed,
            and compare its ``IK_QP`` with the QP row on the first ``rtb_qp_problems`` targets
            (:mod:`symkin.bench.ik_qp`; needs quadprog).

    Returns:
        ``{"robot", "n_problems", "seed", "tol", "tol_on", "backend", "rows": [...], "rtb"}``; each
        row has method, setting, searches_allowed, iterations_allowed, mean/median_iterations
        (solved problems), infeasible, infeasible_pct, mean/max_searches, us_per_solve,
        us_per_iteration (over all iterations, failed searches included), max_error (largest |e|
        among solved problems) and ``paper`` (the published row or None).
    """
    from symkin.core.progress import bar as progress_bar
    from symkin.model.resolve import resolve_robot
    from symkin.runtime.ik import ik

    robot = resolve_robot("ur5" if robot is None else robot)
    labels = list(TABLE1_METHODS) if methods is None else list(methods)
    unknown = [m for m in labels if m not in TABLE1_METHODS]
    if unknown:
        raise ValueError(f"unknown Table 1 method(s) {unknown}; choose from {list(TABLE1_METHODS)}")
    settings = list(settings)
    bad = [s for s in settings if s not in SETTINGS]
    if bad:
        raise ValueError(f"settings must be among {list(SETTINGS)}, not {bad}")
    _, Tep, starts = table1_problems(robot, n_problems, seed)
    N = len(Tep)
    # the solver runs on the generated C kinematics (the fast path); targets and the reported pose
    # errors come from the numeric reference
    if backend == "c":
        from symkin.runtime.load import compile as compile_robot

        solver = with_lanes(compile_robot(robot, backend="c"))
    else:
        solver = robot
    rows = []
    bar = progress_bar(total=N * len(labels) * len(settings), progress=progress, desc="Table 1", unit="IK")
    for setting in settings:
        slimit, ilimit = SETTINGS[setting]
        for label in labels:
            options = dict(TABLE1_METHODS[label], slimit=slimit, ilimit=ilimit, tol=tol, tol_on=tol_on)
            if robot.n != 6 and options["method"] in ("NR", "GN") and not options.get("pinv"):
                bar.update(N)
                continue  # needs a square J
            parts, elapsed = [], 0.0
            solve = functools.partial(ik, solver, backend=backend, starts=starts, seed=seed, **options)
            solve(Tep[:1])  # build / warm up
            for i in range(0, N, chunk):
                t0 = time.thread_time()
                parts.append(solve(Tep[i : i + chunk]))
                elapsed += time.thread_time() - t0
                bar.update(len(Tep[i : i + chunk]))
            rows.append(_row(robot, Tep, label, setting, parts, elapsed))
    bar.close()
    return {
        "robot": robot.name,
        "n_problems": N,
        "seed": seed,
        "tol": tol,
        "tol_on": tol_on,
        "backend": backend,
        "rows": rows,
        "lanes": _time_lanes(solver, Tep, starts, seed, tol, tol_on) if backend == "c" else None,
        "rtb_requested": bool(rtb),
        "rtb": _time_rtb(robot, n_problems, seed, tol) if rtb else None,
        "rtb_qp": _compare_qp(robot, solver, Tep, starts, labels, tol, rtb_qp_problems, seed)
        if rtb and backend == "c"
        else None,
    }


def _compare_qp(
    robot: Any, kin: Any, Tep: np.ndarray, starts: np.ndarray, labels: list[str], tol: float, problems: int,
    seed: int,
) -> dict[str, Any] | None:  # fmt: skip
    """RTB's IK_QP against the QP row (:func:`symkin.bench.ik_qp.compare_rtb_qp`), when that row runs."""
    from symkin.bench.ik_qp import QP_ROW, compare_rtb_qp

    if QP_ROW not in labels:
        return None
    return guarded(
        lambda: compare_rtb_qp(robot, kin, Tep, starts, TABLE1_METHODS[QP_ROW], tol, problems, seed)
    )


def _time_lanes(
    kin: Any, Tep: np.ndarray, starts: np.ndarray, seed: int, tol: float, tol_on: str
) -> dict[str, Any] | None:
    """LM (Chan, lambda 0.1, 100 x 30) as one batch, its four lanes' poses evaluated by one call of
    the generated four-lane ``fkine_jacob0_batch`` against one scalar ``fkine_jacob0`` per lane:
    the same solver otherwise, and the same solutions (checked)."""
    from symkin.runtime.ik_c import CIKSolver

    options = dict(TABLE1_METHODS["LM (Chan lambda=0.1)"], slimit=100, ilimit=30, tol=tol, tol_on=tol_on)
    four = CIKSolver(kin, starts=starts, **options)
    one = CIKSolver(kin, fkjac=kin.c_fkjac, starts=starts, **options)
    if not four._cfg.fkjac_batch:
        return None
    for solver in (four, one):
        solver.solve(Tep[:8], seed=seed)
    best, results = interleaved(
        {"four_lanes": lambda: four.solve(Tep, seed=seed), "scalar": lambda: one.solve(Tep, seed=seed)}
    )
    same = results["four_lanes"].q.tobytes() == results["scalar"].q.tobytes()
    return {
        "four_lanes_us": 1e6 * best["four_lanes"] / len(Tep),
        "scalar_us": 1e6 * best["scalar"] / len(Tep),
        "same_solutions": same,
    }


def _row(
    robot: Any, Tep: np.ndarray, label: str, setting: str, parts: list, elapsed: float
) -> dict[str, Any]:
    from symkin.runtime.ik import pose_error

    q = np.concatenate([p.q for p in parts])
    success = np.concatenate([p.success for p in parts])
    iterations = np.concatenate([p.iterations for p in parts])
    searches = np.concatenate([p.searches for p in parts])
    N = len(success)
    solved = iterations[success]
    err = np.linalg.norm(pose_error(robot.fkine(q[success]), Tep[success]), axis=-1) if success.any() else []
    slimit, ilimit = SETTINGS[setting]
    paper = PAPER_TABLE1.get((label, setting)) if robot.name == "ur5" else None  # the paper solved a UR5
    return {
        "method": label,
        "setting": setting,
        "searches_allowed": slimit,
        "iterations_allowed": ilimit,
        "mean_iterations": float(solved.mean()) if solved.size else float("nan"),
        "median_iterations": float(np.median(solved)) if solved.size else float("nan"),
        "infeasible": int(N - success.sum()),
        "infeasible_pct": 100.0 * float(N - success.sum()) / N,
        "mean_searches": float(searches.mean()),
        "max_searches": int(searches.max()),
        "us_per_solve": 1e6 * elapsed / N,
        "us_per_iteration": 1e6 * elapsed / max(int(iterations.sum()), 1),
        "max_error": float(np.max(err)) if len(err) else float("nan"),
        "paper": dict(zip(_PAPER_KEYS, paper, strict=True)) if paper else None,
    }


def _time_rtb(robot: Any, n_problems: int, seed: int, tol: float) -> dict[str, Any] | None:
    """roboticstoolbox-python's C++ ``ik_LM`` (Chan, lambda 0.1, 100 x 30) on the same problems."""
    from symkin.bench.kin import rtb_ik_lm

    _, Tep, starts = table1_problems(robot, n_problems, seed)
    return rtb_ik_lm(robot, Tep, tol, _rtb_row, starts[0])


def _rtb_row(seconds: float, success: np.ndarray, iterations: np.ndarray) -> dict[str, Any]:
    return {
        "method": "RTB ik_LM (Chan lambda=0.1), 100 x 30",
        "mean_iterations": float(iterations[success].mean()) if success.any() else float("nan"),
        "infeasible": int((~success).sum()),
        "us_per_solve": 1e6 * seconds,
    }


#: the cells of a row of format_table1 after the method, in order (the paper's without "infeasible")
_CELLS = {
    "searches_allowed": "{}",
    "iterations_allowed": "{}",
    "mean_iterations": "{:.2f}",
    "median_iterations": "{:.0f}",
    "infeasible": "{}",
    "infeasible_pct": "{:.2f}%",
    "mean_searches": "{:.2f}",
    "max_searches": "{:.0f}",
    "us_per_solve": "{:.1f}",
    "us_per_iteration": "{:.3f}",
    "max_error": "{:.1e}",
}


def format_table1(result: dict[str, Any]) -> str:
    """A plain-text table of :func:`run_table1`'s result, the paper's figures beside ours."""
    crit = "E" if result["tol_on"] == "E" else "|e|"
    head = (
        f"Table 1 of Haviland and Corke 2023 (Part 1): {result['n_problems']} problems on {result['robot']}, "
        f"random seed {result['seed']}, "
        f"solved when {crit} < {result['tol']:g}, backend {result['backend']}"
    )
    cols = ["Method", "S", "I", "Mean it", "Med it", "Infeas", "Infeas %", "Mean S", "Max S", "us/solve",
            "us/it", "max|e|", "| paper:", "Mean it", "Med it", "Infeas %", "Mean S", "Max S"]  # fmt: skip
    rows: list[list[str] | None] = []
    for i, r in enumerate(result["rows"]):
        if i and r["setting"] != result["rows"][i - 1]["setting"]:
            rows.append(None)
        p = r["paper"]
        paper = [_CELLS[k].format(p[k]) if p else "-" for k in _PAPER_KEYS if k != "infeasible"]
        rows.append([r["method"], *(cell.format(r[k]) for k, cell in _CELLS.items()), "", *paper])
    out = [head, *table(cols, rows)]
    out.append(
        "S, I: searches and iterations allowed; iteration statistics over solved problems; us/it: time "
        "over all iterations (failed searches included)."
    )
    lanes = result.get("lanes")
    if lanes:
        out.append(
            f"LM (Chan lambda=0.1), 100 x 30, one batch: {lanes['four_lanes_us']:.2f} us/solve with the "
            f"four-lane kinematics, {lanes['scalar_us']:.2f} with scalar kinematics "
            f"({lanes['scalar_us'] / lanes['four_lanes_us']:.2f}x); "
            + ("identical solutions" if lanes["same_solutions"] else "SOLUTIONS DIFFER")
        )
    rtb = result.get("rtb")
    if rtb is None and result.get("rtb_requested"):
        out.append("roboticstoolbox-python ik_LM: not timed (not installed: pip install 'symkin[compare]')")
    if rtb:
        if "error" in rtb:
            out.append(f"roboticstoolbox-python ik_LM: not timed ({rtb['error']})")
        else:
            out.append(
                f"{rtb['method']}: {rtb['us_per_solve']:.1f} us/solve, mean iterations "
                f"{rtb['mean_iterations']:.2f}, infeasible {rtb['infeasible']}"
            )
            ours = next(
                (r for r in result["rows"] if r["method"] == "LM (Chan lambda=0.1)" and r["setting"] == "b"),
                None,
            )
            if ours:
                out.append(
                    f"symkin LM (Chan lambda=0.1), 100 x 30: {ours['us_per_solve']:.1f} us/solve: "
                    f"{rtb['us_per_solve'] / ours['us_per_solve']:.1f}x faster than roboticstoolbox-python"
                )
    if "rtb_qp" in result and any(r["method"].startswith("QP") for r in result["rows"]):
        from symkin.bench.ik_qp import format_rtb_qp

        qp = result["rtb_qp"]
        if qp is not None and "error" in qp:
            out.append(f"roboticstoolbox-python IK_QP: not compared ({qp['error']})")
        elif qp is not None or result.get("rtb_requested"):
            out.append(format_rtb_qp(qp))
    return "\n".join(out)
