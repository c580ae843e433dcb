"""Analytical Jacobian, velocity and wrench transforms, and joint torques from a wrench (the
``FrameMethods`` of :mod:`symkin.model.differential`), against finite differences of orientations
extracted here by a different method (peeling one rotation off at a time; a quaternion for the
rotation vector), each extraction checked by re-composing the rotation."""

from __future__ import annotations

import math

import numpy as np
import pytest

import symkin
from symkin import ConfigurationError, ParameterError, PoseError, Robot, Tree
from symkin.model.differential import REPRESENTATIONS, velocity_transform, wrench_transform
from tests.conftest import assert_close


# -- independent orientation extraction ----------------------------------------------------------
def rx(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1.0, 0, 0], [0, c, -s], [0, s, c]])


def ry(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, 0, s], [0, 1.0, 0], [-s, 0, c]])


def rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])


def skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])


def expm_so3(r: np.ndarray) -> np.ndarray:
    """Rodrigues' formula."""
    th = float(np.linalg.norm(r))
    if th == 0.0:
        return np.eye(3)
    K = skew(r / th)
    return np.eye(3) + math.sin(th) * K + (1 - math.cos(th)) * K @ K


def compose(rep: str, g: np.ndarray) -> np.ndarray:
    if rep == "rpy/xyz":  # (roll, pitch, yaw)
        return rx(g[2]) @ ry(g[1]) @ rz(g[0])
    if rep == "rpy/zyx":
        return rz(g[2]) @ ry(g[1]) @ rx(g[0])
    if rep == "eul":  # (phi, theta, psi)
        return rz(g[0]) @ ry(g[1]) @ rz(g[2])
    return expm_so3(g)


def extract(rep: str, R: np.ndarray) -> np.ndarray:
    """Orientation of R: the outer angle first, then the remaining two from ``R_outer^T R``."""
    if rep == "rpy/xyz":  # R = Rx(y) Ry(p) Rz(r); Rx(y)^T R = Ry(p) Rz(r)
        y = math.atan2(-R[1, 2], R[2, 2])
        P = rx(y).T @ R
        g = np.array([math.atan2(P[1, 0], P[1, 1]), math.atan2(P[0, 2], P[2, 2]), y])
    elif rep == "rpy/zyx":  # R = Rz(y) Ry(p) Rx(r); Rz(y)^T R = Ry(p) Rx(r)
        y = math.atan2(R[1, 0], R[0, 0])
        P = rz(y).T @ R
        g = np.array([math.atan2(-P[1, 2], P[1, 1]), math.atan2(-P[2, 0], P[0, 0]), y])
    elif rep == "eul":  # R = Rz(phi) Ry(theta) Rz(psi); Rz(phi)^T R = Ry(theta) Rz(psi)
        phi = math.atan2(R[1, 2], R[0, 2])
        P = rz(phi).T @ R
        g = np.array([phi, math.atan2(P[0, 2], P[2, 2]), math.atan2(P[1, 0], P[1, 1])])
    else:  # unit quaternion (Shepperd), then r = 2 atan2(|v|, w) v / |v| with w >= 0
        t = np.trace(R)
        d = [t, R[0, 0], R[1, 1], R[2, 2]]
        k = int(np.argmax(d))
        if k == 0:
            w = math.sqrt(1 + t) / 2
            v = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / (4 * w)
        else:
            i, j, m = k - 1, k % 3, (k + 1) % 3
            v = np.zeros(3)
            v[i] = math.sqrt(1 + 2 * R[i, i] - t) / 2
            v[j] = (R[j, i] + R[i, j]) / (4 * v[i])
            v[m] = (R[m, i] + R[i, m]) / (4 * v[i])
            w = (R[m, j] - R[j, m]) / (4 * v[i])
        if w < 0:
            w, v = -w, -v
        nv = float(np.linalg.norm(v))
        g = np.zeros(3) if nv == 0 else 2 * math.atan2(nv, w) * v / nv
    assert_close(compose(rep, g), R, 1e-12, f"{rep} extraction re-composes R")
    return g


def wrap(a: np.ndarray) -> np.ndarray:
    return (a + np.pi) % (2 * np.pi) - np.pi


def regular(rep: str, g: np.ndarray, margin: float = 0.15) -> bool:
    """Away from the representation's singularity (and from theta = pi, where r jumps to -r)."""
    if rep.startswith("rpy"):
        return abs(math.cos(g[1])) > margin
    if rep == "eul":
        return abs(math.sin(g[1])) > margin
    return float(np.linalg.norm(g)) < math.pi - margin


