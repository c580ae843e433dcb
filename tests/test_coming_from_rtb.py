"""The claims of docs/guide/coming-from-rtb.md, checked against roboticstoolbox-python (RTB) where it
is installed (the compare extra; the module skips without it): the functions a port replaces give
RTB's numbers, and each listed difference is there."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import symkin

rtb = pytest.importorskip("roboticstoolbox")
SE3 = pytest.importorskip("spatialmath").SE3


@pytest.fixture(scope="module")
def panda():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return rtb.models.Panda()


@pytest.fixture(scope="module")
def kin():
    return symkin.compile("panda", backend="c")


def test_robots_and_configurations(panda, kin):
    for name in ("qr", "qz"):
        np.testing.assert_array_equal(getattr(kin, name), getattr(panda, name))
    assert sorted(kin.configs) == sorted(panda.configs)
    np.testing.assert_allclose(kin.qlim, panda.qlim, atol=1e-12)
    imported = symkin.compile(symkin.Robot.from_rtb(panda), backend="numpy")
    np.testing.assert_array_equal(imported.qr, panda.qr)


def test_kinematics_agree_and_differ_where_the_page_says(panda, kin):
    q = kin.random_q(seed=1)
    T = panda.fkine(q)
    assert isinstance(T, SE3) and isinstance(kin.fkine(q), np.ndarray)
    np.testing.assert_allclose(kin.fkine(q), T.A, atol=1e-14)
    Q = kin.random_q(3, seed=2)
    assert len(panda.fkine(Q)) == 3 and kin.fkine(Q).shape == (3, 4, 4)
    for a, b in ((kin.jacob0(q), panda.jacob0(q)), (kin.jacobe(q), panda.jacobe(q))):
        np.testing.assert_allclose(a, b, atol=1e-14)
    assert kin.hessian0(q).shape == panda.hessian0(q).shape == (7, 6, 7)
    np.testing.assert_allclose(kin.hessian0(q), panda.hessian0(q), atol=1e-14)
    # hessiane: RTB's is H0 rotated into the end-effector frame, symkin's the derivative of jacobe
    R, H0 = kin.fkine(q)[:3, :3], kin.hessian0(q)
    np.testing.assert_allclose(
        panda.hessiane(q), np.einsum("ab,ibj->iaj", np.kron(np.eye(2), R.T), H0), atol=1e-14
    )
    h = 1e-6
    dJe = np.array([(kin.jacobe(q + h * e) - kin.jacobe(q - h * e)) / (2 * h) for e in np.eye(7)])
    np.testing.assert_allclose(kin.hessiane(q), dJe, atol=1e-8)
    assert np.abs(panda.hessiane(q) - dJe).max() > 0.1
    for rep in ("rpy/xyz", "rpy/zyx", "eul", "exp"):
        np.testing.assert_allclose(
            kin.jacob0_analytical(q, representation=rep),
            panda.jacob0_analytical(q, representation=rep),
            atol=1e-13,
        )
    qd = np.linspace(-1, 1, 7)
    np.testing.assert_allclose(kin.jacob0_dot(q, qd), panda.jacob0_dot(q, qd), atol=1e-14)
    for axes in ("all", "trans", "rot"):
        assert kin.manipulability(q, axes=axes) == pytest.approx(
            panda.manipulability(q, axes=axes), abs=1e-14
        )
        ours, theirs = kin.jacobm(q, axes=axes), panda.jacobm(q, axes=axes)
        assert ours.shape == (7,) and theirs.shape == (7, 1)
        fd = [
            (kin.manipulability(q + h * e, axes=axes) - kin.manipulability(q - h * e, axes=axes)) / (2 * h)
            for e in np.eye(7)
        ]
        np.testing.assert_allclose(ours, fd, atol=1e-8)  # symkin's jacobm is the gradient
        if axes == "trans":  # RTB 1.5's is not (the page says so)
            assert np.abs(theirs.ravel() - fd).max() > 0.01
        else:
            np.testing.assert_allclose(theirs.ravel(), fd, atol=1e-8)
    assert len(panda.fkine_all(q)) == 13 and kin.link_poses(q).shape == (7, 4, 4)
    assert not any(hasattr(panda, m) for m in ("jacobs", "jacobb", "cond"))


def test_poses_as_se3(kin):
    two = SE3([SE3(kin.fkine(kin.qr)), SE3(kin.fkine(kin.qz))])
    assert np.asarray(two).shape == (4, 4)  # numpy sees the first pose alone
    res = kin.ik(two, seed=0)
    assert res.batch and len(res) == 2
    np.testing.assert_allclose(
        symkin.ctraj(two[0], two[1], 5), np.asarray(symkin.ctraj(two.A[0], two.A[1], 5))
    )


def test_ik_names_defaults_and_residual(panda, kin):
    q0 = kin.random_q(seed=3)
    Tep = kin.fkine(kin.random_q(seed=4))
    theirs = panda.ik_LM(Tep, q0=q0, tol=1e-6)
    ours = kin.ik(Tep, q0=q0, tol=1e-6)
    assert theirs.success and ours.success
    for name in ("q", "success", "iterations", "searches", "residual", "reason"):
        assert hasattr(theirs, name) and hasattr(ours, name)
    e_theirs = np.linalg.norm(symkin.pose_error(panda.fkine(theirs.q).A, Tep))
    assert theirs.residual == pytest.approx(0.5 * e_theirs**2, rel=1e-3)  # E, not |e|
    assert ours.residual == pytest.approx(np.linalg.norm(symkin.pose_error(kin.fkine(ours.q), Tep)), rel=1e-6)
    import inspect

    assert inspect.signature(panda.ik_LM).parameters["k"].default == 1.0
    from symkin.runtime.ik_problem import IKOptions

    assert np.all(IKOptions.of(kin, method="LM").lam == 0.1)  # LM's lam when none is given
    T1, T2 = kin.fkine(kin.qr), kin.fkine(q0)
    np.testing.assert_allclose(rtb.angle_axis(T1, T2), symkin.pose_error(T1, T2), rtol=0, atol=1e-15)


def test_p_servo_frames(kin):
    """RTB's default (method="rpy") is the end-effector frame: the translation part equals symkin's
    frame="ee" and the rotation part agrees to first order; method="angle-axis" is frame="base"."""
    rng = np.random.default_rng(0)
    Te = kin.fkine(kin.qr)
    for angle, tol in ((0.02, 1.1e-4), (0.1, 3e-3)):
        for _ in range(20):
            axis = rng.normal(size=3)
            Tp = Te.copy()
            Tp[:3, :3] = SE3.AngleAxis(angle, axis / np.linalg.norm(axis)).A[:3, :3] @ Te[:3, :3]
            Tp[:3, 3] += rng.normal(size=3) * 0.05
            a, b = rtb.p_servo(Te, Tp, threshold=0)[0], symkin.p_servo(Te, Tp, threshold=0, frame="ee")[0]
            np.testing.assert_allclose(a[:3], b[:3], atol=1e-15)
            assert np.abs(a[3:] - b[3:]).max() < tol
            c, _ = rtb.p_servo(Te, Tp, gain=(2, 2, 2, 1, 1, 1), threshold=0, method="angle-axis")
            d, _ = symkin.p_servo(Te, Tp, gain=[2, 2, 2, 1, 1, 1], threshold=0, frame="base")
            np.testing.assert_allclose(c, d, atol=1e-15)
    with pytest.raises(symkin.ParameterError, match="roboticstoolbox-python's p_servo default"):
        symkin.p_servo(Te, Te)


def test_transforms_and_statics(panda, kin):
    T = SE3.Rx(0.3) * SE3.Trans(0.1, -0.2, 0.3) * SE3.Rz(-1.1)
    np.testing.assert_allclose(symkin.velocity_transform(T), T.Ad(), atol=1e-15)
    np.testing.assert_allclose(symkin.wrench_transform(T), np.linalg.inv(T.Ad()).T, atol=1e-14)
    q, w = kin.random_q(seed=5), np.array([1.0, -2.0, 3.0, 0.1, 0.2, -0.3])
    np.testing.assert_allclose(symkin.joint_torques(kin, q, w), panda.jacob0(q).T @ w, atol=1e-13)
    np.testing.assert_allclose(kin.joint_torques(q, w, in_frame="ee"), panda.jacobe(q).T @ w, atol=1e-13)


def test_trajectories(kin):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        np.testing.assert_allclose(rtb.jtraj([0.0], [1.0], 5).t, np.linspace(0, 5, 5))
        np.testing.assert_allclose(symkin.jtraj([0.0], [1.0], 5).t, np.linspace(0, 1, 5))
        t = np.linspace(1.5, 3.0, 14)  # a motion starting at t[0] (no sample on a blend boundary)
        for ours, theirs in (
            (symkin.quintic(0.2, 1.5, t, qd0=0.3), rtb.quintic(0.2, 1.5, t, qd0=0.3)),
            (symkin.trapezoidal(1.5, 0.2, t), rtb.trapezoidal(1.5, 0.2, t)),
            (symkin.jtraj([0.1, 0.2], [1.0, -1.0], t), rtb.jtraj([0.1, 0.2], [1.0, -1.0], t)),
        ):
            np.testing.assert_array_equal(ours.t, theirs.t)
            for a, b in ((ours.q, theirs.q), (ours.qd, theirs.qd), (ours.qdd, theirs.qdd)):
                np.testing.assert_allclose(a, b, atol=1e-12)
        tr = rtb.trapezoidal(0.0, 1.0, 10)
        assert symkin.trapezoidal(0.0, 1.0, 10).info["tblend"] == pytest.approx(tr.tblend)
        via = np.array([[0.0, 0.0], [1.0, 2.0], [3.0, 1.0]])
        ms = rtb.mstraj(via, 0.1, 0.2, qdmax=1.0)
        ours = symkin.mstraj(via, 0.1, 0.2, qdmax=1.0)
        np.testing.assert_allclose(ours.q[1:], ms.q, atol=1e-12)
        np.testing.assert_allclose(ours.info["arrive"], ms.arrive, atol=1e-12)
        with pytest.raises(symkin.ParameterError):
            symkin.trapezoidal(0.0, 1.0, np.linspace(0, 1, 5), V=1.0)
        with np.errstate(divide="raise"), pytest.raises(FloatingPointError):
            rtb.trapezoidal(0.0, 1.0, np.linspace(0, 1, 5), V=1.0)  # RTB divides by the zero blend time
        T0, T1 = kin.fkine(kin.qr), kin.fkine(kin.qz)
        theirs = rtb.ctraj(SE3(T0), SE3(T1), 10)
        assert isinstance(theirs, SE3) and len(theirs) == 10
        np.testing.assert_allclose(symkin.ctraj(T0, T1, 10), np.array(theirs.A), atol=1e-12)
        with np.errstate(all="ignore"):
            assert not np.isfinite(rtb.quintic(0.0, 1.0, [0.0, 0.25e-170, 1e-170]).qdd).all()
        with pytest.raises(symkin.ParameterError):
            symkin.quintic(0.0, 1.0, [0.0, 0.25e-170, 1e-170])
