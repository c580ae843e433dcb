"""``symkin bench urdf``: every serial chain of example-robot-data, compiled and checked.

For each URDF of the collection, the chains from the root (or the child of a floating or planar
joint) to every leaf link; identical chains (the same exact ETS) are counted once. Each distinct
chain is compiled on every backend (C, NumPy, CasADi; a fresh cache, so each compile derives,
generates and builds) and its FK and base-frame Jacobian are compared, at 12 configurations,
with the numeric reference and, when Pinocchio is installed, with Pinocchio's frame placement
and LOCAL_WORLD_ALIGNED frame Jacobian, all to 1e-10. A chain through a mimic joint is compiled
as a one-frame :class:`symkin.Tree` (a :class:`symkin.Robot` has independent joints only).
Needs the ``compare`` extra (example-robot-data).

The sweep also compiles the chains of :func:`synthetic_urdfs`, written here: a 6-joint arm with
2, 3 and 4 fixed joints of rpy ``0.1 0.2 0.3`` after it, with 2000 such fixed links after it,
before it and between its joints, and with 2000 fixed links of quarter turns and translations
(what a collection rarely holds, and what once made the compile hang).
"""

from __future__ import annotations

import tempfile
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from symkin.bench.common import figure, fresh_cache, optional, timed
from symkin.bench.tree import erd_robots_dir, pinocchio_q

__all__ = ["Chain", "find_chains", "run_sweep", "format_sweep", "plot_sweep", "synthetic_urdfs", "TOL"]

TOL = 1e-10
_ARM_AXES = ("0 0 1", "0 1 0", "0 1 0", "1 0 0", "0 1 0", "1 0 0")


def _fixed_joints_urdf(name: str, layout: list[int | str], rpy: str, xyz: str = "0.01 0.02 0.03") -> str:
    """A chain of ``layout``: ``"J"`` a revolute joint of a 6-joint arm, a number that many fixed
    joints with origin ``xyz`` and ``rpy``."""
    links, joints = ["base"], []
    for item in layout:
        for _ in range(1 if item == "J" else int(item)):
            parent, child = links[-1], f"link{len(links)}"
            links.append(child)
            if item == "J":
                k = sum(1 for j in joints if 'type="revolute"' in j)
                joints.append(
                    f'<joint name="j{k}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
                    f'<origin xyz="0 0 0.1" rpy="0 0 0"/><axis xyz="{_ARM_AXES[k % 6]}"/>'
                    '<limit lower="-2.8" upper="2.8" velocity="2" effort="10"/></joint>'
                )
            else:
                joints.append(
                    f'<joint name="fixed{len(links)}" type="fixed"><parent link="{parent}"/>'
                    f'<child link="{child}"/><origin xyz="{xyz}" rpy="{rpy}"/></joint>'
                )
    body = "\n  ".join([f'<link name="{n}"/>' for n in links] + joints)
    return f'<?xml version="1.0"?>\n<robot name="{name}">\n  {body}\n</robot>\n'


def synthetic_urdfs() -> dict[str, str]:
    """File name -> URDF text of the sweep's own chains (module docstring)."""
    arm: list[int | str] = ["J"] * 6
    rpy = "0.1 0.2 0.3"
    out = {f"arm6_fixed{k}.urdf": _fixed_joints_urdf(f"arm6_fixed{k}", [*arm, k], rpy) for k in (2, 3, 4)}
    out["arm6_fixed2000.urdf"] = _fixed_joints_urdf("arm6_fixed2000", [*arm, 2000], rpy)
    out["fixed2000_arm6.urdf"] = _fixed_joints_urdf("fixed2000_arm6", [2000, *arm], rpy)
    out["arm6_fixed300_between.urdf"] = _fixed_joints_urdf(
        "arm6_fixed300_between", [x for _ in range(6) for x in ("J", 300)], rpy
    )
    out["arm6_fixed2000_quarter_turns.urdf"] = _fixed_joints_urdf(
        "arm6_fixed2000_quarter_turns", [*arm, 2000], "0 0 1.5707963267948966"
    )
    return out


@dataclass
class Chain:
    """One distinct chain: where it comes from, and what the sweep measured."""

    urdf: str
    base: str
    leaf: str
    n: int
    key: str
    model: Any = None  # Robot, or Tree with one frame (mimic joints on the path)
    also: list[str] = field(default_factory=list)  # the same chain elsewhere (urdf:leaf)
    compile_s: dict[str, float] = field(default_factory=dict)
    error: dict[str, float] = field(default_factory=dict)
    pinocchio: float | None = None
    snap: float = 0.0  # how far the default import (angles snapped within 1e-9) is from the file as written
    failure: str = ""
    joints_key: str = ""  # the chain up to its last joint (without the constant tail to the leaf)
    synthetic: bool = False  # one of synthetic_urdfs(), not of the collection
    mimic: bool = False  # a mimic joint on the path: the model is a one-frame Tree