def fd_analytical(kin, q: np.ndarray, rep: str, frame=None, h: float = 1e-6) -> np.ndarray:
    """Central differences of (position, gamma) of ``kin.fkine(q, frame)``, angles wrapped (exp: the
    rotation vector is continuous away from theta = pi)."""
    cols = []
    for i in range(len(q)):
        dq = np.zeros(len(q))
        dq[i] = h
        Tp, Tm = kin.fkine(q + dq, frame), kin.fkine(q - dq, frame)
        dg = extract(rep, Tp[:3, :3]) - extract(rep, Tm[:3, :3])
        if rep != "exp":
            dg = wrap(dg)
        cols.append(np.r_[Tp[:3, 3] - Tm[:3, 3], dg] / (2 * h))
    return np.array(cols).T


def regular_qs(robot, rep: str, count: int, seed: int, frame=None) -> list[np.ndarray]:
    out = []
    for q in robot.random_q(50, seed=seed):
        if regular(rep, extract(rep, robot.fkine(q, frame)[:3, :3])):
            out.append(q)
        if len(out) == count:
            return out
    raise AssertionError("no regular configuration found")


@pytest.fixture(scope="module")
def panda() -> Robot:
    return symkin.load("panda")


# -- the analytical Jacobian -----------------------------------------------------------------------
@pytest.mark.parametrize("rep", REPRESENTATIONS)
@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_analytical_jacobian_is_the_derivative_of_position_and_orientation(name, rep):
    robot = symkin.load(name)
    for q in regular_qs(robot, rep, 3, seed=5):
        Ja = robot.jacob0_analytical(q, rep)
        assert Ja.shape == (6, robot.n)
        assert_close(Ja, fd_analytical(robot, q, rep), 1e-6, f"{name} {rep}")
        assert_close(Ja[:3], robot.jacob0(q)[:3], 0, "the translational rows are those of J0")


@pytest.mark.parametrize("rep", REPRESENTATIONS)
def test_analytical_jacobian_of_a_batch_and_the_default_representation(panda, rep):
    Q = np.array(regular_qs(panda, rep, 4, seed=9))
    Ja = panda.jacob0_analytical(Q, representation=rep)
    assert Ja.shape == (4, 6, panda.n)
    for k in range(4):
        assert_close(Ja[k], panda.jacob0_analytical(Q[k], rep), 1e-15, f"batch item {k}")
    assert_close(panda.jacob0_analytical(Q[0]), panda.jacob0_analytical(Q[0], "rpy/xyz"), 0)
    assert panda.jacob0_analytical(Q[:0], rep).shape == (0, 6, panda.n)


def test_exp_coordinates_near_zero_rotation():
    """theta -> 0: the series branch of the inverse left Jacobian (A^-1 -> I - [r]x / 2)."""
    robot = Robot.from_ets("Rx(q0) Ry(q1) Rz(q2) tx(0.1)")
    for q in (np.zeros(3), np.array([1e-5, -2e-5, 3e-5]), np.array([0.004, 0.003, -0.002])):
        Ja = robot.jacob0_analytical(q, "exp")
        assert_close(Ja, fd_analytical(robot, q, "exp", h=1e-7), 1e-6, f"q = {q}")


@pytest.mark.parametrize("rep", REPRESENTATIONS)
def test_analytical_jacobian_of_a_link_frame(panda, rep):
    for q in regular_qs(panda, rep, 2, seed=13, frame=3):
        Ja = panda.jacob0_analytical(q, rep, frame=3)
        assert_close(Ja, fd_analytical(panda, q, rep, frame=3), 1e-6, f"{rep} frame 3")
        assert not Ja[:, 4:].any(), "joints after frame 3 do not move it"


