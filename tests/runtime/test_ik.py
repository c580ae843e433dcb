"""Numerical IK (NumPy and C solvers) and the C build cache they compile through."""

from __future__ import annotations

import math
import multiprocessing
import os
from pathlib import Path

import numpy as np
import pytest

import symkin
from symkin import Robot
from symkin.emit.c.build import compile_library, load_library
from symkin.errors import CompileError, ConfigurationError, PoseError
from symkin.model.robots import load
from symkin.runtime.ik import IKOptions, SplitMix64, angle_axis, ik, ik_trace, pose_error
from symkin.runtime.ik_c import CIKSolver
from tests.conftest import assert_close

PI = math.pi
UR5 = load("ur5")  # 6 DoF
PANDA = load("panda")  # 7 DoF, flipped joints
STANFORD = load("stanford")  # joint 2 prismatic
ROBOTS = {"ur5": UR5, "panda": PANDA, "stanford": STANFORD}
METHODS = {  # name: options
    "NR": {"method": "NR"},
    "NR-pinv": {"method": "NR", "pinv": True},
    "GN": {"method": "GN"},
    "GN-pinv": {"method": "GN", "pinv": True},
    "LM-wampler": {"method": "LM", "damping": "wampler", "lam": 1e-6},
    "LM-chan": {"method": "LM", "damping": "chan", "lam": 0.1},
    "LM-sugihara": {"method": "LM", "damping": "sugihara", "lam": 1e-6},
}


def _square_only(robot: Robot, options: dict) -> bool:
    """NR and GN without pinv need a nonsingular square system: 6 joints."""
    return robot.n != 6 and options["method"] in ("NR", "GN") and not options.get("pinv")


def _assert_solved(robot: Robot, result, Tep: np.ndarray, tol: float = 1e-6) -> None:
    assert result.success, result.reason
    assert result.reason == "success"
    e = pose_error(robot.fkine(result.q), Tep)
    assert np.linalg.norm(e) < tol, f"|e| = {np.linalg.norm(e):.3g}"
    assert robot.within_limits(result.q)


# -- solving ----------------------------------------------------------------------------------
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", ROBOTS)
def test_c_solver_solves_reachable_targets_within_limits(name, method):
    robot, options = ROBOTS[name], METHODS[method]
    if _square_only(robot, options):
        pytest.skip("needs 6 joints")
    Q = robot.random_q(20, seed=1)
    Tep = robot.fkine(Q)
    res = ik(robot, Tep, backend="c", seed=2, **options)
    assert res.q.shape == (20, robot.n) and res.success.shape == (20,)
    for i in range(20):
        _assert_solved(robot, res[i], Tep[i])


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", ROBOTS)
def test_numpy_solver_solves_reachable_targets_within_limits(name, method):
    robot, options = ROBOTS[name], METHODS[method]
    if _square_only(robot, options):
        pytest.skip("needs 6 joints")
    for seed in range(2):
        Tep = robot.fkine(robot.random_q(seed=10 + seed))
        _assert_solved(robot, ik(robot, Tep, seed=seed, **options), Tep)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", ROBOTS)
def test_compiled_kinematics_solve_on_every_backend(name, method):
    """kin.ik on generated code: the C loop on the C backend, the NumPy solver on the others;
    solutions are checked with the numeric reference FK."""
    robot, options = ROBOTS[name], METHODS[method]
    if _square_only(robot, options):
        pytest.skip("needs 6 joints")
    Tep = robot.fkine(robot.random_q(8, seed=4))
    for backend in ("c", "numpy"):
        kin = symkin.compile(robot, backend=backend)
        res = kin.ik(Tep if backend == "c" else Tep[0], seed=3, **options)
        if backend == "c":
            for i in range(len(Tep)):
                _assert_solved(robot, res[i], Tep[i])
        else:
            _assert_solved(robot, res, Tep[0])


def test_c_loop_on_generated_code_takes_the_reference_steps():
    """Same start, same steps: the C solver on generated kinematics vs the NumPy solver on the reference."""
    kin = symkin.compile(UR5, backend="c")
    Tep = UR5.fkine(UR5.random_q(seed=7))
    q0 = UR5.random_q(seed=8)
    opt = IKOptions.of(kin)
    c = CIKSolver(kin, opt).trace(Tep, q0, 5)
    ref = ik_trace(UR5, Tep, q0, 5)
    assert_close(c, ref, 1e-9, "iterates")


