"""The collision kernel's self checks written as tables walked by loops (past
``collision_self.UNROLL_PAIRS`` pairs) against the straight-line form, and the four-lane batch with
configurations beyond the joint limits: the same verdicts as the scalar build, as each other and as
the NumPy reference (which checks every pair, proved apart or not); the same distances."""

from __future__ import annotations

import ctypes

import numpy as np
import pytest

import symkin
from symkin.bench.collide import beyond_limits
from symkin.emit import collision_self
from symkin.emit.c.build import compile_library, load_library
from symkin.emit.collision import collision_tables, render_collision
from symkin.geometry import Box, Capsule, Environment, Geometry, Sphere, distances, in_collision, layout_of
from symkin.geometry.clearance import proved_apart
from symkin.runtime.collision import env_args

_P, _I = ctypes.c_void_p, ctypes.c_int


def _kernel(robot, monkeypatch, unroll: int, flags: tuple[str, ...] = ()):
    monkeypatch.setattr(collision_self, "UNROLL_PAIRS", unroll)
    files = render_collision(layout_of(robot))
    lib = load_library(compile_library(files, "skcoll_forms", extra_cflags=flags))
    lib.skcoll_in_collision_batch.argtypes = [_P, ctypes.c_long, _P, _I, _P, _I, _P, _I, _P]
    lib.skcoll_distances_batch.argtypes = [_P, ctypes.c_long, _P, _I, _P, _I, _P, _I, _P, _P]
    return lib


def _verdicts(lib, Q: np.ndarray, env) -> np.ndarray:
    out = np.zeros(len(Q), dtype=np.uint8)
    lib.skcoll_in_collision_batch(Q.ctypes.data, len(Q), *env_args(env).args, out.ctypes.data)
    return out.astype(bool)


def _distances(lib, Q: np.ndarray, env, m: int) -> np.ndarray:
    D = np.empty((len(Q), m))
    lib.skcoll_distances_batch(Q.ctypes.data, len(Q), *env_args(env).args, D.ctypes.data, None)
    return D


def _slider():
    """A chain with a prismatic joint between two revolute ones (its links' reach spheres hold only
    within the stroke) and spheres on every link."""
    robot = symkin.Robot.from_ets(
        "Rz(q0) tx(0.3) tz(q1) Ry(q2) tx(0.25) Rz(q3) tx(0.2)",
        qlim=[[-2.5, 0.0, -2.0, -2.5], [2.5, 0.3, 2.0, 2.5]],
    )
    shapes = [Sphere((0, 0, 0.05), 0.08, "base"), Sphere((0.1, 0, 0), 0.05, "link1")]
    shapes += [Sphere((x, 0, 0), 0.05, link) for link in ("link2", "link3", "link4") for x in (0.0, 0.1, 0.2)]
    shapes += [Sphere((0.05, 0, 0), 0.04, "ee"), Sphere((-0.3, 0, -0.1), 0.05, "link3")]
    return robot.with_geometry(Geometry(tuple(shapes)))


def _capsules(panda):
    extra = (
        Capsule((0, 0, -0.05), (0.03, 0, 0.08), 0.04, "ee"),
        Capsule((0, 0.02, 0), (0, 0.12, 0.05), 0.05, "link3"),
    )
    return panda.with_geometry(Geometry((*panda.geometry.shapes, *extra), panda.geometry.disabled))


