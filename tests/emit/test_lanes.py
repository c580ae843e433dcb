"""The generated C's four-lane batch entry points (issue 21): ``<f>_batch`` runs four configurations
per step through ``<f>_x4_`` with ``skv_sin_``/``skv_cos_``, a scalar tail, and ``-DSYMKIN_SCALAR`` (or
C++, or another compiler) for one configuration per step. Every lane must give bit for bit what the
scalar code gives, so batch and one-at-a-time calls agree exactly, and the inline sin/cos stay
within 1 ulp (``tests/emit/test_sincos.py`` measures that on the batch path)."""

from __future__ import annotations

import ctypes
import re

import numpy as np
import pytest

import symkin
from symkin.emit.c import lanes
from symkin.emit.c.build import compile_library, load_library
from symkin.model.robots import load
from symkin.runtime.kinematics import KIN_METHODS
from tests.emit.test_sincos import _angles

ROBOTS = ("panda", "ur5", "stanford", "gantry", "planar2")


def _with_lanes(kin):
    """``kin`` once its four-lane batch code is built and bound (symkin.emit.c.lanes)."""
    assert lanes.ready(kin.module, timeout=600), lanes.state(kin.module)
    return kin


def _configurations(robot, n: int = 203) -> np.ndarray:
    Q = robot.random_q(n, seed=5)
    Q[5] = 1e7  # beyond the inline range: those lanes call libm
    Q[9, 0] = -0.0
    Q[10, 0] = 1e-30  # sin x = x
    Q[11] = np.pi / 2 * np.arange(1, robot.n + 1)  # the third reduction stage in one lane only
    return Q


def _outputs(out) -> tuple[np.ndarray, ...]:
    return out if isinstance(out, tuple) else (out,)


@pytest.mark.parametrize("name", ROBOTS)
def test_batch_equals_one_at_a_time_bit_for_bit(name):
    """Rows 0-199 go through the four-lane code, 200-202 through the scalar tail; single calls
    through the scalar code: every entry identical, for every generated function."""
    kin = _with_lanes(symkin.compile(name, backend="c"))
    Q = _configurations(kin.robot)
    for method in KIN_METHODS:
        f = getattr(kin, method)
        batch = _outputs(f(Q))
        for i in (*range(0, 16), 100, 101, 199, 200, 202):
            for b, s in zip(batch, _outputs(f(Q[i]))):
                assert np.array_equal(b[i], s), (name, method, i)


def test_the_lanes_are_where_they_pay():
    """Functions with code of their own (fkine, link_poses, jacob0, jacobe, fkine_jacob0; the
    Panda's jacob0_hessian0, whose Hessian is written out) get four-lane bodies, in a file of their
    own; hessian0, which calls jacob0_hessian0, keeps a scalar batch. The scalar bodies take the
    sin and cos of their angles four at a time (sk_sincos_n_, the lanes' kernels), not one call
    per angle nor libm's sin directly; with libm they call sk_sin and sk_cos (libm's) per angle."""
    files = symkin.generate(load("panda"), "c")
    text, four = files["symkin_panda.c"], files["symkin_panda_lanes.c"]
    for f in ("fkine", "link_poses", "jacob0", "jacobe", "fkine_jacob0", "jacob0_hessian0"):
        assert f"static void {f}_x4_(" in four and f"{f}_x4_(" not in text, f
        assert re.search(rf"for \(; i \+ 4 <= N; i \+= 4\)\n\s+{f}_x4_\(", four), f
        assert f"        i = l->{f}(" in text, f  # the batch entry point: through the lanes' table
    assert "static void hessian0_x4_(" not in four and "l->hessian0(" not in text

    def fkine_body(text: str) -> str:
        head = "static void fkine_(const double *SYMKIN_RESTRICT q, double *SYMKIN_RESTRICT T)\n{"
        body = text[text.index(head) :]
        return body[: body.index("\n}\n")]

    body = fkine_body(text)
    angles = "{ q0, q1, q2, q3, q4, q5, q6 + 0.7853981633974483, 0.0 }"
    assert f"const double angle_[8] = {angles};\n        sk_sincos_n_(angle_, 7, sin_, cos_);" in body
    assert "const double t0 = cos_[0];" in body and "const double t1 = sin_[0];" in body
    assert not re.search(r"(?<![\w])(sk_sin|sk_cos|sin|cos)\(", body)
    libm = fkine_body(symkin.generate(load("panda"), "c", libm=True)["symkin_panda.c"])
    assert "sk_sin(q0)" in libm and "sk_cos(q0)" in libm and "sk_sincos_n_" not in libm
    single = symkin.generate(load("panda"), "c", precision="float")["symkin_panda.c"]
    assert "_x4_" not in single and "sk_sincos_n_(" not in single  # single precision: sinf, cosf


