"""``symkin bench calls``: the paths a user calls one thing at a time, each beside its baseline.

Every figure is measured in the same run as the figure it is compared with, and printed as a
ratio next to the goal it answers (symkin's targets for one call at a time):

- IK: one ``kin.ik(T)`` per target against the per-solve time of the scalar batch (the same
  targets one at a time in one C call) and of the four-lane batch ``kin.ik(T_all)``, where one
  call's time goes (arguments, GIL, solver: kinematics and steps, result), and against
  roboticstoolbox-python's C++ ``ik_LM`` (when installed);
- NR and GN with the pseudo-inverse against LM, per iteration;
- an RRMC and an MMC step from Python on the C backend, and ``servo`` steps per second with the
  loop in C and in Python;
- the NumPy backend against Pinocchio (when installed) and the CasADi backend against calling its
  raw ``casadi.Function``, one configuration per call;
- ``import symkin`` and the first ``kin.jacob0`` on a warm cache, each in fresh processes, beside
  ``import numpy``.

Times are CPU times of the calling thread (``time.thread_time``), so that other processes on a
shared machine do not count, best of several rounds (:func:`symkin.bench.kin.per_call_us`), the
paths of one comparison measured in turn within each round; loops over many targets or tasks take
the best of a few rounds too. Start-up figures are wall times in
fresh interpreters (the fastest and the median of several). Trust the ratios.
"""

from __future__ import annotations

import functools
import math
import os
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from symkin.bench.common import best_of, cells, fresh_python, interleaved, table, with_lanes
from symkin.bench.kin import interleaved_us, per_call_us, pinocchio_calls, rtb_ik_lm

__all__ = ["run_calls", "format_calls", "GOALS"]

CLOCK = time.thread_time  # see the module docstring

#: symkin's targets for one call at a time (a ratio or an absolute figure), by check
GOALS: dict[str, tuple[str, float]] = {
    "ik_single_over_scalar_batch": ("<=", 1.5),
    "ik_rtb_over_single": (">=", 10.0),
    "pinv_nr_over_lm_per_iteration": ("<=", 2.0),
    "pinv_gn_over_lm_per_iteration": ("<=", 2.0),
    "rrmc_step_us": ("<=", 3.0),
    "servo_rrmc_steps_per_s": (">=", 200_000.0),
    "servo_mmc_steps_per_s": (">=", 200_000.0),
    "numpy_over_pinocchio_fkine": ("<=", 3.0),
    "numpy_over_pinocchio_jacob0": ("<=", 3.0),
    "numpy_over_pinocchio_manipulability": ("<=", 3.0),
    "casadi_over_raw_fkine": ("<=", 1.2),
    "casadi_over_raw_jacob0": ("<=", 1.2),
    "casadi_over_raw_hessian0": ("<=", 1.2),
    "casadi_over_raw_manipulability": ("<=", 1.2),
    "import_s": ("<=", 0.3),
    "first_jacob0_s": ("<=", 0.5),
}


# -- IK ----------------------------------------------------------------------------------------
def ik_calls(robot: Any, kin: Any, n_targets: int, seed: int, rounds: int, rtb: bool) -> dict[str, Any]:
    """One target per ``kin.ik(T)`` call against the batch ``kin.ik(T_all)`` (default options: LM
    Chan lambda 0.1, 100 x 30, |e| < 1e-6; four targets side by side in vector lanes), the scalar
    batch (the same targets one at a time in one C call: the solver a single call runs, without
    Python) and RTB's C++ ``ik_LM`` with the same options (its tolerance is on E = |e|^2 / 2: 5e-13);
    ``parts_ns``: where one call's time goes (:func:`ik_call_parts`)."""
    from symkin.runtime.ik import default_c_solver

    Tep = np.asarray(robot.fkine(robot.random_q(n_targets, seed=seed)))
    targets = list(Tep)
    kin.ik(Tep[:4])
    kin.ik(targets[0])
    solver = default_c_solver(kin)
    out: dict[str, Any] = {"targets": n_targets}
    best, last = interleaved(
        {
            "batch": lambda: kin.ik(Tep),
            "single": lambda: [kin.ik(T) for T in targets],
            "scalar": lambda: solver.solve_each(Tep, seed),
        },
        rounds,
    )
    res, results = last["batch"], last["single"]
    out["batch_us"] = 1e6 * best["batch"] / n_targets
    out["single_us"] = 1e6 * best["single"] / n_targets
    out["scalar_batch_us"] = 1e6 * best["scalar"] / n_targets
    out["batch_success"] = float(np.mean(res.success))
    out["single_success"] = float(np.mean([r.success for r in results]))
    out["scalar_batch_success"] = float(np.mean(last["scalar"][1]))
    out["mean_iterations"] = float(np.mean([r.iterations for r in results]))
    out["parts_ns"] = ik_call_parts(solver, targets, robot.random_q(n_targets, seed=seed + 2), rounds)
    out["rtb"] = _rtb_ik(robot, targets) if rtb else None
    return out