@pytest.mark.parametrize("which", ["panda", "slider", "capsules"])
def test_tables_and_straight_lines_give_the_same_verdicts_within_and_beyond_the_limits(which, monkeypatch):
    panda = symkin.load("panda")
    robot = {"panda": panda, "slider": _slider(), "capsules": _capsules(panda)}[which]
    layout = layout_of(robot)
    m = len(layout.self_pairs)
    assert proved_apart(layout)  # the pairs checked only beyond the limits are there to test
    # both sides of the threshold
    monkeypatch.setattr(collision_self, "UNROLL_PAIRS", m)
    assert not collision_tables(layout)["self_tables"]
    monkeypatch.setattr(collision_self, "UNROLL_PAIRS", m - 1)
    assert collision_tables(layout)["self_tables"]
    kernels = {
        (form, lanes): _kernel(robot, monkeypatch, unroll, () if lanes else ("-DSKCOLL_SCALAR",))
        for form, unroll in (("straight", m), ("tables", m - 1))
        for lanes in (True, False)
    }
    lo, hi = robot.qlim
    W = beyond_limits(robot, 2001, seed=3)  # about 19 % beyond the limits, a tail of one after the fours
    beyond = ~((lo <= W) & (hi >= W)).all(axis=1)
    assert 0.1 < beyond.mean() < 0.3
    # and configurations far beyond the limits whose only overlapping pairs are proved apart within
    # them, each among three within the limits (blocks of four mixing both)
    proved = np.array([p in proved_apart(layout) for p in layout.self_pairs])
    F = beyond_limits(robot, 3000, seed=6, outside=0.9)
    d = distances(robot, F)[:, :m]
    only = F[(d[:, proved] < 0).any(axis=1) & (d[:, ~proved] >= 0).all(axis=1)][:40]
    assert len(only) >= 10
    mixed = np.vstack([np.vstack([x, robot.random_q(3, seed=k)]) for k, x in enumerate(only)])
    Q = np.ascontiguousarray(np.vstack([robot.random_q(1000, seed=4), W, mixed]))
    centres = 0.6 * np.random.default_rng(5).normal(size=(12, 3))
    table = Box((0.4, 0.0, -0.1), (0.6, 0.8, 0.05))
    envs = [
        Environment(),
        Environment(spheres=tuple(Sphere(c, 0.05) for c in centres)),
        Environment(spheres=(Sphere((0.45, 0.1, 0.5), 0.1),), boxes=(table,)),
    ]
    for env in envs:
        verdicts = {key: _verdicts(lib, Q, env) for key, lib in kernels.items()}
        first = verdicts[("straight", False)]
        assert all(np.array_equal(v, first) for v in verdicts.values())
        assert 0 < first.mean() < 1 and first[1000:3001][beyond].any()
        assert first[3001::4][: len(only)].all()  # the proved pairs, checked beyond the limits
        sample = np.r_[0:150, 1000 : 1000 + 300]  # within and beyond the limits
        assert np.array_equal(first[sample], in_collision(robot, Q[sample], env))
        M = m + len(layout.shapes) * len(env)
        D = [_distances(kernels[(form, True)], Q[:300], env, M) for form in ("straight", "tables")]
        assert np.array_equal(D[0], D[1])


def test_tables_form_past_the_threshold_loops_over_the_pairs(monkeypatch):
    """A kernel past UNROLL_PAIRS holds each self pair once in its tables (rows of the pairs and of
    the first spheres' partners), not as lines of code."""
    panda = symkin.load("panda")
    layout = layout_of(panda)
    monkeypatch.setattr(collision_self, "UNROLL_PAIRS", 10)
    tables = collision_tables(layout)
    assert tables["self_tables"] and not tables["self_code"] and not tables["self_code4"]
    rows = tables["self_rows"]["pairs"] + tables["self_rows"]["inner"]
    rows += tables["self_rows_proved"]["pairs"] + tables["self_rows_proved"]["inner"]
    assert len(rows) == len(layout.self_pairs)
    text = render_collision(layout)["skcoll.c"]
    assert "self_hit(X, &self_main)" in text and "self_hit4(X, &self_proved, &outside, &hit)" in text
    assert text.count("hit2(X[") < 20


def test_a_link_reach_that_holds_only_within_the_stroke_takes_every_obstacle_beyond_it():
    """The slider's links after its prismatic joint reach further when the stroke (0.3 m) is
    exceeded: an obstacle 1.7 m above link 2's sphere at the top of the stroke, beyond that link's
    reach sphere, is found in lanes 2 m up the slide (the batch, four at a time, a block of four
    within the limits after them) as by the scalar code and the reference."""
    robot = _slider()
    kin = symkin.compile(robot, backend="c")
    q = np.array([0.0, 0.3, 1.0, 1.0])  # free of self-collision
    top = kin.collision_points(q)[4]  # link 2's sphere at (0.2, 0, 0)
    env = Environment(spheres=(Sphere(top + [0, 0, 1.7], 0.05),))
    Q = np.tile(q, (12, 1))
    Q[1:8:2, 1] = 2.0
    hits = kin.in_collision(Q, env)
    assert np.array_equal(hits, [kin.in_collision(x, env) for x in Q])
    assert np.array_equal(hits, in_collision(robot, Q, env))
    assert hits[1:8:2].all() and not hits[0:8:2].any() and not hits[8:].any()
