"""Self pairs proved apart within the joint limits and the links' reach spheres
(symkin.geometry.clearance): against closed-form minima, against the numeric reference on random
configurations, and the C kernel's verdicts for configurations outside the limits."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import symkin
from symkin.geometry import (
    Environment,
    Geometry,
    Sphere,
    clearance,
    distances,
    in_collision,
    layout_of,
    points,
)
from symkin.geometry.clearance import MARGIN, proved_apart, reach_sphere


def _two_link(b: float, a: float = 1.0):
    """Two unit links turning about z (q1 in [-a, a], q2 in [-b, b]): a sphere (r 0.1) at the base
    origin and one at the end of link 2, whose distance is |1 + e^(i q2)| = 2 cos(q2 / 2) whatever q1
    is, so the pair's smallest distance within the limits is 2 cos(b / 2) - 0.2."""
    robot = symkin.Robot.from_ets("Rz(q0) tx(1) Rz(q1)", qlim=[[-a, -b], [a, b]])
    return robot.with_geometry(Geometry((Sphere((0, 0, 0), 0.1, "base"), Sphere((1, 0, 0), 0.1, "link2"))))


def test_a_pair_with_clearance_is_proved_and_one_that_touches_is_not(monkeypatch):
    assert 2 * math.cos(2.9 / 2) - 0.2 > 0.04  # closest approach within [-2.9, 2.9]
    assert proved_apart(layout_of(_two_link(2.9))) == {(0, 1)}
    # within [-2.945, 2.945] the spheres overlap for 2.9413 < |q2| <= 2.945 only (0.13% of the
    # range): without the random tries first, the branch and bound itself must refute the pair
    assert 2 * math.cos(2.945 / 2) - 0.2 < 0
    monkeypatch.setattr(clearance, "_SAMPLES", 0)
    assert proved_apart(layout_of(_two_link(2.945))) == frozenset()
    assert proved_apart(layout_of(_two_link(2.9))) == {(0, 1)}


def test_a_pair_that_just_touches_at_the_limit_is_not_proved(monkeypatch):
    monkeypatch.setattr(clearance, "_SAMPLES", 0)
    b = 2 * math.acos(0.1)  # closest approach exactly 0 at q2 = +-b
    assert proved_apart(layout_of(_two_link(b))) == frozenset()


@pytest.mark.parametrize("name", ["panda", "ur5", "lbr_iiwa14"])
def test_proved_pairs_keep_their_distance_on_random_configurations(name):
    """The numeric reference (the tree's O(n) walk) on 20 000 configurations within the limits: no
    proved pair comes closer than MARGIN; and every pair that does come into contact there was left
    to the kernel."""
    robot = symkin.load(name)
    layout = layout_of(robot)
    proved = proved_apart(layout)
    assert proved
    index = [k for k, pair in enumerate(layout.self_pairs) if pair in proved]
    Q = robot.random_q(20_000, seed=5)
    m = len(layout.self_pairs)
    d = np.concatenate([distances(robot, Q[i : i + 5000])[:, :m] for i in range(0, len(Q), 5000)])
    assert d[:, index].min() >= MARGIN
    touching = {layout.self_pairs[k] for k in np.flatnonzero((d < 0).any(axis=0))}
    assert touching and not touching & proved


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_every_sphere_stays_in_its_reach_sphere(name):
    robot = symkin.load(name)
    layout = layout_of(robot)
    X = points(robot, robot.random_q(5000, seed=2))
    for i, s in enumerate(layout.shapes):
        centre, R = reach_sphere(layout, layout.segment[i], s.points[0], s.radius)
        far = np.linalg.norm(X[:, layout.point_index[i]] - centre, axis=-1) + s.radius
        assert far.max() <= R
    # the links next to the base have small reach spheres (what makes them worth having)
    radii = [reach_sphere(layout, k, s.points[0], s.radius)[1] for k, s in zip(layout.segment, layout.shapes)]
    assert min(radii) < 0.4