def _start(graph: Any, leaf: str, root: str) -> str:
    """The chain's base: the root, or the child of the last floating/planar joint on the path."""
    base = root
    for j in graph.path(root, leaf):
        if j.kind in ("floating", "planar"):
            base = j.child
    return base


def _short(exc: Exception, path: Path, rel: str) -> str:
    text = str(exc).replace(f"URDF file {str(path)!r}: ", "").replace(str(path), rel)
    return text if len(text) <= 200 else text[:197] + "..."


def find_chains(root: Path) -> tuple[list[Chain], list[tuple[str, str]], int]:
    """(distinct chains, URDFs that could not be read with the reason, chains found in all)."""
    from symkin.errors import SymkinError
    from symkin.model.robot import Robot
    from symkin.model.tree import Tree
    from symkin.model.urdf import read_graph

    chains: dict[str, Chain] = {}
    bad: list[tuple[str, str]] = []
    found = 0
    for path in sorted(root.rglob("*.urdf")):
        rel = str(path.relative_to(root))
        try:
            graph = read_graph(path)
            roots = graph.roots
            if len(roots) != 1:
                raise SymkinError(f"{len(roots)} root links")
        except SymkinError as exc:
            bad.append((rel, _short(exc, path, rel)))
            continue
        for leaf in graph.leaves(roots[0]):
            base = _start(graph, leaf, roots[0])
            try:
                tree = Tree.from_urdf(path, frames=[leaf], base_link=base)
            except SymkinError as exc:
                bad.append((f"{rel}:{leaf}", _short(exc, path, rel)))
                continue
            if tree.n == 0:
                continue
            found += 1
            mimic = any(s.is_mimic for s in tree.slots)
            model = tree if mimic else Robot.from_urdf(path, base_link=base, end_link=leaf)
            if mimic:  # the structure without names: transforms and slot rules
                last = max(s.segment for s in tree.slots)
                parts = [" ".join(map(str, s.ets)) + f"/{s.parent}" for s in tree.segments]
                rules = [f"{s.joint},{s.multiplier},{s.offset}" for s in tree.slots]
                key, joints_key = "|".join(parts + rules), "|".join(parts[: last + 1] + rules)
            else:
                last = max(i for i, e in enumerate(model.ets) if e.is_joint)
                key, joints_key = str(model.ets), " ".join(map(str, tuple(model.ets)[: last + 1]))
            if key in chains:
                chains[key].also.append(f"{rel}:{leaf}")
                continue
            chains[key] = Chain(rel, base, leaf, tree.n, key, model, joints_key=joints_key, mimic=mimic)
    return list(chains.values()), bad, found


def _pin_errors(
    root: Path, chain: Chain, Q: np.ndarray, T: np.ndarray, J: np.ndarray, cache: dict
) -> float | None:
    """Largest difference from Pinocchio's placement and LOCAL_WORLD_ALIGNED Jacobian of the leaf,
    both taken relative to the chain's base link; None when Pinocchio cannot load the URDF."""
    pin = optional("pinocchio")
    if pin is None:
        return None
    mimic = chain.mimic
    key = (chain.urdf, mimic)
    if key not in cache:
        try:
            model = pin.buildModelFromUrdf(str(root / chain.urdf), mimic)
            cache[key] = (model, model.createData())
        except Exception:  # noqa: BLE001 - Pinocchio refuses some files (its mimic parser)
            cache[key] = None
    if cache[key] is None:
        return None
    model, data = cache[key]
    names = chain.model.joint_names
    if any(not model.existJointName(n) for n in names):
        return None
    fb, fl = model.getFrameId(chain.base), model.getFrameId(chain.leaf)
    cols = [model.idx_vs[model.getJointId(n)] for n in names]
    worst = 0.0
    for q, Tq, Jq in zip(Q, T, J):
        qp = pinocchio_q(model, names, q)
        pin.computeJointJacobians(model, data, qp)
        pin.updateFramePlacements(model, data)
        Tb = data.oMf[fb].homogeneous
        Rt = Tb[:3, :3].T
        Tl = np.linalg.inv(Tb) @ data.oMf[fl].homogeneous
        Jp = pin.getFrameJacobian(model, data, fl, pin.LOCAL_WORLD_ALIGNED)[:, cols]
        Jb = np.vstack((Rt @ Jp[:3], Rt @ Jp[3:]))
        worst = max(worst, float(np.abs(Tl - Tq).max()), float(np.abs(Jb - Jq).max()))
    return worst


