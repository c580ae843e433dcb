"""``symkin bench sincos``: the generated C's sin and cos against the C library's (issue 37).

Two measurements in one run:

- a C microbenchmark: nanoseconds per angle (sin and cos of it) through glibc's ``sincos``, the
  inline scalar ``sk_sin``/``sk_cos`` of ``c/_sincos.c.j2``, the angles of one configuration of m
  joints as a generated scalar function takes them (``sk_sincos_n_``: four at a time) against m
  ``sincos`` calls, and the four-lane kernels of the batch entry points; each over angle sets (the
  joint range, wider angles, the doubles next to multiples of pi/2 that need the reduction's third
  stage), with the largest error against mpmath in ulps and whether the scalar and four-lane
  results are the same bits;
- per call from Python: a robot's C ``fkine``, ``jacob0`` and ``hessian0`` built as usual and
  with ``libm=True`` (glibc's ``sin`` and ``cos`` per angle, which the compiler merges into
  ``sincos``).

Times are CPU times of the calling thread (``time.thread_time``), the paths of a comparison
measured in turn, best of several rounds: trust the ratios on a shared machine.
"""

from __future__ import annotations

import ctypes
import math
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from symkin.bench.common import cells, table
from symkin.bench.kin import interleaved_us

__all__ = ["run_sincos", "format_sincos", "ulp_errors", "angle_sets", "harness", "GOAL"]

GOAL = 1.1  # the inline scalar sin/cos over glibc's sincos, per angle (issue 37)
FUNCS = ("fkine", "jacob0", "hessian0")
PATHS = ("glibc sincos", "sk_sin + sk_cos", "config: m x sincos", "config: sk_sincos_n_", "4 lanes")


def angle_sets(n: int, seed: int = 0) -> dict[str, np.ndarray]:
    """Named sets of ``n`` angles (a multiple of 4 and of every m used): the joint range, wider
    angles, and the doubles nearest k pi/2 (k = 1.. n), where the reduction cancels most bits."""
    import mpmath

    rng = np.random.default_rng(seed)
    with mpmath.workdps(40):
        near = np.array([float(mpmath.mpf(k) * mpmath.pi / 2) for k in range(1, n + 1)])
    return {
        "[-pi, pi]": rng.uniform(-math.pi, math.pi, n),
        "[-100, 100]": rng.uniform(-100.0, 100.0, n),
        "next to k pi/2": near,
    }


def ulp_errors(x: np.ndarray, got: np.ndarray, f: Callable[[Any], Any]) -> np.ndarray:
    """|got - f(x)| in units in the last place of the true value, f an mpmath function evaluated
    with 200 bits (the ulp of 0 taken as the smallest subnormal)."""
    import mpmath

    out = np.empty(len(x))
    with mpmath.workprec(200):
        for i, (xi, gi) in enumerate(zip(x.tolist(), got.tolist())):
            true = f(mpmath.mpf(xi))
            ulp = math.ulp(float(true)) if float(true) != 0 else 5e-324
            out[i] = float(abs(mpmath.mpf(gi) - true) / ulp)
    return out


def harness(m: int = 7) -> ctypes.CDLL:
    """The compiled ``c/bench_sincos.c.j2`` (cached like generated code) for configurations of m
    angles: ``skb_libm``, ``skb_scalar``, ``skb_config``, ``skb_config_libm``, ``skb_lanes`` (when
    built with four lanes), each ``f(x, n, s, c)``."""
    from symkin.emit.c.build import compile_library, load_library
    from symkin.emit.templates import render

    text = render("c/bench_sincos.c.j2", real="double", libm=False, m=m)
    lib = load_library(compile_library({"symkin_bench_sincos.c": text}, f"symkin_bench_sincos{m}"))
    for name in ("skb_libm", "skb_scalar", "skb_config", "skb_config_libm", "skb_lanes"):
        if hasattr(lib, name):
            fn = getattr(lib, name)
            fn.restype = None
            fn.argtypes = (ctypes.c_void_p, ctypes.c_ssize_t, ctypes.c_void_p, ctypes.c_void_p)
    return lib


def _paths(lib: ctypes.CDLL) -> dict[str, Any]:
    names = {
        "glibc sincos": "skb_libm",
        "sk_sin + sk_cos": "skb_scalar",
        "config: m x sincos": "skb_config_libm",
        "config: sk_sincos_n_": "skb_config",
        "4 lanes": "skb_lanes",
    }
    lanes = ctypes.c_int.in_dll(lib, "skb_lanes_built").value == 4
    return {label: getattr(lib, name) for label, name in names.items() if name != "skb_lanes" or lanes}


def _call(f: Any, x: np.ndarray, s: np.ndarray, c: np.ndarray) -> Callable[[], None]:
    """f(x, n, s, c) on the arrays (kept alive by the closure)."""
    return lambda: f(x.ctypes.data, len(x), s.ctypes.data, c.ctypes.data)


