"""Collision queries: active pairs, the NumPy reference against independent computations and finite
differences, the compiled C kernel against the reference, chains and trees through one pipeline."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import symkin
from symkin.errors import ConfigurationError, GeometryError
from symkin.geometry import (
    Box,
    Capsule,
    Environment,
    Geometry,
    Sphere,
    distance_jacobians,
    distances,
    in_collision,
    layout_of,
    points,
)
from symkin.geometry.reference import witnesses

ENV = Environment(
    spheres=(Sphere((0.45, 0.1, 0.5), 0.1), Sphere((-0.3, 0.3, 0.3), 0.15)),
    capsules=(Capsule((0.3, -0.4, 0.0), (0.3, -0.3, 0.8), 0.05),),
    boxes=(Box((0.4, 0.0, -0.1), (0.6, 0.8, 0.05)), Box((0.0, -0.5, 0.5), (0.1, 0.05, 0.3),
           rotation=[[0.8, -0.6, 0], [0.6, 0.8, 0], [0, 0, 1]])),
)  # fmt: skip


@pytest.fixture(scope="module")
def panda():
    return symkin.load("panda")


@pytest.fixture(scope="module")
def panda_c(panda):
    return symkin.compile(panda, backend="c")


def _fd(f, q, h=1e-6):
    return np.stack([(f(q + h * e) - f(q - h * e)) / (2 * h) for e in np.eye(len(q))], axis=-1)


# -- which pairs ---------------------------------------------------------------------------------
def test_active_pairs_skip_one_body_adjacent_and_disabled():
    robot = symkin.load("planar3").with_geometry(
        Geometry(
            (
                Sphere((0, 0, 0), 0.1, "base"),
                Sphere((0, 0, 0), 0.1, "link1"),
                Sphere((0, 0, 0), 0.1, "link2"),
                Sphere((0, 0, 0), 0.1, "link3"),
                Sphere((0.1, 0, 0), 0.05, "ee"),
                Sphere((0, 0, 0), 0.1, 1),
            ),
        )  # fmt: skip
    )
    shapes = robot.geometry.shapes
    assert shapes[5].link == "link2"  # an int k is link frame k: link<k+1>
    pairs = {(shapes[i].link, shapes[j].link) for i, j in layout_of(robot).self_pairs}
    # base-link1, link k-link k+1 adjacent; ee is fixed to link3 (one body, adjacent to link2)
    assert pairs == {
        ("base", "link2"),
        ("base", "link3"),
        ("base", "ee"),
        ("link1", "link3"),
        ("link1", "ee"),
    }
    disabled = robot.with_geometry(robot.geometry.with_disabled([("link1", "ee")]))
    assert ("link1", "ee") not in {
        (shapes[i].link, shapes[j].link) for i, j in layout_of(disabled).self_pairs
    }


def test_bad_geometry_is_refused(panda):
    with pytest.raises(GeometryError, match="no link 'link9'"):
        panda.with_geometry(Geometry((Sphere((0, 0, 0), 0.1, "link9"),)))
    with pytest.raises(GeometryError, match="radius"):
        Sphere((0, 0, 0), -0.1)
    with pytest.raises(GeometryError, match="finite"):
        Sphere((0, np.nan, 0), 0.1)
    with pytest.raises(GeometryError, match="NaN or inf"):
        Environment.from_points([[0, 0, np.inf]], 0.01)
    with pytest.raises(GeometryError, match="rotation"):
        Box((0, 0, 0), (1, 1, 1), rotation=np.diag([1.0, 1.0, -1.0]))
    with pytest.raises(GeometryError, match="Sphere, Capsule and Box"):
        distances(panda, panda.qz, ["table"])
    with pytest.raises(GeometryError, match="no collision geometry"):
        symkin.compile(symkin.load("puma560"), backend="numpy").in_collision(np.zeros(6))
    with pytest.raises(GeometryError, match="disabled pair"):
        panda.with_geometry(Geometry((), [("link1", "nowhere")]))


def test_geometry_is_pickled_and_keys_its_own_kernel(panda, panda_c):
    again = pickle.loads(pickle.dumps(panda))
    assert again.geometry == panda.geometry
    tree = symkin.Tree.from_robot(panda)
    assert pickle.loads(pickle.dumps(tree)).geometry == tree.geometry
    # the kinematics do not depend on the geometry (no recompile), the compiled object and kernel do
    smaller = panda.with_geometry(Geometry(panda.geometry.shapes[:5]))
    assert smaller.fingerprint == panda.fingerprint
    kin = symkin.compile(smaller, backend="c")
    assert kin is not panda_c and kin.files == panda_c.files
    assert kin.model.geometry == smaller.geometry
    assert kin.collision().kernel.files != panda_c.collision().kernel.files
    assert kin.collision_points(panda.qz).shape[0] < panda_c.collision_points(panda.qz).shape[0]
    assert pickle.loads(pickle.dumps(kin)).model.geometry == smaller.geometry


# -- the reference against independent computations ----------------------------------------------
def test_reference_sphere_distances_from_the_chain_link_frames(panda):
    """Sphere-sphere and sphere-obstacle distances from Robot.fkine(q, frame=k) (the chain's own
    link frames, not the tree walk the reference uses) and |c1 - c2| - r1 - r2."""
    env = Environment(spheres=ENV.spheres)
    Q = panda.random_q(20, seed=4)
    geometry = panda.geometry
    layout = layout_of(panda)

    def centre(s, q):
        if s.link == "base":
            T = np.eye(4)
        elif s.link == "ee":
            T = panda.fkine(q)
        else:
            T = panda.fkine(q, frame=int(s.link[4:]) - 1)
        return T[:3, :3] @ np.array(s.center) + T[:3, 3]

    for q in Q:
        d = distances(panda, q, env)
        C = [centre(s, q) for s in geometry.shapes]
        m = 0
        for i, j in layout.self_pairs:
            a, b = geometry.shapes[i], geometry.shapes[j]
            assert d[m] == pytest.approx(np.linalg.norm(C[i] - C[j]) - a.radius - b.radius, abs=1e-12)
            m += 1
        for o in env.spheres:
            for i, s in enumerate(geometry.shapes):
                expect = np.linalg.norm(C[i] - np.array(o.center)) - s.radius - o.radius
                assert d[m] == pytest.approx(expect, abs=1e-12)
                m += 1
        X = points(panda, q)
        assert np.allclose(X, np.array(C), atol=1e-12)


def test_witness_points_of_spheres_lie_on_the_line_of_centres(panda):
    """For two spheres (and a sphere and an obstacle sphere) the witness points are where the line
    of centres leaves each sphere: ``c_i - r_i u`` and ``c_j + r_j u``, ``u`` from j to i."""
    env = Environment(spheres=ENV.spheres)
    layout = layout_of(panda)
    labels = layout.pair_labels(env)
    shapes = panda.geometry.shapes
    for q in panda.random_q(5, seed=9):
        X = points(panda, q)
        d = distances(panda, q, env)
        pairs = list(range(0, len(labels), 37))
        dw, a, b = witnesses(panda, X, [labels[k] for k in pairs], env)
        assert np.allclose(dw, d[pairs], atol=1e-14)
        for m, k in enumerate(pairs):
            kind, i, j = labels[k]
            ci, ri = X[layout.point_index[i]], shapes[i].radius
            cj, rj = (X[layout.point_index[j]], shapes[j].radius) if kind == "self" else (
                np.array(env.spheres[j].center), env.spheres[j].radius)  # fmt: skip
            u = (ci - cj) / np.linalg.norm(ci - cj)
            assert np.allclose(a[m], ci - ri * u, atol=1e-12) and np.allclose(b[m], cj + rj * u, atol=1e-12)


@pytest.mark.parametrize("name", ["panda", "ur5", "lbr_iiwa7"])
def test_distance_jacobians_match_finite_differences(name):
    robot = symkin.load(name)
    geometry = Geometry(
        (*robot.geometry.shapes, Capsule((0, 0, -0.05), (0.05, 0, 0.1), 0.03, "ee"),
         Capsule((0.0, 0.02, 0), (0, 0.1, 0.05), 0.04, "link3")), robot.geometry.disabled,
    )  # fmt: skip
    robot = robot.with_geometry(geometry)
    kin = symkin.compile(robot, backend="c")
    for q in robot.random_q(6, seed=11):
        d, J = distance_jacobians(robot, q, ENV)
        dc, Jc = kin.distance_jacobians(q, ENV)
        F = _fd(lambda x: distances(robot, x, ENV), q)
        ok = d > 1e-4  # gradients of penetrating pairs can be non-unique (a kink of the box SDF)
        assert np.abs(J - F)[ok].max() < 1e-6
        assert np.abs(Jc - F)[ok].max() < 1e-6
        assert np.abs(dc - d).max() < 1e-12


# -- the C kernel against the reference ------------------------------------------------------------
@pytest.mark.parametrize("name", ["panda", "ur5", "lbr_iiwa14"])
def test_c_kernel_matches_the_reference(name):
    robot = symkin.load(name)
    kin = symkin.compile(robot, backend="c")
    Q = robot.random_q(400, seed=2)
    for env in (
        None,
        ENV,
        Environment.from_points(np.random.default_rng(0).uniform(-0.6, 0.6, (30, 3)), 0.04),
    ):
        verdict = kin.in_collision(Q, env)
        assert verdict.dtype == bool and verdict.shape == (400,)
        assert (verdict == in_collision(robot, Q, env)).all()
        assert [kin.in_collision(q, env) for q in Q[:40]] == list(verdict[:40])
        D = kin.distances(Q, env)
        assert D.shape == (400, len(kin.collision_pairs(env)))
        assert np.abs(D - distances(robot, Q, env)).max() < 1e-12
        assert ((D < 0).any(axis=1) == verdict).all()
    assert np.abs(kin.collision_points(Q) - points(robot, Q)).max() < 1e-12
    assert kin.collision_points(Q[0]).shape == (layout_of(robot).n_points, 3)


def test_near_contact_verdicts(panda, panda_c):
    """Obstacles placed 1e-9 m outside and inside a shape: both kernels give the exact verdict."""
    rng = np.random.default_rng(5)
    for q in panda.random_q(30, seed=6):
        if panda_c.in_collision(q):
            continue
        X = panda_c.collision_points(q)
        i = int(rng.integers(len(panda.geometry.shapes)))
        s = panda.geometry.shapes[i]
        c = X[layout_of(panda).point_index[i]]
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        for gap, hit in ((1e-9, False), (-1e-9, True)):
            o = Sphere(c + u * (s.radius + 0.05 + gap), 0.05)
            env = Environment(spheres=(o,))
            others = distances(panda, q, env)
            others = np.delete(others, len(layout_of(panda).self_pairs) + i)
            if (others < 1e-6).any():
                continue  # another shape is as close: not a clean test of shape i
            assert panda_c.in_collision(q, env) is hit
            assert bool(in_collision(panda, q, env)) is hit


def test_numpy_backend_matches_the_c_kernel(panda, panda_c):
    kin = symkin.compile(panda, backend="numpy")
    Q = panda.random_q(50, seed=8)
    assert np.abs(kin.distances(Q, ENV) - panda_c.distances(Q, ENV)).max() < 1e-12
    assert (kin.in_collision(Q, ENV) == panda_c.in_collision(Q, ENV)).all()


def test_generated_c_is_deterministic_and_says_what_made_it(panda, panda_c):
    from symkin.emit.collision import render_collision

    files = render_collision(layout_of(panda))
    assert files == render_collision(layout_of(symkin.load("panda")))
    assert files == panda_c.collision().kernel.files
    text = files["skcoll.c"]
    assert "Generated by symkin" in text and "panda" in text.splitlines()[1]
    assert f"{len(panda.geometry)} shapes" in text


def test_hostile_link_names_stay_in_comments():
    """A tree link name reaches the generated C only inside comments, made inert."""
    from symkin.emit.collision import render_collision

    robot = symkin.load("planar2")
    tree = symkin.Tree.from_robot(robot, frame="tip */ int evil; /*")
    tree = tree.with_geometry(Geometry((Sphere((0, 0, 0), 0.1, "tip */ int evil; /*"),
                                        Sphere((0, 0, 0), 0.1, "base"))))  # fmt: skip
    text = render_collision(layout_of(tree))["skcoll.c"]
    assert "int evil" not in text.replace("int evil; /", "")  # only inside a comment, broken up
    kin = symkin.compile(tree, backend="c")
    assert kin.distances(np.zeros(2)).shape == (1,)


def test_q_is_validated(panda_c):
    with pytest.raises(ConfigurationError):
        panda_c.in_collision(np.full(7, np.nan))
    with pytest.raises(ConfigurationError):
        panda_c.distances(np.zeros(6))
    with pytest.raises(ConfigurationError):
        panda_c.in_collision([0, 0, 0, 0, 0, 0, 1e300])


# -- one pipeline: trees ---------------------------------------------------------------------------
def test_a_chain_as_a_tree_gives_the_same_answers(panda, panda_c):
    tree = symkin.Tree.from_robot(panda)
    kin = symkin.compile(tree, backend="c")
    Q = panda.random_q(100, seed=9)
    assert np.abs(kin.distances(Q, ENV) - panda_c.distances(Q, ENV)).max() < 1e-12
    assert (kin.in_collision(Q, ENV) == panda_c.in_collision(Q, ENV)).all()


def test_tree_with_branches_and_a_mimic_joint():
    from tests.model.tree_urdfs import GRIPPER

    tree = symkin.Tree.from_urdf(GRIPPER)
    assert any(s.multiplier != 1 for s in tree.slots)
    links = tree.link_names
    shapes = tuple(
        Capsule((0, 0, 0), (0.1, 0.02, 0.05), 0.03, link) if k % 2 else Sphere((0.02, 0, 0.03), 0.05, link)
        for k, link in enumerate(links)
    )
    tree = tree.with_geometry(Geometry(shapes))
    kin = symkin.compile(tree, backend="c")
    env = Environment(spheres=(Sphere((0.2, 0.1, 0.3), 0.1),), boxes=(Box((0, 0, -0.2), (1, 1, 0.1)),))
    Q = tree.random_q(50, seed=1)
    assert np.abs(kin.distances(Q, env) - distances(tree, Q, env)).max() < 1e-12
    for q in Q[:5]:
        d, J = kin.distance_jacobians(q, env)
        F = _fd(lambda x: distances(tree, x, env), q)
        assert np.abs(J - F)[d > 1e-4].max() < 1e-6


def test_generated_c_compiles_warning_free_as_c99_and_cpp(panda, tmp_path):
    import shutil
    import subprocess

    from symkin.emit.collision import render_collision

    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler")
    for name, text in render_collision(layout_of(panda)).items():
        (tmp_path / name).write_text(text)
    for argv in ([cc, "-std=c99", "-Wpedantic"], [cc, "-x", "c++"]):
        run = subprocess.run([*argv, "-Wall", "-Wextra", "-Werror", "-c", str(tmp_path / "skcoll.c"), "-o",
                              str(tmp_path / "skcoll.o")], capture_output=True, text=True)  # fmt: skip
        assert run.returncode == 0, run.stderr


def test_an_environment_pickles_without_the_kernel_cache(panda_c, panda):
    env = Environment(spheres=(Sphere((0.45, 0.0, 0.5), 0.1),), boxes=ENV.boxes)
    Q = panda.random_q(50, seed=12)
    before = panda_c.in_collision(Q, env)
    one = [panda_c.in_collision(q, env) for q in Q[:10]]
    assert "_packed" in env.__dict__  # the kernel's cache
    again = pickle.loads(pickle.dumps(env))
    assert again == env and "_packed" not in again.__dict__
    del env
    assert (panda_c.in_collision(Q, again) == before).all()
    assert [panda_c.in_collision(q, again) for q in Q[:10]] == one


def test_tool_and_base_keep_the_shapes_on_their_bodies(panda):
    q = panda.random_q(seed=13)
    X = points(panda, q)
    tool = panda.with_tool("tz(0.1) Rx(0.3)")
    assert np.abs(points(tool, q) - X).max() < 1e-12  # the hand's shapes stay on the hand
    based = panda.with_base("0.1 0.2 0.3 0 0 0.5")
    T = based.fkine(q) @ np.linalg.inv(panda.fkine(q))  # the base transform
    assert np.abs(points(based, q) - (X @ T[:3, :3].T + T[:3, 3])).max() < 1e-12


def test_symkin_check_compares_the_collision_kernel(panda, panda_c, monkeypatch):
    from symkin.check.kinematics import check

    rows = {r.function: r for r in check(panda, [panda_c], samples=4).rows}
    assert rows["collision distances"].ok and rows["collision verdicts"].ok
    kernel = panda_c.collision().kernel
    true = kernel.distances
    monkeypatch.setattr(
        kernel, "distances", lambda q, env=None, jacobians=False: _off(true(q, env, jacobians))
    )
    rows = {r.function: r for r in check(panda, [panda_c], samples=4).rows}
    assert not rows["collision distances"].ok  # a kernel 1 um off is caught


def _off(result):
    if isinstance(result, tuple):
        return result[0] + 1e-6, result[1]
    return result + 1e-6


@pytest.mark.parametrize("capsules", [False, True])
def test_four_lane_batch_gives_the_scalar_verdicts(panda, capsules):
    """The batch path (four configurations per step) against the scalar build of the same kernel
    (-DSKCOLL_SCALAR) and against one configuration at a time: identical verdicts, including the
    lane-by-lane fallback for capsules and obstacle boxes."""
    import ctypes

    from symkin.emit.c.build import compile_library, load_library
    from symkin.emit.collision import render_collision
    from symkin.runtime.collision import env_args

    robot = panda
    if capsules:
        extra = (
            Capsule((0, 0, -0.05), (0.03, 0, 0.08), 0.04, "ee"),
            Capsule((0, 0.02, 0), (0, 0.12, 0.05), 0.05, "link3"),
        )
        robot = panda.with_geometry(Geometry((*panda.geometry.shapes, *extra), panda.geometry.disabled))
    files = render_collision(layout_of(robot))
    libs = [
        load_library(compile_library(files, "skcoll_lanes", extra_cflags=flags))
        for flags in ((), ("-DSKCOLL_SCALAR",))
    ]
    Q = np.ascontiguousarray(robot.random_q(2001, seed=14))  # a tail of one after the groups of four
    kin = symkin.compile(robot, backend="c")
    for env in (None, Environment(spheres=ENV.spheres), ENV):
        args = env_args(symkin.geometry.as_environment(env)).args
        outs = []
        for lib in libs:
            out = np.zeros(len(Q), dtype=np.uint8)
            lib.skcoll_in_collision_batch.argtypes = (
                [ctypes.c_void_p, ctypes.c_long] + [ctypes.c_void_p, ctypes.c_int] * 3 + [ctypes.c_void_p]
            )
            lib.skcoll_in_collision_batch(Q.ctypes.data, len(Q), *args, out.ctypes.data)
            outs.append(out.astype(bool))
        assert np.array_equal(outs[0], outs[1])
        assert 0 < outs[0].mean() < 1
        assert np.array_equal(outs[0][:200], [kin.in_collision(q, env) for q in Q[:200]])


def _self_pair_checks(panda):
    """The Panda's collision tables, its self pairs by point indices (all, and those not proved
    apart within the joint limits) and the points that are links' bounding spheres."""
    from collections import Counter

    from symkin.emit.collision import collision_tables
    from symkin.geometry.clearance import proved_apart

    layout = layout_of(panda)
    tables = collision_tables(layout)
    point = layout.point_index
    proved = proved_apart(layout)
    assert 0 < len(proved) < len(layout.self_pairs)
    expected = Counter(frozenset((point[i], point[j])) for i, j in layout.self_pairs)
    expected4 = Counter(frozenset((point[i], point[j])) for i, j in layout.self_pairs if (i, j) not in proved)
    return tables, expected, expected4, {p for p, _ in tables["bounds"]}


