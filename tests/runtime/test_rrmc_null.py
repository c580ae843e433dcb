"""rrmc's null-space term: qd = J^+ nu + (I - J^+ J) qd_null on every backend (the C controller is
bypassed when qd_null is given)."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin import ParameterError, rrmc
from tests.conftest import assert_close

NU = np.array([0.05, -0.02, 0.03, 0.1, -0.05, 0.02])


@pytest.fixture(scope="module")
def panda() -> symkin.Robot:
    return symkin.load("panda")


@pytest.mark.parametrize("backend", [None, "c", "numpy"])
def test_null_space_motion_keeps_the_end_effector_velocity(panda, backend):
    kin = panda if backend is None else symkin.compile(panda, backend=backend)
    q = panda.random_q(seed=3)
    qd_null = np.linspace(-0.5, 0.5, panda.n)
    qd0, info0 = rrmc(kin, q, NU, qd_max=np.inf)
    qd, info = rrmc(kin, q, NU, qd_max=np.inf, qd_null=qd_null)
    assert info.status == info0.status == "solved"
    J = panda.jacob0(q)
    assert_close(J @ qd, NU, 1e-10, "the end-effector velocity is unchanged")
    assert_close(J @ qd0, NU, 1e-10)
    dn = qd - qd0
    assert np.linalg.norm(dn) > 0.1, "the null-space term moves the joints"
    assert_close(dn, qd_null - np.linalg.pinv(J) @ (J @ qd_null), 1e-10, "(I - J^+ J) qd_null")
    assert abs(dn @ qd0) < 1e-10, "orthogonal to the minimum-norm step"
    assert_close(rrmc(kin, q, NU, qd_max=np.inf, qd_null=np.zeros(panda.n))[0], qd0, 1e-12, "zero")


def test_null_space_motion_is_scaled_to_the_speed_limits(panda):
    q = panda.random_q(seed=4)
    qd_null = np.linspace(-5.0, 5.0, panda.n)
    raw, _ = rrmc(panda, q, NU, qd_max=np.inf, qd_null=qd_null)
    assert np.abs(raw).max() > 0.5
    qd, info = rrmc(panda, q, NU, qd_max=0.2, qd_null=qd_null)
    assert np.abs(qd).max() == pytest.approx(0.2) and info.scale < 1
    assert_close(qd, info.scale * raw, 1e-12, "the sum is scaled")
    J = panda.jacob0(q)
    assert_close(J @ qd, info.scale * NU, 1e-10, "direction of nu kept")


def test_a_square_jacobian_has_no_null_space():
    ur5 = symkin.load("ur5")
    q = ur5.random_q(seed=5)
    qd0, _ = rrmc(ur5, q, NU, qd_max=np.inf)
    qd, _ = rrmc(ur5, q, NU, qd_max=np.inf, qd_null=np.ones(6))
    assert_close(qd, qd0, 1e-9)


@pytest.mark.parametrize("bad", [np.zeros(6), np.full(7, np.nan), "fast", np.zeros((1, 7))])
def test_bad_qd_null_is_refused(panda, bad):
    with pytest.raises(ParameterError, match="qd_null"):
        rrmc(panda, panda.qr, NU, qd_null=bad)
