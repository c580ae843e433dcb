"""Compiled tree kernels on every backend against the numeric reference (and through it, the chains
and finite differences of tests/model/test_tree.py): every frame, every entry point, one
configuration and batches, errors, and safe rendering of arbitrary frame names."""

from __future__ import annotations

import html

import numpy as np
import pytest

import symkin
from symkin import ConfigurationError, FrameError, Tree
from symkin.compiler.compile import generate
from tests.conftest import assert_close
from tests.model.tree_urdfs import GRIPPER, QUADRUPED, fixed, joint, urdf

BACKENDS = ("c", "numpy", "casadi")


@pytest.fixture(scope="module", params=["quadruped", "gripper"])
def tree(request) -> Tree:
    return Tree.from_urdf({"quadruped": QUADRUPED, "gripper": GRIPPER}[request.param])


@pytest.mark.parametrize("backend", BACKENDS)
def test_every_frame_and_entry_point_matches_the_reference(tree, backend):
    kin = symkin.compile(tree, backend)
    assert kin.n == tree.n and kin.frames == tree.frames and kin.backend == backend
    Q = tree.random_q(5, seed=7)
    for q, single in ((Q, False), (Q[0], True)):
        T, J = tree.fkine_all(q), tree.jacob0_all(q)
        assert_close(kin.fkine_all(q), T, 1e-13, "fkine_all")
        assert_close(kin.jacob0_all(q), J, 1e-13, "jacob0_all")
        T2, J2 = kin.fkine_jacob0_all(q)
        assert_close(T2, T, 1e-13, "fkine_jacob0_all T")
        assert_close(J2, J, 1e-13, "fkine_jacob0_all J")
        for k, f in enumerate(tree.frames):
            Tk = T[k] if single else T[:, k]
            Jk = J[k] if single else J[:, k]
            assert_close(kin.fkine(q, frame=f), Tk, 1e-13, f"fkine {f}")
            assert_close(kin.jacob0(q, f), Jk, 1e-13, f"jacob0 {f}")
            assert_close(kin.jacobe(q, frame=f), tree.jacobe(q, f), 1e-13, f"jacobe {f}")
            Tf, Jf = kin.fkine_jacob0(q, frame=f)
            assert_close(Tf, Tk, 1e-13, f"fkine_jacob0 T {f}")
            assert_close(Jf, Jk, 1e-13, f"fkine_jacob0 J {f}")
        assert kin.fkine_all(q).shape == ((len(tree.frames), 4, 4) if single else (5, len(tree.frames), 4, 4))


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_frame_fixed_to_the_base_has_no_joint_on_its_path(backend):
    """Its pose is constant and its J0 and H0 are zero (the NumPy module once failed to import:
    its empty path was written ``(,)``)."""
    text = QUADRUPED.replace('<link name="body"/>', '<link name="body"/><link name="imu"/>').replace(
        "</robot>", fixed("imu_mount", "body", "imu", xyz="0 0 0.1") + "</robot>"
    )
    tree = Tree.from_urdf(text)
    assert "imu" in tree.frames and tree.path_slots("imu") == []
    kin = symkin.compile(tree, backend)
    for q in tree.random_q(3, seed=2):
        assert_close(kin.fkine(q, "imu"), tree.fkine(q, "imu"), 1e-13, "fkine imu")
        J, H = kin.jacob0_hessian0(q, "imu")
        assert not np.asarray(J).any() and not np.asarray(H).any()
        assert_close(kin.jacob0_hessian0(q, "l_foot")[1], tree.hessian0(q, "l_foot"), 1e-12, "H0 l_foot")


@pytest.mark.parametrize("backend", BACKENDS)
def test_errors_are_the_reference_errors(backend):
    tree = Tree.from_urdf(QUADRUPED)
    kin = symkin.compile(tree, backend)
    q = np.zeros(tree.n)
    with pytest.raises(FrameError, match="no frame 'l_fot'"):
        kin.fkine(q, frame="l_fot")
    with pytest.raises(FrameError, match="name one with frame="):
        kin.jacob0(q)
    with pytest.raises(FrameError, match="link name"):
        kin.jacobe(q, frame=1)
    with pytest.raises(ConfigurationError, match="shape"):
        kin.fkine_all(np.zeros(3))
    with pytest.raises(ConfigurationError, match="finite"):
        kin.jacob0(np.full(tree.n, np.nan), frame="l_foot")


