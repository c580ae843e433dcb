"""Tree rows of ``symkin bench kin`` (and ``symkin bench tree``): whole robots from example-robot-data.

For a quadruped (Solo-12, the four feet) and a humanoid (the ``human`` model, hands and feet):
FK + base-frame Jacobians of every frame in one call of the compiled C tree kernel against
Pinocchio (``forwardKinematics`` then the frame Jacobians of the same frames, the fastest of
three ways of asking for them), the batch throughput on N configurations on one core, and the
cold compile time (a fresh process with an empty cache). Needs the ``compare`` extra
(``example-robot-data``; Pinocchio for its column).
"""

from __future__ import annotations

import os
import time
from importlib import metadata
from pathlib import Path
from typing import Any

import numpy as np

from symkin.bench.common import best_of, cell, fresh_cache, fresh_python, optional, rows_per_s, with_lanes
from symkin.bench.kin import per_call_us

__all__ = ["erd_robots_dir", "TREE_CASES", "run_tree_kin", "format_tree_kin", "cold_compile_seconds"]

# (URDF below example-robot-data's robots folder, frames or None for every leaf)
TREE_CASES: dict[str, tuple[str, str | None]] = {
    "quadruped": ("solo_description/robots/solo12.urdf", None),
    "humanoid": ("human_description/robots/human.urdf", "left_hand,right_hand,left_foot,right_foot"),
}


def erd_robots_dir() -> Path | None:
    """example-robot-data's ``robots`` folder when the package is installed, else None."""
    try:
        dist = metadata.distribution("example-robot-data")
    except metadata.PackageNotFoundError:
        return None
    path = Path(str(dist.locate_file("cmeel.prefix/share/example-robot-data/robots")))
    return path if path.is_dir() else None


def cold_compile_seconds(urdf: Path, frames: tuple[str, ...]) -> float:
    """Seconds to import symkin, read the URDF and compile its tree to C in a fresh process with
    an empty cache (derive, generate, gcc, load)."""
    code = (
        "import sys, time; t = time.perf_counter(); import symkin; "
        f"tree = symkin.Tree.from_urdf({str(urdf)!r}, frames={list(frames)!r}); "
        "symkin.compile(tree, 'c'); print(time.perf_counter() - t)"
    )
    with fresh_cache():
        return float(fresh_python(code, dict(os.environ)))


def pinocchio_q(model: Any, names: Any, q: np.ndarray) -> np.ndarray:
    """Pinocchio's configuration for symkin's joint values ``q`` of the joints ``names`` (others
    at their neutral value; a continuous joint is (cos, sin) in Pinocchio)."""
    import pinocchio as pin

    qp = pin.neutral(model)
    for name, x in zip(names, q):
        i = model.getJointId(name)
        k = model.idx_qs[i]
        if model.nqs[i] == 2:
            qp[k], qp[k + 1] = np.cos(x), np.sin(x)
        else:
            qp[k] = x
    return qp


def _pinocchio(urdf: Path, frames: tuple[str, ...], q: np.ndarray, tree: Any) -> dict[str, Any] | None:
    pin = optional("pinocchio")
    if pin is None:
        return None
    model = pin.buildModelFromUrdf(str(urdf))
    data = model.createData()
    qp = pinocchio_q(model, tree.joint_names, q)
    ids = [model.getFrameId(f) for f in frames]
    world = pin.LOCAL_WORLD_ALIGNED

    def fk_then_frames() -> Any:  # forwardKinematics, then each frame's placement and Jacobian
        pin.forwardKinematics(model, data, qp)
        return [
            (pin.updateFramePlacement(model, data, i), pin.computeFrameJacobian(model, data, qp, i, world))
            for i in ids
        ]

    def joint_jacobians() -> Any:  # computeJointJacobians (FK included), frame placements, getFrameJacobian
        pin.computeJointJacobians(model, data, qp)
        pin.updateFramePlacements(model, data)
        return [(data.oMf[i], pin.getFrameJacobian(model, data, i, world)) for i in ids]

    def frames_fk() -> Any:  # framesForwardKinematics, then computeFrameJacobian per frame
        pin.framesForwardKinematics(model, data, qp)
        return [(data.oMf[i], pin.computeFrameJacobian(model, data, qp, i, world)) for i in ids]

    ways = {"fk_then_frames": fk_then_frames, "joint_jacobians": joint_jacobians, "frames_fk": frames_fk}
    # the three agree with symkin's kernel (checked here, not assumed)
    T, J = tree.fkine_jacob0_all(q)
    for fn in ways.values():
        got = fn()
        cols = [model.idx_vs[model.getJointId(n)] for n in tree.joint_names]
        for k, (placement, Jp) in enumerate(got):
            assert np.abs(placement.homogeneous - T[k]).max() < 1e-9
            assert np.abs(Jp[:, cols] - J[k]).max() < 1e-9
    times = {name: per_call_us(fn) for name, fn in ways.items()}
    best = min(times, key=times.get)  # type: ignore[arg-type]
    Qp = np.array([pinocchio_q(model, tree.joint_names, x) for x in tree.random_q(2000, seed=2)])
    fn = ways[best]
    t0 = time.perf_counter()
    for row in Qp:
        qp[:] = row
        fn()
    per_config = (time.perf_counter() - t0) / len(Qp)
    return {"per_call_us": times, "best": best, "batch_per_s": 1.0 / per_config, "version": pin.__version__}