def test_every_self_pair_is_tested_once_in_the_unrolled_checks(panda, monkeypatch):
    """Below UNROLL_PAIRS pairs the self checks are straight-line code that tries a sphere with
    several partners on the other link against that link's bounding sphere first; every active
    self pair must still be tested exactly once in the scalar code, each sphere-first test must use
    the other link's bound. The four-lane code tests every pair not proved apart within the joint
    limits, then the proved pairs for the lanes beyond them."""
    import re
    from collections import Counter

    from symkin.emit import collision_self

    monkeypatch.setattr(collision_self, "UNROLL_PAIRS", 10**9)  # the Panda's 3 240 pairs unrolled
    tables, expected, expected4, bound_points = _self_pair_checks(panda)
    assert not tables["self_tables"]
    checks = (
        (tables["self_code"] + tables["self_code_proved"], "sphere_hit", expected),
        (tables["self_code4"], "hit2", expected4),
        (tables["self_code4"] + tables["self_code4_proved"], "hit2", expected),
    )
    for code, call, expected in checks:
        found = Counter()
        firsts = 0
        for line in code:
            m = re.search(rf"{call}\(X\[(\d+)\], X\[(\d+)\]", line)
            if not m:
                continue
            a, b = int(m.group(1)), int(m.group(2))
            if b in bound_points:
                firsts += a not in bound_points  # a sphere against a link's bound
                continue
            found[frozenset((a, b))] += 1
        assert found == expected
        assert firsts > 0  # the Panda model has spheres with three or more partners


