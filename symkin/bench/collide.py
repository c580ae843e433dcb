"""``symkin bench collide``: collision checks per configuration, one call and batched, with the
robot's sphere model against 0, 10 and 100 obstacle spheres, beside the generated NumPy module and (with
the ``compare`` extra) Pinocchio + coal on the same spheres and capsules, all in the same run; the
batch with about 19 % of its configurations outside the joint limits against one within them;
collision-aware IK against plain IK in three scenes (a table top, 10 random spheres, VAMP's cage of
14 spheres), a batch of targets and one target per call; and the MMC step with obstacle rows (the
velocity dampers of the closest pairs) in C against the Python reference step.

Times are CPU times of the calling thread (``time.thread_time``), best of several repeats.
Obstacles: spheres of radius 0.05 m at uniform random places in a 1.6 m cube around the base
(seeded), so a fraction of configurations collide; the verdict rates are printed too.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from symkin.bench.common import best_of, interleaved, optional
from symkin.bench.kin import per_call_us

__all__ = [
    "run_collide",
    "format_collide",
    "random_spheres",
    "table_scene",
    "cage_scene",
    "pinocchio_collision",
    "beyond_limits",
    "add_obstacles",
]


def random_spheres(count: int, seed: int = 0, radius: float = 0.05) -> Any:
    """``count`` obstacle spheres in [-0.8, 0.8]^2 x [0, 1.2] m (base frame)."""
    from symkin.model.geometry import Environment, Sphere

    rng = np.random.default_rng(seed)
    P = rng.uniform([-0.8, -0.8, 0.0], [0.8, 0.8, 1.2], size=(count, 3))
    return Environment(spheres=tuple(Sphere(p, radius) for p in P))


def table_scene() -> Any:
    """A table top (box under the arm's reach, its top 0.05 m below the base) and two posts on it."""
    from symkin.model.geometry import Box, Capsule, Environment, Sphere

    return Environment(
        spheres=(Sphere((0.45, 0.35, 0.25), 0.08),),
        capsules=(Capsule((0.4, -0.4, 0.0), (0.4, -0.4, 0.5), 0.05),),
        boxes=(Box((0.5, 0.0, -0.1), (0.5, 0.8, 0.05)),),
    )


def cage_scene() -> Any:
    """VAMP's cage around a Panda at the origin (Thomason, Kingston and Kavraki, Motions in
    Microseconds via Vectorized Sampling-Based Planning, 2024, its benchmark scene): 14 spheres of
    radius 0.2 m, seven at z = 0.25 m and seven at z = 0.8 m, on a ring of radius about 0.5 m."""
    from symkin.model.geometry import Environment, Sphere

    low = ((0.55, 0), (0.35, 0.35), (0, 0.55), (-0.55, 0), (-0.35, -0.35), (0, -0.55), (0.35, -0.35))
    high = ((0.35, 0.35), (0, 0.55), (-0.35, 0.35), (-0.55, 0), (-0.35, -0.35), (0, -0.55), (0.35, -0.35))
    rings = ((low, 0.25), (high, 0.8))
    return Environment(spheres=tuple(Sphere((x, y, z), 0.2) for ring, z in rings for x, y in ring))


def beyond_limits(robot: Any, count: int, seed: int = 0, outside: float = 0.19) -> np.ndarray:
    """(count, n) configurations uniform in the joint limits widened about their middle so that a
    fraction ``outside`` of them has a joint beyond its limits (joints with infinite limits keep
    them)."""
    lo, hi = (np.asarray(x, dtype=float) for x in robot.qlim)
    finite = np.isfinite(lo) & np.isfinite(hi)
    grow = (1.0 - outside) ** (-1.0 / max(int(finite.sum()), 1)) - 1.0  # per joint, of its range
    Q = robot.random_q(count, seed=seed)
    w = np.where(finite, hi - lo, 0.0)
    u = np.random.default_rng(seed).random(Q.shape)
    wide = lo - 0.5 * grow * w + (1.0 + grow) * w * u
    return np.ascontiguousarray(np.where(finite, wide, Q))


def pinocchio_collision(robot: Any, env: Any) -> Any:
    """``check(q) -> bool`` with Pinocchio + coal on ``robot``'s spheres and capsules and ``env``'s
    spheres (the same active pairs, in the order of ``kin.distances``), or None without Pinocchio;
    ``check.distances(q)`` gives coal's distance of every pair. Pinocchio's model is the robot's
    serial chain (``symkin.bench.kin.pinocchio_model``)."""
    coal, pin = optional("coal"), optional("pinocchio")
    if coal is None or pin is None:
        return None
    from symkin.bench.kin import pinocchio_model
    from symkin.geometry.pairs import layout_of
    from symkin.model.geometry import Capsule

    model, _, ee = pinocchio_model(robot)
    layout = layout_of(robot)
    geom = pin.GeometryModel()
    for k, s in enumerate(layout.shapes):
        seg = layout.segment[k]  # -1 base, k < n: link frame k (Pinocchio joint k + 1), n: the end effector
        if seg < 0:
            parent_joint, placement = 0, pin.SE3.Identity()
        elif seg < robot.n:
            parent_joint, placement = seg + 1, pin.SE3.Identity()
        else:
            parent_joint, placement = model.frames[ee].parentJoint, model.frames[ee].placement
        if isinstance(s, Capsule):
            a, b = np.array(s.a), np.array(s.b)
            length = float(np.linalg.norm(b - a))
            shape = coal.Capsule(s.radius, length)
            z = (b - a) / length if length > 0 else np.array([0.0, 0.0, 1.0])
            R = _rotation_to(z)
            local = pin.SE3(R, 0.5 * (a + b))
        else:
            shape = coal.Sphere(s.radius)
            local = pin.SE3(np.eye(3), np.array(s.center))
        geom.addGeometryObject(pin.GeometryObject(f"s{k}", parent_joint, placement * local, shape))
    for i, j in layout.self_pairs:
        geom.addCollisionPair(pin.CollisionPair(i, j))
    add_obstacles(pin, coal, geom, env)
    data, gdata = model.createData(), pin.GeometryData(geom)

    def check(q: np.ndarray) -> bool:
        return bool(pin.computeCollisions(model, data, geom, gdata, q, True))

    def distances(q: np.ndarray) -> np.ndarray:
        pin.computeDistances(model, data, geom, gdata, q)
        return np.array([r.min_distance for r in gdata.distanceResults])

    check.distances = distances  # type: ignore[attr-defined]
    return check


def add_obstacles(pin: Any, coal: Any, geom: Any, env: Any, to_world: np.ndarray | None = None) -> int:
    """Add ``env``'s spheres and boxes (symkin's base frame; ``to_world``: the 4x4 pose of that frame
    in Pinocchio's world, default identity) to the Pinocchio GeometryModel ``geom`` on the universe
    joint, each paired with every object already in it (the robot's); returns how many."""
    B = np.eye(4) if to_world is None else to_world
    n = len(geom.geometryObjects)
    shapes = [(coal.Sphere(s.radius), np.eye(3), s.center) for s in env.spheres]
    shapes += [(coal.Box(*(2 * np.array(b.half_extents))), b.R, b.center) for b in env.boxes]
    for k, (shape, R, c) in enumerate(shapes):
        pose = pin.SE3(B[:3, :3] @ R, B[:3, :3] @ np.array(c) + B[:3, 3])
        geom.addGeometryObject(pin.GeometryObject(f"obstacle_{k}", 0, pose, shape))
        for i in range(n):
            geom.addCollisionPair(pin.CollisionPair(i, n + k))
    return len(shapes)


def _rotation_to(z: np.ndarray) -> np.ndarray:
    """A rotation whose third column is the unit vector ``z``."""
    t = np.array([1.0, 0.0, 0.0]) if abs(z[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    x = np.cross(t, z)
    x /= np.linalg.norm(x)
    return np.column_stack((x, np.cross(z, x), z))


def _row(robot: Any, kernel: Any, numpy_kin: Any, Q: np.ndarray, env: Any) -> dict[str, Any]:
    """One row: per call, batched, distances, the generated NumPy module and Pinocchio + coal on ``env``."""
    batch = len(Q)
    row: dict[str, Any] = {"obstacles": len(env)}
    row["one_call_ns"] = per_call_us(lambda: kernel.in_collision(Q[0], env), budget=0.1) * 1e3
    row["batch_ns"] = best_of(lambda: kernel.in_collision(Q, env), 40) / batch * 1e9  # a few ms each
    row["batch_distances_ns"] = best_of(lambda: kernel.distances(Q, env), 1) / batch * 1e9
    small = Q[: max(batch // 20, 1)]
    row["numpy_batch_ns"] = best_of(lambda: numpy_kin.in_collision(small, env), 1) / len(small) * 1e9
    hits = kernel.in_collision(Q, env)
    row["colliding"] = float(np.mean(hits))
    peer = pinocchio_collision(robot, env)
    if peer is not None:
        few = Q[: min(batch, 2000)]
        verdicts = np.array([peer(q) for q in few])
        row["pinocchio_agrees"] = float(np.mean(verdicts == hits[: len(few)]))
        row["pinocchio_ns"] = best_of(lambda: [peer(q) for q in few], 1) / len(few) * 1e9
        row["speedup_batch_vs_pinocchio"] = row["pinocchio_ns"] / row["batch_ns"]
    row["speedup_batch_vs_numpy"] = row["numpy_batch_ns"] / row["batch_ns"]
    return row


def run_collide(
    robot: Any = "panda", batch: int = 20_000, seed: int = 0, progress: bool = True, ik_targets: int = 200
) -> dict:
    """Measure (see the module docstring); ``robot`` a name or a Robot with geometry."""
    from symkin.model.resolve import resolve_robot
    from symkin.runtime.load import compile as compile_robot

    robot = resolve_robot(robot)
    kin = compile_robot(robot, backend="c")
    numpy_kin = compile_robot(robot, backend="numpy")
    Q = robot.random_q(batch, seed=seed)
    kernel = kin.collision()
    rows = []
    for count in (0, 10, 100):
        if progress:
            print(f"  {count} obstacle spheres ...", flush=True)
        rows.append(_row(robot, kernel, numpy_kin, Q, random_spheres(count, seed)))
    if progress:
        print("  outside the joint limits ...", flush=True)
    limits = [_limits_row(kernel, robot, Q, random_spheres(count, seed), seed) for count in (0, 10)]
    ik = []
    for name, scene in (("table top", table_scene()), ("10 random spheres", random_spheres(10, seed)),
                        ("cage", cage_scene())):  # fmt: skip
        if progress:
            print(f"  IK, {name} ...", flush=True)
        ik.append(ik_scene(kin, robot, name, scene, ik_targets, seed))
    if progress:
        print("  MMC with an obstacle ...", flush=True)
    mmc = mmc_obstacle_steps(robot, kin) if robot.n >= 6 else None
    layout = kernel.layout
    return {
        "robot": robot.name,
        "shapes": len(layout.shapes),
        "self_pairs": len(layout.self_pairs),
        "batch": batch,
        "rows": rows,
        "limits": limits,
        "ik": ik,
        "mmc": mmc,
        "pinocchio": rows[0].get("pinocchio_ns") is not None,
    }


def _limits_row(kernel: Any, robot: Any, Q: np.ndarray, env: Any, seed: int) -> dict[str, Any]:
    """The batch check of ``Q`` (within the joint limits) against the same count with about 19 %
    of the configurations beyond them (:func:`beyond_limits`), alternating, best of 40 calls."""
    W = beyond_limits(robot, len(Q), seed)
    lo, hi = robot.qlim
    best, _ = interleaved(
        {"within": lambda: kernel.in_collision(Q, env), "beyond": lambda: kernel.in_collision(W, env)}, 40
    )
    return {
        "obstacles": len(env),
        "outside": float(np.mean(~((lo <= W) & (hi >= W)).all(axis=1))),
        "within_ns": best["within"] / len(Q) * 1e9,
        "beyond_ns": best["beyond"] / len(W) * 1e9,
        "ratio": best["beyond"] / best["within"],
    }


def ik_scene(kin: Any, robot: Any, name: str, env: Any, count: int = 200, seed: int = 0) -> dict[str, Any]:
    """Plain and collision-aware IK (``kin.ik(T, collision=env)``) on ``count`` targets, the poses
    of random collision-free configurations (so a collision-free solution exists): a batch of
    targets in one call and one target per call, alternating, best of three; success rates and
    the solutions in collision."""
    rng = np.random.default_rng(seed)
    targets = []
    while len(targets) < count:
        q = robot.random_q(seed=rng)
        if not kin.in_collision(q, env):
            targets.append(kin.fkine(q))
    T = np.array(targets)
    kin.ik(T[0], seed=seed, collision=env)  # the kernel and the solver made before the clock runs
    best, last = interleaved(
        {
            "plain": lambda: kin.ik(T, seed=seed),
            "aware": lambda: kin.ik(T, seed=seed, collision=env),
            "plain_one": lambda: [kin.ik(t, seed=seed) for t in T],
            "aware_one": lambda: [kin.ik(t, seed=seed, collision=env) for t in T],
        }
    )
    out: dict[str, Any] = {"scene": name, "obstacles": len(env), "targets": len(T)}
    for key in ("plain", "aware", "plain_one", "aware_one"):
        res = last[key]
        q = np.array([r.q for r in res]) if isinstance(res, list) else np.asarray(res.q)
        ok = np.array([r.success for r in res]) if isinstance(res, list) else np.asarray(res.success)
        out[f"{key}_us"] = best[key] / len(T) * 1e6
        out[f"{key}_success"] = float(ok.mean())
        out[f"{key}_in_collision"] = int((ok & kin.in_collision(q, env)).sum())
    out["ratio"] = best["aware"] / best["plain"]
    out["ratio_one"] = best["aware_one"] / best["plain_one"]
    return out


def mmc_obstacle_steps(robot: Any, kin: Any, repeats: int = 3) -> dict[str, Any]:
    """us per MMC step along a servo run past an obstacle sphere (on the straight line from the
    ready pose to a goal 0.4 m along y): the C step with its obstacle rows, the Python reference
    step (the same QP through the Python OSQP) and the C step without obstacles, each controller
    replaying the run's (q, nu) states in order (warm starts as in a run); best of ``repeats``."""
    from symkin.geometry import Environment, Sphere
    from symkin.runtime.control import MMC
    from symkin.runtime.servo import p_servo

    q = np.asarray(robot.qr if getattr(robot, "qr", None) is not None else np.zeros(robot.n), dtype=float)
    T0 = kin.fkine(q)
    Tep = T0.copy()
    Tep[1, 3] += 0.4
    env = Environment(spheres=(Sphere(0.5 * (T0[:3, 3] + Tep[:3, 3]), 0.05),))
    options = {"collision": env, "d_i": 0.3, "d_s": 0.02}
    states, guide = [], MMC(kin, backend="python", **options)
    for _ in range(100):
        nu, done = p_servo(kin.fkine(q), Tep, gain=1.0, threshold=0.01, frame="base")
        if done:
            break
        states.append((q, nu))
        q = q + 0.05 * guide.step(q, nu)[0]
    best: dict[str, float] = {}
    is_self = np.array([kind == "self" for kind, _, _ in kin.collision_pairs(env)])
    d_i = np.where(is_self, guide.d_i_self, guide.d_i)  # self pairs: their own influence distance
    near = sum(bool((kin.distances(q, env) < d_i).any()) for q, _ in states)
    by_osqp = 0
    for name, kwargs in (("c", {**options}), ("python", {**options, "backend": "python"}), ("plain", {})):
        for _ in range(repeats):
            ctrl = MMC(kin, **kwargs)
            ctrl.step(*states[0])  # set up (OSQP in Python, the C library's first call)
            t0 = time.thread_time()
            infos = [ctrl.step(q, nu)[1] for q, nu in states]
            best[name] = min(best.get(name, float("inf")), (time.thread_time() - t0) / len(states) * 1e6)
        if name == "c":
            by_osqp = sum(i.method == "osqp" for i in infos)
    return {
        "steps": len(states),
        "steps_with_obstacle_rows": near,
        "c_steps_by_osqp": by_osqp,
        "c_us": best["c"],
        "python_us": best["python"],
        "plain_c_us": best["plain"],
        "speedup_vs_python": best["python"] / best["c"],
        "c_backend": MMC(kin, **options).backend,
    }


def _ik_line(ik: dict, how: str, label: str) -> str:
    """One line of an IK scene: plain against collision-aware, ``how`` "" (batch) or "_one"."""

    def part(key: str) -> str:
        return f"{ik[key + '_us']:6.1f} ({ik[key + '_success']:.1%}, {ik[key + '_in_collision']})"

    ratio = ik["ratio" + how]
    return f"    {label:>12}: plain {part('plain' + how)}, avoiding {part('aware' + how)}: {ratio:.2f}x"


def format_collide(r: dict) -> str:
    lines = [
        f"symkin bench collide: {r['robot']}, {r['shapes']} shapes, {r['self_pairs']} self pairs; "
        f"ns per configuration, one core, batch of {r['batch']}",
        "",
        f"{'obstacles':>9} {'one call':>10} {'C batch':>9} {'distances':>10} {'NumPy':>10} "
        f"{'x NumPy':>8} {'Pinocchio':>10} {'x Pin.':>7} {'agree':>6} {'colliding':>9}",
    ]
    for row in r["rows"]:
        pin_ns = f"{row['pinocchio_ns']:10.0f}" if "pinocchio_ns" in row else f"{'-':>10}"
        pin_x = f"{row['speedup_batch_vs_pinocchio']:6.1f}x" if "pinocchio_ns" in row else f"{'-':>7}"
        agree = f"{row['pinocchio_agrees']:6.1%}" if "pinocchio_agrees" in row else f"{'-':>6}"
        lines.append(
            f"{row['obstacles']:>9} {row['one_call_ns']:10.0f} {row['batch_ns']:9.0f} "
            f"{row['batch_distances_ns']:10.0f} {row['numpy_batch_ns']:10.0f} "
            f"{row['speedup_batch_vs_numpy']:7.1f}x {pin_ns} {pin_x} {agree} {row['colliding']:9.1%}"
        )
    if not r["pinocchio"]:
        lines.append("(install the compare extra, pip install 'symkin[compare]', for Pinocchio + coal)")
    lines += ["", "Outside the joint limits, ns per configuration in a batch (within them; some beyond):"]
    for row in r["limits"]:
        lines.append(
            f"  {row['obstacles']:>3} obstacle spheres: {row['within_ns']:.0f} ns; {row['outside']:.0%} "
            f"beyond {row['beyond_ns']:.0f} ns ({row['ratio']:.2f}x)"
        )
    lines += ["", "IK on the poses of collision-free configurations, us per target (solved, in collision):"]
    for ik in r["ik"]:
        lines.append(f"  {ik['scene']} ({ik['obstacles']} obstacles, {ik['targets']} targets):")
        lines += [_ik_line(ik, "", "batch"), _ik_line(ik, "_one", "one per call")]
    m = r.get("mmc")
    if m:
        lines += [
            "",
            f"MMC past an obstacle sphere, {m['steps']} steps ({m['steps_with_obstacle_rows']} with a pair "
            f"within d_i; the C step needed OSQP in {m['c_steps_by_osqp']}, the active set settled the "
            "rest), us per step:",
            f"  with obstacle rows: {m['c_backend']} {m['c_us']:.1f} us, Python reference "
            f"{m['python_us']:.1f} us ({m['speedup_vs_python']:.1f}x); without obstacles "
            f"{m['plain_c_us']:.1f} us",
        ]
    return "\n".join(lines)