def run_tree_kin(
    batch: int = 100_000, seed: int = 0, cold: bool = True, cases: tuple[str, ...] = ("quadruped", "humanoid")
) -> dict:
    """Measure every case of :data:`TREE_CASES` (see the module docstring); ``{"skipped": why}``
    without example-robot-data."""
    from symkin.model.tree import Tree
    from symkin.runtime.load import compile as compile_model

    root = erd_robots_dir()
    if root is None:
        return {"skipped": "the tree rows need example-robot-data: pip install 'symkin[compare]'"}
    rows = []
    for name in cases:
        urdf, frames = TREE_CASES[name]
        tree = Tree.from_urdf(root / urdf, frames=frames)
        t0 = time.perf_counter()
        kin = compile_model(tree, "c")
        warm = time.perf_counter() - t0
        with_lanes(kin)
        q = tree.random_q(seed=seed)
        T, J = kin.fkine_jacob0_all(q)
        Tr, Jr = tree.fkine_jacob0_all(q)
        err = max(float(np.abs(T - Tr).max()), float(np.abs(J - Jr).max()))
        row: dict[str, Any] = {
            "case": name,
            "robot": tree.name,
            "urdf": urdf,
            "n": tree.n,
            "frames": list(tree.frames),
            "error_vs_reference": err,
            "symkin_us": {
                fname: per_call_us(lambda fname=fname, kin=kin, q=q: getattr(kin, fname)(q))
                for fname in ("fkine_jacob0_all", "fkine_all", "jacob0_all")
            },
            "reference_us": per_call_us(lambda t=tree, q=q: t.fkine_jacob0_all(q), budget=0.1),
            "compile_s": warm,
        }
        Q = tree.random_q(batch, seed=seed + 1)
        for fname in ("fkine_jacob0_all", "fkine_all"):
            row[f"batch_{fname}_per_s"] = rows_per_s(getattr(kin, fname), Q, time.perf_counter)
        shapes = ((batch, len(tree.frames), 4, 4), (batch, len(tree.frames), 6, tree.n))
        row["batch_write_ceiling_per_s"] = batch / best_of(lambda s=shapes: _fill(s), 3, time.perf_counter)
        row["bytes_per_tree"] = 8 * (16 + 6 * tree.n) * len(tree.frames)
        row["pinocchio"] = _pinocchio(root / urdf, tree.frames, q, tree)
        if cold:
            row["cold_compile_s"] = cold_compile_seconds(root / urdf, tree.frames)
        rows.append(row)
    return {"batch": batch, "rows": rows}


def _fill(shapes: Any) -> None:
    """Allocate and write arrays of the output's size: the memory ceiling of a batch call."""
    for shape in shapes:
        np.empty(shape).fill(1.0)


def format_tree_kin(r: dict) -> str:
    if "skipped" in r:
        return f"trees: skipped ({r['skipped']})"
    lines = ["", "Trees: FK + base-frame Jacobian of every frame, one call from Python (C backend)"]
    head = (
        f"{'case':10} {'robot':8} {'n':>3} {'F':>2} {'symkin us':>10} {'Pinocchio us':>13} {'ratio':>6}  "
        f"{'batch trees/s':>14} {'Pinocchio/s':>12} {'cold compile':>13}"
    )
    lines += [head, "-" * len(head)]
    for row in r["rows"]:
        ours = row["symkin_us"]["fkine_jacob0_all"]
        pin = row["pinocchio"]
        pin_us = pin["per_call_us"][pin["best"]] if pin else None
        lines.append(
            f"{row['case']:10} {row['robot'][:8]:8} {row['n']:>3} {len(row['frames']):>2} {ours:>10.2f} "
            f"{cell(pin_us, '{:.2f}'):>13} {cell(pin_us and pin_us / ours, '{:5.1f}x'):>6}  "
            f"{row['batch_fkine_jacob0_all_per_s']:>14.3g} {cell(pin and pin['batch_per_s'], '{:.3g}'):>12} "
            f"{cell(row.get('cold_compile_s'), '{:.1f} s'):>13}"
        )
    for row in r["rows"]:
        pin = row["pinocchio"]
        extra = ""
        if pin:
            ways = ", ".join(f"{k} {v:.2f} us" for k, v in pin["per_call_us"].items())
            extra = f"; Pinocchio {pin['version']} ways: {ways}"
        us = row["symkin_us"]
        lines.append(
            f"{row['case']}: frames {', '.join(row['frames'])}; fkine_all {us['fkine_all']:.2f} us, "
            f"reference {row['reference_us']:.0f} us, batch fkine_all {row['batch_fkine_all_per_s']:.3g}/s, "
            f"max error vs reference {row['error_vs_reference']:.1e}; allocating and writing the "
            f"{row['bytes_per_tree']} output bytes per tree alone: {row['batch_write_ceiling_per_s']:.3g}/s"
            f"{extra}"
        )
    lines.append(
        f"batch: {r['batch']} configurations on one core; Pinocchio's batch is a Python loop of its best way"
    )
    return "\n".join(lines)