@pytest.mark.parametrize("rep", REPRESENTATIONS)
def test_analytical_jacobian_of_a_tree_frame(panda, rep):
    tree = Tree.from_robot(panda)
    Q = np.array(regular_qs(panda, rep, 3, seed=17))
    ref = panda.jacob0_analytical(Q, rep)
    assert_close(tree.jacob0_analytical(Q, rep, frame="ee"), ref, 1e-12, f"tree {rep}")
    assert_close(tree.jacob0_analytical(Q[0], rep), ref[0], 1e-12, f"tree {rep}, default frame")


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_analytical_jacobian_of_compiled_kinematics(panda, backend):
    kin = symkin.compile(panda, backend=backend)
    for rep in REPRESENTATIONS:
        Q = np.array(regular_qs(panda, rep, 3, seed=21))
        assert_close(kin.jacob0_analytical(Q, rep), panda.jacob0_analytical(Q, rep), 1e-10, rep)
        assert_close(kin.jacob0_analytical(Q[1], rep), panda.jacob0_analytical(Q[1], rep), 1e-10, rep)
        Q3 = np.array(regular_qs(panda, rep, 2, seed=22, frame=3))
        got, ref = kin.jacob0_analytical(Q3, rep, frame=3), panda.jacob0_analytical(Q3, rep, frame=3)
        assert_close(got, ref, 1e-10, f"{rep} frame 3")
        w = np.array([1.0, -2.0, 0.5, 0.1, 0.2, -0.3])
        assert_close(kin.joint_torques(Q, w, in_frame="ee"), panda.joint_torques(Q, w, in_frame="ee"), 1e-10)


# -- representation singularities and bad options -------------------------------------------------
def test_rpy_singularity_is_refused_with_the_angle():
    """A planar arm about y: R = Ry(q0 + q1), so pitch = q0 + q1 for both rpy orders."""
    arm = Robot.from_ets("Ry(q0) tz(0.5) Ry(q1) tz(0.4)")
    q = np.array([0.3, math.pi / 2 - 0.3])
    for rep in ("rpy/xyz", "rpy/zyx"):
        with pytest.raises(ConfigurationError, match=rf"singular for {rep} at pitch = 90 deg.*another"):
            arm.jacob0_analytical(q, rep)
        with pytest.raises(ConfigurationError, match=r"pitch = -90 deg \(configuration 1 of the batch\)"):
            arm.jacob0_analytical(np.array([[0.1, 0.2], [-1.0, 1.0 - math.pi / 2]]), rep)
    for rep in ("eul", "exp"):  # theta = 90 deg, rotation angle 90 deg: regular
        assert np.isfinite(arm.jacob0_analytical(q, rep)).all()
    q = np.array([0.7, -0.5])
    assert_close(arm.jacob0_analytical(q, "rpy/xyz")[4], [1.0, 1.0], 1e-12, "d pitch / dq")


def test_eul_singularity_is_refused_with_the_angle():
    arm = Robot.from_ets("Ry(q0) tz(0.5) Ry(q1) tz(0.4)")
    with pytest.raises(ConfigurationError, match=r"singular for eul at theta = 0 deg"):
        arm.jacob0_analytical([0.4, -0.4], "eul")
    with pytest.raises(ConfigurationError, match=r"singular for eul at theta = 180 deg"):
        arm.jacob0_analytical([math.pi / 2, math.pi / 2], "eul")
    panda = symkin.load("panda")
    with pytest.raises(ConfigurationError, match="eul"):  # qz: the hand points straight down
        panda.jacob0_analytical(panda.qz, "eul")


def test_exp_is_regular_at_a_half_turn():
    arm = Robot.from_ets("Ry(q0) tz(0.5) Ry(q1) tz(0.4)")
    Ja = arm.jacob0_analytical([math.pi / 2, math.pi / 2], "exp")
    assert np.isfinite(Ja).all()
    assert_close(Ja[3:], [[0, 0], [1, 1], [0, 0]], 1e-12, "the rotation vector (0, theta, 0)")


@pytest.mark.parametrize("bad", ["rpy", "RPY/XYZ", "angvec", None, 3])
def test_unknown_representation_lists_the_valid_ones(panda, bad):
    with pytest.raises(ParameterError, match=r"'rpy/xyz', 'rpy/zyx', 'eul', 'exp'"):
        panda.jacob0_analytical(panda.qr, bad)


def test_bad_q_and_frame_are_the_usual_errors(panda):
    with pytest.raises(ConfigurationError):
        panda.jacob0_analytical(np.zeros(6))
    with pytest.raises(symkin.FrameError):
        panda.jacob0_analytical(panda.qr, frame=9)


# -- velocity and wrench transforms ----------------------------------------------------------------
def random_T(rng: np.random.Generator) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = expm_so3(rng.normal(size=3))
    T[:3, 3] = rng.normal(size=3)
    return T


