"""The analytical Hessian ``hessian0_analytical(q, representation)``: against central differences of
``jacob0_analytical`` (an independent derivative), the rate-matrix derivatives against differences
of the rate matrices, the same layout and errors as ``hessian0`` and ``jacob0_analytical``, compiled
kinematics against the numeric reference, and roboticstoolbox-python's numerical derivative of
its analytical Jacobian (``jacob0_dot(q, qd, representation=...)``, compare extra)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import symkin
from symkin import ConfigurationError, ParameterError, Robot, Tree
from symkin.model.orientation import REPRESENTATIONS, omega_to_rates, rates_derivatives
from tests.conftest import assert_close
from tests.model.test_analytical import extract, regular_qs


def fd_hessian(model, q: np.ndarray, rep: str, frame=None, h: float = 1e-6) -> np.ndarray:
    """(n, 6, n): central differences of ``jacob0_analytical`` over each joint."""
    out = []
    for i in range(len(q)):
        dq = np.zeros(len(q))
        dq[i] = h
        Jp = model.jacob0_analytical(q + dq, rep, frame=frame)
        Jm = model.jacob0_analytical(q - dq, rep, frame=frame)
        out.append((Jp - Jm) / (2 * h))
    return np.array(out)


def scaled_error(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / max(1.0, np.abs(b).max()))


@pytest.fixture(scope="module")
def panda() -> Robot:
    return symkin.load("panda")


@pytest.mark.parametrize("rep", REPRESENTATIONS)
@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_analytical_hessian_is_the_derivative_of_the_analytical_jacobian(name, rep):
    robot = symkin.load(name)
    for q in regular_qs(robot, rep, 3, seed=41):
        Ha = robot.hessian0_analytical(q, rep)
        assert Ha.shape == (robot.n, 6, robot.n)
        assert scaled_error(Ha, fd_hessian(robot, q, rep)) < 1e-7, f"{name} {rep}"
        assert_close(Ha[:, :3], robot.hessian0(q)[:, :3], 0, "the translational rows are those of H0")


@pytest.mark.parametrize("rep", REPRESENTATIONS)
def test_rate_matrix_derivatives_are_those_of_the_rate_matrices(rep):
    """d A^-1 / d gamma_k against central differences of A^-1 at random regular orientations (for
    the rotation vector also near 0 and on both sides of the series' switch at theta = 0.2)."""
    rng = np.random.default_rng(3)
    gammas = [rng.uniform(-1.2, 1.2, size=3) for _ in range(6)]
    if rep == "exp":
        u = np.array([0.3, -0.5, 0.8]) / np.linalg.norm([0.3, -0.5, 0.8])
        gammas += [1e-6 * u, 0.005 * u, 0.19 * u, 0.21 * u, 2.9 * u]
    G = np.array(gammas)
    D = rates_derivatives(G, rep)
    h = 1e-6
    for k in range(3):
        dg = np.zeros(3)
        dg[k] = h
        fd = (omega_to_rates(G + dg, rep) - omega_to_rates(G - dg, rep)) / (2 * h)
        assert scaled_error(D[:, k], fd) < 1e-8, f"{rep} d/dgamma_{k}"


def test_exp_hessian_near_the_zero_rotation():
    robot = Robot.from_ets("Rx(q0) Ry(q1) Rz(q2) tx(0.1)")
    for q in ([0.0, 0, 0], [1e-5, -2e-5, 3e-5], [0.1, 0.12, -0.05], [0.15, 0.1, 0]):
        q = np.array(q)
        Ha = robot.hessian0_analytical(q, "exp")
        assert np.isfinite(Ha).all()
        assert scaled_error(Ha, fd_hessian(robot, q, "exp", h=1e-6)) < 1e-7, f"q = {q}"


@pytest.mark.parametrize("rep", REPRESENTATIONS)
def test_hessian_contracted_with_qd_is_the_rate_of_the_analytical_jacobian(panda, rep):
    """sum_i Ha[i] qd_i = d J_a(q + t qd)/dt at t = 0, from a central difference along qd."""
    qd = np.linspace(-0.6, 0.9, panda.n)
    for q in regular_qs(panda, rep, 2, seed=43):
        got = np.tensordot(panda.hessian0_analytical(q, rep), qd, axes=(0, 0))
        h = 1e-6
        want = (panda.jacob0_analytical(q + h * qd, rep) - panda.jacob0_analytical(q - h * qd, rep)) / (2 * h)
        assert scaled_error(got, want) < 1e-7


@pytest.mark.parametrize("rep", REPRESENTATIONS)
def test_batches_link_frames_and_tree_frames(panda, rep):
    Q = np.array(regular_qs(panda, rep, 3, seed=47))
    Ha = panda.hessian0_analytical(Q, representation=rep)
    assert Ha.shape == (3, panda.n, 6, panda.n)
    for k in range(3):
        assert_close(Ha[k], panda.hessian0_analytical(Q[k], rep), 1e-15, f"batch item {k}")
    assert panda.hessian0_analytical(Q[:0], rep).shape == (0, panda.n, 6, panda.n)
    assert_close(panda.hessian0_analytical(Q[0]), panda.hessian0_analytical(Q[0], "rpy/xyz"), 0)
    for q in regular_qs(panda, rep, 2, seed=53, frame=3):
        Ha3 = panda.hessian0_analytical(q, rep, frame=3)
        assert scaled_error(Ha3, fd_hessian(panda, q, rep, frame=3)) < 1e-7
        assert not Ha3[4:].any() and not Ha3[:, :, 4:].any(), "joints after frame 3 do not move it"
    tree = Tree.from_robot(panda)
    assert_close(tree.hessian0_analytical(Q, rep, frame="ee"), Ha, 1e-12, f"tree {rep}")


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_analytical_hessian_of_compiled_kinematics(panda, backend):
    kin = symkin.compile(panda, backend=backend)
    for rep in REPRESENTATIONS:
        Q = np.array(regular_qs(panda, rep, 3, seed=59))
        assert_close(kin.hessian0_analytical(Q, rep), panda.hessian0_analytical(Q, rep), 1e-10, rep)
        assert_close(kin.hessian0_analytical(Q[1], rep), panda.hessian0_analytical(Q[1], rep), 1e-10, rep)
        Q3 = np.array(regular_qs(panda, rep, 2, seed=61, frame=3))
        got = kin.hessian0_analytical(Q3, rep, frame=3)
        assert_close(got, panda.hessian0_analytical(Q3, rep, frame=3), 1e-10, f"{rep} frame 3")


def test_singular_representations_are_refused_like_the_analytical_jacobian():
    arm = Robot.from_ets("Ry(q0) tz(0.5) Ry(q1) tz(0.4)")
    q = np.array([0.3, math.pi / 2 - 0.3])
    for rep in ("rpy/xyz", "rpy/zyx"):
        with pytest.raises(ConfigurationError, match=rf"analytical Jacobian is singular for {rep} at pitch"):
            arm.jacob0_analytical(q, rep)
        message = rf"analytical Hessian is singular for {rep} at pitch = 90 deg.*another"
        with pytest.raises(ConfigurationError, match=message):
            arm.hessian0_analytical(q, rep)
        with pytest.raises(ConfigurationError, match=r"pitch = -90 deg \(configuration 1 of the batch\)"):
            arm.hessian0_analytical(np.array([[0.1, 0.2], [-1.0, 1.0 - math.pi / 2]]), rep)
    with pytest.raises(ConfigurationError, match=r"analytical Hessian is singular for eul at theta = 0 deg"):
        arm.hessian0_analytical([0.4, -0.4], "eul")
    assert np.isfinite(arm.hessian0_analytical([math.pi / 2, math.pi / 2], "exp")).all()  # a half turn


@pytest.mark.parametrize("bad", ["rpy", "angvec", None])
def test_unknown_representation_and_bad_q(panda, bad):
    with pytest.raises(ParameterError, match=r"'rpy/xyz', 'rpy/zyx', 'eul', 'exp'"):
        panda.hessian0_analytical(panda.qr, bad)
    with pytest.raises(ConfigurationError):
        panda.hessian0_analytical(np.zeros(6))


# -- roboticstoolbox-python (skipped when it is not installed) -------------------------------------
@pytest.mark.parametrize("rep", REPRESENTATIONS)
def test_analytical_hessian_matches_roboticstoolbox_numerical_derivative(rep):
    """roboticstoolbox-python 1.5 has no analytic form of this Hessian: ``jacob0_dot(q, qd,
    representation=rep)`` differentiates its analytical Jacobian numerically (spatialmath's
    ``numhess``) and contracts it with qd; its difference step limits the agreement (3e-7 measured)."""
    rtb = pytest.importorskip("roboticstoolbox")
    ref = rtb.models.ETS.Panda()
    robot = Robot.from_rtb(ref)
    qd = np.linspace(0.8, -0.5, robot.n)
    for q in regular_qs(robot, rep, 3, seed=67):
        # the rotation vector away from theta = pi, where the principal one jumps
        if rep == "exp" and np.linalg.norm(extract(rep, robot.fkine(q)[:3, :3])) > math.pi - 0.3:
            continue
        want = np.asarray(ref.jacob0_dot(q, qd, representation=rep))
        got = np.tensordot(robot.hessian0_analytical(q, rep), qd, axes=(0, 0))
        assert scaled_error(got, want) < 2e-6, f"roboticstoolbox {rep}"
