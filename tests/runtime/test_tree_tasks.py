"""IK, servo and MMC on one frame of a tree (the other joints free), on the numeric reference and
on compiled kernels; results checked by the reference's forward kinematics."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import symkin
from symkin import MMC, FrameError, Tree, ik, pose_error, servo
from tests.conftest import assert_close
from tests.model.tree_urdfs import DUAL_ARM, GRIPPER, QUADRUPED

ARM = Tree.from_urdf(QUADRUPED, frames=["r_foot", "l_foot"])
ROOT_UR5 = Path(__file__).resolve().parents[2] / "examples" / "ur5.urdf"  # a tree: tool0 and camera


@pytest.mark.parametrize("backend", ["reference", "c", "numpy"])
def test_ik_on_one_frame_reaches_it_and_leaves_the_other_branch(backend):
    kin = ARM if backend == "reference" else symkin.compile(ARM, backend)
    q_goal = ARM.random_q(seed=11)
    Tep = ARM.fkine(q_goal, "r_foot")
    q0 = q_goal + 0.15
    res = ik(kin, Tep, frame="r_foot", q0=q0, seed=1)
    assert res.success, res.reason
    assert np.abs(pose_error(ARM.fkine(res.q, "r_foot"), Tep)).max() < 1e-6
    left = [ARM.joint_names.index(n) for n in ("l_haa", "l_hfe", "l_kfe")]
    assert_close(res.q[left], q0[left], 1e-15, "joints off the frame's path keep their start values")
    if backend == "c":
        assert hasattr(kin.select("r_foot"), "c_fkjac")  # the C loop on the frame's generated kernel
        res_c = kin.ik(Tep, frame="r_foot", q0=q0, seed=1)
        assert res_c.success and np.abs(pose_error(ARM.fkine(res_c.q, "r_foot"), Tep)).max() < 1e-6


def test_ik_with_a_mimic_joint_on_the_path():
    tree = Tree.from_urdf(GRIPPER)
    q_goal = np.array([0.4, -0.3, 0.02])
    Tep = tree.fkine(q_goal, "fa_tip2")
    res = ik(tree, Tep, frame="fa_tip2", q0=np.array([0.2, 0.1, 0.01]), joint_limits=False, seed=2)
    assert res.success, res.reason
    assert np.abs(pose_error(tree.fkine(res.q, "fa_tip2"), Tep)).max() < 1e-6


def test_frame_is_required_on_a_tree_and_a_chain_takes_link_indices():
    with pytest.raises(FrameError, match="name one with frame="):
        ik(ARM, np.eye(4))
    with pytest.raises(FrameError, match="link frame index 0..6"):
        ik(symkin.load("panda"), np.eye(4), frame="tool")
    with pytest.raises(FrameError, match="link frames 0..6"):
        symkin.compile(symkin.load("panda"), "c").ik(np.eye(4), frame=7)


@pytest.mark.parametrize("controller", ["rrmc", "mmc"])
def test_servo_moves_one_frame_to_its_target(controller):
    kin = symkin.compile(ARM, "c")
    q0 = np.full(ARM.n, 0.3)
    q_goal = q0 + np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.2, -0.2, 0.2, 0.0, 0.0, 0.0])[: ARM.n]
    Tep = ARM.fkine(q_goal, "r_foot")
    res = servo(kin, q0, Tep, frame="r_foot", controller=controller, max_steps=300)
    assert res.arrived
    assert np.abs(pose_error(ARM.fkine(res.q[-1], "r_foot"), Tep)).sum() < 0.1
    off = [ARM.joint_names.index(n) for n in ("l_haa", "l_hfe", "l_kfe")]
    assert_close(res.q[-1][off], q0[off], 1e-12, "the other leg does not move")


def test_mmc_on_one_arm_of_a_dual_arm_robot():
    tree = Tree.from_urdf(DUAL_ARM)
    assert tree.n == 13 and tree.frames == ("l_tool", "r_tool")
    kin = symkin.compile(tree, "numpy")
    ctrl = MMC(kin, frame="l_tool")
    q = tree.random_q(seed=5)
    J, Jm, m = ctrl.kinematics(q)
    assert_close(J, tree.jacob0(q, "l_tool"), 1e-13, "J0 of the frame")
    assert_close(Jm, tree.select("l_tool").jacobm(q), 1e-9, "manipulability Jacobian against the reference's")
    assert m == pytest.approx(tree.select("l_tool").manipulability(q), rel=1e-9)
    nu = np.array([0.02, -0.01, 0.01, 0.0, 0.05, 0.0])
    qd, info = ctrl.step(q, nu)
    assert info.ok, info
    assert_close(tree.jacob0(q, "l_tool") @ qd, nu, 1e-8, "the step achieves nu")
    right = [tree.joint_names.index(f"r_j{i}") for i in range(1, 7)]
    assert not qd[right].any(), "the other arm does not move"
    res = servo(kin, q, tree.fkine(q + 0.05, "l_tool"), frame="l_tool", max_steps=200)
    assert res.arrived


def test_frame_view_hessian_from_the_compiled_jacobian_matches_the_reference():
    kin = symkin.compile(ARM, "c")
    q = ARM.random_q(seed=6)
    for f in ARM.frames:
        assert_close(kin.hessian0(q, frame=f), ARM.hessian0(q, f), 1e-12, f)


@pytest.mark.parametrize("backend", ["reference", "c", "numpy"])
def test_manipulability_and_jacobm_of_a_frame_match_its_chain_and_finite_differences(backend):
    tree = symkin.Tree.from_urdf(ROOT_UR5)
    kin = tree if backend == "reference" else symkin.compile(tree, backend)
    camera = tree.chain("camera")
    Q = tree.random_q(6, seed=11)
    for axes in ("all", "trans"):
        m = kin.manipulability(Q, frame="camera", axes=axes)
        assert np.abs(m - camera.manipulability(Q, axes=axes)).max() < 1e-12
        Jm = kin.jacobm(Q, frame="camera", axes=axes)
        assert np.abs(Jm - camera.jacobm(Q, axes=axes)).max() < 1e-10
        q, h = Q[0], 1e-6
        steps = h * np.eye(tree.n)
        m = kin.manipulability(np.concatenate([q + steps, q - steps]), "camera", axes)
        fd = (m[: tree.n] - m[tree.n :]) / (2 * h)
        assert np.abs(Jm[0] - fd).max() < 1e-7
    assert isinstance(kin.manipulability(Q[0], frame="tool0"), float)


def test_controllers_on_a_c_tree_frame_run_in_c_with_the_python_path_s_results():
    tree = Tree.from_urdf(DUAL_ARM)
    kin = symkin.compile(tree, "c")
    view = kin.select("l_tool")
    c_mmc, py_mmc = MMC(view, lam=0.005), MMC(view, lam=0.005, backend="python")
    assert (c_mmc.backend, py_mmc.backend) == ("c", "python")
    rng, solved = np.random.default_rng(3), 0
    for q in tree.random_q(20, seed=7):
        nu = rng.normal(0, 0.02, 6)
        qd_c, info_c = c_mmc.step(q, nu)
        qd_py, info_py = py_mmc.step(q, nu)
        assert (info_c.status, info_c.method) == (info_py.status, info_py.method)
        assert_close(qd_c, qd_py, 1e-7, "C step against the Python step")  # J, H and m from C vs NumPy
        if info_c.ok:
            solved += 1
            assert_close(tree.jacob0(q, "l_tool") @ qd_c, nu, 1e-8, "the C step achieves nu")
    assert solved >= 10
    q0 = tree.random_q(seed=8)
    Tep = tree.fkine(q0 + 0.1, "l_tool")
    for controller in ("mmc", "rrmc"):
        in_c = servo(kin, q0, Tep, frame="l_tool", controller=controller, max_steps=300, backend="c")
        in_py = servo(kin, q0, Tep, frame="l_tool", controller=controller, max_steps=300, backend="python")
        assert in_c.arrived and in_py.arrived and len(in_c.q) == len(in_py.q)
        assert_close(
            np.asarray(in_c.q), np.asarray(in_py.q), 1e-9, f"{controller}: C loop against Python loop"
        )
    with pytest.raises(symkin.SymkinError):
        servo(kin, q0, Tep, frame="l_tool", controller="mmc", backend="c", max_steps=1, dt=float("nan"))


def test_a_frame_behind_a_mimic_joint_runs_its_controllers_in_c():
    """Its H0 is generated too (from the slot columns, both multipliers per block): the C MMC step
    runs and takes the Python step's values."""
    tree = Tree.from_urdf(GRIPPER)
    kin = symkin.compile(tree, "c")
    mimic_frames = [f for f in tree.frames if any(tree.slots[i].is_mimic for i in tree.path_slots(f))]
    assert mimic_frames
    ctrl, py = MMC(kin, frame=mimic_frames[0]), MMC(kin, frame=mimic_frames[0], backend="python")
    assert ctrl.backend == "c" and py.backend == "python"
    q = tree.random_q(seed=4)
    nu = np.array([0.01, 0.0, 0.0, 0.0, 0.0, 0.0])
    qd, _ = ctrl.step(q, nu)
    assert np.isfinite(qd).all()
    assert_close(qd, py.step(q, nu)[0], 1e-6, "the C step as the Python one (OSQP's tolerance)")


