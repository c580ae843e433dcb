"""The straight-line program derivation: against the numeric reference, against finite
differences, its size as chains grow, and the memoised walks over deep and shared expressions."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from symkin import Robot
from symkin.bench.compile import random_chain
from symkin.model.robots import load
from symkin.symbolic.cse import count_ops, depth, floatify, tree_size
from symkin.symbolic.functions import (
    build_functions,
    choose_strategy,
    derive_kinematics,
    fk_j_h_counts,
)
from symkin.symbolic.kinematics import const_to_sympy, joint_symbols
from symkin.symbolic.program import KinematicProgram, derive_program
from tests.conftest import assert_close
from tests.emit.test_backends import random_robots


def evaluator(kp: KinematicProgram):
    """The program as a Python function of q (math floats), independent of the emitters."""
    names = [str(s) for s in kp.q]
    src = [f"def f({', '.join(names)}):"]
    src += [f"    {s} = {sp.pycode(floatify(e))}" for s, e in kp.lines]
    outs = {"T": [kp.T], "links": list(kp.links), "J0": [kp.J0], "Je": [kp.Je]}
    if kp.H0 is not None:
        outs |= {"H0": list(kp.H0), "He": list(kp.He)}
    flat = [[sp.pycode(floatify(x)) for M in mats for x in M] for mats in outs.values()]
    src.append("    return [" + ", ".join("[" + ", ".join(f) + "]" for f in flat) + "]")
    scope = {"math": math}
    exec("\n".join(src), scope)

    def run(q: np.ndarray) -> dict[str, np.ndarray]:
        values = scope["f"](*q)
        return {
            key: np.array(v, dtype=float).reshape((len(mats), *mats[0].shape))
            for (key, mats), v in zip(outs.items(), values)
        }

    return run


def evaluate(kp: KinematicProgram, q: np.ndarray) -> dict[str, np.ndarray]:
    return evaluator(kp)(q)


def _program(robot: Robot, hessians: bool = True) -> KinematicProgram:
    return derive_program(robot.ets, joint_symbols(robot.n), const_to_sympy, robot.name, hessians)


def assert_program_matches_reference(got, robot, q):
    """An evaluated program ``got`` at ``q``: T, link poses, J0, Je, H0, He against the numeric reference."""
    assert_close(got["T"][0], robot.fkine(q), 1e-12, "T")
    assert_close(got["links"], robot.link_poses(q), 1e-12, "links")
    assert_close(got["J0"][0], robot.jacob0(q), 1e-12, "J0")
    assert_close(got["Je"][0], robot.jacobe(q), 1e-12, "Je")
    assert_close(got["H0"], robot.hessian0(q), 1e-10, "H0")
    assert_close(got["He"], robot.hessiane(q), 1e-10, "He")


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(robot=random_robots(), seed=st.integers(0, 2**16))
def test_program_matches_the_numeric_reference(robot, seed):
    kp = _program(robot)
    q = robot.random_q(seed=seed)
    got = evaluate(kp, q)
    assert_program_matches_reference(got, robot, q)


@pytest.mark.parametrize("n", [9, 20])
def test_long_chain_program_against_finite_differences(n):
    """Independent of the reference's Jacobian and Hessian: J from FK, H from J (central differences)."""
    robot = random_chain(n, seed=3)
    f = evaluator(_program(robot))
    q = robot.random_q(seed=1)
    got = f(q)
    h = 1e-6
    T = got["T"][0]
    for i in range(n):
        dq = np.zeros(n)
        dq[i] = h
        up, down = f(q + dq), f(q - dq)
        dT = (up["T"][0] - down["T"][0]) / (2 * h)
        w = dT[:3, :3] @ T[:3, :3].T
        fd = np.r_[dT[:3, 3], w[2, 1], w[0, 2], w[1, 0]]
        assert_close(got["J0"][0][:, i], fd, 1e-8, f"J0 column {i}")
        assert_close(got["H0"][i], (up["J0"][0] - down["J0"][0]) / (2 * h), 1e-8, f"H0[{i}]")
        assert_close(got["He"][i], (up["Je"][0] - down["Je"][0]) / (2 * h), 1e-8, f"He[{i}]")