def test_the_kernel_checks_proved_pairs_outside_the_limits():
    """The two-link robot collides with itself only for |q2| > 2.9413, beyond its limit 2.9: the
    batch (four lanes and the scalar tail) and the one-call check find those collisions when asked
    about configurations outside the limits, and agree with the reference everywhere."""
    robot = _two_link(2.9)
    kin = symkin.compile(robot, backend="c")
    rng = np.random.default_rng(1)
    Q = np.column_stack([rng.uniform(-1, 1, 103), rng.uniform(-3.1, 3.1, 103)])
    Q[5] = [0.2, 3.05]  # outside the limit, colliding
    Q[6] = [0.2, 2.5]
    expected = np.array([in_collision(robot, q) for q in Q])
    assert expected[5] and not expected[6] and 0 < expected.mean() < 0.5
    assert np.array_equal(kin.in_collision(Q), expected)
    assert kin.in_collision(Q[5]) and not kin.in_collision(Q[6])


def test_the_batch_agrees_with_the_reference_beyond_the_limits_and_near_the_base():
    """Panda configurations up to 30% beyond the limits (the proved pairs and the reach spheres do
    not hold there) and obstacle spheres near the base column and the reach spheres' edges."""
    robot = symkin.load("panda")
    kin = symkin.compile(robot, backend="c")
    lo, hi = robot.qlim
    mid, half = 0.5 * (lo + hi), 0.5 * (hi - lo)
    rng = np.random.default_rng(3)
    Q = mid + 1.3 * half * rng.uniform(-1, 1, (2000, 7))
    layout = layout_of(robot)
    edges = []
    for i, s in enumerate(layout.shapes[:12]):  # around the base, link 1 and link 2
        c, R = reach_sphere(layout, layout.segment[i], s.points[0], s.radius)
        u = rng.normal(size=3)
        edges.append(Sphere(c + (R + 0.02 - 1e-9) * u / np.linalg.norm(u), 0.02))
    env = Environment(spheres=(*edges, Sphere((0.1, 0.0, 0.2), 0.05), Sphere((0.5, 0.2, 0.4), 0.1)))
    expected = np.concatenate([in_collision(robot, Q[i : i + 500], env) for i in range(0, len(Q), 500)])
    got = kin.in_collision(Q, env)
    assert np.array_equal(got, expected)
    outside = ((lo > Q) | (hi < Q)).any(axis=1)
    assert outside.mean() > 0.5 and expected[outside].any() and expected[~outside].any()


