"""RRMC, MMC, position-based servoing and the Table I benchmark (Part 1 eqs 35-43, the MMC paper)."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

import symkin
from symkin.bench.mmc import (
    format_step_timing,
    format_table1,
    plot_task,
    run_table1,
    step_timing,
    table1_tasks,
)
from symkin.errors import ConfigurationError, ParameterError, PoseError
from symkin.runtime.control import (
    MMC,
    StepInfo,
    joint_velocity_bounds,
    manipulability_jacobian,
    mmc_closed_form,
    mmc_qp,
    rrmc,
)
from symkin.runtime.ik import angle_axis, pose_error
from symkin.runtime.loop import servo
from symkin.runtime.servo import p_servo, servo_velocity
from tests.conftest import assert_close

PANDA_ETS = (
    "tz(0.333) Rz(q0) Rx(-pi/2) Rz(q1) Rx(pi/2) tz(0.316) Rz(q2) tx(0.0825) Rx(pi/2) Rz(q3) "
    "tx(-0.0825) Rx(-pi/2) tz(0.384) Rz(q4) Rx(pi/2) Rz(q5) tx(0.088) Rx(pi/2) tz(0.107) Rz(q6) "
    "tz(0.1034) Rz(-pi/4)"
)
PANDA_QLIM = [
    [-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973],
    [2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973],
]
PANDA_QD_MAX = [2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61]


@pytest.fixture(scope="module")
def panda() -> symkin.Robot:
    """The Panda of Fig. 1 of Part 1 with its datasheet limits (independent of the built-in robots)."""
    return symkin.Robot.from_ets(
        PANDA_ETS,
        qlim=PANDA_QLIM,
        name="panda",
        qd_max=PANDA_QD_MAX,
        configs={"qr": [0, -0.3, 0, -2.2, 0, 2.0, math.pi / 4]},
    )


@pytest.fixture(scope="module")
def tasks(panda):
    """Eight Table I tasks (MMC paper eq 14)."""
    return table1_tasks(panda, 8, np.random.default_rng(7))


def _rot(axis, angle):
    axis = np.asarray(axis, float) / np.linalg.norm(axis)
    K = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def _pose(R, t=(0, 0, 0)):
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, t
    return T


# -- servo: pose error and velocity command (eqs 37-43) ------------------------------------------
@pytest.mark.parametrize(
    "axis, angle",
    [
        ([1, 0, 0], 0.3),
        ([0, 1, 1], 2.0),
        ([1, 2, 3], math.pi - 1e-9),
        ([1, 1, 0], math.pi),
        ([0, 0, 1], 1e-9),
    ],
)
def test_angle_axis_recovers_the_rotation_vector(axis, angle):
    R = _rot(axis, angle)
    a = pose_error(np.eye(4), _pose(R, (0, 0, 0)))[3:]  # one pose: the scalar path
    assert_close(angle_axis(R[None])[0], a, 1e-15, "batched path")
    assert_close(a, angle * np.asarray(axis) / np.linalg.norm(axis), 1e-8, "alpha(R)")


@pytest.mark.parametrize("diag", [(1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1)])
def test_angle_axis_of_diagonal_rotations_is_eq_40(diag):
    expected = np.zeros(3) if diag == (1, 1, 1) else math.pi / 2 * (np.array(diag) + 1.0)
    assert_close(angle_axis(np.diag(diag).astype(float)), expected, 1e-15, "eq 40")
    T = _pose(np.diag(diag).astype(float), (0, 0, 0))
    assert_close(pose_error(np.eye(4), T)[3:], expected, 1e-15, "eq 40, one pose")


def test_pose_error_of_one_pose_matches_the_batched_path(panda):
    rng = np.random.default_rng(0)
    Te, Tep = panda.fkine(panda.random_q(50, seed=rng)), panda.fkine(panda.random_q(50, seed=rng))
    batched = pose_error(Te, Tep)
    for i in range(50):
        assert_close(pose_error(Te[i], Tep[i]), batched[i], 1e-14, "eq 37")


def test_pose_error_is_translation_and_base_frame_rotation():
    Te = _pose(_rot([0, 0, 1], 0.5), (0.1, 0.2, 0.3))
    Tep = _pose(_rot([1, 0, 0], 0.4) @ Te[:3, :3], (0.4, 0.2, 0.0))
    assert_close(pose_error(Te, Tep), [0.3, 0.0, -0.3, 0.4, 0.0, 0.0], 1e-12, "e")


def test_p_servo_gain_forms_arrival_and_caps():
    Te, Tep = np.eye(4), _pose(_rot([0, 0, 1], 0.2), (0.3, 0.0, 0.0))
    nu, arrived = p_servo(Te, Tep, gain=(2.0, 0.5), frame="base")
    assert not arrived
    assert_close(nu, [0.6, 0, 0, 0, 0, 0.1], 1e-12, "k e")
    nu, _ = p_servo(Te, Tep, gain=1.0, nu_max=0.1, frame="base")  # eq 43: |k e| capped, direction kept
    assert_close(np.linalg.norm(nu), 0.1, 1e-12, "|nu|")
    assert_close(nu / np.linalg.norm(nu), np.array([0.3, 0, 0, 0, 0, 0.2]) / math.hypot(0.3, 0.2), 1e-12)
    nu, _ = p_servo(
        Te, Tep, gain=1.0, nu_max=(0.1, 1.0), frame="base"
    )  # translation and rotation capped separately
    assert_close(nu, [0.1, 0, 0, 0, 0, 0.2], 1e-12, "separate caps")
    nu, arrived = p_servo(Te, Tep, threshold=0.6, frame="base")
    assert arrived and not nu.any()
    with pytest.raises(ValueError):
        servo_velocity(np.ones(6), gain=(1.0, 2.0, 3.0))
    with pytest.raises(PoseError):
        p_servo(np.eye(3), Tep, frame="base")


# -- the manipulability Jacobian and the QP -------------------------------------------------------
@pytest.mark.parametrize("axes", ["all", "trans", "rot"])
def test_manipulability_jacobian_matches_finite_differences(panda, axes):
    rng = np.random.default_rng(1)
    for _ in range(5):
        q = panda.random_q(seed=rng)
        Jm, m = manipulability_jacobian(panda.jacob0(q), panda.hessian0(q), axes)
        h = 1e-6
        fd = np.array(
            [
                (panda.manipulability(q + h * e, axes) - panda.manipulability(q - h * e, axes)) / (2 * h)
                for e in np.eye(7)
            ]
        )
        assert_close(m, panda.manipulability(q, axes), 1e-12, "m")
        assert_close(Jm, fd, 1e-7, f"Jm ({axes})")
        assert_close(Jm, panda.jacobm(q, axes), 1e-12, "Robot.jacobm")


def test_qp_matrices_have_the_fixed_structure(panda):
    q, nu = panda.qr, np.arange(6) / 10
    J, H = panda.jacob0(q), panda.hessian0(q)
    Jm, m = manipulability_jacobian(J, H)
    lo, hi = -np.ones(7), np.ones(7)
    qp = mmc_qp(J, Jm, nu, lo, hi, lam=0.01)
    assert qp.P.shape == (7, 7) and qp.A.shape == (13, 7) and not qp.has_slack
    assert_close(qp.P, 0.01 * np.eye(7), 0, "P")
    assert_close(qp.c, -Jm, 0, "c")
    assert_close(qp.A, np.vstack((J, np.eye(7))), 0, "A")
    assert_close(qp.l, np.r_[nu, lo], 0, "l")
    assert_close(qp.u, np.r_[nu, hi], 0, "u")
    qs = mmc_qp(J, Jm, nu, lo, hi, lam=0.01, slack_weight=1e4)
    assert qs.P.shape == (13, 13) and qs.has_slack
    assert_close(qs.A[:6, 7:], np.eye(6), 0, "slack columns")
    assert_close(np.diag(qs.P)[7:], np.full(6, 1e4), 0, "slack weight")
    built = MMC(panda, lam=0.01, qd_max=1.0).build(q, nu)
    assert_close(built.A, qp.A, 1e-14, "MMC.build A")
    assert_close(built.c, qp.c, 1e-12, "MMC.build c")


def test_closed_form_agrees_with_the_qp_without_active_inequalities(panda):
    rng = np.random.default_rng(2)
    ctrl = MMC(panda, qd_max=np.inf, closed_form=False)
    for _ in range(10):
        q, nu = panda.random_q(seed=rng), rng.normal(0, 0.2, 6)
        qp = ctrl.build(q, nu)
        qd, info = ctrl.solve(qp)
        assert info.method == "osqp" and info.status == "solved", info
        assert_close(qd, mmc_closed_form(qp.J, qp.Jm, nu, ctrl.lam), 1e-7, "QP vs closed form")


def test_closed_form_with_slack_is_the_slack_qp_solution(panda):
    rng = np.random.default_rng(12)
    cf = MMC(panda, qd_max=np.inf, slack=True)
    qp_ = MMC(panda, qd_max=np.inf, slack=True, closed_form=False)
    for _ in range(10):
        q, nu = panda.random_q(seed=rng), rng.normal(0, 0.2, 6)
        qd, info = cf.step(q, nu)
        ref, info_ref = qp_.step(q, nu)
        assert info.method == "closed_form" and info_ref.method == "osqp" and info_ref.ok
        assert np.abs(qd - ref).max() <= 1e-9 * max(1.0, np.abs(ref).max())
        assert_close(info.slack, info_ref.slack, 1e-9, "|s|")
        assert info.slack > 0


def test_step_is_solve_of_build(panda):
    rng = np.random.default_rng(5)
    for kwargs in ({"qd_max": np.inf}, {"qd_max": 0.3}, {"qd_max": 0.3, "joint_limits": True, "dt": 0.05}):
        a, b = MMC(panda, **kwargs), MMC(panda, **kwargs)
        for _ in range(5):
            q, nu = panda.random_q(seed=rng), rng.normal(0, 0.2, 6)
            qd_a, info_a = a.step(q, nu)
            qd_b, info_b = b.solve(b.build(q, nu))
            assert info_a.status == info_b.status and info_a.method == info_b.method, kwargs
            assert_close(qd_a, qd_b, 1e-9, f"step vs solve(build) {kwargs}")


def test_mmc_raises_the_manipulability_rate_over_rrmc_at_every_step(panda):
    # the QP optimum has lam/2|qd|^2 - Jm.qd <= that of J^+ nu (feasible, least norm),
    # so Jm.qd_mmc >= Jm.qd_rrmc: MMC never lowers the manipulability rate below RRMC's
    rng = np.random.default_rng(3)
    ctrl = MMC(panda, qd_max=np.inf)
    for _ in range(30):
        q, nu = panda.random_q(seed=rng), rng.normal(0, 0.3, 6)
        qd_m, _ = ctrl.step(q, nu)
        qd_r, _ = rrmc(panda, q, nu, qd_max=np.inf)
        Jm = panda.jacobm(q)
        assert Jm @ qd_m >= Jm @ qd_r - 1e-9


# -- servo runs ------------------------------------------------------------------------------------
def test_equality_and_speed_limits_hold_on_every_osqp_step(panda, tasks):
    q0s, Teps = tasks
    ctrl = MMC(panda, closed_form=False)  # OSQP on every step, the Panda's speed limits
    r = servo(panda, q0s[0], Teps[0], ctrl, nu_max=(0.2, 0.4), max_steps=60)
    assert r.steps == 60 or r.arrived
    qd_max = np.array(PANDA_QD_MAX)
    for k, info in enumerate(r.info):
        assert info.method == "osqp" and info.ok, info
        J = panda.jacob0(r.q[k])
        assert np.abs(J @ r.qd[k] - _nu_of(r, k)).max() < 1e-7, f"step {k}: J qd != nu"
        assert (np.abs(r.qd[k]) <= qd_max + 1e-12).all()


def _nu_of(result, k, cap=(0.2, 0.4)):
    nu, _ = servo_velocity(result.e[k], 1.0, 0.1, cap)
    return nu


def test_small_speed_limits_hold_and_infeasible_steps_fall_back(panda, tasks):
    q0s, Teps = tasks
    alpha = np.full(7, 0.05)
    r = servo(panda, q0s[1], Teps[1], "mmc", qd_max=alpha, max_steps=20)
    assert np.isfinite(r.qd).all()
    assert (np.abs(r.qd) <= alpha + 1e-12).all()
    assert "infeasible" in r.status
    bad = [i for i in r.info if i.status == "infeasible"]
    assert all(i.fallback == "rrmc" for i in bad)


def test_infeasible_velocity_bound_is_reported_not_raised(panda):
    nu = np.array([0.5, 0, 0, 0, 0, 1.0])
    qd, info = MMC(panda, qd_max=0.01).step(panda.qr, nu)
    assert info.status == "infeasible" and info.fallback == "rrmc"
    assert np.isfinite(qd).all() and (np.abs(qd) <= 0.01 + 1e-15).all()
    qd_s, info_s = MMC(panda, qd_max=0.01, slack=True).step(panda.qr, nu)  # slack keeps it feasible
    assert info_s.status == "solved" and info_s.fallback is None and info_s.slack > 0.1
    assert (np.abs(qd_s) <= 0.01 + 1e-12).all()


def test_singular_start_is_handled(panda, tasks):
    q = panda.qz  # joints 1 and 3 aligned: J has rank 5
    nu = np.array([0.1, 0.0, -0.1, 0.0, 0.2, 0.0])
    qd, info = MMC(panda).step(q, nu)
    assert info.status == "singular" and info.fallback == "rrmc" and np.isfinite(qd).all()
    qd, info = rrmc(panda, q, nu)
    assert info.status == "singular" and info.method == "damped" and np.isfinite(qd).all()
    _, Teps = tasks
    Tep = panda.fkine(panda.qr)
    for c in ("rrmc", "mmc"):
        r = servo(panda, q, Tep, c)
        assert r.arrived and np.isfinite(r.q).all() and r.status[0] == "singular", c
        assert r.status[-1] == "solved"


def test_planar_arm_stretched_out_gives_finite_steps():
    planar = symkin.Robot.from_ets("Rz(q0) tx(1) Rz(q1) tx(1) Rz(q2) tx(1)", name="planar3")
    qd, info = rrmc(planar, np.zeros(3), np.array([0.1, 0.1, 0, 0, 0, 0.1]))
    assert info.status == "singular" and np.isfinite(qd).all()
    qd, info = MMC(planar).step(np.zeros(3), np.array([0.1, 0.1, 0, 0, 0, 0.1]))
    assert info.fallback == "rrmc" and np.isfinite(qd).all()


def test_both_controllers_arrive_at_reachable_targets(panda, tasks):
    q0s, Teps = tasks
    mmc = MMC(panda, qd_max=np.inf)
    for q0, Tep in zip(q0s[:4], Teps[:4]):
        for c in ("rrmc", mmc):
            r = servo(panda, q0, Tep, c, qd_max=np.inf)
            assert r.arrived and np.abs(r.e[-1]).sum() < 0.1
            assert r.q.shape == (r.steps + 1, 7) and r.qd.shape == (r.steps, 7)
            assert r.e.shape == (r.steps + 1, 6) and r.manipulability.shape == (r.steps + 1,)
            assert r.step_time.shape == (r.steps,) and len(r.info) == r.steps
            assert_close(r.q[1:], r.q[:-1] + 0.05 * r.qd, 1e-14, "integration")
            assert np.isfinite(r.manipulability).all()


def test_mmc_raises_manipulability_on_average(panda, tasks):
    q0s, Teps = tasks
    mmc = MMC(panda, qd_max=np.inf)
    mean_r, mean_m, fin_r, fin_m = [], [], [], []
    for q0, Tep in zip(q0s, Teps):
        r = servo(panda, q0, Tep, "rrmc", qd_max=np.inf)
        m = servo(panda, q0, Tep, mmc)
        mean_r.append(r.mean_manipulability)
        mean_m.append(m.mean_manipulability)
        fin_r.append(r.final_manipulability)
        fin_m.append(m.final_manipulability)
    # MMC is greedy: a single task can end lower (about 1 in 20 Panda tasks), the average does not
    assert np.mean(mean_m) > 1.1 * np.mean(mean_r)
    assert np.mean(fin_m) > 1.1 * np.mean(fin_r)
    assert_close(mean_m[0], servo(panda, q0s[0], Teps[0], mmc).mean_manipulability, 1e-9, "repeatable")


def test_joint_limit_dampers_keep_joints_inside(panda):
    q0s, Teps = table1_tasks(panda, 10, np.random.default_rng(0))
    mmc = MMC(panda, qd_max=np.inf)
    for q0, Tep in zip(q0s, Teps):
        if servo(panda, q0, Tep, mmc, max_steps=150).left_limits:
            break
    else:
        pytest.fail("no task left the joint limits with plain MMC")
    r = servo(panda, q0, Tep, "mmc", qd_max=np.inf, joint_limits=True, max_steps=150)
    assert r.limit_violations == 0 and panda.within_limits(r.q).all()
    assert np.isfinite(r.qd).all()
    assert all(i.slack >= 0 for i in r.info)


def test_joint_velocity_bounds_dampers():
    qlim = np.array([[-1.0, -1.0], [1.0, 1.0]])
    alpha = np.array([2.0, 2.0])
    lo, hi = joint_velocity_bounds(np.array([0.0, 0.5]), qlim, alpha, True, rho_i=0.6, rho_s=0.1, xi=1.0)
    assert_close(lo, [-2.0, -2.0], 0, "far from lower limits")
    assert_close(hi, [2.0, (0.5 - 0.1) / 0.5], 1e-15, "damper near the upper limit")
    lo, hi = joint_velocity_bounds(np.array([0.95, 0.0]), qlim, alpha, True, rho_i=0.6, rho_s=0.1, dt=0.1)
    # joint 0 is inside the safety distance: it must move away, by (0.05 - 0.1) / dt in one step
    assert_close(hi, [(0.05 - 0.1) / 0.1, 2.0], 1e-12, "one-step position bound")
    assert_close(lo, [-2.0, -2.0], 0, "lower")


def test_rrmc_speed_scaling_keeps_direction(panda):
    rng = np.random.default_rng(4)
    qd_max = np.full(7, 0.3)
    scaled_once = False
    for _ in range(20):
        q, nu = panda.random_q(seed=rng), rng.normal(0, 0.5, 6)
        raw, info_raw = rrmc(panda, q, nu, qd_max=np.inf)
        qd, info = rrmc(panda, q, nu, qd_max=qd_max)
        assert (np.abs(qd) <= qd_max + 1e-12).all()
        assert_close(qd, info.scale * raw, 1e-12, "same direction")
        if info.scale < 1:
            scaled_once = True
            assert np.isclose(np.abs(qd).max(), 0.3)
        else:
            assert info_raw.residual < 1e-10
    assert scaled_once


def test_rrmc_inverts_a_six_joint_jacobian():
    ur = symkin.Robot.from_ets(
        "tz(0.089) Rz(q0) Rx(pi/2) Rz(q1) tx(-0.425) Rz(q2) tx(-0.392) Rz(q3) tz(0.109) Rx(pi/2) Rz(q4) "
        "tz(0.095) Rx(-pi/2) Rz(q5) tz(0.082)",
        name="ur5",
    )
    q = np.array([0.1, -1.0, 1.2, -0.5, 1.3, 0.2])
    nu = np.array([0.1, -0.2, 0.05, 0.1, 0.0, -0.3])
    qd, info = rrmc(ur, q, nu)
    assert info.method == "inverse" and info.status == "solved"
    assert_close(qd, np.linalg.solve(ur.jacob0(q), nu), 1e-10, "J^-1 nu")


def test_kinematics_fallbacks_give_the_same_step(panda):
    class JmOnly:  # no hessian0: Jm comes from kin.jacobm
        n, qlim, qd_max = panda.n, panda.qlim, None
        fkine, jacob0, jacobm, manipulability = panda.fkine, panda.jacob0, panda.jacobm, panda.manipulability

    class Combined(JmOnly):  # one call for J and H
        def jacob0_hessian0(self, q):
            return panda.jacob0(q), panda.hessian0(q)

    q, nu = panda.qr, np.array([0.1, 0, 0, 0, 0.1, 0])
    ref, _ = MMC(panda, qd_max=np.inf).step(q, nu)
    for kin in (JmOnly(), Combined()):
        qd, info = MMC(kin).step(q, nu)
        assert_close(qd, ref, 1e-10, type(kin).__name__)
        assert info.ok


def test_bad_input_raises():
    kin = symkin.Robot.from_ets(PANDA_ETS)
    with pytest.raises(ConfigurationError):
        MMC(kin).step(np.zeros(6), np.zeros(6))
    with pytest.raises(ValueError):
        MMC(kin).step(np.zeros(7), np.full(6, np.nan))
    with pytest.raises(ValueError):
        MMC(kin, axes="xyz")
    with pytest.raises(ValueError):
        servo(kin, np.zeros(7), np.eye(4), controller="pid")
    with pytest.raises(ValueError):
        servo(kin, np.zeros(7), np.eye(4), controller="rrmc", joint_limits=True)


def test_step_info_is_frozen():
    info = StepInfo("solved", "osqp", 0.1)
    with pytest.raises(AttributeError):
        info.status = "x"  # type: ignore[misc]


# -- the benchmark ---------------------------------------------------------------------------------
def test_table1_benchmark_runs_and_formats(panda, tmp_path):
    res = run_table1((panda,), n_tasks=2, progress=False, max_steps=100, timing=False)
    json.dumps(res)
    r = res["robots"]["panda"]
    assert {"rrmc", "mmc", "mmc_jl", "paper"} <= set(r)
    assert r["mmc_jl"]["left_limits"] == 0
    text = format_table1(res)
    assert "paper" in text and "self-colliding" in text
    pytest.importorskip("matplotlib")
    q0s, Teps = table1_tasks(panda, 1, np.random.default_rng(0))
    out = plot_task(panda, q0s[0], Teps[0], tmp_path / "fig3.png", qd_max=np.inf, max_steps=100)
    assert (tmp_path / "fig3.png").stat().st_size > 1000
    assert set(out) == {"rrmc", "mmc"}


# -- the C path (symkin.runtime.mmc_c) -------------------------------------------------------------
@pytest.fixture(scope="module")
def cpanda():
    """The built-in Panda compiled with the C backend (the MMC library is compiled on first use)."""
    return symkin.compile(symkin.load("panda"), backend="c")


def test_c_path_is_used_for_c_kinematics(cpanda, panda):
    assert MMC(cpanda).backend == "c" and "backend='c'" in repr(MMC(cpanda))
    assert MMC(cpanda, backend="python").backend == "python"
    assert MMC(panda).backend == "python"
    assert (
        servo(cpanda, cpanda.robot.qr, cpanda.fkine(cpanda.robot.qz), "mmc", max_steps=2).info[0].method
        == "closed_form"
    )
    with pytest.raises(ConfigurationError):
        MMC(panda, backend="c")
    with pytest.raises(ValueError):
        MMC(cpanda, backend="cuda")


def test_c_path_unavailable_falls_back_to_python(cpanda, monkeypatch):
    from symkin.errors import CompileError
    from symkin.runtime import mmc_c

    def broken(mmc):
        raise CompileError("no compiler")

    monkeypatch.setattr(mmc_c, "CMMC", broken)
    with pytest.warns(UserWarning, match="MMC runs in Python"):
        assert MMC(cpanda).backend == "python"
    with pytest.raises(CompileError):
        MMC(cpanda, backend="c")


C_CONFIGS = [
    {"qd_max": np.inf},
    {"qd_max": None},  # the Panda's speed limits: active set and OSQP steps
    {"qd_max": 0.3},  # mostly infeasible: OSQP says so, the RRMC step is scaled into the bounds
    {"qd_max": np.inf, "joint_limits": True, "dt": 0.05},  # dampers with the slack
    {"qd_max": 0.5 * np.array(PANDA_QD_MAX), "closed_form": False},  # OSQP on every step
    {"qd_max": 1.0, "joint_limits": True, "closed_form": False},  # OSQP with the slack
    {"qd_max": None, "axes": "trans"},
    {"qd_max": None, "axes": "rot", "active_set": False},
]


@pytest.mark.parametrize("kwargs", C_CONFIGS, ids=lambda k: ",".join(sorted(k)))
def test_c_path_agrees_with_the_python_path_on_servo_runs(cpanda, kwargs):
    q0s, Teps = table1_tasks(cpanda, 2, np.random.default_rng(7))
    c, p = MMC(cpanda, **kwargs), MMC(cpanda, backend="python", **kwargs)
    seen = set()
    for q0, Tep in zip(q0s, Teps):
        q = q0.copy()
        for _ in range(60):
            nu, arrived = p_servo(cpanda.fkine(q), Tep, frame="base")
            if arrived:
                break
            a, ia = c.step(q, nu)
            b, ib = p.step(q, nu)
            assert (ia.status, ia.method, ia.fallback) == (ib.status, ib.method, ib.fallback), (ia, ib)
            assert np.abs(a - b).max() <= 1e-6 * max(1.0, np.abs(b).max()), (ia, a, b)
            assert_close(ia.manipulability, ib.manipulability, 1e-12, "m")
            assert ia.iterations == ib.iterations or ia.method == "osqp", (ia, ib)
            lo, hi = c.bounds(q)
            assert (a >= lo - 1e-12).all() and (a <= hi + 1e-12).all()
            J = cpanda.jacob0(q)
            assert_close(ia.residual, np.abs(J @ a - nu).max(), 1e-12, "residual")
            if ia.ok and not c.slack:
                assert ia.residual < 1e-9, ia
            seen.add(ia.method if ia.fallback is None else ia.fallback)
            q = q + 0.05 * b
    assert seen


def test_c_path_covers_every_outcome(cpanda):
    methods = set()
    for kwargs in C_CONFIGS:
        c = MMC(cpanda, **kwargs)
        for q0, Tep in zip(*table1_tasks(cpanda, 2, np.random.default_rng(7))):
            methods |= {(i.method, i.status) for i in servo(cpanda, q0, Tep, c, max_steps=60).info}
    assert {
        ("closed_form", "solved"),
        ("active_set", "solved"),
        ("osqp", "solved"),
        ("osqp", "infeasible"),
    } <= methods


def test_c_path_singular_start_and_infeasible_bound(cpanda):
    q, nu = cpanda.robot.qz, np.array([0.1, 0.0, -0.1, 0.0, 0.2, 0.0])  # qz: J has rank 5
    for kwargs in ({}, {"qd_max": 0.05}):
        (a, ia), (b, ib) = (
            MMC(cpanda, **kwargs).step(q, nu),
            MMC(cpanda, backend="python", **kwargs).step(q, nu),
        )
        assert ia.status == ib.status == "singular" and ia.fallback == ib.fallback == "rrmc"
        assert_close(a, b, 1e-9, "damped step")
        assert_close(ia.scale, ib.scale, 1e-12, "scale")
    nu = np.array([0.5, 0, 0, 0, 0, 1.0])
    qd, info = MMC(cpanda, qd_max=0.01).step(cpanda.robot.qr, nu)
    ref, _ = MMC(cpanda, qd_max=0.01, backend="python").step(cpanda.robot.qr, nu)
    assert info.status == "infeasible" and info.fallback == "rrmc" and info.method == "osqp"
    assert (np.abs(qd) <= 0.01 + 1e-15).all() and info.scale < 1
    assert_close(qd, ref, 1e-12, "scaled RRMC step")
    qd, info = MMC(cpanda, qd_max=0.01, slack=True).step(cpanda.robot.qr, nu)
    assert info.ok and info.slack > 0.1 and (np.abs(qd) <= 0.01 + 1e-12).all()


def test_c_controllers_sharing_a_solver_do_not_interfere(cpanda):
    """Controllers of one library share its embedded OSQP; each keeps its own iterate and rho."""
    q0s, Teps = table1_tasks(cpanda, 1, np.random.default_rng(3))
    kwargs = {"qd_max": 0.5 * np.array(PANDA_QD_MAX), "closed_form": False}
    alone = servo(cpanda, q0s[0], Teps[0], MMC(cpanda, **kwargs), max_steps=40)
    a, b = MMC(cpanda, **kwargs), MMC(cpanda, lam=0.05, **kwargs)
    for k in range(alone.steps):
        nu, _ = p_servo(cpanda.fkine(alone.q[k]), Teps[0], frame="base")
        qd, info = a.step(alone.q[k], nu)
        b.step(alone.q[k] + 0.01, -nu)  # another controller on the same solver in between
        assert info.iterations == alone.info[k].iterations and info.status == alone.info[k].status
        assert_close(qd, alone.qd[k], 1e-12, f"step {k}")


def test_c_path_input_errors(cpanda):
    ctrl = MMC(cpanda)
    with pytest.raises(ConfigurationError):
        ctrl.step(np.zeros(6), np.zeros(6))
    with pytest.raises(ConfigurationError):
        ctrl.step(np.full(7, np.nan), np.zeros(6))
    with pytest.raises(ValueError):
        ctrl.step(np.zeros(7), np.full(6, np.inf))
    with pytest.raises(ValueError):
        ctrl.step(np.zeros(7), np.zeros(5))
    qd, info = ctrl.step([0.0, -0.3, 0, -2.2, 0, 2.0, 0.8], (0.01, 0, 0, 0, 0, 0))  # sequences work
    assert qd.shape == (7,) and info.ok


def test_active_set_answer_is_the_qp_solution(panda):
    rng = np.random.default_rng(11)
    n_as = 0
    for slack in (False, True):
        fast = MMC(panda, qd_max=0.6, slack=slack)
        ref = MMC(panda, qd_max=0.6, slack=slack, closed_form=False, osqp_settings={"polishing": False})
        for _ in range(30):
            q, nu = panda.random_q(seed=rng), rng.normal(0, 0.1, 6)
            qd, info = fast.step(q, nu)
            qd_ref, info_ref = ref.step(q, nu)
            if info.method == "active_set":
                n_as += 1
                assert info_ref.status == "solved", info_ref
                assert np.abs(qd - qd_ref).max() < 1e-4  # OSQP unpolished: eps / lam
    assert n_as > 10


def test_step_timing_reports_both_paths(cpanda):
    res = step_timing(cpanda, n_tasks=1, max_steps=20, configs=("mmc", "mmc_jl"), rtb=False, rounds=1)
    for r in res["configs"].values():
        assert {"c", "python"} <= set(r["median_us"]) and r["steps"] > 0
        assert r["max_diff_python"] < 1e-6
    assert "MMC step" in format_step_timing(res)


def test_servo_rejects_invalid_targets(panda):
    T = panda.fkine(panda.qr)
    bad = T.copy()
    bad[0, 0] = np.nan
    with pytest.raises(PoseError, match="NaN"):
        servo(panda, panda.qr, bad)
    skew = T.copy()
    skew[0, 1] += 0.5
    with pytest.raises(PoseError, match="orthonormal"):
        servo(panda, panda.qr, skew)


# -- RRMC and the servo loop in C -------------------------------------------------------------------
@pytest.mark.parametrize("name", ["panda", "ur5", "planar3"])
def test_c_rrmc_agrees_with_the_numpy_rrmc_on_the_reference(name):
    # the C step (generated J, Cholesky of J J^T) against the NumPy step on the numeric reference:
    # all six rows solved, the manipulability of `axes` reported (the servo loop's step)
    from symkin.runtime.control import servo_rrmc_step

    robot = symkin.load(name)
    kin = symkin.compile(robot, backend="c")
    rng = np.random.default_rng(5)
    configs = [robot.qz, *robot.random_q(6, seed=rng)]
    for qd_max in (None, np.inf, 0.3):
        for axes in ("all", "trans", "rot"):
            c_step, numpy_step = servo_rrmc_step(kin, qd_max, axes), servo_rrmc_step(robot, qd_max, axes)
            for q in configs:
                nu = rng.normal(0, 0.3, 6)
                a, ia = c_step(q, nu)
                b, ib = numpy_step(q, nu)
                assert (ia.status, ia.method, ia.fallback) == (ib.status, ib.method, ib.fallback), (ia, ib)
                assert_close(a, b, 1e-8, f"qd at {q}")
                assert_close(ia.manipulability, ib.manipulability, 1e-9, "m")
                assert_close(ia.scale, ib.scale, 1e-9, "scale")
                assert_close(ia.residual, np.abs(robot.jacob0(q) @ a - nu).max(), 1e-9, "residual")
    assert rrmc(kin, robot.qz, np.ones(6))[1].method == "damped"  # stretched out: singular


def test_rrmc_axes_solve_the_sub_jacobian_of_an_under_actuated_task():
    """A planar 3R (3 joints) cannot follow a spatial velocity; its task is x, y and the rotation
    about z: rrmc(axes=(0, 1, 5)) solves J0[[0, 1, 5]] qd = nu[[0, 1, 5]] exactly (the full J0,
    of rank 3, only by the damped step), "trans" the first three rows of a 6-joint arm, with the
    manipulability and residual of those rows; bad rows are refused."""
    robot = symkin.load("planar3")
    kin = symkin.compile(robot, backend="c")
    q = np.array([0.3, 0.7, -0.4])
    nu = np.array([0.1, -0.05, 0.3, 0.2, -0.1, 0.2])  # z, omega_x, omega_y: not the arm's to do
    for k in (kin, robot):
        qd, info = rrmc(k, q, nu, qd_max=np.inf, axes=(0, 1, 5))
        J = robot.jacob0(q)[[0, 1, 5]]
        assert info.status == "solved" and info.method == "inverse"
        assert_close(J @ qd, nu[[0, 1, 5]], 1e-12, "the task is done exactly")
        assert_close(qd, np.linalg.solve(J, nu[[0, 1, 5]]), 1e-12, "Jt^-1 nut")
        assert_close(info.manipulability, abs(np.linalg.det(J)), 1e-12, "m of the task rows")
        assert info.residual < 1e-12
        full, finfo = rrmc(k, q, nu, qd_max=np.inf)  # all six rows: rank 3, the damped step
        assert finfo.status == "singular" and np.abs(robot.jacob0(q)[[0, 1]] @ full - nu[[0, 1]]).max() > 1e-6
    ur5 = symkin.load("ur5")
    q6 = ur5.random_q(seed=3)
    qd, info = rrmc(ur5, q6, nu, qd_max=np.inf, axes="trans")
    J = ur5.jacob0(q6)[:3]
    assert_close(J @ qd, nu[:3], 1e-12, "v") and info.method == "pinv"
    assert_close(qd, np.linalg.pinv(J) @ nu[:3], 1e-10, "Jv^+ v")
    for bad in ((0, 0), (6,), (), "xyz", (0.5,), (True, 1)):
        with pytest.raises(ParameterError, match="axes"):
            rrmc(ur5, q6, nu, axes=bad)


def test_rrmc_is_the_pseudo_inverse_step_away_from_singularities(panda):
    rng = np.random.default_rng(8)
    for _ in range(5):
        q, nu = panda.random_q(seed=rng), rng.normal(0, 0.3, 6)
        qd, info = rrmc(panda, q, nu, qd_max=np.inf)
        assert info.method == "pinv" and info.status == "solved"
        assert_close(qd, np.linalg.pinv(panda.jacob0(q)) @ nu, 1e-10, "J^+ nu")
        assert_close(info.manipulability, panda.manipulability(q), 1e-12, "m")


SERVO_CASES = [
    ("rrmc", {}),
    ("rrmc", {"qd_max": 0.4, "gain": (2.0, 1.0), "nu_max": (0.3, 0.6)}),
    ("mmc", {"qd_max": np.inf}),
    ("mmc", {"joint_limits": True, "nu_max": 0.5}),
]


@pytest.mark.parametrize("controller,kwargs", SERVO_CASES, ids=lambda c: str(c))
def test_servo_loop_in_c_gives_the_python_loop_s_run(cpanda, controller, kwargs):
    # the same step function, the pose error and velocity command with the same arithmetic: the
    # same run to the bit (MMC runs near the joint limits are chaotic: any rounding difference
    # would grow to radians within a few hundred steps)
    for q0, Tep in zip(*table1_tasks(cpanda, 2, np.random.default_rng(9))):
        a = servo(cpanda, q0, Tep, controller, backend="c", **kwargs)
        b = servo(cpanda, q0, Tep, controller, backend="python", **kwargs)
        assert (a.steps, a.arrived, a.limit_violations, a.controller) == (
            b.steps,
            b.arrived,
            b.limit_violations,
            b.controller,
        )
        for x, y in ((a.q, b.q), (a.qd, b.qd), (a.e, b.e), (a.manipulability, b.manipulability)):
            np.testing.assert_array_equal(x, y)
        assert a.info == b.info
        assert a.step_time.shape == (a.steps,) and (a.step_time >= 0).all()
        default = servo(cpanda, q0, Tep, controller, **kwargs)  # the C loop by default
        np.testing.assert_array_equal(default.q, a.q)


def test_servo_loop_in_c_checks_its_inputs(cpanda, panda):
    q0, T = cpanda.robot.qr, cpanda.fkine(cpanda.robot.qz)
    bad = T.copy()
    bad[0, 1] += 0.5
    with pytest.raises(PoseError, match="orthonormal"):
        servo(cpanda, q0, bad, "rrmc")
    with pytest.raises(PoseError, match="one target"):
        servo(cpanda, q0, T[None], "mmc")
    with pytest.raises(ValueError, match="positive"):
        servo(cpanda, q0, T, "rrmc", nu_max=0.0)
    with pytest.raises(ValueError, match="threshold"):
        servo(cpanda, q0, T, "rrmc", threshold=-1.0)
    with pytest.raises(ConfigurationError, match="backend='c'"):
        servo(panda, panda.qr, T, "rrmc", backend="c")
    with pytest.raises(ConfigurationError, match="backend='c'"):
        servo(cpanda, q0, T, lambda q, nu: rrmc(cpanda, q, nu), backend="c")
    with pytest.raises(ValueError, match="backend"):
        servo(cpanda, q0, T, backend="gpu")
    res = servo(cpanda, q0, T, "mmc", max_steps=0)
    assert res.steps == 0 and res.q.shape == (1, 7) and res.e.shape == (1, 6)
    assert res.manipulability.shape == (1,)
