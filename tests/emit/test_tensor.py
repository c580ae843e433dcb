"""The generated JAX and PyTorch modules (symkin.emit.tensor) against the numeric reference
(``robot.fkine/jacob0/hessian0``, the ETS evaluated in NumPy): every built-in robot and two trees,
float64 and float32, and the library transforms the modules are written for (jit, vmap, grad,
jacfwd/jacrev, torch.compile), dtypes and devices, and bad input."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import symkin
from symkin import ConfigurationError, FrameError, Tree
from symkin.model.robots import list_robots, load
from tests.conftest import assert_close
from tests.diff_libs import BACKENDS, lib
from tests.model.tree_urdfs import GRIPPER, QUADRUPED

KINDS = ("fkine", "link_poses", "jacob0", "jacobe", "hessian0", "hessiane")
# float32 against the float64 reference at the same (float32-rounded) q, relative to max(1, |ref|):
# 16 float32 ulps of 1 (eps = 1.19e-7); measured worst 9.1e-7 (ur10 fkine, both libraries)
F32_TOL = 2e-6


def _kin(robot, backend):
    lib(backend)  # skips without the library
    return symkin.compile(robot, backend=backend)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", list_robots())
def test_every_builtin_robot_matches_the_reference_in_float64(name, backend):
    L = lib(backend)
    robot = load(name)
    kin = _kin(robot, backend)
    assert kin.backend == backend and kin.n == robot.n
    rng = np.random.default_rng(0)
    q = robot.random_q(seed=rng)
    Q = robot.random_q(6, seed=rng).reshape(2, 3, robot.n)  # any batch shape, batch first
    for x in (q, Q):
        lead = x.shape[:-1]

        def ref(kind, x=x, lead=lead):  # the reference takes (n,) or (N, n)
            out = getattr(robot, kind)(x.reshape(-1, robot.n) if lead else x)
            return out.reshape(lead + out.shape[1:]) if lead else out

        for kind in KINDS:
            out = kin.function(kind)(L.array(x))  # JAX: eager (jit is tested below)
            assert out.dtype == L.float64
            assert_close(L.numpy(out), ref(kind), 1e-12, f"{backend} {name} {kind} {x.shape}")
        T, J = kin.function("fkine_jacob0")(L.array(x))
        assert_close(L.numpy(T), ref("fkine"), 1e-12, "fkine_jacob0 T")
        assert_close(L.numpy(J), ref("jacob0"), 1e-12, "fkine_jacob0 J")
        J, H = kin.function("jacob0_hessian0")(L.array(x))
        assert_close(L.numpy(J), ref("jacob0"), 1e-12, "jacob0_hessian0 J")
        assert_close(L.numpy(H), ref("hessian0"), 1e-12, "jacob0_hessian0 H")


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", list_robots())
def test_float32_in_gives_float32_out_within_a_stated_bound(name, backend):
    L = lib(backend)
    robot = load(name)
    kin = _kin(robot, backend)
    Q = robot.random_q(50, seed=1).astype(np.float32)
    for kind in ("fkine", "jacob0", "hessian0"):
        out = kin.function(kind)(L.array(Q, L.float32))
        assert out.dtype == L.float32
        assert_close(L.numpy(out), getattr(robot, kind)(Q.astype(float)), F32_TOL, f"{name} {kind} float32")


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("urdf", [QUADRUPED, GRIPPER], ids=["quadruped", "gripper"])
def test_tree_frames_match_the_reference(urdf, backend):
    L = lib(backend)
    tree = Tree.from_urdf(urdf)
    kin = _kin(tree, backend)
    assert kin.frames == tree.frames and kin.n == tree.n
    Q = tree.random_q(4, seed=7)
    x = L.array(Q)  # the plain functions (JAX eager: jit compiles each frame apart, slowly)
    assert_close(L.numpy(kin.function("fkine_all")(x)), tree.fkine_all(Q), 1e-12, "fkine_all")
    assert_close(L.numpy(kin.function("jacob0_all")(x)), tree.jacob0_all(Q), 1e-12, "jacob0_all")
    for f in tree.frames:
        for kind in ("fkine", "jacob0", "hessian0"):
            out = kin.function(kind, f)(x)
            assert_close(L.numpy(out), getattr(tree, kind)(Q, frame=f), 1e-12, f"{kind} {f}")
    with pytest.raises(FrameError, match="nope"):
        kin.function("fkine", "nope")(x)


def _twist_of_pose_derivative(dT: np.ndarray, T: np.ndarray) -> np.ndarray:
    """(4, 4, n) dT/dq -> (6, n): dp/dq and the vee of dR/dq R^T (base frame angular velocity)."""
    v = dT[:3, 3, :]
    W = np.einsum("abk,cb->ack", dT[:3, :3, :], T[:3, :3])
    return np.concatenate((v, np.stack((W[2, 1], W[0, 2], W[1, 0]))), 0)


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", ["panda", "stanford", "cobra600", "gantry", "ur5"])
def test_autodiff_of_the_emitted_fk_equals_the_emitted_jacobian_and_hessian(name, backend):
    L = lib(backend)
    robot = load(name)
    kin = _kin(robot, backend)
    for q in robot.random_q(3, seed=2):
        x = L.array(q)
        dT = L.numpy(L.jacfwd(kin.function("fkine"))(x))  # (4, 4, n)
        T, J = (L.numpy(a) for a in kin.function("fkine_jacob0")(x))
        assert_close(_twist_of_pose_derivative(dT, T), J, 1e-12, f"{name} d fkine / dq")
        dJ = L.numpy(L.jacfwd(kin.function("jacob0"))(x))  # (6, n, n): dJ[a, b] / dq_i
        assert_close(
            np.moveaxis(dJ, -1, 0), L.numpy(kin.function("hessian0")(x)), 1e-12, f"{name} d jacob0 / dq"
        )


def test_jax_jit_vmap_and_grad():
    """On the Puma 560 (XLA compiles the Panda's functions in about a second each on an idle CPU)."""
    L = lib("jax")
    jax, jnp = L.mod, L.xp
    robot = load("puma560")
    kin = _kin(robot, "jax")
    Q = robot.random_q(5, seed=3)
    assert_close(L.numpy(kin.fkine(L.array(Q))), robot.fkine(Q), 1e-12, "jitted fkine")  # kin.fkine is jitted
    assert_close(L.numpy(jax.vmap(kin.function("jacob0"))(L.array(Q))), robot.jacob0(Q), 1e-12, "vmap jacob0")
    target = jnp.array([0.4, 0.1, 0.5])

    def loss(q):
        return 0.5 * jnp.sum((kin.function("fkine")(q)[:3, 3] - target) ** 2)

    for q in Q:
        g = L.numpy(jax.jit(jax.grad(loss))(L.array(q)))
        r = robot.fkine(q)[:3, 3] - np.asarray(target)
        assert_close(g, robot.jacob0(q)[:3].T @ r, 1e-12, "grad of a position loss = Jv^T (p - p*)")


def test_torch_autograd_and_func_vmap():
    L = lib("torch")
    torch = L.mod
    robot = load("panda")
    kin = _kin(robot, "torch")
    Q = robot.random_q(5, seed=3)
    out = torch.func.vmap(kin.function("jacob0"))(L.array(Q))
    assert_close(L.numpy(out), robot.jacob0(Q), 1e-12, "torch.func.vmap jacob0")
    q = L.array(Q).requires_grad_(True)
    target = torch.tensor([0.4, 0.1, 0.5], dtype=torch.float64)
    (0.5 * ((kin.fkine(q)[:, :3, 3] - target) ** 2).sum()).backward()
    r = robot.fkine(Q)[:, :3, 3] - target.numpy()
    expected = np.einsum("bij,bi->bj", robot.jacob0(Q)[:, :3], r)
    assert_close(L.numpy(q.grad), expected, 1e-12, "backward of a position loss = Jv^T (p - p*)")


def test_torch_compile_runs_the_generated_code():
    """torch.compile (inductor, CPU) of a small robot's FK and Jacobian (about 10 s the first time
    in a process: inductor's start-up; larger robots take longer to compile, see ``bench diff``)."""
    L = lib("torch")
    torch = L.mod
    robot = load("planar2")
    kin = _kin(robot, "torch")
    Q = robot.random_q(8, seed=4)
    f = torch.compile(kin.function("fkine_jacob0"), dynamic=False)
    T, J = f(L.array(Q))
    assert_close(L.numpy(T), robot.fkine(Q), 1e-12, "compiled fkine")
    assert_close(L.numpy(J), robot.jacob0(Q), 1e-12, "compiled jacob0")


def test_torch_output_follows_the_input_device():
    """The 'meta' device (shapes only, no data) stands in for a GPU: nothing is created on the CPU."""
    L = lib("torch")
    torch = L.mod
    kin = _kin(load("panda"), "torch")
    q = torch.zeros(5, 7, device="meta", dtype=torch.float32)
    for kind, shape in (("fkine", (5, 4, 4)), ("jacob0", (5, 6, 7)), ("hessian0", (5, 7, 6, 7))):
        out = getattr(kin, kind)(q)
        assert out.device.type == "meta" and out.dtype == torch.float32 and tuple(out.shape) == shape


@pytest.mark.parametrize("backend", BACKENDS)
def test_pickles_as_robot_and_backend(backend):
    L = lib(backend)
    robot = load("planar3")
    kin = _kin(robot, backend)
    back = pickle.loads(pickle.dumps(kin))
    assert type(back) is type(kin) and back.backend == backend and back.name == robot.name
    q = robot.random_q(3, seed=0)
    assert_close(L.numpy(back.function("fkine")(L.array(q))), robot.fkine(q), 1e-12, "unpickled fkine")


@pytest.mark.parametrize("backend", BACKENDS)
def test_bad_q_raises_a_configuration_error_naming_the_robot(backend):
    L = lib(backend)
    kin = _kin(load("panda"), backend)
    bad = [
        (L.array(np.zeros((3, 6))), r"shape \(\.\.\., 7\)"),
        (L.array(np.zeros((3, 7)), L.xp.int32), "float32 or float64"),
        (L.array(0.0), r"shape \(\.\.\., 7\)"),
    ]
    if backend == "torch":
        bad.append((np.zeros((3, 7)), "torch.Tensor"))
    for q, match in bad:
        with pytest.raises(ConfigurationError, match=match) as info:
            kin.fkine(q)
        assert "panda" in str(info.value)