def test_vector_sin_cos_are_the_scalar_ones_on_the_hard_angles():
    """Rz(q): T[0, 0] = cos q, T[1, 0] = sin q. The doubles nearest k pi/2 (the reduction's third
    stage), huge, tiny and signed-zero angles, four per step against one at a time."""
    kin = _with_lanes(symkin.compile(symkin.Robot.from_ets("Rz(q)", name="rz_lanes"), backend="c"))
    x = _angles()
    x = x[: len(x) // 4 * 4]
    batch = kin.fkine(x[:, None])
    single = np.array([kin.fkine(np.array([v])) for v in x])
    assert np.array_equal(batch.view(np.uint64), single.view(np.uint64))  # -0.0 included


def test_scalar_build_gives_the_same_numbers():
    """The same generated C built with -DSYMKIN_SCALAR (one configuration per step) against the
    default build: identical batch outputs."""
    robot = load("ur5")
    files = symkin.generate(robot, "c", prefix="lanes_ur5")
    sources = {k: v for k, v in files.items() if not k.endswith("_pymodule.c")}
    Q = np.ascontiguousarray(_configurations(robot, 41))
    outs = []
    for name, flags in (("lanes_ur5_vec", ()), ("lanes_ur5_scalar", ("-DSYMKIN_SCALAR",))):
        lib = load_library(compile_library(sources, name, extra_cflags=flags))
        T = np.empty((len(Q), 16))
        J = np.empty((len(Q), 6 * robot.n))
        fn = lib.lanes_ur5_fkine_jacob0_batch
        fn.restype = None
        fn(*(a.ctypes.data_as(ctypes.c_void_p) for a in (Q, T, J)), ctypes.c_ssize_t(len(Q)))
        outs.append((T, J))
    (T4, J4), (T1, J1) = outs
    assert np.array_equal(T4, T1) and np.array_equal(J4, J1)
    np.testing.assert_allclose(T4[:5].reshape(-1, 4, 4), robot.fkine(Q[:5]), atol=1e-14)


@pytest.mark.parametrize("which", ["quadruped", "gripper"])
def test_tree_batch_equals_one_at_a_time_bit_for_bit(which):
    """A tree's every-frame functions (fkine_all, jacob0_all, fkine_jacob0_all) run four
    configurations per step in a batch: identical to one call per configuration, the always-zero
    entries included (a prismatic joint, mimic joints with multipliers and offsets)."""
    from tests.model.tree_urdfs import GRIPPER, QUADRUPED

    tree = symkin.Tree.from_urdf({"quadruped": QUADRUPED, "gripper": GRIPPER}[which])
    kin = _with_lanes(symkin.compile(tree, backend="c"))
    text = symkin.generate(tree, "c")
    assert any("fkine_jacob0_all_x4_(" in t for t in text.values())
    Q = tree.random_q(43, seed=8)
    Q[3] = 1e7
    for method in ("fkine_all", "jacob0_all", "fkine_jacob0_all"):
        f = getattr(kin, method)
        batch = _outputs(f(Q))
        for i in (0, 1, 2, 3, 4, 39, 40, 42):
            for b, s in zip(batch, _outputs(f(Q[i]))):
                assert np.array_equal(b[i], s), (which, method, i)


@pytest.mark.parametrize("which", ["quadruped", "gripper"])
def test_tree_frame_batch_equals_one_at_a_time_bit_for_bit(which):
    """Each frame's fkine, jacob0, jacobe and fkine_jacob0 batch (kin.fkine(Q, frame=...), ...)
    runs four configurations per step: identical to one call per configuration for every frame;
    and the poses and Jacobians agree with the tree's numeric reference."""
    from tests.model.tree_urdfs import GRIPPER, QUADRUPED

    tree = symkin.Tree.from_urdf({"quadruped": QUADRUPED, "gripper": GRIPPER}[which])
    kin = _with_lanes(symkin.compile(tree, backend="c"))
    text = "".join(symkin.generate(tree, "c").values())
    for base in ("fkine", "jacob0", "jacobe", "fkine_jacob0"):
        assert re.search(rf"(^|[^_]){base}_0_x4_\(", text, re.M), base
    Q = tree.random_q(23, seed=10)
    Q[5] = 1e7
    for frame in tree.frames:
        T4, J4 = kin.fkine_jacob0(Q, frame=frame)
        assert np.array_equal(kin.fkine(Q, frame=frame), T4)
        assert np.array_equal(kin.jacob0(Q, frame=frame), J4)
        Je4 = kin.jacobe(Q, frame=frame)
        for i in (0, 3, 4, 5, 19, 20, 22):
            T1, J1 = kin.fkine_jacob0(Q[i], frame=frame)
            assert np.array_equal(T4[i], T1) and np.array_equal(J4[i], J1), (which, frame, i)
            assert np.array_equal(kin.jacob0(Q[i], frame=frame), J1), (which, frame, i)
            assert np.array_equal(Je4[i], kin.jacobe(Q[i], frame=frame)), (which, frame, i)
        np.testing.assert_allclose(T4[:5], tree.fkine(Q[:5], frame=frame), atol=1e-12)
        np.testing.assert_allclose(J4[:5], tree.jacob0(Q[:5], frame=frame), atol=1e-12)
        np.testing.assert_allclose(Je4[:5], tree.jacobe(Q[:5], frame=frame), atol=1e-12)


def test_tree_batch_writes_the_zero_entries_too():
    """``<f>_batch`` (not ``_zeroed``) writes every entry, the always-zero ones included, in the
    four-lane steps as in the scalar tail: outputs poisoned with NaN come back equal to the
    extension's (zero-filled) batch."""
    from tests.model.tree_urdfs import QUADRUPED

    tree = symkin.Tree.from_urdf(QUADRUPED)
    kin = _with_lanes(symkin.compile(tree, backend="c"))
    files = symkin.generate(tree, "c", prefix="lanes_tree")
    sources = {k: v for k, v in files.items() if not k.endswith("_pymodule.c")}
    lib = load_library(compile_library(sources, "lanes_tree"))
    Q = np.ascontiguousarray(tree.random_q(10, seed=9))
    T, J = kin.fkine_jacob0_all(Q)
    T2, J2 = np.full(T.shape, np.nan), np.full(J.shape, np.nan)
    fn = lib.lanes_tree_fkine_jacob0_all_batch
    fn.restype = None
    fn(*(a.ctypes.data_as(ctypes.c_void_p) for a in (Q, T2, J2)), ctypes.c_ssize_t(len(Q)))
    assert np.array_equal(T2, T) and np.array_equal(J2, J)


def test_lane_calls_find_whole_arguments():
    """sin/cos calls become the branch-free lane kernels with their whole (nested) argument."""
    from symkin.emit.c.backend import lane_calls

    assert lane_calls("-sk_sin(q6 + 0.785)") == "-skv_sin_(q6 + 0.785, &far_)"
    assert (
        lane_calls("t1*sk_cos((0.5)*(q0 + q1)) + sk_sin(sk_cos(q2))")
        == "t1*skv_cos_((0.5)*(q0 + q1), &far_) + skv_sin_(skv_cos_(q2, &far_), &far_)"
    )
    assert lane_calls("t3*t4") == "t3*t4"


def test_a_far_lane_sends_its_four_configurations_through_the_scalar_code():
    """The four-lane bodies are straight-line code; a lane beyond the inline range makes the body
    compute its four configurations with the scalar code, so the blocks with one huge angle still
    give, in every lane, what one call gives."""
    kin = _with_lanes(symkin.compile("ur5", backend="c"))
    Q = kin.robot.random_q(8, seed=2)
    Q[6, 2] = 3e9
    Q[1, 4] = -2e6
    T = kin.fkine(Q)
    for i in range(8):
        assert np.array_equal(T[i], kin.fkine(Q[i])), i


def test_the_lanes_library_is_built_at_the_first_batch_and_changes_no_result():
    """A robot new to the cache: compiling it and calling it one configuration at a time (or three)
    builds no four-lane code; the first batch of four or more starts it in the background, and
    batches before and after it is bound, and single calls, give the same bits."""
    import uuid

    ets = "Rz(q) tx(0.3) Ry(q) tz(0.2) Rx(q) tx(0.1)"
    robot = symkin.Robot.from_ets(ets, name=f"lazy_{uuid.uuid4().hex[:8]}")  # new to the cache
    kin = symkin.compile(robot, backend="c")
    st = lanes.state(kin.module)
    assert st is not None and not st.bound and st.thread is None
    Q = _configurations(robot, 13)
    singles = {m: [_outputs(getattr(kin, m)(q)) for q in Q] for m in KIN_METHODS}
    kin.fkine(Q[:3])
    assert st.thread is None and not st.bound  # fewer than four: no lanes wanted
    before = {m: _outputs(getattr(kin, m)(Q)) for m in KIN_METHODS}
    assert st.thread is not None
    assert lanes.ready(kin.module, timeout=600) and st.bound, st.error
    for m in KIN_METHODS:
        after = _outputs(getattr(kin, m)(Q))
        for a, b in zip(after, before[m]):
            assert a.tobytes() == b.tobytes(), m
        for i, single in enumerate(singles[m]):
            for a, s in zip(after, single):
                assert a[i].tobytes() == np.ascontiguousarray(s).tobytes(), (m, i)
