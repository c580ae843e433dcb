"""``symkin bench ik --analytic``: the closed-form IK against EAIK and against sampling.

For each robot: ``n`` random poses (forward kinematics of configurations uniform within the joint
limits). Measured in one run: the derivation time (sympy, cold), the C solver per pose batched
and one call at a time from Python, the NumPy backend batched, and, when the ``compare`` extra is
installed, EAIK (Ostermeier et al., 2024; subproblem decomposition after IK-Geo, C++) one call at
a time and batched on one thread, with the ratio. Times are per pose: the least process CPU time
of 5 passes over all poses, symkin's and EAIK's passes interleaved
(:func:`symkin.bench.common.interleaved`) so both see the same load on the machine; one call at a
time means a loop that drops each result before the next call. Solution counts and the largest
forward-kinematics error (numeric reference ``Robot.fkine``) of every returned solution, for both.

Branch completeness: per pose, ``starts`` numerical LM searches (C solver, one search each, from
random configurations, no joint limits) sample the solution set; a pose agrees when every sampled
solution is among the closed-form ones (none missed) and every closed-form solution reproduces the
pose to 1e-10 (none spurious). The same count is made for EAIK's exact solutions.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from symkin.bench.common import best_of, cell, interleaved, optional, timed

__all__ = ["run_analytic", "format_analytic", "sampled_solutions"]

MATCH_TOL = 1e-6  # rad or m: a sampled solution matches a closed-form one
EXACT_TOL = 1e-10  # FK error of a returned solution


def _each(f: Any, items: list[Any]) -> None:
    """One call per item, each result dropped before the next call (as a control loop would)."""
    for x in items:
        f(x)


def _wrap(d: np.ndarray, rev: np.ndarray) -> np.ndarray:
    return np.where(rev, np.remainder(d + np.pi, 2 * np.pi) - np.pi, d)


def _contains(rows: np.ndarray, q: np.ndarray, rev: np.ndarray) -> bool:
    return bool(len(rows)) and bool((np.abs(_wrap(rows - q, rev)).max(axis=1) <= MATCH_TOL).any())


def sampled_solutions(kin: Any, T: np.ndarray, starts: int, seed: int) -> list[np.ndarray]:
    """Distinct solutions of each pose in T (N, 4, 4) found by ``starts`` single LM searches."""
    N = len(T)
    rev = np.array([e.is_revolute for e in kin.robot.ets.joints])
    lo = np.where(rev, -np.pi, kin.qlim[0])
    hi = np.where(rev, np.pi, kin.qlim[1])
    TT = np.repeat(T, starts, axis=0)
    Q0 = np.random.default_rng(seed).uniform(lo, hi, size=(N * starts, kin.n))
    res = kin.ik(TT, q0=Q0, slimit=1, ilimit=60, tol=1e-12, joint_limits=False, seed=seed)
    out = []
    for i in range(N):
        found: list[np.ndarray] = []
        for s in range(starts):
            k = i * starts + s
            if res.success[k] and not any(np.abs(_wrap(f - res.q[k], rev)).max() <= 1e-4 for f in found):
                found.append(res.q[k])
        out.append(np.array(found).reshape(len(found), kin.n))
    return out


def _eaik_robot(robot: Any) -> Any:
    """EAIK's robot from symkin's exact joint geometry (IK-Geo H, P convention), or None."""
    EAIK = optional("eaik.pybindings.EAIK")  # noqa: N806
    if EAIK is None:
        return None
    from symkin.symbolic.ik_geometry import geometry, snap

    g = geometry(snap(robot.ets))
    if g.joint != tuple(range(g.n)) or not all(g.revolute):
        return None
    H = np.array([[float(x) for x in h] for h in g.h]).T
    p = np.array([[float(x) for x in v] for v in g.p])
    tM = np.array([float(g.M[i, 3]) for i in range(3)])
    P = np.vstack((p[0], np.diff(p, axis=0), tM - p[-1])).T
    RM = np.array(g.M[:3, :3].tolist(), dtype=float)
    return EAIK.Robot(H, P, RM, [], True)


def run_analytic(
    robots: tuple[str, ...] = ("ur5",), n: int = 1000, starts: int = 32, seed: int = 0, progress: bool = False
) -> dict[str, Any]:
    """Measure every robot of ``robots`` (see the module docstring)."""
    from symkin.core.progress import bar

    out: dict[str, Any] = {"n": n, "starts": starts, "seed": seed, "robots": {}}
    for name in bar(robots, progress, desc="closed-form IK", unit="robot"):
        robot, row = _measure(name, n, starts, seed)
        out["robots"][robot.name] = row
    return out


def _measure(name: str, n: int, starts: int, seed: int) -> tuple[Any, dict[str, Any]]:
    import symkin
    from symkin.compiler.analytic_ik import generate_analytic
    from symkin.model.resolve import resolve_robot
    from symkin.runtime.analytic_ik import compile_analytic

    robot = resolve_robot(name)
    t_derive = timed(lambda: generate_analytic(robot, "c"))[1]
    kin = symkin.compile(robot, "c")
    solver = compile_analytic(robot, "c")
    kin_np = compile_analytic(robot, "numpy")
    Q = np.random.default_rng(seed).uniform(robot.qlim[0], robot.qlim[1], size=(n, robot.n))
    T = np.ascontiguousarray(robot.fkine(Q))
    rev = np.array([e.is_revolute for e in robot.ets.joints])
    row: dict[str, Any] = {"derive_s": t_derive, "kind": solver.kind, "S": solver.max_solutions}
    batch = solver.ik_all(T, joint_limits=False)
    one = [T[i] for i in range(n)]
    kin.ik_all(one[0], None, False)
    bot = _eaik_robot(robot)
    paths = {
        "c_batch_us": lambda: solver.ik_all(T, joint_limits=False),
        "c_one_us": lambda: _each(lambda x: kin.ik_all(x, None, False), one),
    }
    if bot is not None:
        paths["eaik_one_us"] = lambda: _each(bot.calculate_IK, one)
        if hasattr(bot, "calculate_IK_batched"):
            paths["eaik_batch_us"] = lambda: bot.calculate_IK_batched(one, 1)
    # the least process CPU time (time the shared machine gives to other jobs is not counted,
    # threads of a peer library are)
    row.update({k: v / n * 1e6 for k, v in interleaved(paths, 5, time.process_time)[0].items()})
    m = min(n, 200)
    row["numpy_batch_us"] = (
        best_of(lambda: kin_np.ik_all(T[:m], joint_limits=False), 2, time.process_time) / m * 1e6
    )
    sols = [b[~np.isnan(b[:, 0])] for b in batch]
    sampled = sampled_solutions(kin, T, starts, seed) if starts else None
    row.update(_solution_sets("", sols, robot, T, sampled, rev))
    if sampled is not None:
        row["sampled_mean"] = float(np.mean([len(s) for s in sampled]))
    if bot is not None:
        res = [bot.calculate_IK(T[i]) for i in range(n)]
        exact = [np.array([q for q, ls in zip(r.Q, r.is_LS) if not ls]).reshape(-1, robot.n) for r in res]
        row.update(_solution_sets("eaik_", exact, robot, T, sampled, rev))
        row["speedup_one"] = row["eaik_one_us"] / row["c_one_us"]
        if "eaik_batch_us" in row:
            row["speedup_batch"] = row["eaik_batch_us"] / row["c_batch_us"]
    return robot, row


def _solution_sets(
    prefix: str, sets: list[np.ndarray], robot: Any, T: np.ndarray, sampled: list | None, rev: np.ndarray
) -> dict[str, Any]:
    """One solver's solutions of every pose: their mean count, the largest FK error of any and, with
    ``sampled``, the poses that agree (none missed, none spurious; module docstring)."""
    errors = [float(np.abs(robot.fkine(s) - T[i]).max()) if len(s) else 0.0 for i, s in enumerate(sets)]
    out = {
        f"{prefix}mean_solutions": float(np.mean([len(s) for s in sets])),
        f"{prefix}max_fk_error": max(errors, default=0.0),
    }
    if sampled is not None:
        out[f"{prefix}agree"] = sum(
            all(_contains(s, q, rev) for q in sampled[i]) and errors[i] <= EXACT_TOL
            for i, s in enumerate(sets)
        )
    return out


def format_analytic(result: dict[str, Any]) -> str:
    """The result of :func:`run_analytic` as a table."""
    lines = [
        f"closed-form IK, {result['n']} random poses per robot (random seed {result['seed']}); "
        f"sampling: {result['starts']} LM searches per pose",
        f"{'robot':10} {'kind':30} {'derive':>7} {'C batch':>8} {'C one':>7} {'NumPy':>7} {'sols':>5} "
        f"{'max err':>8} {'agree':>6} | {'EAIK one':>8} {'batch':>7} {'sols':>5} {'max err':>8} {'agree':>6} "
        f"{'x one':>6} {'x batch':>7}",
    ]
    for name, r in result["robots"].items():
        lines.append(
            f"{name:10} {r['kind']:30} {r['derive_s']:6.2f}s {r['c_batch_us']:6.2f}us {r['c_one_us']:5.2f}us "
            f"{r['numpy_batch_us']:5.0f}us {r['mean_solutions']:5.2f} {r['max_fk_error']:8.1e} "
            f"{cell(r.get('agree'), '{:d}'):>6} | {cell(r.get('eaik_one_us'), '{:6.2f}'):>6}us "
            f"{cell(r.get('eaik_batch_us'), '{:5.2f}'):>5}us "
            f"{cell(r.get('eaik_mean_solutions'), '{:5.2f}'):>5} "
            f"{cell(r.get('eaik_max_fk_error'), '{:8.1e}'):>8} {cell(r.get('eaik_agree'), '{:d}'):>6} "
            f"{cell(r.get('speedup_one'), '{:5.1f}'):>5}x {cell(r.get('speedup_batch'), '{:6.1f}'):>6}x"
        )
    if not any("eaik_one_us" in r for r in result["robots"].values()):
        lines.append("EAIK not installed (pip install 'symkin[compare]'): no comparison")
    return "\n".join(lines)
