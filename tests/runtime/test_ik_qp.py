"""QP inverse kinematics (Haviland and Corke, Manipulator Differential Kinematics, Part 2): the QP of
one step against roboticstoolbox-python's IK_QP, OSQP and the KKT system; the C step against the
NumPy one; solutions checked by the numeric reference's forward kinematics and joint limits."""

from __future__ import annotations

import importlib
import threading

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import symkin
from symkin.errors import ConfigurationError, ParameterError
from symkin.model.robots import load
from symkin.runtime.ik import ik, ik_trace, pose_error
from symkin.runtime.ik_c import CIKSolver
from symkin.runtime.ik_problem import IKOptions
from symkin.runtime.ik_qp import build_ik_qp, ik_qp, manipulability_term, solve_ik_qp
from symkin.runtime.ik_qp_c import QPStep
from tests.conftest import assert_close

UR5 = load("ur5")  # 6 DoF, every joint +-2 pi: no dampers
PANDA = load("panda")  # 7 DoF, limits within a turn: every joint damped


@pytest.fixture(scope="module")
def ur5_c():
    return symkin.compile(UR5, backend="c")


@pytest.fixture(scope="module")
def panda_c():
    return symkin.compile(PANDA, backend="c")


def _near_limits(robot, seed: int) -> np.ndarray:
    """A configuration with joint 0 0.3 below its upper limit and joint 1 0.2 above its lower one."""
    q = robot.random_q(seed=seed)
    lo, hi = robot.qlim
    q[0], q[1] = hi[0] - 0.3, lo[1] + 0.2
    return q


def _step_inputs(robot, q, Tep):
    return robot.jacob0(q), pose_error(robot.fkine(q), Tep)


# -- the QP of one step ---------------------------------------------------------------------------
def test_qp_matrices_are_roboticstoolbox_ik_qp_matrices(monkeypatch):
    """The QP roboticstoolbox-python's IK_QP hands to qpsolvers (captured) has our P, c, the equality
    [J 1] x = e and, for the joints within pi of a limit, our damper bounds; both solutions agree."""
    rtb = pytest.importorskip("roboticstoolbox")
    pytest.importorskip("quadprog")
    rtb_ik = importlib.import_module("roboticstoolbox.robot.IK")  # where IK_QP calls qpsolvers
    from symkin.bench.kin import rtb_ets

    ets = rtb_ets(rtb, PANDA)
    ets.qlim = PANDA.qlim
    q = _near_limits(PANDA, 3)
    Tep = PANDA.fkine(q + 0.02 * np.sin(np.arange(7.0)))  # a small step: our step bound does not bind
    captured = {}
    real = rtb_ik.qp

    class Capture:
        @staticmethod
        def solve_qp(*args, **kwargs):
            captured["args"] = args
            captured["x"] = real.solve_qp(*args, **kwargs)
            return captured["x"]

    monkeypatch.setattr(rtb_ik, "qp", Capture)
    solver = rtb.IK_QP(kj=0.01, ks=1.0, kq=2.0, km=100.0, ps=0.05, pi=0.9)
    solver.step(ets, Tep, q.copy())
    Q, c, Ain, bin_, Aeq, beq = captured["args"]
    opt = IKOptions.of(PANDA, method="QP", lam=0.01, slack_gain=1.0, xi=0.5, rho_i=0.9, rho_s=0.05,
                       manipulability=0.01)  # fmt: skip
    J, e = _step_inputs(PANDA, q, Tep)
    qp = ik_qp(q, J, e, opt, manipulability_term(PANDA, q, J))
    n = PANDA.n
    assert_close(qp.P, Q, 1e-12, "P: lambda_q 1_n, lambda_delta / sum|e| 1_6")
    assert_close(qp.c, c, 1e-9, "c: -Jm / lambda_m")
    assert_close(qp.A[:6], Aeq, 1e-12, "the equality J qd + s = e")
    assert_close(qp.l[:6], beq, 1e-12, "e")
    assert_close(qp.u[:6], beq, 1e-12, "e")
    upper, lower = np.diag(Ain)[:n] == 1, np.diag(Ain)[:n] == -1
    assert upper[0] and lower[1]  # the two dampers this q sets off
    assert_close(qp.upper[upper], bin_[:n][upper], 1e-12, "upper dampers")
    assert_close(qp.lower[lower], -bin_[:n][lower], 1e-12, "lower dampers")
    assert_close(solve_ik_qp(qp), captured["x"][:n], 1e-6, "the step")