def test_default_tolerance_bounds_the_error_norm_and_paper_criterion_bounds_E():
    Tep = UR5.fkine(UR5.random_q(50, seed=3))
    res = ik(UR5, Tep, backend="c", seed=0)
    assert res.success.all() and (res.residual < 1e-6).all()
    errs = np.linalg.norm(pose_error(UR5.fkine(res.q), Tep), axis=-1)
    np.testing.assert_allclose(errs, res.residual, rtol=1e-6, atol=1e-12)
    paper = ik(UR5, Tep, backend="c", seed=0, tol=1e-6, tol_on="E")
    assert paper.success.all() and (0.5 * paper.residual**2 < 1e-6).all()


def test_unreachable_target_fails_with_a_reason_on_both_backends():
    Tep = np.eye(4)
    Tep[:3, 3] = [5.0, 0.0, 0.0]  # 5 m away: the UR5 reaches about 1 m
    for backend in ("numpy", "c"):
        res = ik(UR5, Tep, backend=backend, slimit=3, ilimit=20, seed=0)
        assert not res.success
        assert "no solution within 3 search(es) x 20 iterations" in res.reason
        assert res.iterations == 60 and res.searches == 3
        assert np.isfinite(res.q).all() and res.residual > 3.0


def test_solution_outside_joint_limits_is_rejected():
    robot = Robot.from_ets("Rz(q0) tx(1)", qlim=[[0.0], [0.5]], name="arm1")
    Tep = robot.fkine(np.array([1.0]))  # only q = 1 + 2 pi k reach it, all outside [0, 0.5]
    for backend in ("numpy", "c"):
        res = ik(robot, Tep, backend=backend, slimit=4, seed=1)
        assert not res.success
        assert "rejected for joint limits" in res.reason
        free = ik(robot, Tep, backend=backend, slimit=4, seed=1, joint_limits=False)
        assert free.success and abs(math.remainder(free.q[0] - 1.0, 2 * PI)) < 1e-6


def test_revolute_solution_is_wrapped_into_the_limits():
    robot = Robot.from_ets("Rz(q0) tx(1) Rz(q1) tx(1)", qlim=[[-PI, -PI], [PI, PI]], name="planar")
    q_true = np.array([3.0, -2.5])
    Tep = robot.fkine(q_true)
    for backend in ("numpy", "c"):
        res = ik(robot, Tep, backend=backend, q0=q_true + [2 * PI, -2 * PI], slimit=1, seed=0)
        assert res.success and res.iterations == 1
        np.testing.assert_allclose(res.q, q_true, atol=1e-12)


def test_searches_start_from_q0_then_starts_then_random():
    q_true = UR5.random_q(seed=4)
    Tep = UR5.fkine(q_true)
    far = q_true + 2.0
    for backend in ("numpy", "c"):
        res = ik(UR5, Tep, backend=backend, ilimit=1, slimit=3, starts=[far, far, q_true], seed=0)
        assert res.success and res.searches == 3 and res.iterations == 3
        res = ik(UR5, Tep, backend=backend, ilimit=1, slimit=2, q0=q_true, starts=[far], seed=0)
        assert res.success and res.searches == 1


def test_batch_results_and_per_target_q0():
    Q = PANDA.random_q(4, seed=5)
    Tep = PANDA.fkine(Q)
    for backend in ("numpy", "c"):
        res = ik(PANDA, Tep, backend=backend, q0=Q, seed=0)
        assert res.success.all() and (res.iterations == 1).all() and len(res) == 4
        assert isinstance(res.reason, tuple) and res[2].reason == "success"
        np.testing.assert_allclose(res.q, Q, atol=1e-12)
    with pytest.raises(TypeError):
        len(ik(PANDA, Tep[0], q0=Q[0]))


