"""``symkin bench compile``: what a cold compile costs as chains grow.

For random serial chains of 6, 12, 24 and 36 joints (and the Panda as a reference arm), each in a
fresh process with an empty cache: the derivation, building the code of every function (CSE for
the expanded strategy, dead-code removal for the program strategy), rendering the three
backends' sources, gcc and loading the extension (with ``--derivatives K``, also with the
derivatives of orders 3..K: their cost and size beside the kinematics alone); the operation
counts of FK + J + H computed together (:func:`symkin.symbolic.functions.fk_j_h_counts`) and of
FK + J; and the peak memory of the process and of the compiler it ran.
"""

from __future__ import annotations

import json
import os
import resource
import sys
import time
from collections.abc import Sequence
from typing import Any

import numpy as np

from symkin.bench.common import cpu_seconds, figure, fresh_cache, fresh_python

__all__ = [
    "random_chain",
    "measure",
    "run_compile",
    "format_compile",
    "format_derivatives",
    "plot_compile",
    "DEFAULT_JOINTS",
]

DEFAULT_JOINTS = (6, 12, 24, 36)


def random_chain(n: int, seed: int = 0, name: str | None = None) -> Any:
    """A random serial chain of ``n`` revolute joints: each joint about a random axis (x, y or z)
    followed by one or two translations along random axes of -0.2..0.2 m (to the millimetre), as
    in ``Rz(q0) tx(0.1) Ry(q1) tx(0.05) ...``. Same ``n`` and ``seed``, same chain."""
    from symkin.model.robot import Robot

    rng = np.random.default_rng([n, seed])
    parts = []
    for j in range(n):
        parts.append(f"{rng.choice(['Rx', 'Ry', 'Rz'])}(q{j})")
        for t in rng.choice(["tx", "ty", "tz"], size=int(rng.integers(1, 3)), replace=False):
            parts.append(f"{t}({rng.integers(-200, 201) / 1000})")
    return Robot.from_ets(" ".join(parts), name=name or f"chain{n}_{seed}")


def _peak_mb() -> tuple[float, float]:
    """Peak resident memory (MB) of this process and of the largest child it waited for."""
    scale = 1 / 1024 if sys.platform != "darwin" else 1 / 1024**2
    own = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * scale
    child = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss * scale
    return own, child