def ik_call_parts(
    solver: Any, targets: list[np.ndarray], Q: np.ndarray, rounds: int
) -> dict[str, float] | None:
    """Nanoseconds of one ``solve(T)`` call by part, the least over ``rounds`` passes over the
    targets, from the extension's timing build (:meth:`CIKSolver.profiled`; its clock reads add a
    few tens of ns): taking the arguments, releasing and retaking the GIL, the solver, the result
    object; and per iteration of the solver, one pose and Jacobian evaluation (the time of
    evaluating at ``Q``, one at a time in C) and the rest (error, convergence test, LM step)."""
    profiled = solver.profiled()
    if profiled is None:
        return None
    solve, parts = profiled
    names = ("arguments", "gil", "solver", "result")
    best = dict.fromkeys(names, math.inf)
    iterations = 0
    for _ in range(rounds):
        parts()
        iterations = sum(int(solve(T).iterations) for T in targets)
        calls, *ns = parts()
        for name, t in zip(names, ns):
            best[name] = min(best[name], t / calls)
    kin_ns = 1e9 * best_of(lambda: solver.kin_each(Q), rounds, CLOCK) / len(Q)
    per_call = iterations / len(targets)
    return best | {
        "iterations_per_call": per_call,
        "kinematics_per_iteration": kin_ns,
        "rest_per_iteration": best["solver"] / per_call - kin_ns,
    }


def _rtb_ik(robot: Any, targets: list[np.ndarray]) -> dict[str, Any] | None:
    return rtb_ik_lm(robot, targets, 5e-13, lambda s, ok, _: {"us": 1e6 * s, "success": float(np.mean(ok))})


def pinv_per_iteration(robot: Any, kin: Any, n_targets: int, seed: int, rounds: int) -> dict[str, Any]:
    """Microseconds per iteration (pose evaluation) of LM, NR and GN with the pseudo-inverse, over the
    same targets, batched (as Table 1 runs them) and one target per call."""
    Tep = np.asarray(robot.fkine(robot.random_q(n_targets, seed=seed + 1)))
    methods = {"LM": {}, "NR pinv": {"method": "NR", "pinv": True}, "GN pinv": {"method": "GN", "pinv": True}}
    paths: dict[tuple[str, str], Callable[[], Any]] = {}
    for label, options in methods.items():
        kin.ik(Tep[:2], seed=seed, **options)
        paths[(label, "batch")] = lambda o=options: kin.ik(Tep, seed=seed, **o)
        paths[(label, "single")] = lambda o=options: [kin.ik(T, seed=seed, **o) for T in Tep]
    best, last = interleaved(paths, rounds)  # the methods in turn, so that each sees the same machine
    out = {}
    for label in methods:
        res, sols = last[(label, "batch")], last[(label, "single")]
        out[label] = {
            "batch_us_per_iteration": 1e6 * best[(label, "batch")] / int(np.sum(res.iterations)),
            "success": float(np.mean(res.success)),
            "single_us_per_iteration": 1e6 * best[(label, "single")] / sum(int(s.iterations) for s in sols),
        }
    return out