@pytest.mark.parametrize("name", ROBOTS)
def test_c_batch_gives_each_target_what_solving_it_alone_gives(name):
    # a batch of LM solves runs several targets side by side, their steps in vector lanes; each
    # must get bit for bit what the one-target solver gives: through restarts (no random ones
    # here, so the seed streams do not matter), failures, weights and, with lam = 0 at the
    # singular q = 0, the LU fallback when the Cholesky factorisation fails
    robot = ROBOTS[name]
    Tep = robot.fkine(robot.random_q(9, seed=12))
    Tep[4, :3, 3] += 10.0  # unreachable
    starts = np.zeros((4, robot.n))
    starts[1:] = robot.random_q(3, seed=13)
    for options in (
        {},
        {"damping": "wampler", "lam": 0.0},
        {"damping": "sugihara", "lam": 1e-3, "we": [1, 1, 1, 0.5, 0.5, 0.5]},
    ):
        solver = CIKSolver(robot, slimit=4, ilimit=20, starts=starts, **options)
        batch = solver.solve(Tep, seed=3)
        assert batch.success.any() and not batch.success[4]
        for i in range(len(Tep)):
            alone = solver.solve(Tep[i], seed=3)
            assert alone.q.tobytes() == batch.q[i].tobytes()
            assert (alone.iterations, alone.searches, alone.reason) == (
                batch.iterations[i],
                batch.searches[i],
                batch.reason[i],
            )
            assert alone.residual == batch.residual[i]


@pytest.mark.parametrize(
    "name, options",
    [
        ("ur5", {}),
        ("panda", {}),
        ("ur5", {"method": "GN", "pinv": True}),
        ("panda", {"method": "NR", "pinv": True}),
        ("planar3", {"method": "GN", "we": [1, 1, 0, 0, 0, 1]}),
    ],
)
def test_c_batch_on_four_lane_kinematics_keeps_every_iterate(name, options):
    """On compiled kinematics a batch of solves (LM, GN, NR, any joint count) evaluates its four
    lanes' poses in one call of the generated four-lane fkine_jacob0_batch: each target must
    still get, bit for bit, what it gets from a batch without the four-lane call, and target 0
    what it gets alone (scalar kinematics), through random restarts and an unreachable target."""
    kin = symkin.compile(name, backend="c")
    Tep = kin.fkine(kin.robot.random_q(11, seed=21))
    Tep[6, :3, 3] += 10.0  # unreachable: every search fails, random restarts
    four = CIKSolver(kin, slimit=3, ilimit=30, **options)
    one = CIKSolver(kin, fkjac=kin.c_fkjac, slimit=3, ilimit=30, **options)
    assert four._cfg.fkjac_batch and not one._cfg.fkjac_batch
    batch, plain = four.solve(Tep, seed=5), one.solve(Tep, seed=5)
    # successes and failures both happen (Panda: some rejected for limits; NR converges less)
    assert batch.success.sum() >= (3 if options.get("method") == "NR" else 6) and not batch.success[6]
    assert batch.q.tobytes() == plain.q.tobytes()
    assert np.array_equal(batch.iterations, plain.iterations)
    assert np.array_equal(batch.searches, plain.searches)
    alone = four.solve(Tep[0], seed=5)  # target 0: the random stream (5, 0), as alone
    assert alone.q.tobytes() == batch.q[0].tobytes() and alone.iterations == batch.iterations[0]


def test_array_options_are_copied_and_memoised_by_value():
    # ik(..., starts=array) memoises its validated options by the array's contents: the caller's
    # array stays writable and unshared, and changing it in place changes the next solve
    kin = symkin.compile(UR5, backend="c")
    S = UR5.random_q(3, seed=4)
    T = UR5.fkine(UR5.random_q(seed=5))
    a = ik(kin, T, backend="c", starts=S, slimit=1, seed=1)  # one search, from S[0]
    assert S.flags.writeable
    S[0] = UR5.random_q(seed=6)
    b = ik(kin, T, backend="c", starts=S, slimit=1, seed=1)
    fresh = ik(kin, T, backend="c", starts=S.copy(), slimit=1, seed=1)
    assert b.q.tobytes() == fresh.q.tobytes() and b.iterations == fresh.iterations
    assert a.q.tobytes() != b.q.tobytes()


def test_same_seed_reproduces_results():
    Tep = PANDA.fkine(PANDA.random_q(5, seed=6))
    a = ik(PANDA, Tep, backend="c", seed=11)
    b = ik(PANDA, Tep, backend="c", seed=11)
    np.testing.assert_array_equal(a.q, b.q)
    np.testing.assert_array_equal(a.iterations, b.iterations)