def test_the_kernel_shares_what_frames_share():
    """The all-frames function computes the common trunk once: fewer operations than the frames'
    own functions together, and no more than their sum minus the trunk."""
    trunk = [
        joint(f"t{i}", f"k{i}", f"k{i + 1}", xyz="0 0 0.1", axis="0 1 0" if i % 2 else "1 0 0")
        for i in range(6)
    ]
    branches = [
        joint(f"{s}{i}", f"{s}{i}" if i else "k6", f"{s}{i + 1}", xyz="0.1 0 0")
        for s in "ab"
        for i in range(3)
    ]
    xml = urdf([f"k{i}" for i in range(7)] + [f"{s}{i}" for s in "ab" for i in range(1, 4)], trunk + branches)
    from symkin.compiler.compile import derived_functions

    tree = Tree.from_urdf(xml)
    assert tree.n == 12 and tree.frames == ("a3", "b3")
    fns = {f.name: f.code.counts.total for f in derived_functions(tree)}
    both = fns["fkine_jacob0_0"] + fns["fkine_jacob0_1"]
    assert fns["fkine_jacob0_all"] < both
    one_chain = Tree.from_urdf(xml, frames=["a3"])
    trunk_ops = {f.name: f.code.counts.total for f in derived_functions(one_chain)}["fkine"]
    assert fns["fkine_jacob0_all"] <= both - trunk_ops // 2


def test_generated_code_is_deterministic_and_says_what_made_it():
    tree = Tree.from_urdf(QUADRUPED, frames=["r_foot", "l_foot"])
    for backend in BACKENDS:
        a, b = generate(tree, backend), generate(tree, backend)
        assert a == b
        text = next(iter(a.values()))
        assert "Generated by symkin" in text and "Frames: r_foot, l_foot" in text
        assert "shared" in text or "share" in text


def test_arbitrary_frame_names_are_rendered_safely():
    weird = ['tip */ "x"', "a\\b'c", "ünï code"]
    e = [html.escape(n, quote=True) for n in weird]
    xml = urdf(
        ["base", "l1", *e],
        [joint("j1", "base", "l1")]
        + [fixed(f"f{i}", "l1", n, xyz=f"0.{i + 1} 0 0") for i, n in enumerate(e)],
        name=html.escape('evil */ "name', quote=True),
    )
    tree = Tree.from_urdf(xml)
    assert tree.frames == tuple(weird)
    q = np.array([0.3])
    for backend in BACKENDS:
        kin = symkin.compile(tree, backend)
        for f in weird:
            assert_close(kin.fkine(q, frame=f), tree.fkine(q, f), 1e-14, f"{backend} {f!r}")
        assert_close(kin.fkine_all(q), tree.fkine_all(q), 1e-14, backend)


def test_tuple_results_of_the_c_extension_do_not_leak():
    """Functions returning (T, J) hand their arrays to the tuple: each array's only other reference
    is the caller's (a leak here once cost 0.7 KB per call and made the call several times slower)."""
    import sys

    chain = symkin.compile("planar3", "c")
    tree = symkin.compile(Tree.from_urdf(QUADRUPED), "c")
    q3, qt = np.zeros(3), np.zeros(tree.n)
    calls = (
        lambda: chain.fkine_jacob0(q3),
        lambda: chain.jacob0_hessian0(q3),
        lambda: tree.fkine_jacob0_all(qt),
        lambda: tree.fkine_jacob0(qt, frame="l_foot"),
    )
    for call in calls:
        a, b = call()  # the tuple is gone: the names hold the only references
        assert sys.getrefcount(a) == sys.getrefcount(b) == 2  # the name and getrefcount's argument


