"""Stored outputs of the compiled kinematics and collision queries, to compare later code against.

``python -m tests.data.kernel_reference`` (from the repository root, with ``PYTHONPATH=.``) writes
``tests/data/kernel_reference.npz``: for every built-in robot, the tree fixtures of the tests, a
chain given as a one-frame tree and the URDF sweep's own chains (:func:`symkin.bench.urdf_sweep.
synthetic_urdfs`), at seeded configurations, on the C, NumPy and CasADi backends, each output of
one configuration at a time and of the batch: a chain's ``fkine``, ``jacob0``, ``jacobe``,
``hessian0``, ``hessiane``, ``link_poses``, the link frames' ``fkine``/``jacob0``/``jacobe``,
``manipulability`` and ``jacobm``; a tree's per frame ``fkine``, ``jacob0``, ``jacobe``,
``jacob0_hessian0`` and its ``*_all`` functions. And, on C and NumPy, the collision queries
(``distances``, ``in_collision``, ``distance_jacobians``, with and without obstacles) of the
built-in robots' sphere models and of two trees with shapes, each stored with its geometry (the
test builds the model from the stored shapes, not from today's built-in ones).

``--sweep`` writes ``tests/data/sweep_reference.npz``: every distinct chain of example-robot-data
(:func:`symkin.bench.urdf_sweep.find_chains`), FK, J0, Je and H0 of two configurations on C and
NumPy (needs the ``compare`` extra; a long run: every chain is compiled twice).

:func:`compare` checks the current code against a stored file: FK, J and distances to 2e-15 and
Hessians to 1e-14, each relative to ``max(1, |x|)``, collision verdicts identical.
"""

from __future__ import annotations

import json
import sys
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np

import symkin
from symkin.model.geometry import Box, Capsule, Environment, Geometry, Sphere
from symkin.runtime.kinematics import KIN_METHODS

HERE = Path(__file__).resolve().parent
KERNEL = HERE / "kernel_reference.npz"
SWEEP = HERE / "sweep_reference.npz"
BACKENDS = ("c", "numpy", "casadi")
COLLISION_BACKENDS = ("c", "numpy")
TOL, TOL_H = 2e-15, 1e-14  # FK, J, distances; Hessians (and jacobm, made of them)
K = 4  # configurations per model (one four-lane batch of the C code)

ENV = Environment(
    spheres=(Sphere((0.45, 0.1, 0.5), 0.1), Sphere((-0.3, 0.3, 0.3), 0.15)),
    capsules=(Capsule((0.3, -0.4, 0.0), (0.3, -0.3, 0.8), 0.05),),
    boxes=(Box((0.4, 0.0, -0.1), (0.6, 0.8, 0.05)),),
)


# -- the models ---------------------------------------------------------------------------------
def _tree_fixtures() -> dict[str, Any]:
    from tests.model import tree_urdfs as t

    trees = {
        name: symkin.Tree.from_urdf(getattr(t, name.upper()))
        for name in ("quadruped", "arm_camera", "gripper", "gripper_free", "dual_arm")
    }
    trees["ur5_as_tree"] = symkin.Tree.from_robot(symkin.load("ur5"))
    return trees


def _synthetic() -> dict[str, Any]:
    from symkin.bench.urdf_sweep import synthetic_urdfs

    return {f"sweep_{name[:-5]}": symkin.Robot.from_urdf(text) for name, text in synthetic_urdfs().items()}


def models() -> dict[str, Any]:
    """Name -> model (Robot or Tree) of the kernel reference."""
    from symkin.model.robots import list_robots

    out = {name: symkin.load(name).with_geometry(None) for name in list_robots()}
    return {**out, **_tree_fixtures(), **_synthetic()}