# -- C against NumPy --------------------------------------------------------------------------
@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("name", ROBOTS)
def test_c_and_numpy_take_the_same_iterates(name, method):
    robot, options = ROBOTS[name], METHODS[method]
    if _square_only(robot, options):
        pytest.skip("needs 6 joints")
    solver = CIKSolver(robot, **options)
    rng = np.random.default_rng(0)
    for seed in range(3):
        q_true = robot.random_q(seed=100 + seed)
        Tep = robot.fkine(q_true)
        near = q_true + rng.uniform(-0.2, 0.2, robot.n)  # converging: every iterate agrees
        qs_py, qs_c = ik_trace(robot, Tep, near, 5, **options), solver.trace(Tep, near, 5)
        # compare up to the first iterate with |e| < 1e-4: closer in, a redundant arm's null-space
        # step is rounding noise amplified by the nearly singular J^T J + lam E I (Chan, E -> 0)
        res = [np.linalg.norm(pose_error(robot.fkine(q), Tep)) for q in qs_py]
        k = next((i for i, r in enumerate(res) if r < 1e-4), len(res) - 1) + 1
        assert k >= 3 and len(qs_c) >= k
        assert_close(qs_c[:k], qs_py[:k], 1e-9, "iterates from a nearby start")
        # from a random start the first step agrees where J is well conditioned (later steps of
        # NR/GN can be huge and chaotic, amplifying rounding differences)
        far = robot.random_q(seed=200 + seed)
        if np.linalg.cond(robot.jacob0(far)) < 1e3:
            qs_py, qs_c = ik_trace(robot, Tep, far, 1, **options), solver.trace(Tep, far, 1)
            assert_close(qs_c, qs_py, 1e-9, "first step from a random start")


def test_c_and_numpy_give_the_same_solutions_and_restarts():
    Tep = UR5.fkine(UR5.random_q(6, seed=7))
    a = ik(UR5, Tep, backend="numpy", seed=3, slimit=20)
    b = ik(UR5, Tep, backend="c", seed=3, slimit=20)
    np.testing.assert_array_equal(a.iterations, b.iterations)
    np.testing.assert_array_equal(a.searches, b.searches)
    np.testing.assert_allclose(a.q, b.q, atol=1e-9)
    solver = CIKSolver(UR5)
    rng = SplitMix64(3, stream=4)
    expected = np.array([rng.random_q(solver.options.sample) for _ in range(5)])
    np.testing.assert_array_equal(solver.random_q(3, 5, stream=4), expected)


@pytest.mark.parametrize("name", ["ur5", "panda", "puma560", "planar3"])
def test_pinv_steps_at_singularities_are_the_pseudo_inverse_steps(name):
    # the C pseudo-inverse steps solve with a Cholesky factor when J is well conditioned; at and
    # near a singularity they must still be pinv's (numpy.linalg.pinv, rcond 1e-12), which drops
    # the lost directions: for GN those with sigma < 1e-6 sigma_max (pinv of J^T J), so at qz + 1e-7
    # a plain solve would step ~1e7 rad where pinv steps ~1
    robot = load(name)
    Tep = robot.fkine(robot.random_q(seed=1))
    for method in ("NR", "GN"):
        solver = CIKSolver(robot, method=method, pinv=True)
        starts = [robot.qz, robot.qz + 1e-7] if method == "GN" else [robot.qz]
        for q0 in [*starts, robot.random_q(seed=2)]:
            ref = ik_trace(robot, Tep, q0, 1, method=method, pinv=True)
            step = ref[1] - ref[0]
            assert_close(solver.trace(Tep, q0, 1)[1] - q0, step, 1e-9, f"{method} step at {q0}")
            if method == "GN" and q0 is starts[1]:
                assert np.abs(step).max() < 10.0