def test_the_c_tree_s_hessian_and_manipulability_match_the_reference():
    import ctypes

    tree = Tree.from_urdf(DUAL_ARM)
    fns = symkin.compile(tree, "c").select("r_tool").c_controller_fns
    P = ctypes.POINTER(ctypes.c_double)
    jh, manip = fns["jacob0_hessian0"], fns["manipulability"]
    jh.argtypes, jh.restype = [P, P, P], None
    manip.argtypes, manip.restype = [P, ctypes.c_int], ctypes.c_double
    n = tree.n
    for q in tree.random_q(10, seed=12):
        J, H = np.zeros(6 * n), np.zeros(n * 6 * n)
        jh(q.ctypes.data_as(P), J.ctypes.data_as(P), H.ctypes.data_as(P))
        assert_close(J.reshape(6, n), tree.jacob0(q, "r_tool"), 1e-13, "J0")
        assert_close(H.reshape(n, 6, n), tree.hessian0(q, "r_tool"), 1e-13, "H0 from J (eq 20)")
        for code, axes in ((0, "all"), (1, "trans"), (2, "rot")):
            m = tree.manipulability(q, "r_tool", axes)
            assert manip(q.ctypes.data_as(P), code) == pytest.approx(m, rel=1e-10, abs=1e-15)


def test_frame_views_do_not_keep_compiled_trees_alive():
    import gc
    import weakref

    kin = symkin.compile(Tree.from_urdf(QUADRUPED), "numpy", cache=False)
    view = kin.select("l_foot")
    assert kin.select("l_foot") is view  # memoised on the kinematics object
    ref = weakref.ref(kin)
    del kin, view
    gc.collect()
    assert ref() is None


@pytest.mark.parametrize("backend", ["reference", "numpy"])
def test_the_tree_and_its_compiled_kinematics_both_have_ik_with_frame(backend):
    """``Tree.ik`` exists like ``Robot.ik`` (it did on compiled trees only)."""
    kin = ARM if backend == "reference" else symkin.compile(ARM, backend)
    q_goal = ARM.random_q(seed=5)
    Tep = ARM.fkine(q_goal, "l_foot")
    res = kin.ik(Tep, frame="l_foot", q0=q_goal + 0.1, seed=2)
    assert res.success, res.reason
    assert np.abs(pose_error(ARM.fkine(res.q, "l_foot"), Tep)).max() < 1e-6