def geometry_models() -> dict[str, Any]:
    """Name -> model with collision shapes: the built-in robots with a sphere model, and two trees."""
    from symkin.model.builtin_geometry import builtin_geometry
    from symkin.model.robots import list_robots

    out = {}
    for name in list_robots():
        g = builtin_geometry(name)
        if g is not None:
            out[f"collide_{name}"] = symkin.load(name).with_geometry(g)
    trees = _tree_fixtures()
    for name in ("gripper", "quadruped"):
        tree = trees[name]
        shapes = tuple(
            Capsule((0, 0, 0), (0.1, 0.02, 0.05), 0.03, link)
            if k % 2
            else Sphere((0.02, 0, 0.03), 0.05, link)
            for k, link in enumerate(tree.link_names)
        )
        out[f"collide_{name}"] = tree.with_geometry(Geometry(shapes))
    return out


def configurations(model: Any, seed: int = 0, k: int = K) -> np.ndarray:
    """``k`` seeded configurations: ``k - 1`` random within the limits, then one at 0."""
    return np.vstack((model.random_q(k - 1, seed=seed), np.zeros(model.n)))


# -- geometry as JSON -------------------------------------------------------------------------------
def geometry_json(g: Geometry) -> str:
    shapes = []
    for s in g.shapes:
        if isinstance(s, Sphere):
            shapes.append({"kind": "sphere", "link": s.link, "center": list(s.center), "radius": s.radius})
        else:
            shapes.append(
                {"kind": "capsule", "link": s.link, "a": list(s.a), "b": list(s.b), "radius": s.radius}
            )
    return json.dumps({"shapes": shapes, "disabled": [list(p) for p in g.disabled]})


def geometry_of(text: str) -> Geometry:
    data = json.loads(text)
    shapes = tuple(
        Sphere(tuple(s["center"]), s["radius"], s["link"])
        if s["kind"] == "sphere"
        else Capsule(tuple(s["a"]), tuple(s["b"]), s["radius"], s["link"])
        for s in data["shapes"]
    )
    return Geometry(shapes, tuple(tuple(p) for p in data["disabled"]))


# -- what is stored ---------------------------------------------------------------------------------
ONE = 2  # of them evaluated one at a time too (the scalar code; the batch runs four lanes at a time)


def _both(f: Callable[[Any], Any], Q: np.ndarray) -> Iterator[tuple[str, Any]]:
    """``f`` of the first :data:`ONE` configurations one at a time (stacked) and of the batch."""
    yield "one", [f(q) for q in Q[:ONE]]
    yield "batch", f(Q)


def _arrays(prefix: str, value: Any) -> dict[str, np.ndarray]:
    """``value`` (an array, a tuple of arrays or a list of either, one per configuration) as arrays."""
    if isinstance(value, list):
        parts = [_arrays(prefix, v) for v in value]
        return {k: np.stack([p[k] for p in parts]) for k in parts[0]}
    if isinstance(value, tuple):
        return {f"{prefix}.{i}": np.asarray(v, dtype=float) for i, v in enumerate(value)}
    return {prefix: np.asarray(value, dtype=float)}


# Outputs that repeat others (the same quantity from another generated function) are compared
# with those instead of being stored: name -> (stored name, index into it or None)
def _same(kind: str, name: str, model: Any) -> tuple[str, Any]:
    if kind == "tree":
        F = len(model.frames)
        table = {
            "fkine_all": [f"fkine@{f}" for f in range(F)],
            "jacob0_all": [f"jacob0@{f}" for f in range(F)],
        }
        table["fkine_jacob0_all.0"], table["fkine_jacob0_all.1"] = table["fkine_all"], table["jacob0_all"]
        table.update({f"jacob0_hessian0@{f}.0": f"jacob0@{f}" for f in range(F)})
        return name, table.get(name)
    table = {
        "fkine_jacob0.0": "fkine",
        "fkine_jacob0.1": "jacob0",
        "jacob0_hessian0.0": "jacob0",
        "jacob0_hessian0.1": "hessian0",
    }
    table.update({f"fkine@{k}": ("link_poses", k) for k in range(model.n)})
    return name, table.get(name)