def test_one_target_call_takes_any_array_and_checks_it():
    # kin.ik(T) with the default options goes straight to the C entry point; whatever it does not
    # take directly (lists, big-endian, batches, bad values) goes through the checked path
    kin = symkin.compile(UR5, backend="c")
    q = UR5.random_q(seed=21)
    T = UR5.fkine(q)
    first = kin.ik(T)
    for variant in (T.tolist(), T.astype(">f8"), np.asfortranarray(T)):
        res = kin.ik(variant)
        _assert_solved(UR5, res, T)
    assert kin.ik(T[None]).q.shape == (1, 6)  # a batch of one
    a, b = symkin.ik(kin, T, backend="c", seed=5), symkin.ik(kin, T, backend="c", seed=np.int64(5))
    assert a.q.tobytes() == b.q.tobytes() and a.iterations == b.iterations
    far = T.copy()
    far[:3, 3] += 5.0
    res = kin.ik(far)
    assert not res.success and "no solution" in res.reason and res.q.shape == (6,)
    bad = T.copy()
    bad[1, 1] = np.nan
    with pytest.raises(PoseError, match="NaN"):
        kin.ik(bad)
    with pytest.raises(PoseError, match="orthonormal"):
        kin.ik(T + np.diag([0.1, 0, 0, 0]))
    with pytest.raises(ConfigurationError):
        symkin.ik(kin, T, backend="c", q0=np.full(6, np.inf))
    with pytest.raises(ConfigurationError):
        symkin.ik(kin, T, backend="c", q0=np.zeros(5))
    assert first.success and kin.ik(T).success
    # after the first call kin.ik is the C entry point itself; it passes every other call on to
    # Kinematics.ik: keyword options, the target by keyword, no target
    assert type(kin.ik).__name__ == "BoundIK" and type(kin).ik.__name__ == "ik"
    a, b = kin.ik(T, seed=7), kin.ik(Tep=T, seed=7)
    assert (
        a.q.tobytes() == b.q.tobytes() and a.q.tobytes() == symkin.ik(kin, T, backend="c", seed=7).q.tobytes()
    )
    _assert_solved(UR5, kin.ik(T, method="GN", pinv=True, seed=1), T)
    with pytest.raises(TypeError):
        kin.ik()
    import pickle

    _assert_solved(UR5, pickle.loads(pickle.dumps(kin)).ik(T), T)


def test_keyword_options_seen_before_solve_in_one_c_call():
    # kin.ik(T, lam=..., seed=..., q0=...) with options seen before runs no Python function (the
    # bound entry point finds their solver by the options in C) and returns what the solver does
    import sys

    kin = symkin.compile(UR5, backend="c")
    q = UR5.random_q(seed=23)
    T = UR5.fkine(q)
    options = {"method": "LM", "lam": 0.05, "ilimit": 40}
    kin.ik(T, **options)  # first call: the solver is made and validated in Python
    solver = kin._c_ik_solver(dict(options))
    python_calls: list[str] = []

    def profile(frame, event, arg):
        if event == "call":
            python_calls.append(frame.f_code.co_name)

    q0 = q + 0.05
    sys.setprofile(profile)
    try:
        a = kin.ik(T, seed=9, **options)
        b = kin.ik(T, q0=q0, **options)
        c = kin.ik(T, seed=9)
    finally:
        sys.setprofile(None)
    assert python_calls == []
    ref = solver.solve(T, None, 9)
    assert a.q.tobytes() == ref.q.tobytes() and a.iterations == ref.iterations
    assert b.q.tobytes() == solver.solve(T, q0, None).q.tobytes()
    assert c.q.tobytes() == symkin.ik(kin, T, backend="c", seed=9).q.tobytes()
    assert a.q.tobytes() != c.q.tobytes() or a.iterations != c.iterations  # another solver's search
    # options in another order are another key: the Python path, the same answer
    assert kin.ik(T, seed=9, ilimit=40, lam=0.05, method="LM").q.tobytes() == a.q.tobytes()
    # what the C path does not take still goes through the checks
    with pytest.raises(ConfigurationError):
        kin.ik(T, q0=np.full(6, np.nan), **options)
    with pytest.raises(TypeError):
        kin.ik(T, lamda=0.1)
    _assert_solved(UR5, kin.ik(T, lam=np.array(0.05)), T)  # unhashable: the NumPy-checked path
    # past 64 option sets the memo restarts; kin.ik keeps solving with every set
    for i in range(70):
        _assert_solved(UR5, kin.ik(T, lam=0.05 + i * 1e-3, seed=i), T)
    assert len(kin._ik_by_options) <= 64 and kin.ik(T, seed=9, **options).q.tobytes() == a.q.tobytes()


