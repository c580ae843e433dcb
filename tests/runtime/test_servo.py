"""p_servo's frame (issue 36, item 14): required, "base" for jacob0 and "ee" for jacobe; the "ee"
velocity is the base-frame one rotated into the end effector, with gains, arrival and caps on its
axes; a ported jacobe loop converges with it and goes astray with the base-frame velocity.
(roboticstoolbox-python's p_servo: tests/test_coming_from_rtb.py.)"""

from __future__ import annotations

import math

import numpy as np
import pytest

import symkin
from symkin.errors import ParameterError, PoseError
from tests.runtime.rotations import pose, rot


@pytest.fixture(scope="module")
def kin():
    return symkin.compile("panda", backend="c")


def _target(kin):
    Tep = kin.fkine(kin.qr)
    return pose(rot([0, 0, 1], 0.5) @ Tep[:3, :3], Tep[:3, 3] + [0.1, 0.1, -0.1])


def test_the_frame_is_required_and_named_in_the_error(kin):
    Te, Tep = kin.fkine(kin.qr), _target(kin)
    for frame in (None, "world", 0, "EE"):
        with pytest.raises(
            ParameterError, match=r"frame='base'.*jacob0.*frame='ee'.*jacobe.*roboticstoolbox"
        ):
            symkin.p_servo(Te, Tep, frame=frame)
    with pytest.raises(TypeError):
        symkin.p_servo(Te, Tep, 1.0, 0.1, None, "ee")  # keyword only: a ported positional call fails loudly


def test_ee_velocity_is_the_base_velocity_rotated(kin):
    Te, Tep = kin.fkine(kin.qr), _target(kin)
    R = Te[:3, :3]
    base, _ = symkin.p_servo(Te, Tep, threshold=0, frame="base")
    ee, _ = symkin.p_servo(Te, Tep, threshold=0, frame="ee")
    np.testing.assert_allclose(ee, np.r_[R.T @ base[:3], R.T @ base[3:]], atol=1e-15)
    np.testing.assert_allclose(base, symkin.pose_error(Te, Tep), atol=0)
    # the Jacobians relate the same way: jacobe qd is the ee velocity of jacob0 qd
    q = kin.qr
    qd = np.linalg.pinv(kin.jacobe(q)) @ ee
    np.testing.assert_allclose(kin.jacob0(q) @ qd, base, atol=1e-12)
    # gains act on the ee axes: a gain on x alone scales the ee x component alone
    g = np.array([3.0, 1, 1, 1, 1, 1])
    ee_g, _ = symkin.p_servo(Te, Tep, gain=g, threshold=0, frame="ee")
    np.testing.assert_allclose(ee_g, g * ee, atol=1e-15)
    # arrival: sum |e| of the frame's error; caps keep their norms under rotation
    e_ee = np.abs(ee).sum()
    assert symkin.p_servo(Te, Tep, threshold=e_ee * 1.0001, frame="ee")[1]
    assert not symkin.p_servo(Te, Tep, threshold=e_ee * 0.9999, frame="ee")[1]
    capped, _ = symkin.p_servo(Te, Tep, threshold=0, nu_max=(0.01, 0.02), frame="ee")
    assert math.isclose(np.linalg.norm(capped[:3]), 0.01) and math.isclose(np.linalg.norm(capped[3:]), 0.02)


def test_a_ported_jacobe_loop_needs_the_ee_frame(kin):
    Tep = _target(kin)
    out = {}
    for frame in ("ee", "base"):
        q = kin.qr.copy()
        for _ in range(200):
            v, arrived = symkin.p_servo(kin.fkine(q), Tep, threshold=1e-3, frame=frame)
            if arrived:
                break
            q = q + 0.05 * np.linalg.pinv(kin.jacobe(q)) @ v
        out[frame] = (arrived, np.abs(symkin.pose_error(kin.fkine(q), Tep)).sum())
    assert out["ee"][0] and out["ee"][1] < 1e-3  # measured: 131 steps
    assert not out["base"][0] and out["base"][1] > 1.0  # measured: 5.0 after 200 steps


def test_poses_follow_the_pose_rule(kin):
    Te = kin.fkine(kin.qr)
    bad = Te.copy()
    bad[3] = [1.0, 0.0, 0.0, 1.0]
    with pytest.raises(PoseError, match="Tep has bottom row"):
        symkin.p_servo(Te, bad, frame="ee")
    with pytest.raises(PoseError, match="Te rotation is not orthonormal"):
        symkin.p_servo(Te * np.r_[2.0, 1, 1, 1][:, None], Te, frame="base")