def test_velocity_transform_moves_the_reference_point_and_rotates():
    """A body spinning with omega: the velocity of its point at B's origin, expressed in B, and that
    of its point at A's origin, expressed in A, from rigid-body kinematics directly."""
    rng = np.random.default_rng(1)
    T = random_T(rng)
    R, t = T[:3, :3], T[:3, 3]
    v_b, w_b = rng.normal(size=3), rng.normal(size=3)
    # in A's coordinates: the point at B's origin (position t) moves at R v_b; the body point at A's
    # origin (position 0) moves at R v_b + (R w_b) x (0 - t)
    v_a = R @ v_b + np.cross(R @ w_b, -t)
    assert_close(velocity_transform(T) @ np.r_[v_b, w_b], np.r_[v_a, R @ w_b], 1e-12)
    # a force f at B's origin has moment t x f about A's origin
    f_b, m_b = rng.normal(size=3), rng.normal(size=3)
    assert_close(wrench_transform(T) @ np.r_[f_b, m_b], np.r_[R @ f_b, np.cross(t, R @ f_b) + R @ m_b], 1e-12)


def test_velocity_and_wrench_transforms_compose_invert_and_keep_power():
    rng = np.random.default_rng(2)
    for _ in range(5):
        T1, T2 = random_T(rng), random_T(rng)
        X1, X2 = velocity_transform(T1), velocity_transform(T2)
        assert_close(velocity_transform(T1 @ T2), X1 @ X2, 1e-12, "composition")
        assert_close(wrench_transform(T1 @ T2), wrench_transform(T1) @ wrench_transform(T2), 1e-12)
        assert_close(velocity_transform(np.linalg.inv(T1)) @ X1, np.eye(6), 1e-12, "inverse")
        assert_close(wrench_transform(T1), np.linalg.inv(X1).T, 1e-12, "inverse transpose")
        v, w = rng.normal(size=6), rng.normal(size=6)
        assert (wrench_transform(T1) @ w) @ (X1 @ v) == pytest.approx(w @ v, rel=1e-12, abs=1e-12)
    Ts = np.stack([random_T(rng) for _ in range(3)])
    assert velocity_transform(Ts).shape == wrench_transform(Ts).shape == (3, 6, 6)
    assert_close(velocity_transform(Ts)[2], velocity_transform(Ts[2]), 0)
    assert_close(velocity_transform(np.eye(4)), np.eye(6), 0)


def test_velocity_transform_relates_the_jacobians_of_a_tool(panda):
    """Je of the tool frame = velocity_transform(inv(T_tool)) @ Je of the flange."""
    T_tool = np.eye(4)
    T_tool[:3, :3] = rx(0.3) @ rz(-0.4)
    T_tool[:3, 3] = [0.02, -0.03, 0.1]
    tool = panda.with_tool(T_tool)
    q = panda.random_q(seed=3)
    got = velocity_transform(np.linalg.inv(T_tool)) @ panda.jacobe(q)
    assert_close(tool.jacobe(q), got, 1e-12, "tool Je")


@pytest.mark.parametrize("bad", [np.eye(3), np.ones((4, 4)), np.full((4, 4), np.nan), "T"])
def test_transforms_refuse_non_se3(bad):
    with pytest.raises(PoseError):
        velocity_transform(bad)
    with pytest.raises(PoseError):
        wrench_transform(bad)


# -- joint torques ---------------------------------------------------------------------------------
def test_joint_torques_are_the_transposed_jacobian_times_the_wrench(panda):
    rng = np.random.default_rng(4)
    Q, W = panda.random_q(3, seed=4), rng.normal(size=(3, 6))
    tau = panda.joint_torques(Q, W)
    assert tau.shape == (3, panda.n)
    for k in range(3):
        assert_close(tau[k], panda.jacob0(Q[k]).T @ W[k], 1e-14)
        assert_close(panda.joint_torques(Q[k], W[k]), tau[k], 0)
        assert_close(panda.joint_torques(Q[k], W[k], frame=2), panda.jacob0(Q[k], frame=2).T @ W[k], 1e-14)
    # frame="base" | "ee" on a chain (no frame of that name): the wrench's frame at the end effector
    assert_close(panda.joint_torques(Q, W, frame="ee"), np.einsum("Nrj,Nr->Nj", panda.jacobe(Q), W), 1e-14)
    assert_close(panda.joint_torques(Q, W, frame="base"), tau, 0)
    with pytest.raises(ParameterError, match="two frames for the wrench"):
        panda.joint_torques(Q, W, frame="base", in_frame="ee")
    assert_close(panda.joint_torques(Q, W[0]), np.stack([panda.jacob0(q).T @ W[0] for q in Q]), 1e-14)
    assert_close(panda.joint_torques(Q[0], W), np.stack([panda.jacob0(Q[0]).T @ w for w in W]), 1e-14)
    tree = Tree.from_robot(panda)
    assert_close(tree.joint_torques(Q, W, frame="ee"), tau, 1e-12, "tree")