# -- threads ----------------------------------------------------------------------------------
def test_ik_from_two_threads_returns_each_thread_its_own_solutions():
    # one compiled robot, one default solver, two threads solving different targets at once (the
    # solve releases the GIL): every success must solve its own target, checked with the reference
    import threading

    kin = symkin.compile(UR5, backend="c")
    count = 1500
    targets = [UR5.fkine(UR5.random_q(count, seed=40 + t)) for t in range(2)]
    results: list[list] = [[], []]
    barrier = threading.Barrier(2)

    def work(t: int) -> None:
        barrier.wait()
        results[t] = [kin.ik(T) for T in targets[t]]

    threads = [threading.Thread(target=work, args=(t,)) for t in range(2)]
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    for t in range(2):
        assert len(results[t]) == count
        ok = np.array([r.success for r in results[t]])
        assert ok.mean() > 0.99
        q = np.array([r.q for r in results[t]])[ok]
        e = np.linalg.norm(pose_error(UR5.fkine(q), targets[t][ok]), axis=-1)
        assert e.max() < 1e-6, f"thread {t}: {(e >= 1e-6).sum()} successes do not solve their target"


class _DuckKinematics:
    """Only what ik() needs: n, qlim, fkine, jacob0; optionally ``revolute`` (no ets)."""

    def __init__(self, robot: Robot, revolute: bool = False) -> None:
        self.n, self.qlim, self.fkine, self.jacob0 = robot.n, robot.qlim, robot.fkine, robot.jacob0
        if revolute:  # which joints wrap by 2 pi
            self.revolute = [e.is_revolute for e in robot.ets.joints]


def test_any_object_with_n_qlim_fkine_jacob0_works():
    Tep = UR5.fkine(UR5.random_q(seed=9))
    res = ik(_DuckKinematics(UR5), Tep, seed=0)
    _assert_solved(UR5, res, Tep)


def test_c_solver_takes_a_kinematics_function_pointer():
    import ctypes

    from symkin.runtime.ik_c import FKJAC

    n = UR5.n
    dbl = ctypes.POINTER(ctypes.c_double)

    def fkjac(q_ptr, T_ptr, J_ptr):  # symkin_fkjac_fn through the numeric reference
        q = np.ctypeslib.as_array(ctypes.cast(q_ptr, dbl), (n,)).copy()
        np.ctypeslib.as_array(ctypes.cast(T_ptr, dbl), (4, 4))[:] = UR5.fkine(q)
        np.ctypeslib.as_array(ctypes.cast(J_ptr, dbl), (6, n))[:] = UR5.jacob0(q)

    callback = FKJAC(fkjac)
    by_pointer = CIKSolver(_DuckKinematics(UR5, revolute=True), fkjac=callback)
    by_table = CIKSolver(UR5)
    Tep = UR5.fkine(UR5.random_q(3, seed=10))
    a, b = by_pointer.solve(Tep, seed=1), by_table.solve(Tep, seed=1)
    assert a.success.all()
    np.testing.assert_array_equal(a.iterations, b.iterations)
    np.testing.assert_allclose(a.q, b.q, atol=1e-9)


@pytest.mark.parametrize("name", ROBOTS)
def test_c_ets_kinematics_match_the_reference(name):
    robot = ROBOTS[name]
    solver = CIKSolver(robot)
    for q in robot.random_q(5, seed=8):
        T, J = solver.fkine_jacob0(q)
        np.testing.assert_allclose(T, robot.fkine(q), atol=1e-14)
        np.testing.assert_allclose(J, robot.jacob0(q), atol=1e-14)


# -- pose error -------------------------------------------------------------------------------
def _rot(axis, theta: float) -> np.ndarray:
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0, -a[2], a[1]], [a[2], 0, -a[0]], [-a[1], a[0], 0]])
    return np.eye(3) + math.sin(theta) * K + (1 - math.cos(theta)) * K @ K


