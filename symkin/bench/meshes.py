"""``symkin bench meshes``: the covering sphere model of a built-in arm against Pinocchio + coal on
the arm's real collision meshes (the ``compare`` and ``meshes`` extras).

Pinocchio reads the same URDF with its own parser and loads the meshes with coal (assimp): its
forward kinematics, mesh placement and triangle tests are independent of symkin's. For each
configuration symkin's compiled kernel answers with the stored spheres, and coal with the meshes
(the gripper's fingers at a random opening); the pairs checked on the coal side are every pair of
collision objects on bodies neither the same nor joined by one joint, less the URDF's SRDF
``disable_collisions`` pairs where example-robot-data ships one, and every object against every
obstacle. The claim checked: **symkin never says free where coal says collision**. Reported:
that count (must be 0), and how often symkin says collision where coal finds the meshes free (the
price of the outward excess).

Configurations: uniform within the joint limits (self-collision only, then against random scenes
of obstacle spheres and a box), and near contact: between a configuration coal calls free and one
it calls colliding, bisected along the joint-space segment to within 1e-3 of its length, the last
colliding configuration and the last free one.
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

from symkin.bench.collide import add_obstacles
from symkin.bench.common import optional

__all__ = ["MeshOracle", "run_meshes", "format_meshes", "random_scene"]


def random_scene(rng: np.random.Generator, spheres: int = 6) -> Any:
    """Obstacle spheres (radius 0.03-0.15 m) in [-0.9, 0.9]^2 x [-0.1, 1.2] m and one box (base frame)."""
    from symkin.model.geometry import Box, Environment, Sphere

    P = rng.uniform([-0.9, -0.9, -0.1], [0.9, 0.9, 1.2], size=(spheres, 3))
    R = rng.uniform(0.03, 0.15, size=spheres)
    box = Box(rng.uniform([-0.7, -0.7, 0.0], [0.7, 0.7, 1.0]), rng.uniform(0.02, 0.2, size=3))
    return Environment(spheres=tuple(Sphere(p, r) for p, r in zip(P, R)), boxes=(box,))


class MeshOracle:
    """Pinocchio + coal on built-in robot ``name``'s URDF meshes: ``check(q, fingers) -> bool``,
    ``pairs(q, fingers)`` (the colliding URDF link pairs) for one environment set with
    :meth:`set_environment` (obstacles given in symkin's base frame)."""

    def __init__(self, name: str) -> None:
        from symkin.geometry.builtin_meshes import MESH_SOURCES, locate

        self.pin, self.coal = optional("pinocchio"), optional("coal")
        if self.pin is None or self.coal is None:
            raise RuntimeError("the mesh comparison needs Pinocchio and coal: pip install 'symkin[compare]'")
        pin = self.pin
        self.source = MESH_SOURCES[name]
        path, packages = locate(self.source)
        self._tmp = tempfile.TemporaryDirectory(prefix="symkin-meshes-")
        dirs = [str(up.parent) for up in path.parents if up.name == "example-robot-data"]  # its share/
        for pkg, folder in packages.items():  # other packages: a folder of links named as the packages
            (Path(self._tmp.name) / pkg).symlink_to(folder)
            dirs.append(self._tmp.name)
        self.model = pin.buildModelFromUrdf(str(path))
        self.robot_geom = pin.buildGeomFromUrdf(
            self.model, str(path), pin.GeometryType.COLLISION, package_dirs=dirs
        )
        srdf = path.parent.parent / "srdf" / f"{path.stem.replace('_robot', '')}.srdf"
        self.srdf = srdf if srdf.is_file() else None
        self.B = np.eye(4)
        c, s = math.cos(self.source.base_yaw), math.sin(self.source.base_yaw)
        self.B[:2, :2] = [[c, -s], [s, c]]
        self.fingers = [j for j in range(1, self.model.njoints) if "finger" in self.model.names[j]]
        self.set_environment(None)

    def _adjacent(self, a: int, b: int) -> bool:
        """Joints a and b move one body or two bodies joined by one joint (fingers ride on the hand)."""

        def body(j: int) -> int:
            while j in self.fingers:
                j = self.model.parents[j]
            return j

        a, b = body(a), body(b)
        return a == b or self.model.parents[a] == b or self.model.parents[b] == a

    def set_environment(self, env: Any) -> None:
        """Rebuild the collision model: the robot's objects and pairs, and ``env``'s obstacles."""
        pin, coal = self.pin, self.coal
        geom = self.robot_geom.copy()
        n = len(geom.geometryObjects)
        skip: set[tuple[str, str]] = set()
        if self.srdf is not None:
            from symkin.geometry.srdf import read_srdf

            skip = set(read_srdf(self.srdf))
        objs = geom.geometryObjects
        link = [o.name.rsplit("_", 1)[0] for o in objs]
        for i in range(n):
            for j in range(i + 1, n):
                if self._adjacent(objs[i].parentJoint, objs[j].parentJoint):
                    continue
                if tuple(sorted((link[i], link[j]))) in skip:
                    continue
                geom.addCollisionPair(pin.CollisionPair(i, j))
        count = 0 if env is None else add_obstacles(pin, coal, geom, env, np.linalg.inv(self.B))
        self.geom, self.link = geom, link + [f"obstacle {k}" for k in range(count)]
        self.data, self.gdata = self.model.createData(), pin.GeometryData(geom)

    def q_of(self, q: np.ndarray, fingers: float) -> np.ndarray:
        """Pinocchio's configuration: symkin's joint values, then each finger at ``fingers`` m."""
        out = np.zeros(self.model.nq)
        out[: len(q)] = q
        for j in self.fingers:
            out[self.model.idx_qs[j]] = fingers
        return out

    def check(self, q: np.ndarray, fingers: float = 0.0) -> bool:
        return bool(
            self.pin.computeCollisions(
                self.model, self.data, self.geom, self.gdata, self.q_of(q, fingers), True
            )
        )

    def pairs(self, q: np.ndarray, fingers: float = 0.0) -> list[tuple[str, str]]:
        self.pin.computeCollisions(self.model, self.data, self.geom, self.gdata, self.q_of(q, fingers), False)
        out = []
        for k, res in enumerate(self.gdata.collisionResults):
            if res.isCollision():
                p = self.geom.collisionPairs[k]
                out.append((self.link[p.first], self.link[p.second]))
        return out


def srdf_model(robot: Any, oracle: MeshOracle) -> Any:
    """``robot`` with the link pairs its SRDF leaves unchecked unchecked too (a symkin link pair is
    left out when every URDF link pair on it is): the pairs coal checks, for the price of the excess
    alone. None without an SRDF."""
    if oracle.srdf is None:
        return None
    from symkin.geometry.builtin_meshes import on_ee, source_frames
    from symkin.geometry.meshes import link_placements
    from symkin.geometry.srdf import read_srdf
    from symkin.model.tree import Tree
    from symkin.model.urdf import read_graph

    path = oracle.srdf.parent.parent / "urdf"
    urdf = next(p for p in path.iterdir() if p.name == Path(oracle.source.urdf).name)
    tree = Tree.from_urdf(urdf, frames=list(oracle.source.links))
    frames, _ = source_frames(robot.with_geometry(None), tree, oracle.source)
    placed, _ = link_placements(read_graph(urdf), frames)
    on = {ln: p.link for ln, p in on_ee(robot, placed, oracle.source).items()}
    skip = set(read_srdf(oracle.srdf))
    urdf_links = [ln for ln in on if ln in set(oracle.link)]
    pairs = []
    for a in set(on.values()):
        for b in set(on.values()):
            if a >= b:
                continue
            under = [(x, y) for x in urdf_links for y in urdf_links if on[x] == a and on[y] == b]
            if under and all(tuple(sorted(p)) in skip for p in under):
                pairs.append((a, b))
    return robot.with_geometry(robot.geometry.with_disabled(pairs))


def _near_contact(
    oracle: MeshOracle, robot: Any, free: np.ndarray, hit: np.ndarray, f: float, steps: int = 10
) -> tuple[np.ndarray, np.ndarray]:
    """Bisect from a coal-free to a coal-colliding configuration: (last colliding, last free)."""
    lo, hi = 0.0, 1.0
    for _ in range(steps):
        mid = 0.5 * (lo + hi)
        if oracle.check(free + mid * (hit - free), f):
            hi = mid
        else:
            lo = mid
    return free + hi * (hit - free), free + lo * (hit - free)


def run_meshes(
    name: str = "panda", n: int = 100_000, near: int = 5_000, seed: int = 0, scenes: int = 10
) -> dict[str, Any]:
    """Uniform configurations (``n`` self-only and ``n`` against ``scenes`` random scenes) and
    ``near`` near-contact pairs of each kind: counts of the four verdict combinations, and the
    configurations where symkin says free and coal collision (must be none)."""
    from symkin.model.robots import load
    from symkin.runtime.load import compile as compile_robot

    robot = load(name)
    kin = compile_robot(robot, backend="c")
    oracle = MeshOracle(name)
    same = srdf_model(robot, oracle)
    kin_same = compile_robot(same, backend="c") if same is not None else kin
    rng = np.random.default_rng(seed)
    stroke = 0.04 if oracle.fingers else 0.0
    rows: dict[str, Any] = {}
    t0 = time.perf_counter()
    for kind in ("self", "obstacles"):
        per = n // (scenes if kind == "obstacles" else 1)
        counts = dict.fromkeys(
            ("both", "sym_only", "coal_only", "neither", "near_both", "near_coal_only", "near_free_sym",
             "near_free", "srdf_sym_only", "srdf_coal_only"), 0,
        )  # fmt: skip
        missed: list[dict[str, Any]] = []
        for _ in range(scenes if kind == "obstacles" else 1):
            env = random_scene(rng) if kind == "obstacles" else None
            oracle.set_environment(env)
            Q = robot.random_q(per, seed=int(rng.integers(1 << 31)))
            F = rng.uniform(0.0, stroke, size=per)
            ours = kin.in_collision(Q, env)
            theirs = np.array([oracle.check(q, f) for q, f in zip(Q, F)])
            counts["both"] += int((ours & theirs).sum())
            counts["sym_only"] += int((ours & ~theirs).sum())
            counts["coal_only"] += int((~ours & theirs).sum())
            counts["neither"] += int((~ours & ~theirs).sum())
            same_v = kin_same.in_collision(Q, env)
            counts["srdf_sym_only"] += int((same_v & ~theirs).sum())
            counts["srdf_coal_only"] += int((~same_v & theirs).sum())
            for k in np.flatnonzero(~ours & theirs)[:20]:
                missed.append({"q": Q[k].tolist(), "fingers": float(F[k]), "pairs": oracle.pairs(Q[k], F[k])})
            free, hit = np.flatnonzero(~theirs), np.flatnonzero(theirs)
            m = min(near // (scenes if kind == "obstacles" else 1), len(free), len(hit))
            for a, b in zip(rng.choice(free, m, replace=False), rng.choice(hit, m, replace=False)):
                f = float(F[b])
                q_hit, q_free = _near_contact(oracle, robot, Q[a], Q[b], f)
                v_hit, v_free = kin.in_collision(np.stack([q_hit, q_free]), env)
                counts["near_both" if v_hit else "near_coal_only"] += 1
                counts["near_free_sym"] += int(v_free)
                counts["near_free"] += 1
                if not v_hit:
                    missed.append(
                        {"q": q_hit.tolist(), "fingers": f, "pairs": oracle.pairs(q_hit, f), "near": True}
                    )
        rows[kind] = {
            "counts": counts,
            "missed": missed,
            "configurations": per * (scenes if kind == "obstacles" else 1),
        }
    rows["seconds"] = time.perf_counter() - t0
    rows["robot"], rows["spheres"], rows["self_pairs"] = name, len(robot.geometry), len(kin.collision_pairs())
    rows["srdf"] = str(oracle.srdf.name) if oracle.srdf else None
    rows["srdf_disabled"] = [list(p) for p in same.geometry.disabled] if same is not None else None
    return rows


def format_meshes(r: dict[str, Any]) -> str:
    lines = [
        f"{r['robot']}: {r['spheres']} covering spheres ({r['self_pairs']} self pairs) against Pinocchio + "
        f"coal on the URDF meshes (pairs less {r['srdf'] or 'adjacent bodies'}), {r['seconds']:.0f} s",
    ]
    for kind in ("self", "obstacles"):
        c, N = r[kind]["counts"], r[kind]["configurations"]
        coal_hits = c["both"] + c["coal_only"]
        free = c["sym_only"] + c["neither"]
        lines.append(
            f"  {kind}: {N} uniform configurations: coal collision {coal_hits}, symkin free there "
            f"{c['coal_only']}; coal free {free}, symkin collision there {c['sym_only']} "
            f"({100 * c['sym_only'] / max(free, 1):.1f}%)"
        )
        if r["srdf"]:
            lines.append(
                f"  {kind}: with the SRDF's pairs left out in symkin too: symkin free where coal collides "
                f"{c['srdf_coal_only']}, symkin collision where coal free {c['srdf_sym_only']} "
                f"({100 * c['srdf_sym_only'] / max(free, 1):.1f}%)"
            )
        lines.append(
            f"  {kind}: {c['near_free']} near-contact pairs: symkin free where coal collides "
            f"{c['near_coal_only']}, symkin collision just outside contact {c['near_free_sym']} "
            f"({100 * c['near_free_sym'] / max(c['near_free'], 1):.1f}%)"
        )
    return "\n".join(lines)
