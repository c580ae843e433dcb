"""The C IK solver's one-target paths: ``kin.ik(T)`` (one C call through the bound entry point)
gives what the batch gives, and the benchmark entry points (the scalar batch ``solve_each``,
``kin_each``, the timing build ``profiled``) compute what the solver computes."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin.errors import PoseError
from symkin.runtime.ik import default_c_solver


@pytest.fixture(scope="module")
def ur5():
    return symkin.compile("ur5", backend="c")


def _targets(kin, n: int = 12) -> np.ndarray:
    Tep = np.asarray(kin.robot.fkine(kin.robot.random_q(n, seed=21)))
    Tep[3, :3, 3] += 10.0  # unreachable: every search, random restarts included
    return Tep


def test_one_kin_ik_call_is_the_batch_solution(ur5):
    """The first search starts at q0; the batch draws target i's random restarts from the stream
    (seed, i), one call from (seed, 0): target 0 and every target solved by its first search must
    be bit for bit the batch's; the unreachable one fails in both."""
    Q = ur5.robot.random_q(12, seed=21)
    Tep = _targets(ur5)
    q0 = Q + np.random.default_rng(2).normal(0.0, 0.3, Q.shape)
    batch = ur5.ik(Tep, q0=q0, seed=7)
    assert type(ur5.ik).__name__ == "BoundIK"  # later single calls: one C call
    first_search = [i for i in range(len(Tep)) if batch.searches[i] == 1]
    assert len(first_search) >= len(Tep) // 2
    for i in {0, *first_search}:
        alone = ur5.ik(Tep[i], q0=q0[i], seed=7)
        assert alone.q.tobytes() == batch.q[i].tobytes(), i
        assert (alone.success, alone.iterations, alone.searches, alone.reason) == (
            batch.success[i],
            batch.iterations[i],
            batch.searches[i],
            batch.reason[i],
        )
    assert not batch.success[3] and not ur5.ik(Tep[3], q0=q0[3], seed=7).success
    np.testing.assert_allclose(ur5.fkine(batch.q[batch.success]), Tep[batch.success], atol=1e-6)


def test_a_solver_on_another_library_solves_one_target_as_the_default_one(ur5):
    """Without the default library's extension, one target is a batch of one through ctypes: the
    same q, counts and reason as the extension's call, the unreachable target included."""
    from symkin.runtime.ik_c import CIKSolver, ik_library

    Tep, q0 = _targets(ur5, 4), ur5.robot.random_q(4, seed=3)
    default, other = CIKSolver(ur5, slimit=3), CIKSolver(ur5, slimit=3, lib=ik_library())
    assert other.fast is None
    for i in range(4):
        a, b = default.solve(Tep[i], q0[i], seed=5), other.solve(Tep[i], q0[i], seed=5)
        assert type(b.success) is bool and b.q.shape == (6,)
        assert a.q.tobytes() == b.q.tobytes(), i
        assert (a.success, a.iterations, a.searches, a.residual, a.reason) == (
            b.success,
            b.iterations,
            b.searches,
            b.residual,
            b.reason,
        )
    assert not other.solve(Tep[3], seed=5).success


def test_scalar_batch_solves_each_target_as_one_call_does(ur5):
    solver = default_c_solver(ur5)
    Tep = _targets(ur5)
    q, success = solver.solve_each(Tep, seed=40)
    for i, T in enumerate(Tep):
        alone = solver.solve(T, seed=40 + i)
        assert alone.q.tobytes() == q[i].tobytes(), i
        assert alone.success == success[i]
    assert success.sum() == len(Tep) - 1 and not success[3]
    bad = Tep.copy()
    bad[5, 0, 0] = np.nan
    with pytest.raises(PoseError, match=r"target \[5\]"):
        solver.solve_each(bad)


def test_kin_each_evaluates_the_solvers_kinematics(ur5):
    solver = default_c_solver(ur5)
    Q = ur5.robot.random_q(5, seed=3)
    T, J = solver.kin_each(Q)
    T1, J1 = solver.fkine_jacob0(Q[-1])  # the last row's, overwritten in turn
    assert T.tobytes() == T1.tobytes() and J.tobytes() == J1.tobytes()
    np.testing.assert_allclose(T, ur5.robot.fkine(Q[-1]), atol=1e-14)
    np.testing.assert_allclose(J, ur5.robot.jacob0(Q[-1]), atol=1e-14)


def test_the_timing_build_solves_as_the_default_one_and_counts_its_calls(ur5):
    solver = default_c_solver(ur5)
    solve, parts = solver.profiled()
    Tep = _targets(ur5, 5)
    parts()  # reset
    for i, T in enumerate(Tep):
        timed, plain = solve(T, None, i), solver.solve(T, seed=i)
        assert timed.q.tobytes() == plain.q.tobytes() and timed.reason == plain.reason
    calls, *ns = parts()
    assert calls == len(Tep) and all(t >= 0 for t in ns) and ns[2] > 0  # the solver's time
    assert parts()[0] == 0  # reset by the last call