@pytest.mark.parametrize(
    ("axis", "theta"),
    [((0, 0, 1), 0.3), ((1, 2, 3), 1e-9), ((1, -2, 0.5), 2.0), ((1, 1, 0), PI), ((0.3, -1, 2), PI - 1e-8)],
)
def test_angle_axis_is_the_euler_vector(axis, theta):
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    alpha = angle_axis(_rot(axis, theta))
    if abs(theta - PI) < 1e-6:  # +-pi a describe the same rotation
        alpha = alpha if alpha @ a > 0 else -alpha
    np.testing.assert_allclose(alpha, theta * a, atol=1e-9)
    T = np.eye(4)
    T[:3, :3] = _rot(axis, theta)
    e_c = CIKSolver(UR5).pose_error(np.eye(4), T)
    np.testing.assert_allclose(e_c, pose_error(np.eye(4), T), atol=1e-15)


def test_angle_axis_of_diagonal_matrices_follows_eq_40():
    np.testing.assert_array_equal(angle_axis(np.eye(3)), [0, 0, 0])
    np.testing.assert_allclose(angle_axis(np.diag([1.0, -1, -1])), [PI, 0, 0])
    np.testing.assert_allclose(angle_axis(np.diag([-1.0, 1, -1])), [0, PI, 0])
    np.testing.assert_allclose(angle_axis(np.diag([-1.0, -1, 1])), [0, 0, PI])


def test_invalid_targets_raise_pose_error_on_both_backends():
    good = UR5.fkine(UR5.qz)
    nan = good.copy()
    nan[0, 3] = np.nan
    skew = good.copy()
    skew[:3, :3] *= 1.001
    bottom = good.copy()
    bottom[3, 0] = 0.1
    reflect = good.copy()
    reflect[:3, 0] *= -1
    cases = {"NaN": nan, "not orthonormal": skew, "bottom row": bottom, "reflection": reflect}
    for backend in ("numpy", "c"):
        for what, T in cases.items():
            with pytest.raises(PoseError, match=what):
                ik(UR5, T, backend=backend)
        with pytest.raises(PoseError, match=r"target \[1\]"):
            ik(UR5, np.stack((good, nan)), backend=backend)
        with pytest.raises(PoseError, match="shape"):
            ik(UR5, np.eye(3), backend=backend)
        with pytest.raises(ConfigurationError):
            ik(UR5, good, q0=[np.nan] * 6, backend=backend)


def test_bad_options_are_rejected():
    Tep = PANDA.fkine(PANDA.qz)
    with pytest.raises(ValueError, match="square"):
        ik(PANDA, Tep, method="NR")
    with pytest.raises(ValueError, match="method"):
        ik(UR5, Tep, method="XX")
    with pytest.raises(ValueError, match="damping"):
        ik(UR5, Tep, damping="foo")
    with pytest.raises(ValueError, match="we"):
        ik(UR5, Tep, we=[0] * 6)


# -- the C build cache ------------------------------------------------------------------------
_SRC = {
    "add.h": "double add(double a, double b);\n",
    "add.c": '#include "add.h"\ndouble add(double a, double b) { return a + b; }\n',
}


def _add(path: Path, a: float, b: float) -> float:
    import ctypes

    lib = load_library(path)
    lib.add.restype, lib.add.argtypes = ctypes.c_double, [ctypes.c_double, ctypes.c_double]
    return lib.add(a, b)


