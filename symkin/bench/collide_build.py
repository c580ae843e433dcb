"""``symkin bench collide --build``: what building the collision kernel of a model with many spheres
costs (about 300 spheres and 29 000 self pairs on the Panda), in a fresh cache: the proof of the
self pairs apart (:func:`symkin.geometry.proved_apart`), the C source, the compiler; then the batch
check of that kernel (its self pairs as tables, :mod:`symkin.emit.collision_self`) and, with
``unrolled``, of the same model written as straight-line code, with their verdicts compared.

Wall times (``time.perf_counter``; the compiler runs in another process) and CPU times (this
process, and the compiler's from ``resource``) are both given: a shared machine stretches the
first.
"""

from __future__ import annotations

import ctypes
import time
from typing import Any

import numpy as np

from symkin.bench.common import cpu_seconds, fresh_cache, interleaved

__all__ = ["dense_spheres", "run_build", "format_build"]


def dense_spheres(robot: Any, total: int = 300, seed: int = 0) -> Any:
    """``robot`` with each sphere of its model replaced by about ``total / len(model)`` spheres of
    half its radius, centred at random within half its radius of its centre (seeded): a model of
    ``total`` spheres on the same links (capsules are left out)."""
    from symkin.model.geometry import Geometry, Sphere

    shapes = [s for s in robot.geometry.shapes if isinstance(s, Sphere)]
    rng = np.random.default_rng(seed)
    out = []
    for k, s in enumerate(shapes):
        for _ in range(total // len(shapes) + (k < total % len(shapes))):
            d = rng.normal(size=3)
            c = np.asarray(s.center) + 0.5 * s.radius * rng.random() * d / np.linalg.norm(d)
            out.append(Sphere(c, 0.5 * s.radius, s.link))
    source = f"{len(out)} spheres within the {len(shapes)} of {robot.name}'s model (symkin bench)"
    return robot.with_geometry(Geometry(tuple(out), robot.geometry.disabled, source))


def _timed(f: Any) -> tuple[Any, float, float]:
    """(f(), wall seconds, CPU seconds of this process and its finished children)."""
    w, c = time.perf_counter(), cpu_seconds()
    out = f()
    return out, time.perf_counter() - w, cpu_seconds() - c


def _library(layout: Any, unroll: int | None) -> tuple[Any, dict[str, float]]:
    """The compiled kernel of ``layout`` (straight-line self checks up to ``unroll`` pairs; None:
    the default) and the seconds its source and its compilation took."""
    from symkin.emit import collision_self
    from symkin.emit.c.build import compile_library, load_library
    from symkin.emit.collision import render_collision

    old = collision_self.UNROLL_PAIRS
    collision_self.UNROLL_PAIRS = old if unroll is None else unroll
    try:
        files, w_src, c_src = _timed(lambda: render_collision(layout))
    finally:
        collision_self.UNROLL_PAIRS = old
    path, w_cc, c_cc = _timed(lambda: compile_library(files, "skcoll_build"))
    lib = load_library(path)
    P, i = ctypes.c_void_p, ctypes.c_int
    lib.skcoll_in_collision_batch.argtypes = [P, ctypes.c_long, P, i, P, i, P, i, P]
    times = {"source_s": w_src, "source_cpu_s": c_src, "compile_s": w_cc, "compile_cpu_s": c_cc}
    return lib, times


def _batch_call(lib: Any, Q: np.ndarray, args: list, out: np.ndarray) -> Any:
    """A call of ``lib``'s batch check of ``Q`` against the packed obstacles ``args`` into ``out``."""
    return lambda: lib.skcoll_in_collision_batch(Q.ctypes.data, len(Q), *args, out.ctypes.data)


def run_build(
    robot: Any = "panda", total: int = 300, seed: int = 0, unrolled: bool = False, batch: int = 20_000
) -> dict[str, Any]:
    """Measure (see the module docstring); ``robot`` a name or a Robot with a sphere model."""
    from symkin.bench.collide import random_spheres
    from symkin.emit import collision_self
    from symkin.geometry.clearance import proved_apart
    from symkin.geometry.pairs import layout_of
    from symkin.model.resolve import resolve_robot
    from symkin.runtime.collision import env_args

    model = dense_spheres(resolve_robot(robot), total, seed)
    layout = layout_of(model)
    out: dict[str, Any] = {
        "robot": model.name,
        "spheres": len(layout.shapes),
        "pairs": len(layout.self_pairs),
    }
    with fresh_cache():
        proved, wall, cpu = _timed(lambda: proved_apart(layout))
        out.update(proved=len(proved), proof_s=wall, proof_cpu_s=cpu)
        libs = {"tables": _library(layout, None)}
        if unrolled:
            libs["unrolled"] = _library(layout, len(layout.self_pairs))
    out["tables"] = out["pairs"] > collision_self.UNROLL_PAIRS
    for name, (_, times) in libs.items():
        out[name + "_build"] = times
    Q = np.ascontiguousarray(model.random_q(batch, seed=seed))
    verdicts: dict[str, np.ndarray] = {}
    for count in (0, 10):
        args = env_args(random_spheres(count, seed)).args
        outs = {name: np.zeros(batch, dtype=np.uint8) for name in libs}
        calls = {name: _batch_call(libs[name][0], Q, args, outs[name]) for name in libs}
        best, _ = interleaved(calls, 20)
        for name in libs:
            out[f"{name}_ns_{count}"] = best[name] / batch * 1e9
            verdicts[f"{name}_{count}"] = outs[name]
    if unrolled:
        out["same_verdicts"] = all(
            np.array_equal(verdicts[f"tables_{c}"], verdicts[f"unrolled_{c}"]) for c in (0, 10)
        )
    return out


def format_build(r: dict[str, Any]) -> str:
    t = r["tables_build"]
    build = r["proof_s"] + t["source_s"] + t["compile_s"]
    lines = [
        f"Building the kernel of a {r['spheres']}-sphere {r['robot']} ({r['pairs']} self pairs, "
        f"{'tables' if r['tables'] else 'straight-line code'}) in a fresh cache: {build:.1f} s "
        f"(proof of {r['proved']} pairs apart {r['proof_s']:.1f} s, CPU {r['proof_cpu_s']:.1f} s; source "
        f"{t['source_s']:.1f} s; compiler {t['compile_s']:.1f} s, CPU {t['compile_cpu_s']:.1f} s)",
        f"  batch check: {r['tables_ns_0']:.0f} ns per configuration, {r['tables_ns_10']:.0f} ns against 10 "
        "spheres",
    ]
    if "unrolled_build" in r:
        u = r["unrolled_build"]
        x0, x10 = r["tables_ns_0"] / r["unrolled_ns_0"], r["tables_ns_10"] / r["unrolled_ns_10"]
        lines.append(
            f"  as straight-line code: compiler {u['compile_s']:.1f} s (CPU {u['compile_cpu_s']:.1f} s); "
            f"{r['unrolled_ns_0']:.0f} / {r['unrolled_ns_10']:.0f} ns (tables {x0:.2f}x / {x10:.2f}x); "
            f"same verdicts: {r['same_verdicts']}"
        )
    return "\n".join(lines)
