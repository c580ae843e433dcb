"""The built-in arms' sphere models (covering models from the stored fits, the iiwa 7's
hand-written one): on known links, free at the named configurations, in collision when folded
(own NumPy check: sphere centres through link_poses). Their coverage of the real meshes is
checked in test_covering_models.py."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

import symkin
from symkin.model.builtin_geometry import BUILTIN_GEOMETRY, COVERING, builtin_geometry
from symkin.model.geometry import Geometry, Sphere

NAMES = ["panda", "ur3", "ur5", "ur10", "lbr_iiwa7", "lbr_iiwa14"]

#: clearly folded configurations (within the joint limits) and a link pair they must bring together
FOLDED = {  # pairs sorted as Geometry sorts them
    "panda": ([0, 0, 0, -3.0, 0, 0.5, 0], ("link2", "link7")),  # the hand folded into the shoulder
    "ur3": ([0, -1.57, 3.0, 0, 0, 0], ("link2", "link5")),  # the forearm folded onto the upper arm
    "ur5": ([0, -1.57, 3.0, 0, 0, 0], ("link2", "link5")),
    "ur10": ([0, -1.57, 3.0, 0, 0, 0], ("link2", "link5")),
    "lbr_iiwa7": ([0, 2.0, 0, -2.0, 0, 2.0, 0], ("base", "link6")),  # the wrist folded into the base
    "lbr_iiwa14": ([0, 2.0, 0, -2.0, 0, 2.0, 0], ("base", "link6")),
}


def frames_of(robot: symkin.Robot, q) -> dict[str, np.ndarray]:
    """Base-frame pose of every link geometry attaches to."""
    L = robot.link_poses(q)
    return {"base": np.eye(4), "ee": robot.fkine(q), **{f"link{k + 1}": L[k] for k in range(robot.n)}}


def centres(robot: symkin.Robot, g: Geometry, q) -> np.ndarray:
    F = frames_of(robot, q)
    return np.array([F[s.link][:3, :3] @ s.center + F[s.link][:3, 3] for s in g.shapes])


def body(robot: symkin.Robot, link: str) -> int:
    """Chain position of a link's rigid body: base 0, link<k> k, ee on the last link."""
    return 0 if link == "base" else robot.n if link == "ee" else int(link[4:])


def checked_pairs(robot: symkin.Robot, g: Geometry) -> list[tuple[int, int]]:
    """Sphere pairs on bodies neither the same nor adjacent, and not a disabled link pair."""
    disabled = set(g.disabled)
    out = []
    for i, j in itertools.combinations(range(len(g.shapes)), 2):
        a, b = g.shapes[i].link, g.shapes[j].link
        if abs(body(robot, a) - body(robot, b)) <= 1 or tuple(sorted((a, b))) in disabled:
            continue
        out.append((i, j))
    return out


def colliding(robot: symkin.Robot, g: Geometry, q) -> dict[tuple[str, str], float]:
    """Colliding link pairs at q with their deepest overlap (negative distance, m)."""
    C = centres(robot, g, q)
    out: dict[tuple[str, str], float] = {}
    for i, j in checked_pairs(robot, g):
        d = float(np.linalg.norm(C[i] - C[j])) - g.shapes[i].radius - g.shapes[j].radius
        if d < 0:
            key = tuple(sorted((g.shapes[i].link, g.shapes[j].link)))
            out[key] = min(out.get(key, 0.0), d)
    return out


def test_names() -> None:
    assert set(BUILTIN_GEOMETRY) == set(NAMES)
    assert set(NAMES) <= set(symkin.list_robots())
    for other in ("puma560", "sawyer", "planar2", "gantry", "nope"):
        assert builtin_geometry(other) is None
    assert builtin_geometry(42) is None  # type: ignore[arg-type]
    assert builtin_geometry(" LBR-iiwa7 ") == builtin_geometry("lbr_iiwa7")