def run_sweep(
    backends: tuple[str, ...] = ("c", "numpy", "casadi"),
    progress: bool = True,
    limit: int | None = None,
    seed: int = 0,
    synthetic: bool = True,
) -> dict:
    """Compile and check every distinct chain (module docstring); the summary and each chain's row.
    ``limit`` takes the first chains of the collection; ``synthetic`` adds :func:`synthetic_urdfs`."""
    from symkin.compiler.compile import BACKENDS
    from symkin.core.progress import bar
    from symkin.runtime.load import compile as compile_model

    for b in backends:
        if b not in BACKENDS:
            raise ValueError(f"unknown backend {b!r}: choose from {', '.join(BACKENDS)}")
    root = erd_robots_dir()
    if root is None:
        return {
            "ok": False,
            "skipped": "symkin bench urdf needs example-robot-data: pip install 'symkin[compare]'",
        }
    (chains, bad, found), t_find = timed(lambda: find_chains(root))
    chains = chains[:limit] if limit else chains
    pin_cache: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        own = Path(tmp) / "synthetic"
        own.mkdir()
        for name, text in synthetic_urdfs().items() if synthetic else ():
            (own / name).write_text(text)
        extra = find_chains(own)[0]
        for ch in extra:
            ch.synthetic = True
        todo = [(c, root) for c in chains] + [(c, own) for c in extra]
        with fresh_cache():  # every compile derives, generates and builds
            for ch, where in bar(todo, progress, desc="chains"):
                _one(ch, backends, compile_model, where, pin_cache, seed)
    rows = [
        {"urdf": c.urdf, "base": c.base, "leaf": c.leaf, "n": c.n,
         "mimic": c.mimic, "same_as": c.also, "compile_s": c.compile_s,
         "error": c.error, "pinocchio": c.pinocchio, "snap": c.snap, "failure": c.failure,
         "synthetic": c.synthetic}
        for c in chains + extra
    ]  # fmt: skip
    return {
        "ok": all(not r["failure"] for r in rows),
        "files": len({c.urdf for c in chains} | {b[0].split(":")[0] for b in bad}),
        "unreadable": bad,
        "found": found,
        "distinct": len(chains),
        "distinct_to_last_joint": len({c.joints_key for c in chains}),
        "find_s": t_find,
        "backends": list(backends),
        "rows": rows,
    }


def _one(
    ch: Chain, backends: tuple[str, ...], compile_model: Any, root: Path, pin_cache: dict, seed: int
) -> None:
    model = ch.model
    rng = np.random.default_rng(seed)
    Q = np.vstack((model.random_q(10, seed=rng), np.zeros(model.n), np.full(model.n, 0.1)))
    T_ref, J_ref = model.fkine(Q), model.jacob0(Q)  # a Robot, or a Tree of the one frame
    fails = []
    for b in backends:
        try:
            kin, ch.compile_s[b] = timed(lambda b=b: compile_model(model, b))
        except Exception as exc:  # noqa: BLE001 - a bench reports every failure and goes on
            fails.append(f"{b}: compile failed: {type(exc).__name__}: {str(exc).splitlines()[0][:200]}")
            continue
        T, J = kin.fkine(Q), kin.jacob0(Q)
        err = max(float(np.abs(T - T_ref).max()), float(np.abs(J - J_ref).max()))
        ch.error[b] = err
        if not err <= TOL:
            fails.append(f"{b}: FK/J differ from the reference by {err:.2e}")
    # Pinocchio reads the numbers as written: compare it with symkin's import as written
    # (snap_tol=0), and report how far snapping moved the default import from that
    T_exact, J_exact = _as_written(root, ch, Q)
    ch.snap = max(float(np.abs(T_exact - T_ref).max()), float(np.abs(J_exact - J_ref).max()))
    ch.pinocchio = _pin_errors(root, ch, Q, T_exact, J_exact, pin_cache)
    if ch.pinocchio is not None and not ch.pinocchio <= TOL:
        fails.append(f"reference differs from Pinocchio by {ch.pinocchio:.2e}")
    ch.failure = "; ".join(fails)