def c_sincos(m: int = 7, n: int = 0, rounds: int = 7, seed: int = 0) -> dict[str, Any]:
    """Nanoseconds per angle of each path (:data:`PATHS`) on each angle set (``n`` angles, default
    1024 m), the largest ulp error
    of glibc and of the inline code against mpmath (on up to 2000 angles of each set), and whether
    the scalar, configuration and four-lane results are the same bits."""
    from symkin.bench.common import interleaved

    n = n or 1024 * m
    lib = harness(m)
    paths = _paths(lib)
    out: dict[str, Any] = {"m": m, "n": n, "ns_per_angle": {}, "max_ulp": {}, "same_bits": True}
    for label, x in angle_sets(n, seed).items():
        x = np.ascontiguousarray(x)
        res = {p: (np.empty(n), np.empty(n)) for p in paths}
        calls = {p: _call(f, x, *res[p]) for p, f in paths.items()}
        best, _ = interleaved(calls, rounds)
        out["ns_per_angle"][label] = {p: 1e9 * t / n for p, t in best.items()}
        scalar = res["sk_sin + sk_cos"]
        for p in ("config: sk_sincos_n_", "4 lanes"):
            if p in res:
                for a, b in zip(res[p], scalar):
                    out["same_bits"] &= bool(np.array_equal(a.view(np.uint64), b.view(np.uint64)))
        import mpmath

        k = slice(0, min(n, 2000))
        out["max_ulp"][label] = {
            who: max(
                float(ulp_errors(x[k], res[p][0][k], mpmath.sin).max()),
                float(ulp_errors(x[k], res[p][1][k], mpmath.cos).max()),
            )
            for who, p in (("glibc", "glibc sincos"), ("symkin", "sk_sin + sk_cos"))
        }
    return out


def python_calls(robot: Any, seed: int = 0, budget: float = 0.5) -> dict[str, dict[str, float]]:
    """Nanoseconds per call from Python of the robot's C ``fkine``, ``jacob0`` and ``hessian0``,
    built as usual ("inline") and with ``libm=True`` ("libm"), measured in turn."""
    import symkin
    from symkin.compiler.compile import load_artifact
    from symkin.runtime.kinematics import kinematics_of

    q = robot.random_q(seed=seed)
    kins = {
        "inline": symkin.compile(robot, backend="c"),
        "libm": kinematics_of(robot, load_artifact(symkin.generate(robot, "c", libm=True), "c"), "c"),
    }
    paths = {(label, f): (lambda k=k, f=f: getattr(k, f)(q)) for label, k in kins.items() for f in FUNCS}
    us = interleaved_us(paths, budget, clock=time.thread_time)
    return {label: {f: 1e3 * t for f, t in row.items()} for label, row in us.items()}


def run_sincos(robot_spec: Any = "panda", seed: int = 0, progress: bool = True) -> dict[str, Any]:
    """Both measurements (module docstring) for the joints of ``robot_spec``; a JSON-able dict."""
    from symkin.core.progress import bar
    from symkin.model.resolve import resolve_robot

    robot = resolve_robot(robot_spec)
    m = sum(1 for e in robot.ets if e.is_joint and e.axis.is_rotation) or 1
    out: dict[str, Any] = {"robot": robot.name}
    for name, run in bar(
        [("c", lambda: c_sincos(m, seed=seed)), ("python", lambda: python_calls(robot, seed))],
        progress,
        desc="bench sincos",
    ):
        out[name] = run()
    joint = out["c"]["ns_per_angle"]["[-pi, pi]"]
    ratio = joint["sk_sin + sk_cos"] / joint["glibc sincos"]
    out["check"] = {"scalar_over_glibc": ratio, "goal": f"<= {GOAL:g}", "met": ratio <= GOAL}
    return out


def format_sincos(r: dict[str, Any]) -> str:
    """Plain text of :func:`run_sincos`'s result."""
    c, py, ck = r["c"], r["python"], r["check"]
    ns = c["ns_per_angle"]
    rows = [
        cells(k, row, PATHS, "{:.2f}") + [f"{row['sk_sin + sk_cos'] / row['glibc sincos']:.2f}x"]
        for k, row in ns.items()
    ]
    lines = [
        f"symkin bench sincos: sin and cos of one angle, ns per angle ({c['n']} angles per call, CPU time)",
        "",
    ]
    lines += table(["angles", *(p.replace(" m ", f" {c['m']} ") for p in PATHS), "scalar / glibc"], rows)
    lines += ["", "largest error against mpmath (ulp, first 2000 angles of each set): glibc / symkin"]
    lines += [f"  {label:16} {e['glibc']:.3f} / {e['symkin']:.3f}" for label, e in c["max_ulp"].items()]
    lines.append(
        f"scalar, configuration and four-lane results the same bits: {'yes' if c['same_bits'] else 'NO'}"
    )
    lines += ["", f"{r['robot']}: one call from Python (ns), inline sin/cos against libm=True (glibc)"]
    ratio = {f: py["inline"][f] / py["libm"][f] for f in FUNCS}
    rows = [cells(k, py[k], FUNCS, "{:.1f}") for k in ("inline", "libm")] + [
        cells("ratio", ratio, FUNCS, "{:.2f}x")
    ]
    lines += table(["", *FUNCS], rows)
    lines += [
        "",
        f"goal: scalar sk_sin + sk_cos within {GOAL:g}x glibc's sincos on [-pi, pi]: "
        f"{ck['scalar_over_glibc']:.2f}x, {'met' if ck['met'] else 'MISSED'}",
    ]
    return "\n".join(lines)