def _osqp_solution(qp) -> np.ndarray:
    osqp = pytest.importorskip("osqp")
    import scipy.sparse as sp

    solver = osqp.OSQP()
    inf = float(osqp.constant("OSQP_INFTY"))
    l, u = np.maximum(qp.l, -inf), np.minimum(qp.u, inf)
    settings = {"eps_abs": 1e-11, "eps_rel": 1e-11, "max_iter": 200000, "polishing": True, "verbose": False}
    solver.setup(sp.csc_matrix(qp.P), qp.c, sp.csc_matrix(qp.A), l, u, **settings)
    res = solver.solve(raise_error=False)
    assert res.info.status == "solved"
    return np.asarray(res.x)[: qp.n]


@pytest.mark.parametrize("seed", range(6))
def test_qp_step_is_what_osqp_finds(seed):
    """Dampers active (joints near their limits), a manipulability term, and distance rows for half
    of the cases: the closed form / active-set answer is OSQP's (an independent solver)."""
    rng = np.random.default_rng(seed)
    q = _near_limits(PANDA, seed)
    Tep = PANDA.fkine(PANDA.random_q(seed=100 + seed))  # far: the step pushes into the dampers
    opt = IKOptions.of(PANDA, method="QP", manipulability=0.01, xi=0.3, rho_i=1.0, rho_s=0.05)
    J, e = _step_inputs(PANDA, q, Tep)
    Jd = dl = None
    if seed % 2:
        Jd, dl = rng.normal(size=(3, 7)), np.array([-0.05, -0.2, -np.inf])
    qp = ik_qp(q, J, e, opt, manipulability_term(PANDA, q, J), Jd, dl)
    qd = solve_ik_qp(qp)
    assert (qd <= qp.upper + 1e-12).all() and (qd >= qp.lower - 1e-12).all()
    assert_close(qd, _osqp_solution(qp), 2e-6, "QP step vs OSQP")


@pytest.mark.parametrize("manipulability", [0.0, 0.01])
def test_qp_step_without_bounds_solves_the_kkt_system(manipulability):
    """No inequalities (joint_limits=False): the step is x of [[P, A^T], [A, 0]] [x; y] = [-c; e]."""
    q = PANDA.random_q(seed=4)
    Tep = PANDA.fkine(PANDA.random_q(seed=5))
    opt = IKOptions.of(PANDA, method="QP", joint_limits=False, manipulability=manipulability)
    J, e = _step_inputs(PANDA, q, Tep)
    qp = ik_qp(q, J, e, opt, manipulability_term(PANDA, q, J))
    n = PANDA.n
    A = qp.A[:6]
    K = np.block([[qp.P, A.T], [A, np.zeros((6, 6))]])
    x = np.linalg.solve(K, np.concatenate((-qp.c, e)))
    assert np.isinf(qp.lower).all() and np.isinf(qp.upper).all()
    assert_close(solve_ik_qp(qp), x[:n], 1e-10, "KKT")
    assert_close(J @ x[:n] + x[n : n + 6], e, 1e-12, "J qd + s = e")


def test_build_from_kinematics_is_the_qp_of_its_arrays(panda_c):
    q = _near_limits(PANDA, 9)
    Tep = PANDA.fkine(PANDA.random_q(seed=9))
    qp = build_ik_qp(panda_c, q, Tep, manipulability=0.01)
    opt = IKOptions.of(PANDA, method="QP", manipulability=0.01)
    J, e = _step_inputs(PANDA, q, Tep)
    ref = ik_qp(q, J, e, opt, manipulability_term(PANDA, q, J))
    for name in ("P", "c", "A", "l", "u"):
        assert_close(getattr(qp, name), getattr(ref, name), 1e-10, name)


# -- C against NumPy --------------------------------------------------------------------------------
@pytest.mark.parametrize("options", [{}, {"manipulability": 0.01}, {"xi": 0.2, "rho_i": 1.2}])
@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_c_search_takes_the_numpy_steps(name, options, ur5_c, panda_c):
    robot, kin = (UR5, ur5_c) if name == "ur5" else (PANDA, panda_c)
    Tep = robot.fkine(robot.random_q(seed=21))
    q0 = robot.random_q(seed=22)
    c = CIKSolver(kin, method="QP", **options).trace(Tep, q0, 12)
    ref = ik_trace(robot, Tep, q0, 12, method="QP", **options)
    assert len(c) == len(ref) == 13
    assert_close(c, ref, 1e-8, "iterates")


def test_c_step_is_the_numpy_step_also_at_a_singular_configuration(ur5_c):
    opt = IKOptions.of(UR5, method="QP", manipulability=0.01)
    step = QPStep(ur5_c, opt)
    Tep = UR5.fkine(UR5.random_q(seed=2))
    for q in (UR5.random_q(seed=1), np.zeros(6)):  # q = 0: the stretched UR5, J singular
        J, e = _step_inputs(UR5, q, Tep)
        assert_close(
            step.step(q, e), solve_ik_qp(ik_qp(q, J, e, opt, manipulability_term(UR5, q, J))), 1e-9, "qd"
        )
    assert step.step(np.zeros(6), np.zeros(6)) is None  # no error, no step