def test_the_proof_is_kept_in_the_cache_and_a_damaged_file_is_recomputed(tmp_path, monkeypatch):
    monkeypatch.setenv("SYMKIN_CACHE", str(tmp_path))
    first = proved_apart(layout_of(_two_link(2.9)))
    (path,) = (tmp_path / "clearance").glob("*.json")
    assert json.loads(path.read_text())["body"] == [[0, 1]]
    monkeypatch.setattr(clearance, "_compute", lambda layout: pytest.fail("recomputed"))
    assert proved_apart(layout_of(_two_link(2.9))) == first  # read back, not recomputed
    monkeypatch.undo()
    monkeypatch.setenv("SYMKIN_CACHE", str(tmp_path))
    pristine = path.read_text()
    stored = json.loads(pristine)
    for damaged in (
        "{not json",
        pristine[: len(pristine) // 2],
        json.dumps({"key": path.stem, "pairs": [[0, 1]]}),  # the format before the checksum
        json.dumps({**stored, "body": []}),
        json.dumps({**stored, "sha256": stored["sha256"][::-1]}),
        '{"pairs": 3}',
        "[" * 100_000,  # nested too deeply for the JSON reader
    ):
        path.write_text(damaged)
        assert proved_apart(layout_of(_two_link(2.9))) == first
        assert path.read_text() == pristine
    # other limits are another proof: with contact possible, nothing is proved
    assert proved_apart(layout_of(_two_link(3.1))) == frozenset()


def _two_link_and_elbow() -> symkin.Robot:
    """:func:`_two_link` (2.9) and a third sphere on link 2, 0.95 m back towards its joint: it
    overlaps the base sphere at q = 0 (0.05 m apart, radii 0.1), so of the two self pairs only
    (0, 1) is proved apart."""
    robot = _two_link(2.9)
    shapes = (*robot.geometry.shapes, Sphere((-0.95, 0, 0), 0.1, "link2"))
    return robot.with_geometry(Geometry(shapes))


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_a_flipped_digit_in_a_cached_proof_is_not_trusted(tmp_path, monkeypatch, backend):
    """Issue 36, item 1: one digit of the stored proof flipped ([[0, 1]] -> [[0, 2]]: still JSON,
    still the file's key, still pairs of the layout) made the kernels skip the colliding pair and
    call q = 0 free. The entry's checksum fails, so the proof is recomputed."""
    from symkin.runtime.collision import Collision

    monkeypatch.setenv("SYMKIN_CACHE", str(tmp_path))
    robot = _two_link_and_elbow()
    assert in_collision(robot, np.zeros(2))  # the numeric reference
    assert proved_apart(layout_of(robot)) == {(0, 1)}
    (path,) = (tmp_path / "clearance").glob("*.json")
    text = path.read_text()
    assert text.count("[[0, 1]]") == 1
    path.write_text(text.replace("[[0, 1]]", "[[0, 2]]"))
    assert proved_apart(layout_of(_two_link_and_elbow())) == {(0, 1)}
    assert Collision(_two_link_and_elbow(), backend).in_collision(np.zeros(2))
    assert path.read_text() == text  # and the cache holds the proof again


@pytest.mark.parametrize("name", ["gripper", "quadruped"])
def test_proofs_on_trees_with_mimic_and_prismatic_joints(name):
    """A gripper (branches, a mimic joint with a multiplier) and a quadruped (general axes, a
    prismatic tail): the proved pairs keep their distance on random configurations, and each shape
    stays in its reach sphere."""
    from tests.emit.test_collision_numpy import MODELS

    model = MODELS[name]()
    layout = layout_of(model)
    proved = proved_apart(layout)
    assert proved
    index = [k for k, pair in enumerate(layout.self_pairs) if pair in proved]
    Q = model.random_q(20_000, seed=5)
    d = distances(model, Q)[:, : len(layout.self_pairs)]
    assert d[:, index].min() >= MARGIN
    X = points(model, Q[:2000])
    for i, s in enumerate(layout.shapes):
        centre, R = reach_sphere(layout, layout.segment[i], s.points[0], s.radius)
        assert (np.linalg.norm(X[:, layout.point_index[i]] - centre, axis=-1) + s.radius).max() <= R


def test_the_generated_numpy_module_checks_proved_pairs_outside_the_limits():
    """The generated NumPy module skips the proved pairs only for rows within the limits: the
    two-link robot's collisions beyond its limit are found, in a batch and one at a time."""
    from symkin.runtime.collision import collision_module

    robot = _two_link(2.9)
    module = collision_module(layout_of(robot), "numpy")
    assert module.TABLES.proved == ((0, 1),)
    rng = np.random.default_rng(1)
    Q = np.column_stack([rng.uniform(-1, 1, 103), rng.uniform(-3.1, 3.1, 103)])
    Q[5] = [0.2, 3.05]
    expected = np.array([in_collision(robot, q) for q in Q])
    assert expected[5] and 0 < expected.mean() < 0.5
    assert np.array_equal(module.in_collision(Q), expected)
    assert module.in_collision(Q[5]) and not module.in_collision([0.2, 2.5])


@pytest.mark.parametrize("seed", range(6))
def test_proofs_on_random_arms_hold_on_dense_samples(seed):
    """Random four-joint arms (joint axes along x, y or z, random offsets between them, random
    limits) with two spheres per link: every proved pair keeps its distance on 20 000 random
    configurations within the limits (the reference's O(n) walk)."""
    rng = np.random.default_rng(seed)
    parts = []
    for k in range(4):
        dx, dy, dz = rng.uniform(-0.3, 0.3, 3)
        parts.append(f"tx({dx:.3f}) ty({dy:.3f}) tz({dz:.3f}) R{'xyz'[rng.integers(3)]}(q{k})")
    lo = rng.uniform(-3.0, -0.5, 4)
    hi = rng.uniform(0.5, 3.0, 4)
    robot = symkin.Robot.from_ets(" ".join(parts), qlim=[lo, hi])
    links = ["base", "link1", "link2", "link3", "link4"]
    shapes = tuple(
        Sphere(tuple(rng.uniform(-0.15, 0.15, 3)), float(rng.uniform(0.02, 0.08)), link)
        for link in links
        for _ in range(2)
    )
    robot = robot.with_geometry(Geometry(shapes))
    layout = layout_of(robot)
    proved = proved_apart(layout)
    Q = robot.random_q(20_000, seed=seed)
    d = distances(robot, Q)[:, : len(layout.self_pairs)]
    index = [k for k, pair in enumerate(layout.self_pairs) if pair in proved]
    assert index  # 12 to 24 of each arm's pairs are proved
    assert d[:, index].min() >= MARGIN