def _measure_here(spec: str, seed: int, derivatives: int = 0) -> dict[str, Any]:
    """Cold compile of one robot in this process (the caller provides an empty cache), with the
    derivatives of orders 3..``derivatives``."""
    from symkin.compiler.kernel import kernel_of
    from symkin.emit.c.backend import compile_c, render_c
    from symkin.emit.c.build import load_extension
    from symkin.emit.casadi.backend import render_casadi
    from symkin.emit.numpy.backend import render_numpy
    from symkin.model.resolve import resolve_robot
    from symkin.model.tree import as_tree
    from symkin.symbolic.cse import OpCounts
    from symkin.symbolic.functions import (
        build_functions,
        derivative_functions,
        derive_kinematics,
        fk_j_h_counts,
    )

    robot = random_chain(int(spec), seed) if spec.isdigit() else resolve_robot(spec)
    cpu0 = cpu_seconds()
    t0 = time.perf_counter()
    derived = derive_kinematics(robot)
    t1 = time.perf_counter()
    functions = build_functions(derived)
    t_d = time.perf_counter()
    more = derivative_functions(robot, range(3, derivatives + 1)) if derivatives >= 3 else []
    functions += more
    t2 = time.perf_counter()
    kernel = kernel_of(robot, as_tree(robot), functions, "symkin bench compile")
    files = render_c(kernel)
    t3 = time.perf_counter()
    cpu3 = cpu_seconds()
    python = {**render_numpy(kernel), **render_casadi(kernel)}
    t4 = time.perf_counter()
    cpu4 = cpu_seconds()
    name, path = compile_c(files)
    t5 = time.perf_counter()
    module = load_extension(name, path)
    q = robot.random_q(seed=1)
    err = float(np.abs(module.jacob0(q) - robot.jacob0(q)).max())
    t6 = time.perf_counter()
    cpu6 = cpu_seconds()
    by_name = {f.name: f.code.counts for f in functions}
    own, child = _peak_mb()
    extra: dict[str, Any] = {}
    if more:
        from symkin.bench.common import best_of

        fn = getattr(module, f"derivative{derivatives}")

        def calls() -> None:  # each result dropped at once: its memory serves the next call
            for _ in range(100):
                fn(q)

        extra = dict(
            derivative_error=float(np.abs(fn(q) - robot.derivative(q, derivatives)).max()),
            derivative_us=best_of(calls, 5) * 1e4,
            derivative_ops=sum((f.code.counts for f in more), OpCounts()).total,
            derivative_distinct=max(len(set(f.code.outputs["D"][1])) for f in more if f.order == derivatives),
        )
    return dict(
        robot=robot.name,
        n=robot.n,
        derivatives=derivatives,
        derivatives_s=t2 - t_d,
        numpy_kb=sum(len(t) for n_, t in python.items() if not n_.endswith("_casadi.py")) / 1024,
        casadi_kb=sum(len(t) for n_, t in python.items() if n_.endswith("_casadi.py")) / 1024,
        library_kb=path.stat().st_size / 1024,
        **extra,
        strategy=functions[0].code.strategy,
        derive_s=t1 - t0,
        cse_s=t_d - t1,
        render_c_s=t3 - t2,
        render_py_s=t4 - t3,
        gcc_s=t5 - t4,
        load_s=t6 - t5,
        total_c_s=(t3 - t0) + (t6 - t4),  # derivatives_s included (t_d..t2)
        cpu_c_s=(cpu6 - cpu0) - (cpu4 - cpu3),
        ops_fk_j_h=fk_j_h_counts(derived).total,
        ops_fk_j=fk_j_h_counts(derived, hessian=False).total,
        ops_all=sum((c for c in by_name.values()), OpCounts()).total,
        source_kb=sum(len(t) for t in files.values()) / 1024,
        peak_mb=own,
        gcc_peak_mb=child,
        jacob0_error=err,
    )


def measure(spec: str, seed: int = 0, timeout: float = 1800, derivatives: int = 0) -> dict[str, Any]:
    """Measure one cold compile (``spec``: a joint count for :func:`random_chain`, or a robot; with
    the derivatives of orders 3..``derivatives``) in a fresh Python process with an empty cache, so
    neither imports nor caches carry over."""
    code = (
        "import json, sys; from symkin.bench.compile import _measure_here; "
        f"print(json.dumps(_measure_here({spec!r}, {seed}, {derivatives})))"
    )
    with fresh_cache():
        return json.loads(fresh_python(code, dict(os.environ), timeout, what=f"measuring {spec}"))


def run_compile(
    joints: Sequence[int] = DEFAULT_JOINTS,
    seed: int = 0,
    reference: str | None = "panda",
    progress: bool = False,
    derivatives: int = 0,
) -> list[dict[str, Any]]:
    """One cold compile per chain length (and of ``reference``), each in its own process; with
    ``derivatives`` (3 or more) each one without derivatives, then with those up to order 3, 4, ...,
    ``derivatives`` (each in its own process)."""
    from symkin.core.progress import bar

    specs = ([reference] if reference else []) + [str(n) for n in joints]
    orders = (0, *range(3, derivatives + 1)) if derivatives >= 3 else (0,)
    runs = [(s, d) for s in specs for d in orders]
    return [measure(s, seed, derivatives=d) for s, d in bar(runs, progress, desc="compiling")]