def test_build_cache_is_reused_without_building(tmp_path, monkeypatch):
    monkeypatch.setenv("SYMKIN_CACHE", str(tmp_path))
    path = compile_library(_SRC, "addlib")
    assert _add(path, 1.5, 2.0) == 3.5
    mtime = path.stat().st_mtime_ns

    def no_build(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        raise AssertionError("a cached library was built again")

    monkeypatch.setattr("symkin.emit.c.build._build", no_build)
    again = compile_library(_SRC, "addlib")  # the cached entry, without invoking the compiler
    assert again == path and path.stat().st_mtime_ns == mtime
    assert (path.parent / (path.name + ".sha256")).is_file()
    assert [p.name for p in tmp_path.iterdir()] == [path.parent.name]  # no temporary folders left


def test_corrupted_cache_entry_is_rebuilt(tmp_path, monkeypatch):
    monkeypatch.setenv("SYMKIN_CACHE", str(tmp_path))
    path = compile_library(_SRC, "addlib2")
    size = path.stat().st_size
    with open(path, "r+b") as f:
        f.truncate(size // 3)
    rebuilt = compile_library(_SRC, "addlib2")
    assert rebuilt == path and rebuilt.stat().st_size == size
    assert _add(rebuilt, 2.0, 2.0) == 4.0


def _compile_in_child(cache: str, barrier, queue) -> None:
    os.environ["SYMKIN_CACHE"] = cache
    barrier.wait()
    try:
        queue.put(str(compile_library(_SRC, "addlib_race")))
    except Exception as exc:  # noqa: BLE001 - report any failure to the parent
        queue.put(f"error: {exc!r}")


def test_concurrent_builds_of_the_same_library_all_succeed(tmp_path):
    ctx = multiprocessing.get_context("spawn")  # not fork: the worker may have started JAX threads
    barrier, queue = ctx.Barrier(4), ctx.Queue()
    procs = [ctx.Process(target=_compile_in_child, args=(str(tmp_path), barrier, queue)) for _ in range(4)]
    for p in procs:
        p.start()
    results = [queue.get(timeout=120) for _ in procs]
    for p in procs:
        p.join(timeout=60)
    assert len(set(results)) == 1, results
    assert not results[0].startswith("error"), results[0]
    assert _add(Path(results[0]), 1.0, 2.0) == 3.0
    assert [p.name for p in tmp_path.iterdir()] == [Path(results[0]).parent.name]


def test_missing_compiler_raises_compile_error(tmp_path, monkeypatch):
    monkeypatch.setenv("SYMKIN_CACHE", str(tmp_path))
    monkeypatch.setenv("CC", "/nonexistent/cc")
    with pytest.raises(CompileError, match="NumPy backend"):
        compile_library(_SRC, "addlib3")


def test_compiler_error_is_reported(tmp_path, monkeypatch):
    monkeypatch.setenv("SYMKIN_CACHE", str(tmp_path))
    with pytest.raises(CompileError, match="error"):
        compile_library({"bad.c": "int f(void) { return undefined_symbol; }\n"}, "badlib")
    assert list(tmp_path.iterdir()) == []


# -- Table 1 benchmark ------------------------------------------------------------------------
def test_table1_benchmark_runs_and_formats():
    from symkin.bench.ik import PAPER_TABLE1, format_table1, run_table1

    methods = ["NR", "LM (Chan lambda=0.1)"]
    result = run_table1(UR5, n_problems=40, seed=0, methods=methods, progress=False, rtb=False)
    assert [(r["method"], r["setting"]) for r in result["rows"]] == [(m, s) for s in "ab" for m in methods]
    for row in result["rows"]:
        assert row["paper"]["infeasible_pct"] == PAPER_TABLE1[(row["method"], row["setting"])][3]
        assert row["max_error"] < math.sqrt(2e-6)  # what E < 1e-6 allows
        if row["setting"] == "b":
            assert row["infeasible"] == 0 and row["max_searches"] <= 100
    text = format_table1(result)
    assert "LM (Chan lambda=0.1)" in text and "paper" in text
    assert result["lanes"]["same_solutions"] and "identical solutions" in text  # four lanes vs scalar


def test_keyword_options_reuse_their_solver_and_give_the_functions_results():
    """kin.ik(T, **options) goes to the C solver made for those options the first time (no
    validation per call) and answers exactly as symkin.ik with the same options and seed."""
    import symkin
    from symkin.errors import ParameterError

    robot = symkin.load("ur5")
    kin = symkin.compile(robot, "c")
    Q = robot.random_q(6, seed=21)
    options = [
        {},
        {"method": "LM", "lam": 0.05, "ilimit": 40},
        {"damping": "wampler", "we": [1, 1, 1, 1, 1, 0]},
    ]
    for opts in options:
        for i in range(len(Q)):
            T = robot.fkine(Q[i])
            for _ in range(2):  # the second call takes the memoised solver
                got = kin.ik(T, seed=7 + i, **opts)
                want = symkin.ik(kin, T, seed=7 + i, backend="c", **opts)
                assert np.array_equal(got.q, want.q) and got.success == want.success
    assert kin.ik(robot.fkine(Q[0]), q0=Q[0], we=np.ones(6)).success  # an unhashable option
    for _ in range(2):
        with pytest.raises(ParameterError):
            kin.ik(robot.fkine(Q[0]), method="XX")
    assert kin.ik(robot.fkine(Q[0]), method="analytic").success
