"""``symkin bench collide``: collision checks per configuration, one call and batched, with the
robot's sphere model against 0, 10 and 100 obstacle spheres, beside the generated NumPy module and (with
the ``compare`` extra) Pinocchio + coal on the same spheres and capsules, all in the same run; then
collision-aware IK against plain IK on a table-top scene, and the MMC step with obstacle rows
(the velocity dampers of the closest pairs) in C against the Python reference step.

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

__all__ = ["run_collide", "format_collide", "random_spheres", "table_scene", "pinocchio_collision"]


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
    n_robot = len(layout.shapes)
    for o, s in enumerate(env.spheres):
        geom.addGeometryObject(pin.GeometryObject(f"o{o}", 0, pin.SE3(np.eye(3), np.array(s.center)),
                                                  coal.Sphere(s.radius)))  # fmt: skip
    for i, j in layout.self_pairs:
        geom.addCollisionPair(pin.CollisionPair(i, j))
    for o in range(len(env.spheres)):
        for i in range(n_robot):
            geom.addCollisionPair(pin.CollisionPair(i, n_robot + o))
    data, gdata = model.createData(), pin.GeometryData(geom)

    def check(q: np.ndarray) -> bool:
        return bool(pin.computeCollisions(model, data, geom, gdata, q, True))

    def distances(q: np.ndarray) -> np.ndarray:
        pin.computeDistances(model, data, geom, gdata, q)
        return np.array([r.min_distance for r in gdata.distanceResults])

    check.distances = distances  # type: ignore[attr-defined]
    return check


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
        print("  IK on a table-top scene ...", flush=True)
    scene = table_scene()
    targets = []
    rng = np.random.default_rng(seed)
    while len(targets) < ik_targets:
        q = robot.random_q(seed=rng)
        if not kin.in_collision(q, scene):
            targets.append(kin.fkine(q))
    T = np.array(targets)
    # alternating, best of three: the two share the machine's drift
    best, last = interleaved(
        {"plain": lambda: kin.ik(T, seed=seed), "aware": lambda: kin.ik(T, seed=seed, collision=scene)}
    )
    plain, aware = last["plain"], last["aware"]
    plain_hits = kin.in_collision(plain.q, scene) & np.asarray(plain.success)
    aware_hits = kin.in_collision(aware.q, scene) & np.asarray(aware.success)
    ik = {
        "targets": len(T),
        "plain_us": best["plain"] / len(T) * 1e6,
        "collision_aware_us": best["aware"] / len(T) * 1e6,
        "ratio": best["aware"] / best["plain"],
        "plain_success": float(np.mean(plain.success)),
        "aware_success": float(np.mean(aware.success)),
        "plain_solutions_in_collision": int(plain_hits.sum()),
        "aware_solutions_in_collision": int(aware_hits.sum()),
    }
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
        "ik": ik,
        "mmc": mmc,
        "pinocchio": rows[0].get("pinocchio_ns") is not None,
    }


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
    ik = r["ik"]
    lines += [
        "",
        f"IK on a table-top scene, {ik['targets']} collision-free targets (us per target):",
        f"  plain {ik['plain_us']:.1f} us ({ik['plain_success']:.1%} solved, "
        f"{ik['plain_solutions_in_collision']} solutions in collision)",
        f"  collision-aware {ik['collision_aware_us']:.1f} us ({ik['aware_success']:.1%} solved, "
        f"{ik['aware_solutions_in_collision']} in collision): {ik['ratio']:.2f}x plain",
    ]
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