@pytest.mark.parametrize("name", NAMES)
def test_model_on_known_links(name: str) -> None:
    robot, g = symkin.load(name), builtin_geometry(name)
    assert isinstance(g, Geometry)
    if name in COVERING:
        assert g.source.startswith("spheres covering the collision meshes of ")
    else:
        assert g.source.startswith("approximate sphere model written for symkin")
    assert all(isinstance(s, Sphere) and 0.001 < s.radius < 0.25 for s in g.shapes)
    assert set(g.links) <= set(robot.link_names)
    bodies = {"ee" if link == f"link{robot.n}" else link for link in g.links}
    assert bodies >= {"base", "ee", *(f"link{k}" for k in range(1, robot.n))}  # every body has spheres
    for a, b in g.disabled:
        assert a in robot.link_names and b in robot.link_names
    assert robot.with_geometry(g).geometry == g  # the Robot's own check accepts it
    lo, hi = (15, 40) if name not in COVERING else (60, 250)
    assert lo <= len(g) <= hi
    assert builtin_geometry(name) == g  # the same model every time


@pytest.mark.parametrize("name", NAMES)
def test_spheres_on_the_bodies(name: str) -> None:
    """Each link's spheres lie near the segment from its frame's origin to the next link frame's
    origin (where the link's body is), at the zero pose."""
    robot, g = symkin.load(name), builtin_geometry(name)
    q = robot.qz
    F = frames_of(robot, q)
    order = ["base", *(f"link{k + 1}" for k in range(robot.n)), "ee"]
    C = centres(robot, g, q)
    for i, s in enumerate(g.shapes):
        k = order.index(s.link)
        a = F[s.link][:3, 3]
        b = F[order[min(k + 1, len(order) - 1)]][:3, 3]
        t = np.clip(np.dot(C[i] - a, b - a) / max(np.dot(b - a, b - a), 1e-12), 0, 1)
        # within a link's length or two of its body line (bodies bulge around offsets)
        assert np.linalg.norm(C[i] - (a + t * (b - a))) < 0.3, (s.link, s.center)


@pytest.mark.parametrize("name", NAMES)
def test_free_at_named_configurations(name: str) -> None:
    robot, g = symkin.load(name), builtin_geometry(name)
    assert robot.configs  # qz at least
    for cname, q in robot.configs.items():
        if robot.within_limits(q):  # the Panda's qz is not (q4 = 0)
            assert colliding(robot, g, q) == {}, (name, cname)


@pytest.mark.parametrize("name", NAMES)
def test_collides_when_folded(name: str) -> None:
    robot, g = symkin.load(name), builtin_geometry(name)
    q, pair = FOLDED[name]
    assert robot.within_limits(q)
    hits = colliding(robot, g, q)
    assert pair in hits, (name, sorted(hits))
    assert min(hits.values()) < -0.015  # clearly, not by a rounding


@pytest.mark.parametrize("name", NAMES)
def test_mostly_free_in_random_configurations(name: str) -> None:
    """A model too fat would collide almost everywhere: most random configurations of the
    limited arms are free, and no checked pair collides at every one of them."""
    robot, g = symkin.load(name), builtin_geometry(name)
    Q = robot.random_q(60, seed=3)
    counts: dict[tuple[str, str], int] = {}
    free = 0
    for q in Q:
        hits = colliding(robot, g, q)
        free += not hits
        for p in hits:
            counts[p] = counts.get(p, 0) + 1
    assert max(counts.values(), default=0) < len(Q)
    if name in ("panda", "lbr_iiwa7", "lbr_iiwa14"):  # UR joints turn +-360 deg: often folded
        assert free > len(Q) // 2


@pytest.mark.parametrize("name", NAMES)
def test_disabled_pairs_touch_at_the_named_configurations(name: str) -> None:
    """Each disabled pair's spheres overlap at a named configuration (so the model would be in
    collision there without it)."""
    robot, g = symkin.load(name), builtin_geometry(name)
    open_g = Geometry(g.shapes, (), g.source)
    touching = set()
    for q in [robot.qz, *robot.configs.values()]:
        if robot.within_limits(q):
            touching |= set(colliding(robot, open_g, q))
    assert set(g.disabled) <= touching