def kinematics_outputs(model: Any, backend: str, Q: np.ndarray) -> dict[str, np.ndarray]:
    """Every kinematic output of ``model`` compiled for ``backend`` at ``Q`` (``backend/one|batch/name``)."""
    kin = symkin.compile(model, backend=backend)
    calls: dict[str, Callable[[Any], Any]] = {}
    if isinstance(model, symkin.Tree):
        for f, frame in enumerate(model.frames):
            for name in ("fkine", "jacob0", "jacobe", "jacob0_hessian0"):
                calls[f"{name}@{f}"] = lambda q, name=name, frame=frame: getattr(kin, name)(q, frame)
        for name in ("fkine_all", "jacob0_all", "fkine_jacob0_all"):
            calls[name] = getattr(kin, name)
    else:
        for name in (*KIN_METHODS, "manipulability", "jacobm"):
            calls[name] = getattr(kin, name)
        for k in range(model.n):
            for name in ("fkine", "jacob0", "jacobe"):
                calls[f"{name}@{k}"] = lambda q, name=name, k=k: getattr(kin, name)(q, k)
    out = {}
    for key, f in calls.items():
        for how, value in _both(f, Q):
            out.update(_arrays(f"{backend}/{how}/{key}", value))
    return out


def _stored(model: Any, outputs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    """``outputs`` without those :func:`_same` compares with others."""
    kind = "tree" if isinstance(model, symkin.Tree) else "chain"
    return {k: v for k, v in outputs.items() if _same(kind, k.rsplit("/", 1)[-1], model)[1] is None}


def _expected(model: Any, stored: dict[str, np.ndarray], key: str) -> np.ndarray | None:
    """The stored array an output ``key`` is compared with (itself, or what it repeats)."""
    if key in stored:
        return stored[key]
    head, name = key.rsplit("/", 1)
    kind = "tree" if isinstance(model, symkin.Tree) else "chain"
    same = _same(kind, name, model)[1]
    if same is None:
        return None
    if isinstance(same, list):  # a tree's *_all: every frame's, stacked on axis 1
        parts = [stored.get(f"{head}/{s}") for s in same]
        return None if any(p is None for p in parts) else np.stack(parts, axis=1)
    if isinstance(same, tuple):  # a link frame's pose: link_poses[:, k]
        links = stored.get(f"{head}/{same[0]}")
        return None if links is None else links[:, same[1]]
    return stored.get(f"{head}/{same}")


def collision_outputs(model: Any, backend: str, Q: np.ndarray) -> dict[str, np.ndarray]:
    """Distances and verdicts of ``model``'s geometry at ``Q`` with the obstacles :data:`ENV` (the
    self pairs come first), the verdicts of the self pairs alone, and the distance Jacobians of
    the first :data:`ONE` configurations."""
    from symkin.runtime.collision import Collision

    check = Collision(model, backend)
    out = {}
    for how, value in _both(lambda q: check.distances(q, ENV), Q):
        out[f"{backend}/{how}/D"] = np.asarray(value, dtype=float)
    for tag, env in (("self", None), ("env", ENV)):
        for how, value in _both(lambda q, env=env: check.in_collision(q, env), Q):
            out[f"{backend}/{how}/verdict@{tag}"] = np.asarray(value, dtype=bool)
    out[f"{backend}/batch/Jd"] = np.asarray(check.distance_jacobians(Q[:ONE], ENV)[1], dtype=float)
    out[f"{backend}/one/Jd"] = np.asarray(check.distance_jacobians(Q[0], ENV)[1], dtype=float)[None]
    return out


def kernel_entries(names: list[str] | None = None) -> dict[str, dict[str, np.ndarray]]:
    """Model name -> its stored arrays (with ``Q``, and ``geometry`` for the collision models)."""
    out: dict[str, dict[str, np.ndarray]] = {}
    for name, model in models().items():
        if names is None or name in names:
            Q = configurations(model)
            out[name] = {"Q": Q, **_stored(model, fresh_outputs(model, Q, BACKENDS))}
    for name, model in geometry_models().items():
        if names is None or name in names:
            Q = configurations(model, seed=1, k=8)
            geometry = np.array(geometry_json(model.geometry))
            out[name] = {"Q": Q, "geometry": geometry, **fresh_outputs(model, Q, COLLISION_BACKENDS, True)}
    return out


SWEEP_OUTPUTS = ("fkine", "jacob0", "jacobe", "hessian0")


def sweep_outputs(model: Any, backend: str, Q: np.ndarray) -> dict[str, np.ndarray]:
    """FK, J0, Je and H0 of a sweep chain (a Robot, or a one-frame Tree) on ``backend``."""
    kin = symkin.compile(model, backend=backend)
    frame = model.frames[0] if isinstance(model, symkin.Tree) else None
    out = {}
    for key in SWEEP_OUTPUTS:
        for how, value in _both(lambda q, key=key: getattr(kin, key)(q, frame), Q):
            out.update(_arrays(f"{backend}/{how}/{key}", value))
    return out


def sweep_entries(limit: int | None = None) -> dict[str, dict[str, np.ndarray]]:
    """Every distinct chain of example-robot-data: FK, J0, Je and H0 of two configurations (C, NumPy)."""
    from symkin.bench.tree import erd_robots_dir
    from symkin.bench.urdf_sweep import find_chains

    chains = find_chains(erd_robots_dir())[0][:limit]
    out = {}
    for i, ch in enumerate(chains):
        Q = configurations(ch.model, seed=i, k=2)
        where = np.array(f"{ch.urdf}|{ch.base}|{ch.leaf}")
        out[f"chain{i:03d}"] = {
            "Q": Q,
            "where": where,
            **fresh_outputs(ch.model, Q, ("c", "numpy"), sweep=True),
        }
        print(f"{i + 1}/{len(chains)} {ch.urdf}:{ch.leaf}", file=sys.stderr, flush=True)
    return out


def sweep_model(where: str) -> Any:
    """The chain of a sweep entry (``urdf|base|leaf``) as the sweep imports it."""
    from symkin.bench.tree import erd_robots_dir

    urdf, base, leaf = where.split("|")
    path = erd_robots_dir() / urdf
    tree = symkin.Tree.from_urdf(path, frames=[leaf], base_link=base)
    if any(s.is_mimic for s in tree.slots):
        return tree
    return symkin.Robot.from_urdf(path, base_link=base, end_link=leaf)


def fresh_outputs(
    model: Any, Q: np.ndarray, backends: tuple[str, ...], collision: bool = False, sweep: bool = False
) -> dict[str, np.ndarray]:
    """The current code's outputs of ``model`` at ``Q`` on ``backends``."""
    out: dict[str, np.ndarray] = {}
    for b in backends:
        what = collision_outputs if collision else sweep_outputs if sweep else kinematics_outputs
        out.update(what(model, b, Q))
    return out


# -- storing and comparing ---------------------------------------------------------------------------
def _base(key: str) -> tuple[str, int | None] | None:
    """The array a stored output is kept relative to (its difference compresses to almost nothing):
    one configuration at a time -> the batch's first rows, NumPy and CasADi -> C; None for C's batch."""
    backend, how, name = key.split("/", 2)
    if how == "one":
        return f"{backend}/batch/{name}", ONE
    return (f"c/{how}/{name}", None) if backend != "c" else None


def save(entries: dict[str, dict[str, np.ndarray]], path: Path) -> None:
    """Write ``entries`` into one npz; each float output stored as its difference from its
    :func:`_base` where adding it back gives the output exactly."""
    flat = {}
    for model, entry in entries.items():
        for key, value in entry.items():
            base = _base(key) if "/" in key and value.dtype != bool else None
            ref = entry[base[0]][: base[1]] if base is not None and base[0] in entry else None
            diff = value - ref if ref is not None and ref.shape == value.shape else None
            if diff is not None and np.array_equal(ref + diff, value, equal_nan=True):
                flat[f"{model}::{key}~"] = diff
            else:  # no base, or not exact that way (values near 0 of opposite signs)
                flat[f"{model}::{key}"] = value
    np.savez_compressed(path, **flat)


def load(path: Path) -> dict[str, dict[str, np.ndarray]]:
    """The entries :func:`save` wrote (differences added back to their bases)."""
    out: dict[str, dict[str, np.ndarray]] = {}
    relative: list[tuple[str, str, np.ndarray]] = []
    with np.load(path) as data:
        for key in data.files:
            model, name = key.split("::", 1)
            if name.endswith("~"):
                relative.append((model, name[:-1], data[key]))
            else:
                out.setdefault(model, {})[name] = data[key]
    # bases first: C's batch, then C one at a time and the other backends' batches, then theirs
    for model, name, diff in sorted(
        relative, key=lambda r: (r[1].startswith("c/") is False, "/one/" in r[1])
    ):
        base, rows = _base(name)  # type: ignore[misc]
        out[model][name] = out[model][base][:rows] + diff
    return out


def tolerance(key: str) -> float:
    """1e-14 for a Hessian (``hessian0``, ``hessiane``, ``jacobm``, the second output of
    ``jacob0_hessian0``), else 2e-15."""
    name = key.rsplit("/", 1)[-1]
    base, part = name.split("@")[0].split(".")[0], name.rsplit(".", 1)[-1] if "." in name else ""
    hessian = base in ("hessian0", "hessiane", "jacobm") or (base == "jacob0_hessian0" and part == "1")
    return TOL_H if hessian else TOL


def differences(model: Any, stored: dict[str, np.ndarray], fresh: dict[str, np.ndarray]) -> list[str]:
    """What in ``fresh`` differs from ``stored`` beyond the tolerances (module docstring), and what
    of ``stored`` ``fresh`` lacks."""
    bad = [f"{key}: missing" for key in stored if "/" in key and key not in fresh]
    for key, got in fresh.items():
        want = _expected(model, stored, key)
        if want is None:
            bad.append(f"{key}: not stored")
        elif got.shape != want.shape:
            bad.append(f"{key}: shape {got.shape} != {want.shape}")
        elif want.dtype == bool:
            if (got != want).any():
                bad.append(f"{key}: {int((got != want).sum())} verdicts differ")
        else:
            tol = tolerance(key)
            same_inf = (np.isfinite(got) == np.isfinite(want)).all()
            err = np.abs(got - want) / np.maximum(1.0, np.abs(want))
            worst = float(err[np.isfinite(err)].max(initial=0.0))
            if not same_inf or worst > tol:
                bad.append(f"{key}: relative difference {worst:.3g} > {tol:g}")
    return bad


def check(name: str, stored: dict[str, np.ndarray], model: Any) -> list[str]:
    """The differences of the current code from a stored entry (kinematics, collision or sweep)."""
    backends = tuple(sorted({k.split("/", 1)[0] for k in stored if "/" in k}))
    if "geometry" in stored:
        model = model.with_geometry(geometry_of(str(stored["geometry"])))
    fresh = fresh_outputs(model, stored["Q"], backends, "geometry" in stored, "where" in stored)
    return [f"{name}: {line}" for line in differences(model, stored, fresh)]


def main(argv: list[str]) -> int:
    if "--sweep" in argv:
        save(sweep_entries(), SWEEP)
        print(f"wrote {SWEEP}")
        return 0
    save(kernel_entries(), KERNEL)
    print(f"wrote {KERNEL}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