def _as_written(root: Path, ch: Chain, Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The chain's reference FK and J imported with ``snap_tol=0`` (every number as written)."""
    from symkin.model.robot import Robot
    from symkin.model.tree import Tree

    path = root / ch.urdf
    if ch.mimic:
        model = Tree.from_urdf(path, frames=[ch.leaf], base_link=ch.base, snap_tol=0.0)
    else:
        model = Robot.from_urdf(path, base_link=ch.base, end_link=ch.leaf, snap_tol=0.0)
    return model.fkine(Q), model.jacob0(Q)


def format_sweep(r: dict) -> str:
    if "skipped" in r:
        return f"symkin bench urdf: skipped ({r['skipped']})"
    rows = [row for row in r["rows"] if not row.get("synthetic")]
    own = [row for row in r["rows"] if row.get("synthetic")]
    to_last = r.get("distinct_to_last_joint", "?")
    lines = [
        f"symkin bench urdf: example-robot-data, {r['files']} URDF files, {r['found']} root-to-leaf chains "
        f"with joints, {r['distinct']} distinct (same ETS counted once; {to_last} distinct up to the last "
        f"joint), found in {r['find_s']:.1f} s",
    ]
    hist = Counter(row["n"] for row in rows)
    lines.append("joints per distinct chain: " + ", ".join(f"{n}: {hist[n]}" for n in sorted(hist)))
    mimic = sum(row["mimic"] for row in rows)
    lines.append(f"chains through mimic joints (compiled as one-frame trees): {mimic}")
    lines.append("")
    head = (
        f"{'backend':8} {'compiled':>9} {'within 1e-10':>13} {'median s':>9} {'max s':>7} {'total s':>8}"
        "  slowest chain"
    )
    lines += [head, "-" * len(head)]
    for b in r["backends"]:
        times = [(row["compile_s"][b], row) for row in rows if b in row["compile_s"]]
        ok = sum(1 for row in rows if row["error"].get(b, np.inf) <= TOL)
        if not times:
            lines.append(f"{b:8} {0:>9} {ok:>13}")
            continue
        ts = np.array([t for t, _ in times])
        slow = max(times, key=lambda x: x[0])[1]
        lines.append(
            f"{b:8} {len(times):>9} {ok:>13} {np.median(ts):>9.2f} {ts.max():>7.2f} {ts.sum():>8.0f}  "
            f"{slow['urdf']}:{slow['leaf']} ({slow['n']} joints)"
        )
    by_n: dict[int, list[float]] = {}
    for row in rows:
        if "c" in row["compile_s"]:
            by_n.setdefault(row["n"], []).append(row["compile_s"]["c"])
    if by_n:
        lines.append("C compile (derive + generate + gcc + load) by joints: " + ", ".join(
            f"{n}: {np.median(v):.1f} s" for n, v in sorted(by_n.items())))  # fmt: skip
    errs = [e for row in rows for e in row["error"].values()]
    if errs:
        lines.append(f"largest FK/J difference from the numeric reference: {max(errs):.1e}")
    pins = [row["pinocchio"] for row in rows if row["pinocchio"] is not None]
    if pins:
        lines.append(
            f"Pinocchio compared on {len(pins)} chains (symkin's import as written, snap_tol=0): largest "
            f"difference {max(pins):.1e}"
        )
    else:
        lines.append("Pinocchio: not installed or no chain comparable")
    snaps = [row.get("snap", 0.0) for row in rows]
    moved = sum(1 for s in snaps if s > 0)
    lines.append(
        f"snapping (the default, angles within 1e-9 of k pi/4 made exact) moved {moved} chains' FK/J by at "
        f"most {max(snaps, default=0.0):.1e} from the file as written"
    )
    if own:
        lines += ["", f"the sweep's own chains (fixed joints with rpy, long fixed chains): {len(own)}"]
        for row in own:
            times = ", ".join(f"{b} {t:.1f} s" for b, t in row["compile_s"].items())
            err = max(row["error"].values(), default=float("nan"))
            pin = "" if row.get("pinocchio") is None else f", from Pinocchio {row['pinocchio']:.1e}"
            lines.append(f"  {row['urdf']} ({row['n']} joints): compile {times}; FK/J error {err:.1e}{pin}")
    fails = [row for row in rows + own if row["failure"]]
    lines += ["", f"failures: {len(fails)}" + ("" if fails else " (every chain compiled and matched)")]
    lines += [f"  {row['urdf']}:{row['leaf']}: {row['failure']}" for row in fails]
    if r["unreadable"]:
        lines.append(f"URDF files or chains symkin refuses ({len(r['unreadable'])}), with the reason:")
        lines += [f"  {name}: {why}" for name, why in r["unreadable"]]
    return "\n".join(lines)


def plot_sweep(r: dict, path: str) -> None:
    with figure(path, "plot_sweep", 120, figsize=(7, 4)) as (_, ax):
        for b in r.get("backends", []):
            pts = [(row["n"], row["compile_s"][b]) for row in r["rows"] if b in row["compile_s"]]
            if pts:
                x, y = zip(*pts)
                ax.scatter(x, y, s=12, label=b)
        ax.set_xlabel("joints")
        ax.set_ylabel("compile time (s)")
        ax.set_title("every distinct chain of example-robot-data")
        ax.legend()