def test_program_size_grows_linearly_with_the_chain():
    """FK + J: each 12 more joints add the same operations and lines (second difference within 10 %);
    with the Hessian (an n^2 output) the operations per joint grow linearly."""

    def linear(v: dict[int, int]) -> bool:
        first, second = v[24] - v[12], v[36] - v[24]
        return abs(second - first) < 0.1 * first

    chains = {n: derive_kinematics(random_chain(n), "program") for n in (12, 24, 36)}
    fkj = {n: fk_j_h_counts(d, hessian=False).total for n, d in chains.items()}
    assert linear(fkj), fkj
    assert fkj[24] < 2.5 * fkj[12], fkj
    lines = {n: len(_program(random_chain(n), hessians=False).lines) for n in (12, 24, 36)}
    assert linear(lines), lines
    per_joint = {n: fk_j_h_counts(d).total / n for n, d in chains.items()}
    first, second = per_joint[24] - per_joint[12], per_joint[36] - per_joint[24]
    assert abs(second - first) < 0.15 * first, per_joint


def test_panda_stays_at_or_below_525_operations():
    """FK + J0 + H0 after CSE: 525 with the expanded derivation when it landed; the strategy
    chosen by size must not be larger."""
    strategy, derived = choose_strategy(load("panda"))
    assert fk_j_h_counts(derived).total <= 525, strategy
    assert fk_j_h_counts(derive_kinematics(load("panda"), "expanded")).total <= 525


@pytest.mark.parametrize(
    "name, strategy",
    [("planar3", "expanded"), ("ur5", "expanded"), ("panda", "program")],
)
def test_strategy_is_chosen_by_size(name, strategy):
    chosen, _ = choose_strategy(load(name))
    assert chosen == strategy
    assert choose_strategy(random_chain(14))[0] == "program"


def test_every_function_of_both_strategies_has_counts_and_the_same_outputs():
    robot = load("stanford")  # a prismatic joint
    for strategy in ("expanded", "program"):
        fs = build_functions(derive_kinematics(robot, strategy))
        assert [f.name for f in fs][:2] == ["fkine", "link_poses"]
        assert all(f.code.counts.total > 0 for f in fs), strategy
        assert all(f.code.strategy == strategy for f in fs)


def test_hessians_become_loops_beyond_the_unroll_limit():
    fs = build_functions(derive_kinematics(random_chain(14), "program"))
    by_name = {f.name: f for f in fs}
    assert by_name["jacob0_hessian0"].code.hessians and by_name["hessiane"].code.hessians
    assert by_name["hessian0"].delegate == "jacob0_hessian0"
    fs = build_functions(derive_kinematics(random_chain(8), "program"))
    assert not any(f.code.hessians for f in fs)


def test_walks_do_not_recurse_on_deep_expressions():
    """A 5000-level nesting would overflow any recursive walk (Python's limit is 1000)."""
    x = sp.Symbol("x")
    e = x
    for k in range(5000):
        e = sp.Add(sp.Mul(e, sp.Integer(k + 2), evaluate=False), sp.sqrt(2), evaluate=False)
    assert depth(e) >= 5000
    assert count_ops(e).total >= 10000
    assert tree_size([e]) > 15000
    f = floatify(e)
    assert not f.has(sp.sqrt(2)) and depth(f) >= 5000


def test_walks_are_linear_in_the_distinct_subexpressions():
    """x_{k+1} = x_k * x_k + x_k: 60 shared levels stand for about 3^60 tree nodes."""
    x = sp.Symbol("x")
    e = x
    for _ in range(60):
        e = sp.Add(sp.Mul(e, e, evaluate=False), e, evaluate=False)
    nodes, ops, levels = tree_size([e]), count_ops(e), depth(e)  # plain ints: no repr of e below
    assert nodes == 2 * 3**60 - 1
    assert (ops.mul, ops.add) == ((3**60 - 1) // 2, (3**60 - 1) // 2)
    assert levels == 120