@pytest.mark.parametrize("backend", BACKENDS)
def test_every_backend_takes_and_refuses_the_inputs_the_chains_do(backend):
    tree = Tree.from_urdf(QUADRUPED)
    kin = symkin.compile(tree, backend)
    q = tree.random_q(seed=2)
    T = tree.fkine_all(q)
    for same in (q.astype(">f8"), q.astype(np.float32).astype(object), list(q), q[None][::1, :][0]):
        assert_close(kin.fkine_all(same), tree.fkine_all(np.asarray(same, dtype=float)), 1e-6, "converted q")
    assert_close(kin.fkine_all(q.astype(">f8")), T, 1e-15, "big-endian q")
    assert kin.fkine_all(np.zeros((0, tree.n))).shape == (0, len(tree.frames), 4, 4)
    T0, J0 = kin.fkine_jacob0_all(np.zeros((0, tree.n)))
    assert T0.shape == (0, len(tree.frames), 4, 4) and J0.shape == (0, len(tree.frames), 6, tree.n)
    with pytest.raises(ConfigurationError, match="within"):
        kin.fkine_all(np.full(tree.n, 1e300))  # as the chains: |q| <= 1e15
    with pytest.raises(ConfigurationError, match="real"):
        kin.fkine_all(q.astype(complex))


@pytest.mark.parametrize("backend", BACKENDS)
def test_trees_differing_only_in_limits_get_their_own_compiled_object(backend):
    # the same structure shares generated code, never the limits a controller reads
    loose = Tree.from_urdf(QUADRUPED)
    old, new = 'lower="-2.5" upper="2.5" velocity="2"', 'lower="-0.2" upper="0.2" velocity="0.1"'
    tight_xml = QUADRUPED.replace(old, new)
    assert tight_xml != QUADRUPED
    tight = Tree.from_urdf(tight_xml)
    a, b = symkin.compile(loose, backend), symkin.compile(tight, backend)
    assert a is not b and a is symkin.compile(loose, backend)
    assert np.array_equal(a.qlim, loose.qlim) and np.array_equal(b.qlim, tight.qlim)
    assert b.tree is tight and not np.array_equal(a.tree.velocity, b.tree.velocity, equal_nan=True)
    assert np.array_equal(b.select("l_foot").qlim, tight.qlim) and not np.array_equal(tight.qlim, loose.qlim)


def test_c_trees_give_generated_hessians_checked_by_finite_differences():
    """The C kernel's per-frame J0 and H0 (generated for frames without mimic joints) through the
    extension module: H0 equals the reference's and the central differences of the compiled J0;
    a frame with a mimic joint on its path falls back and still matches the reference."""
    tree = Tree.from_urdf(QUADRUPED)
    kin = symkin.compile(tree, "c")
    Q = tree.random_q(6, seed=4)
    h = 1e-6
    for frame in tree.frames:
        assert kin.module.jacob0_hessian0(Q[0], frame) is not NotImplemented  # generated for this frame
        J, H = kin.jacob0_hessian0(Q, frame=frame)
        assert_close(J, tree.jacob0(Q, frame), 1e-12, f"J0 of {frame}")
        assert_close(H, tree.hessian0(Q, frame), 1e-12, f"H0 of {frame}")
        for j in range(tree.n):
            dq = np.zeros(tree.n)
            dq[j] = h
            fd = (kin.jacob0(Q + dq, frame=frame) - kin.jacob0(Q - dq, frame=frame)) / (2 * h)
            assert_close(H[:, j], fd, 1e-7, f"dJ0/dq{j} of {frame}")
        H1 = kin.hessian0(Q[0], frame=frame)
        assert H1.shape == (tree.n, 6, tree.n)
        assert_close(H1, H[0], 0.0, "one configuration is the batch's first")
    mimic = Tree.from_urdf(GRIPPER)
    kin_m = symkin.compile(mimic, "c")
    Qm = mimic.random_q(3, seed=5)
    for frame in mimic.frames:
        assert_close(kin_m.hessian0(Qm, frame=frame), mimic.hessian0(Qm, frame), 1e-12, f"H0 of {frame}")