# -- control -------------------------------------------------------------------------------------
def control_calls(kin: Any, seed: int, n_tasks: int, rounds: int, budget: float = 0.25) -> dict[str, Any]:
    """RRMC and MMC steps from Python (C backend) and servo steps per second, Table I tasks (MMC paper
    eq 14, joint speeds unbounded as in the paper), loop in C and in Python."""
    from symkin.bench.mmc import table1_tasks
    from symkin.runtime.control import MMC, rrmc
    from symkin.runtime.loop import servo

    robot = kin.robot
    rng = np.random.default_rng(seed)
    q = robot.random_q(seed=rng)
    nu = rng.normal(0.0, 0.1, 6)
    mmc = MMC(kin, qd_max=np.inf)
    us = functools.partial(per_call_us, budget=budget, clock=CLOCK)  # microseconds per call
    steps = {
        "jacob0 (yardstick)": us(lambda: kin.jacob0(q)),
        "rrmc (C)": us(lambda: rrmc(kin, q, nu, qd_max=np.inf)),
        "MMC.step (C)": us(lambda: mmc.step(q, nu)),
        "rrmc (NumPy, reference kinematics)": us(lambda: rrmc(robot, q, nu, qd_max=np.inf)),
    }
    q0s, Teps = table1_tasks(kin, n_tasks, np.random.default_rng([seed, 1]))
    tasks = list(zip(q0s, Teps))
    loops: dict[str, dict[str, float]] = {"rrmc": {}, "mmc": {}}
    for name in loops:
        for backend, subset in (("c", tasks), ("python", tasks[: max(1, n_tasks // 10)])):

            def run(backend: str = backend, subset: list = subset, name: str = name) -> int:
                return sum(servo(kin, q0, T, name, qd_max=np.inf, backend=backend).steps for q0, T in subset)

            total = run()
            loops[name][backend] = total / best_of(run, rounds, CLOCK)
            loops[name][f"{backend}_steps"] = total
    return {"step_us": steps, "servo_steps_per_s": loops, "tasks": n_tasks}


# -- backends ------------------------------------------------------------------------------------
def numpy_vs_pinocchio(robot: Any, q: np.ndarray, budget: float = 0.25) -> dict[str, Any]:
    """One configuration per call: the NumPy backend, the C backend and Pinocchio (FK of one frame
    by ``forwardKinematics`` + ``updateFramePlacement``; ``computeFrameJacobian``, LOCAL_WORLD_ALIGNED;
    manipulability as sqrt(det(J J^T)) of that Jacobian through numpy)."""
    import symkin

    kn, kc = symkin.compile(robot, backend="numpy"), symkin.compile(robot, backend="c")
    paths: dict[tuple[str, str], Callable[[], Any]] = {}
    for label, k in (("numpy", kn), ("c", kc)):
        paths[(label, "fkine")] = lambda k=k: k.fkine(q)
        paths[(label, "jacob0")] = lambda k=k: k.jacob0(q)
        paths[(label, "manipulability")] = lambda k=k: k.manipulability(q)
    pin = pinocchio_calls(robot, q)
    if pin is not None:
        paths[("pinocchio", "fkine")] = pin["fkine"]
        paths[("pinocchio", "jacob0")] = pin["frame_jacobian"]
        paths[("pinocchio", "manipulability")] = pin["manipulability"]
        paths[("pinocchio (all frames)", "fkine")] = pin["fkine_all_frames"]
    return interleaved_us(paths, budget, clock=CLOCK)


def casadi_vs_raw(robot: Any, q: np.ndarray, budget: float = 0.25) -> dict[str, Any]:
    """One configuration per call: the CasADi backend's methods against calling its raw
    ``casadi.Function`` with the same numpy array (which returns a DM)."""
    import symkin

    ka = symkin.compile(robot, backend="casadi")
    raw = ka.functions  # type: ignore[attr-defined]
    pairs = {
        "fkine": (lambda: ka.fkine(q), lambda: raw["fkine"](q)),
        "jacob0": (lambda: ka.jacob0(q), lambda: raw["jacob0"](q)),
        "hessian0": (lambda: ka.hessian0(q), lambda: raw["hessian0"](q)),
        "manipulability": (lambda: ka.manipulability(q), lambda: raw["manipulability_all"](q)),
    }
    paths = {(k, "backend"): a for k, (a, _) in pairs.items()}
    paths.update({(k, "raw"): b for k, (_, b) in pairs.items()})
    return interleaved_us(paths, budget, clock=CLOCK)


# -- start-up ------------------------------------------------------------------------------------
_IMPORT = "import time; t = time.perf_counter(); import {m}; print(time.perf_counter() - t)"
_FIRST = (
    "import time; t = time.perf_counter(); import symkin; kin = symkin.compile({robot!r}); "
    "kin.jacob0(kin.robot.qz); print(time.perf_counter() - t)"
)


def startup(robot: str, runs: int) -> dict[str, Any]:
    """Seconds for ``import numpy``, ``import symkin`` and import + compile (warm cache) + the first
    ``kin.jacob0``, each in ``runs`` fresh interpreters after one warm-up (min and median).

    The interpreters keep byte code as an installed package does (``pip install`` compiles it): in
    a temporary ``PYTHONPYCACHEPREFIX``, also when ``PYTHONDONTWRITEBYTECODE`` is set (without byte
    code every import compiles symkin's sources, about 0.15 s)."""
    import tempfile

    import symkin

    symkin.compile(robot)  # warm the cache
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    out: dict[str, Any] = {}
    with tempfile.TemporaryDirectory(prefix="symkin-bench-pycache-") as pycache:
        env["PYTHONPYCACHEPREFIX"] = pycache
        for key, code in (
            ("import_numpy_s", _IMPORT.format(m="numpy")),
            ("import_s", _IMPORT.format(m="symkin")),
            ("first_jacob0_s", _FIRST.format(robot=robot)),
        ):
            fresh_python(code, env, 300)  # a warm-up (page cache, byte code)
            times = [float(fresh_python(code, env, 300)) for _ in range(runs)]
            out[key] = {"min": min(times), "median": float(np.median(times))}
    return out


# -- all -----------------------------------------------------------------------------------------
def run_calls(
    robot_spec: Any = "ur5",
    control_robot: Any = "panda",
    n_targets: int = 500,
    n_tasks: int = 100,
    seed: int = 0,
    rounds: int = 5,
    startup_runs: int = 7,
    progress: bool = True,
    budget: float = 0.25,
) -> dict[str, Any]:
    """Every section (module docstring); returns a JSON-able dict with ``checks``: each goal of
    :data:`GOALS` with the measured figure and whether it meets the bar. ``budget``: seconds per
    timed call path (about)."""
    import symkin
    from symkin.model.resolve import resolve_robot

    robot = resolve_robot(robot_spec)
    crobot = resolve_robot(control_robot)
    kin = with_lanes(symkin.compile(robot, backend="c"))
    q = robot.random_q(seed=seed)
    sections: list[tuple[str, Callable[[], Any]]] = [
        ("ik", lambda: ik_calls(robot, kin, n_targets, seed, rounds, rtb=True)),
        ("pinv", lambda: pinv_per_iteration(robot, kin, n_targets, seed, max(2, rounds // 2))),
        (
            "control",
            lambda: control_calls(symkin.compile(crobot, backend="c"), seed, n_tasks, rounds, budget),
        ),
        ("numpy", lambda: numpy_vs_pinocchio(robot, q, budget)),
        ("casadi", lambda: casadi_vs_raw(robot, q, budget)),
        ("startup", lambda: startup(robot_spec if isinstance(robot_spec, str) else robot.name, startup_runs)),
    ]
    from symkin.core.progress import bar

    out: dict[str, Any] = {"robot": robot.name, "control_robot": crobot.name}
    for name, run in bar(sections, progress, desc="bench calls"):
        out[name] = run()
    out["checks"] = _checks(out)
    return out


def _checks(r: dict[str, Any]) -> dict[str, dict[str, Any]]:
    ik, pinv, ctl, npy, cas, st = (r[k] for k in ("ik", "pinv", "control", "numpy", "casadi", "startup"))
    lm = pinv["LM"]["single_us_per_iteration"]
    fig: dict[str, float | None] = {
        "ik_single_over_scalar_batch": ik["single_us"] / ik["scalar_batch_us"],
        "ik_rtb_over_single": (ik["rtb"]["us"] / ik["single_us"])
        if ik.get("rtb") and "us" in ik["rtb"]
        else None,
        "pinv_nr_over_lm_per_iteration": pinv["NR pinv"]["single_us_per_iteration"] / lm,
        "pinv_gn_over_lm_per_iteration": pinv["GN pinv"]["single_us_per_iteration"] / lm,
        "rrmc_step_us": ctl["step_us"]["rrmc (C)"],
        "servo_rrmc_steps_per_s": ctl["servo_steps_per_s"]["rrmc"]["c"],
        "servo_mmc_steps_per_s": ctl["servo_steps_per_s"]["mmc"]["c"],
        "import_s": st["import_s"]["min"],
        "first_jacob0_s": st["first_jacob0_s"]["min"],
    }
    for f in ("fkine", "jacob0", "manipulability"):
        pin_row = npy.get("pinocchio")
        fig[f"numpy_over_pinocchio_{f}"] = npy["numpy"][f] / pin_row[f] if pin_row else None
    for f, row in cas.items():
        fig[f"casadi_over_raw_{f}"] = row["backend"] / row["raw"]
    checks = {}
    for key, (op, bar) in GOALS.items():
        v = fig.get(key)
        ok = None if v is None else (v <= bar if op == "<=" else v >= bar)
        checks[key] = {"value": v, "goal": f"{op} {bar:g}", "met": ok}
    return checks


def format_calls(r: dict[str, Any]) -> str:
    """Plain text of :func:`run_calls`'s result."""
    ik, pinv, ctl = r["ik"], r["pinv"], r["control"]
    scalar = ik["scalar_batch_us"]
    lines = [
        f"symkin bench calls: {r['robot']} (IK, backends, start-up), {r['control_robot']} (control)",
        "",
        f"IK, {ik['targets']} targets, LM Chan lambda 0.1, 100 x 30, |e| < 1e-6 (us per solve):",
        f"  batched kin.ik(T_all)      {ik['batch_us']:8.2f}   success {ik['batch_success']:.3f}",
        f"  scalar batch (one C call)  {scalar:8.2f}   success {ik['scalar_batch_success']:.3f}   "
        f"({scalar / ik['batch_us']:.2f}x batched)",
        f"  one kin.ik(T) per target   {ik['single_us']:8.2f}   success {ik['single_success']:.3f}   "
        f"({ik['single_us'] / scalar:.2f}x scalar batch, {ik['single_us'] / ik['batch_us']:.2f}x batched; "
        f"mean iterations {ik['mean_iterations']:.1f})",
    ]
    parts = ik.get("parts_ns")
    if parts:
        lines.append(
            "  one call (ns): arguments {arguments:.0f}, GIL {gil:.0f}, solver {solver:.0f} "
            "(per iteration: kinematics {kinematics_per_iteration:.0f}, rest {rest_per_iteration:.0f}), "
            "result {result:.0f}".format(**parts)
        )
    rtb = ik.get("rtb")
    if rtb and "us" in rtb:
        lines.append(
            f"  RTB C++ ik_LM, same options {rtb['us']:6.1f}   success {rtb['success']:.3f}   "
            f"(one symkin call is {rtb['us'] / ik['single_us']:.1f}x faster)"
        )
    elif rtb:
        lines.append(f"  RTB ik_LM: not timed ({rtb['error']})")
    lines += ["", "IK per iteration (us): batched / one target per call"]
    lm = pinv["LM"]
    for label, row in pinv.items():
        lines.append(
            f"  {label:8} {row['batch_us_per_iteration']:7.3f} / {row['single_us_per_iteration']:7.3f}   "
            f"({row['batch_us_per_iteration'] / lm['batch_us_per_iteration']:.2f}x / "
            f"{row['single_us_per_iteration'] / lm['single_us_per_iteration']:.2f}x LM)   "
            f"success {row['success']:.3f}"
        )
    lines += ["", "Control steps from Python (us):"]
    lines += [f"  {label:36} {us:8.2f}" for label, us in ctl["step_us"].items()]
    lines.append(f"servo, {ctl['tasks']} Table I tasks (steps per second):")
    for name, row in ctl["servo_steps_per_s"].items():
        lines.append(
            f"  {name:5} loop in C {row['c']:10.0f}   loop in Python {row['python']:8.0f}   "
            f"({row['c'] / row['python']:.1f}x)"
        )
    funcs, one = ("fkine", "jacob0", "manipulability"), r["numpy"]
    rows = [cells(label, row, funcs, "{:.2f}") for label, row in one.items()]
    if "pinocchio" in one:
        p, npy, c = one["pinocchio"], one["numpy"], one["c"]
        rows.append(cells("numpy / pinocchio", {f: npy[f] / p[f] for f in funcs}, funcs, "{:.2f}x"))
        rows.append(cells("pinocchio / c", {f: p[f] / c[f] for f in funcs}, funcs, "{:.2f}x"))
        all_frames = {"fkine": npy["fkine"] / one["pinocchio (all frames)"]["fkine"]}
        rows.append(cells("numpy / pinocchio all fr.", all_frames, funcs, "{:.2f}x"))
    lines += ["", "One configuration per call (us):", *("  " + x for x in table(["path", *funcs], rows))]
    if "pinocchio" not in one:
        lines.append("  (install the compare extra for Pinocchio)")
    lines.append("  CasADi backend vs its raw casadi.Function:")
    for f, row in r["casadi"].items():
        lines.append(
            f"    {f:16} {row['backend']:8.2f} vs {row['raw']:8.2f}   ({row['backend'] / row['raw']:.2f}x)"
        )
    st = r["startup"]
    lines += ["", "Fresh interpreter, wall time (s, fastest / median):"]
    for key, label in (
        ("import_numpy_s", "import numpy"),
        ("import_s", "import symkin"),
        ("first_jacob0_s", "import, compile (warm), first jacob0"),
    ):
        lines.append(f"  {label:38} {st[key]['min']:.3f} / {st[key]['median']:.3f}")
    lines += ["", "Goals (targets for one call at a time):"]
    for key, c in r["checks"].items():
        v = c["value"]
        shown = "n/a" if v is None else (f"{v:.0f}" if abs(v) >= 1000 else f"{v:.3g}")
        verdict = "n/a" if c["met"] is None else ("met" if c["met"] else "MISSED")
        lines.append(f"  {key:40} {shown:>10}   goal {c['goal']:>10}   {verdict}")
    return "\n".join(lines)