def format_derivatives(rows: list[dict[str, Any]]) -> str:
    """The cold compiles with and without derivatives, side by side."""
    head = (
        "| robot | joints | derivatives up to | derive derivatives s | gcc s | total (to C) s | CPU s "
        "| C source kB | library kB | NumPy kB | CasADi kB | ops of the derivatives "
        "| distinct values (highest order) | highest order, us per call | max error vs reference |"
    )
    lines = [head, "|" + "---|" * 15]
    for r in rows:
        d = r["derivatives"]
        extra = (
            f"{r['derivative_ops']} | {r['derivative_distinct']} | {r['derivative_us']:.2f} | "
            f"{r['derivative_error']:.1e}"
            if d
            else "- | - | - | -"
        )
        lines.append(
            f"| {r['robot']} | {r['n']} | {d or '-'} | {r['derivatives_s']:.2f} | {r['gcc_s']:.2f} | "
            f"**{r['total_c_s']:.2f}** | {r['cpu_c_s']:.2f} | {r['source_kb']:.0f} | {r['library_kb']:.0f} | "
            f"{r['numpy_kb']:.0f} | {r['casadi_kb']:.0f} | {extra} |"
        )
    lines.append("")
    lines.append(
        "Cold cache, each compile in a fresh process: the kinematics alone, then with the derivatives of "
        "orders 3..k (`symkin.compile(robot, derivatives=k)`; also what the first `kin.derivative(q, k)` "
        "compiles). total = derive + code + C source + gcc + load, wall clock; CPU s in CPU time of Python "
        "and the compiler. us per call: the C extension's derivative<k>(q), one configuration, best of 5 "
        "runs of 100 calls (CPU time of the thread; each result dropped before the next call). Error: "
        "against the numeric reference (Part 2's recursion) at one random q."
    )
    return "\n".join(lines)


def format_compile(rows: list[dict[str, Any]]) -> str:
    head = (
        "| robot | joints | strategy | derive s | code s | C source s | gcc s | load s | total (to C) s "
        "| CPU s | ops FK+J+H | ops/joint | ops FK+J | peak MB (python / gcc) |"
    )
    lines = [head, "|" + "---|" * 14]
    for r in rows:
        lines.append(
            f"| {r['robot']} | {r['n']} | {r['strategy']} | {r['derive_s']:.2f} | {r['cse_s']:.2f} | "
            f"{r['render_c_s']:.2f} | {r['gcc_s']:.2f} | {r['load_s']:.2f} | **{r['total_c_s']:.2f}** | "
            f"{r['cpu_c_s']:.2f} | "
            f"{r['ops_fk_j_h']} | {r['ops_fk_j_h'] / r['n']:.0f} | {r['ops_fk_j']} | "
            f"{r['peak_mb']:.0f} / {r['gcc_peak_mb']:.0f} |"
        )
    lines.append("")
    lines.append(
        "Cold cache, each robot in a fresh process. total = derive + code + C source + gcc + load, wall "
        "clock (what `symkin.compile(robot, 'c')` costs the first time); CPU s = the same in CPU time of "
        "Python and the compiler, which a loaded machine inflates less. Rendering the NumPy and "
        "CasADi sources as well takes a further " + ", ".join(f"{r['render_py_s']:.2f}" for r in rows) + " s."
    )
    return "\n".join(lines)


def plot_compile(rows: list[dict[str, Any]], path: str) -> None:
    """Compile time (stacked by phase) and operations per joint against the number of joints."""
    chains = [r for r in rows if r["robot"].startswith("chain") and not r.get("derivatives")]
    n = [r["n"] for r in chains]
    with figure(path, "plot_compile", 120, ncols=2, figsize=(10, 4)) as (fig, (a, b)):
        bottom = np.zeros(len(chains))
        for key, label in (
            ("derive_s", "derive"),
            ("cse_s", "code"),
            ("render_c_s", "C source"),
            ("gcc_s", "gcc"),
        ):
            v = np.array([r[key] for r in chains])
            a.bar([str(x) for x in n], v, bottom=bottom, label=label)
            bottom += v
        a.set_xlabel("joints")
        a.set_ylabel("cold compile to C (s)")
        a.legend()
        b.plot(n, [r["ops_fk_j_h"] / r["n"] for r in chains], "o-", label="FK + J + H")
        b.plot(n, [r["ops_fk_j"] / r["n"] for r in chains], "s-", label="FK + J")
        b.set_xlabel("joints")
        b.set_ylabel("operations per joint (after CSE)")
        b.legend()
        fig.suptitle("symkin bench compile: random serial chains")
