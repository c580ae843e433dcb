"""Long chains through the compiler: every backend against the numeric reference, both program
variants (Hessians written out and as loops), link-frame Jacobians and the frame argument."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin import FrameError, Robot
from symkin.bench.compile import random_chain
from symkin.model.robots import load
from tests.conftest import assert_close
from tests.emit.test_backends import TOL
from tests.model.test_frames import truncated

BACKENDS = ("c", "numpy", "casadi")


def mobile_panda() -> Robot:
    """A Panda on an XY base with a yaw joint: 10 joints, 3 of them first (2 prismatic)."""
    return Robot(symkin.ETS.parse("tx(q) ty(q) Rz(q) tz(0.2)") * load("panda").ets, name="mobile_panda")


CHAINS = {
    "chain9 (Hessians written out)": lambda: random_chain(9, seed=5),
    "chain14 (Hessians as loops)": lambda: random_chain(14, seed=6),
    "mobile panda": mobile_panda,
}


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("chain", list(CHAINS))
def test_long_chain_matches_reference(backend, chain):
    robot = CHAINS[chain]()
    kin = symkin.compile(robot, backend=backend)
    assert "straight-line program" in next(iter(kin.files.values()))
    q = robot.random_q(seed=1)
    Q = robot.random_q(6, seed=2)
    for name, tol in TOL.items():
        f, ref = getattr(kin, name), getattr(robot, name)
        assert_close(f(q), ref(q), tol, f"{backend} {chain} {name}")
        assert_close(f(Q), ref(Q), tol, f"{backend} {chain} {name} batch")
    J, H = kin.jacob0_hessian0(Q)
    assert_close(J, robot.jacob0(Q), 1e-12, "jacob0_hessian0 J")
    assert_close(H, robot.hessian0(Q), 1e-10, "jacob0_hessian0 H")
    T, J = kin.fkine_jacob0(q)
    assert_close(T, robot.fkine(q), 1e-12)
    assert_close(J, robot.jacob0(q), 1e-12)


@pytest.mark.parametrize("backend", BACKENDS)
def test_link_frame_jacobians_on_every_backend(backend):
    robot = load("panda")
    kin = symkin.compile(robot, backend=backend)
    q, Q = robot.random_q(seed=3), robot.random_q(4, seed=4)
    for k in range(robot.n):
        sub = truncated(robot, k)
        assert_close(kin.jacob0(q, frame=k)[:, : k + 1], sub.jacob0(q[: k + 1]), 1e-12, f"J0 frame {k}")
        assert_close(kin.jacobe(Q, frame=k)[:, :, : k + 1], sub.jacobe(Q[:, : k + 1]), 1e-12, f"Je {k}")
        assert not kin.jacob0(Q, frame=k)[:, :, k + 1 :].any()
        assert_close(kin.fkine(Q, k), robot.link_poses(Q)[:, k], 1e-12, f"T frame {k}")
    assert kin.jacob0(q, frame=None).shape == (6, 7)
    assert_close(kin.jacob0(q, frame=np.int64(2)), robot.jacob0(q, frame=2), 1e-12)
    for bad in (7, -1, 1.5, "2"):
        with pytest.raises(FrameError):
            kin.jacob0(q, frame=bad)


def test_c_frame_argument_is_checked_like_a_python_function():
    kin = symkin.compile(load("ur5"), backend="c")
    q = np.zeros(6)
    with pytest.raises(TypeError, match="unexpected keyword"):
        kin.jacob0(q, fram=2)
    with pytest.raises(TypeError, match="from 1 to 2 positional arguments but 3 were given"):
        kin.fkine(q, 1, 2)
    with pytest.raises(TypeError, match="from 1 to 3 positional arguments but 4 were given"):
        kin.jacobm(q, 1, "all", 2)
    with pytest.raises(TypeError, match="unexpected keyword"):
        kin.manipulability(q, axis="trans")
    with pytest.raises(TypeError, match="multiple values for argument 'frame'"):
        kin.hessian0(q, 1, frame=2)
    with pytest.raises(TypeError, match="unexpected keyword"):
        kin.hessian0(q, axes="all")
    assert kin.manipulability(q, axes="trans") == kin.manipulability(q, "trans")
    with pytest.raises(ValueError, match="axes given twice"):
        kin.manipulability(q, "trans", "rot")


def test_strategy_can_be_forced_and_is_part_of_the_cache_key():
    robot = load("ur5")
    a = symkin.compile(robot, "numpy", strategy="expanded")
    b = symkin.compile(robot, "numpy", strategy="program")
    assert a is not b
    assert "expanded" in a.files[next(iter(a.files))] and "straight-line" in b.files[next(iter(b.files))]
    q = robot.random_q(seed=1)
    assert_close(a.hessiane(q), b.hessiane(q), 1e-12)
    with pytest.raises(symkin.SymkinError, match="unknown strategy"):
        symkin.compile(robot, "numpy", strategy="fast")