def test_joint_torques_do_the_virtual_work_of_the_wrench(panda):
    """tau . dq = f . dp + m . dtheta for a small joint motion dq (finite differences of the pose)."""
    rng = np.random.default_rng(5)
    q, w, dq = panda.random_q(seed=5), rng.normal(size=6), rng.normal(size=panda.n)
    h = 1e-6
    Tp, Tm = panda.fkine(q + h * dq), panda.fkine(q - h * dq)
    dp = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
    dtheta = extract("exp", Tp[:3, :3] @ Tm[:3, :3].T) / (2 * h)  # base-frame rotation increment
    work = w @ np.r_[dp, dtheta]
    assert panda.joint_torques(q, w) @ dq == pytest.approx(work, rel=1e-7, abs=1e-8)


def test_joint_torques_of_a_wrench_in_the_end_effector_frame(panda):
    rng = np.random.default_rng(6)
    Q, W_e = panda.random_q(3, seed=6), rng.normal(size=(3, 6))
    R = panda.fkine(Q)[:, :3, :3]
    W_0 = np.concatenate((np.einsum("Nij,Nj->Ni", R, W_e[:, :3]), np.einsum("Nij,Nj->Ni", R, W_e[:, 3:])), 1)
    assert_close(panda.joint_torques(Q, W_e, in_frame="ee"), panda.joint_torques(Q, W_0), 1e-12)
    assert_close(panda.joint_torques(Q[0], W_e[0], in_frame="ee"), panda.jacobe(Q[0]).T @ W_e[0], 1e-14)
    T3 = panda.fkine(Q[0], frame=3)
    w_3 = np.r_[T3[:3, :3].T @ W_0[0, :3], T3[:3, :3].T @ W_0[0, 3:]]
    got = panda.joint_torques(Q[0], w_3, frame=3, in_frame="ee")
    assert_close(got, panda.joint_torques(Q[0], W_0[0], frame=3), 1e-12, "frame 3")


@pytest.mark.parametrize(
    "wrench, match",
    [
        (np.zeros(5), "shape"),
        (np.zeros((2, 3)), "shape"),
        (np.zeros((2, 2, 6)), "shape"),
        (np.r_[np.zeros(5), np.nan], "NaN"),
        (np.r_[np.zeros(5), np.inf], "NaN or infinite"),
        ("force", "wrench"),
        (np.zeros(6, dtype=complex), "wrench"),
        (np.zeros((2, 6)), "3 and 2"),
    ],
)
def test_bad_wrenches_are_refused(panda, wrench, match):
    with pytest.raises(ParameterError, match=match):
        panda.joint_torques(panda.random_q(3, seed=1), wrench)


def test_bad_in_frame_is_refused(panda):
    with pytest.raises(ParameterError, match="in_frame"):
        panda.joint_torques(panda.qr, np.zeros(6), in_frame="tool")


# -- roboticstoolbox-python (skipped when it is not installed) -------------------------------------
@pytest.mark.parametrize("rep", REPRESENTATIONS)
def test_analytical_jacobian_matches_roboticstoolbox(panda, rep):
    rtb = pytest.importorskip("roboticstoolbox")
    ref = rtb.models.ETS.Panda()
    robot = symkin.Robot.from_rtb(ref)  # the toolbox's flange is tz(0.103), symkin's panda (Fig. 1) 0.1034
    for q in regular_qs(robot, rep, 3, seed=31):
        assert_close(robot.fkine(q), np.asarray(ref.fkine(q)), 1e-12, "same Panda")
        want = np.asarray(ref.jacob0_analytical(q, rep))
        assert_close(robot.jacob0_analytical(q, rep), want, 1e-9, f"roboticstoolbox {rep}")


def test_velocity_transform_matches_spatialmath():
    """spatialmath's tr2adjoint is [[R, [t]x R], [0, R]], the same (v, omega) order."""
    smb = pytest.importorskip("spatialmath.base")
    T = random_T(np.random.default_rng(7))
    assert_close(velocity_transform(T), np.asarray(smb.tr2adjoint(T)), 1e-12)