# -- solutions ----------------------------------------------------------------------------------
@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_solutions_reach_the_target_by_the_reference_kinematics(name, ur5_c, panda_c):
    robot, kin = (UR5, ur5_c) if name == "ur5" else (PANDA, panda_c)
    Tep = robot.fkine(robot.random_q(30, seed=8))
    res = kin.ik(Tep, method="QP", seed=3)
    assert res.success.all(), set(res.reason)
    err = np.linalg.norm(pose_error(robot.fkine(res.q), Tep), axis=-1)
    assert (err < 1e-6).all(), err.max()
    assert all(robot.within_limits(q) for q in res.q)
    np.testing.assert_allclose(res.residual, err, rtol=1e-6, atol=1e-12)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(
    target=st.integers(0, 10**6),
    start=st.integers(0, 10**6),
    xi=st.floats(0.05, 5.0),
    rho_i=st.floats(0.1, 1.5),
    rho_s=st.floats(0.0, 0.09),
    lam=st.floats(1e-3, 1.0),
    manipulability=st.sampled_from([0.0, 0.01, 0.1]),
)
def test_joint_limits_hold_for_every_iterate_and_every_answer(
    panda_c, target, start, xi, rho_i, rho_s, lam, manipulability
):
    """Random reachable Panda targets and QP settings: every iterate of a search stays within the
    limits, rho_s inside them, and every answer (solved or not) lies within the limits."""
    options = {"xi": xi, "rho_i": rho_i, "rho_s": rho_s, "lam": lam, "manipulability": manipulability}
    Tep = PANDA.fkine(PANDA.random_q(seed=target))
    q0 = PANDA.random_q(seed=start)
    lo, hi = PANDA.qlim
    trace = CIKSolver(panda_c, method="QP", **options).trace(Tep, q0, 30)
    assert len(trace) == 31  # q0 (within the limits), then steps that end rho_s inside them
    assert (trace[1:] >= lo + rho_s - 1e-9).all() and (trace[1:] <= hi - rho_s + 1e-9).all()
    res = panda_c.ik(Tep, method="QP", q0=q0, slimit=3, seed=start, **options)
    assert PANDA.within_limits(res.q)
    if res.success:
        assert np.linalg.norm(pose_error(PANDA.fkine(res.q), Tep)) < 1e-6


def test_unreachable_target_fails_with_a_reason(ur5_c):
    Tep = np.eye(4)
    Tep[:3, 3] = [5.0, 0.0, 0.0]  # 5 m away: the UR5 reaches about 1 m
    for kin in (UR5, ur5_c):
        res = ik(kin, Tep, method="QP", slimit=3, ilimit=20, seed=0)
        assert not res.success
        assert "no solution within 3 search(es) x 20 iterations" in res.reason
        assert res.iterations == 60 and res.searches == 3 and res.residual > 3.0
        assert UR5.within_limits(res.q)


def test_singular_targets_and_starts_are_solved(ur5_c):
    """A target at a wrist singularity (q5 = 0), a start at the stretched configuration (q = 0, J
    singular) and a 3-joint arm (J J^T always singular): the QP still steps (Jm = 0 there)."""
    q_sing = UR5.random_q(seed=6)
    q_sing[4] = 0.0
    Tep = UR5.fkine(q_sing)
    for kin in (UR5, ur5_c):
        res = ik(kin, Tep, method="QP", q0=np.zeros(6), seed=1, manipulability=0.01)
        assert res.success, res.reason
        assert np.linalg.norm(pose_error(UR5.fkine(res.q), Tep)) < 1e-6
    planar = load("planar3")
    Tp = planar.fkine(planar.random_q(10, seed=2))
    res = symkin.compile(planar, backend="c").ik(Tp, method="QP", seed=0)
    assert res.success.all()
    assert (np.linalg.norm(pose_error(planar.fkine(res.q), Tp), axis=-1) < 1e-6).all()


def test_one_target_alone_is_its_row_of_a_batch(ur5_c):
    """Every QP step depends on (q, e) alone (OSQP cold-started): a batch, whose lanes interleave
    the targets' steps, gives each target the answer it gets alone."""
    Q0 = UR5.random_q(12, seed=30)
    Tep = UR5.fkine(UR5.random_q(12, seed=31))
    batch = ur5_c.ik(Tep, method="QP", q0=Q0, slimit=1, seed=0)
    for i in range(12):
        alone = ur5_c.ik(Tep[i], method="QP", q0=Q0[i], slimit=1, seed=0)
        assert alone.q.tobytes() == batch.q[i].tobytes() and alone.iterations == batch.iterations[i]