def test_every_self_pair_is_a_table_row_once(panda):
    """Past UNROLL_PAIRS pairs (the Panda's covering model has 3 240) the self checks are C table
    rows that loops walk: every active self pair is one row, either a pair row or a sphere-first
    row's inner entry (whose outer test is against the other link's bounding sphere); the proved
    pairs' rows are the rest."""
    import re
    from collections import Counter

    tables, expected, expected4, bound_points = _self_pair_checks(panda)
    assert tables["self_tables"]

    def pairs_of(rows):
        found, firsts = Counter(), 0
        nums = {k: [[float(x) for x in re.findall(r"-?[\d.e+-]+", r)] for r in v] for k, v in rows.items()}
        for xo, xb, i0, i1, _ in nums["firsts"]:
            assert int(xb) in bound_points and int(xo) not in bound_points
            firsts += 1
            for x, _ in nums["inner"][int(i0) : int(i1)]:
                found[frozenset((int(xo), int(x)))] += 1
        for a, b, cap, _ in nums["pairs"]:
            assert cap == 0  # the Panda's model is spheres only
            found[frozenset((int(a), int(b)))] += 1
        return found, firsts

    unproved, firsts = pairs_of(tables["self_rows"])
    proved, _ = pairs_of(tables["self_rows_proved"])
    assert unproved == expected4
    assert unproved + proved == expected
    assert firsts > 0