def test_threads_share_a_solver(panda_c):
    Tep = PANDA.fkine(PANDA.random_q(16, seed=40))
    serial = panda_c.ik(Tep, method="QP", seed=5)
    out: dict[int, np.ndarray] = {}

    def work(k: int) -> None:
        out[k] = np.array([panda_c.ik(T, method="QP", seed=5).q for T in Tep])

    threads = [threading.Thread(target=work, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    alone = np.array([panda_c.ik(T, method="QP", seed=5).q for T in Tep])
    assert serial.success.all()
    for k in range(2):
        np.testing.assert_array_equal(out[k], alone)


def test_tree_frame_is_solved_on_every_backend():
    from tests.model.tree_urdfs import DUAL_ARM

    tree = symkin.Tree.from_urdf(DUAL_ARM)
    q_goal = tree.random_q(seed=11)
    Tep = tree.fkine(q_goal, "r_tool")
    q0 = q_goal + 0.15
    off = [i for i in range(tree.n) if not tree.jacob0(q0, "r_tool")[:, i].any()]
    for kin in (tree, symkin.compile(tree, "c"), symkin.compile(tree, "numpy")):
        res = ik(kin, Tep, frame="r_tool", method="QP", q0=q0, seed=1)
        assert res.success, res.reason
        assert np.linalg.norm(pose_error(tree.fkine(res.q, "r_tool"), Tep)) < 1e-6
        assert_close(res.q[off], q0[off], 1e-15, "joints off the frame's path keep their start values")


# -- obstacles ------------------------------------------------------------------------------------
def test_collision_rows_step_and_collision_free_solutions(panda_c):
    from symkin.runtime.collision import Collision
    from symkin.runtime.control import MMC

    env = symkin.Environment(spheres=(symkin.Sphere([0.45, 0.0, 0.45], 0.12),))
    opt = IKOptions.of(PANDA, method="QP")
    step = QPStep(panda_c, opt, env)
    rows = MMC(panda_c, collision=env, backend="python", slack=True)
    feasible = 0
    for seed in range(60):  # configurations with a pair within d_i: the step keeps the rows
        q = PANDA.random_q(seed=seed)
        Jd, dl, near = rows._distance_rows(q)
        if not len(near):
            continue
        Tep = PANDA.fkine(PANDA.random_q(seed=seed + 1000))
        J, e = _step_inputs(PANDA, q, Tep)
        qp = ik_qp(q, J, e, opt, None, Jd, dl)
        qd = step.step(q, e)
        assert_close(qd, solve_ik_qp(qp), 1e-7, "C step with collision rows")
        if (dl[: len(near)] <= 0).all():  # every pair at least d_s apart: qd = 0 is feasible
            assert (Jd[: len(near)] @ qd >= dl[: len(near)] - 1e-8).all()
            feasible += 1
    assert feasible >= 3
    Tep = PANDA.fkine(PANDA.random_q(12, seed=50))
    res = panda_c.ik(Tep, method="QP", collision=env, seed=2)
    reference = Collision(PANDA, "numpy")  # the NumPy reference of the collision queries
    assert res.success.sum() >= 8
    assert not np.asarray(reference.in_collision(res.q[res.success], env)).any()
    assert all(PANDA.within_limits(q) for q in res.q)


# -- errors ---------------------------------------------------------------------------------------
def test_bad_options_raise_clear_errors(ur5_c):
    Tep = UR5.fkine(UR5.qz)
    cases = {
        "lam as one number > 0": {"lam": [0.01, 0.02, 0.01, 0.01, 0.01, 0.01]},
        "lam must be finite and >= 0": {"lam": -1.0},
        "slack_gain must be finite and > 0": {"slack_gain": 0.0},
        "xi must be finite and > 0": {"xi": -1.0},
        "manipulability must be finite and >= 0": {"manipulability": -0.1},
        "rho_i .* must exceed rho_s": {"rho_i": 0.1, "rho_s": 0.2},
        "rho_s must be finite": {"rho_s": np.nan},
        "every weight of we > 0": {"we": [1, 1, 1, 0, 0, 0]},
    }
    for message, options in cases.items():
        for kin in (UR5, ur5_c):
            with pytest.raises(ParameterError, match=message):
                ik(kin, Tep, method="QP", **options)
    with pytest.raises(ConfigurationError, match="compiled C kinematics"):
        ik(UR5, Tep, method="QP", backend="c")  # the reference Robot has no generated Hessian
    with pytest.raises(TypeError):
        ik(UR5, Tep, method="QP", d_i=0.2)  # a collision-row option without collision=
    opt = IKOptions.of(UR5, method="QP")
    J = UR5.jacob0(UR5.qz)
    with pytest.raises(ParameterError, match="not zero"):
        ik_qp(UR5.qz, J, np.zeros(6), opt)
    with pytest.raises(ParameterError, match="ik_qp takes q"):
        ik_qp(UR5.qz, J[:, :5], np.ones(6), opt)
