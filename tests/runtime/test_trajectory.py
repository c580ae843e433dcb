"""Trajectories (quintic, jtraj, trapezoidal, mstraj): values, the RTB semantics and extreme inputs.

Independent checks always run (boundary conditions, derivatives against finite differences, the
piecewise structure, finite samples or ParameterError over extreme inputs); the comparisons with
roboticstoolbox-python run only where it
is installed.
"""

from __future__ import annotations

import dataclasses
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symkin.errors import ParameterError
from symkin.runtime.cartesian import ctraj
from symkin.runtime.trajectory import MAX_SAMPLES, Trajectory, jtraj, mstraj, quintic, trapezoidal


def central(y: np.ndarray, h: float) -> np.ndarray:
    """Central differences of samples y (N, ...) spaced h apart, at samples 1..N-2."""
    return (y[2:] - y[:-2]) / (2 * h)


# -- quintic and jtraj --------------------------------------------------------------------------
def test_jtraj_boundary_conditions_and_shapes():
    q0, qf = np.array([0.1, -0.5, 2.0]), np.array([1.0, 0.5, -1.0])
    tr = jtraj(q0, qf, 50)
    assert isinstance(tr, Trajectory) and tr.name == "jtraj" and tr.istime
    assert len(tr) == 50 and tr.naxes == 3
    assert tr.q.shape == tr.qd.shape == tr.qdd.shape == (50, 3)
    np.testing.assert_allclose(tr.t, np.linspace(0, 1, 50))  # an int: normalised time 0..1
    np.testing.assert_allclose(tr.q[0], q0, atol=1e-15)
    np.testing.assert_allclose(tr.q[-1], qf, atol=1e-14)
    np.testing.assert_allclose(tr.qd[[0, -1]], 0, atol=1e-13)
    np.testing.assert_allclose(tr.qdd[[0, -1]], 0, atol=1e-12)
    # symmetric rest-to-rest quintic: midpoint halfway, peak speed 15/8 of the mean there
    np.testing.assert_allclose(jtraj(q0, qf, 51).q[25], (q0 + qf) / 2, atol=1e-14)
    np.testing.assert_allclose(jtraj(q0, qf, 51).qd[25], 15 / 8 * (qf - q0), rtol=1e-12)


def test_jtraj_time_vector_scales_the_polynomial_to_the_final_time():
    q0, qf, T = np.array([0.0, 1.0]), np.array([2.0, -1.0]), 2.5
    unit, timed = jtraj(q0, qf, 41), jtraj(q0, qf, np.linspace(0, T, 41))
    np.testing.assert_allclose(timed.t, np.linspace(0, T, 41))
    np.testing.assert_allclose(timed.q, unit.q, atol=1e-14)
    np.testing.assert_allclose(timed.qd, unit.qd / T, atol=1e-14)
    np.testing.assert_allclose(timed.qdd, unit.qdd / T**2, atol=1e-13)


def test_jtraj_given_boundary_velocities():
    q0, qf, v0, v1 = np.array([0.0, 1.0]), np.array([1.0, 0.0]), np.array([0.5, -1.0]), np.array([2.0, 0.3])
    tr = jtraj(q0, qf, np.linspace(0, 2, 21), qd0=v0, qd1=v1)
    np.testing.assert_allclose(tr.q[[0, -1]], [q0, qf], atol=1e-14)
    np.testing.assert_allclose(tr.qd[[0, -1]], [v0, v1], atol=1e-13)
    np.testing.assert_allclose(tr.qdd[[0, -1]], 0, atol=1e-12)


@pytest.mark.parametrize("make", ["jtraj", "quintic", "quintic-steps", "trapezoidal", "trapezoidal-V"])
def test_velocity_and_acceleration_are_the_derivatives_of_q(make):
    h = 1e-3
    t = np.arange(0, 2001) * h  # 0..2 s
    q0, qf = np.array([0.2, -1.0, 3.0]), np.array([1.5, 0.5, 3.0])
    tr = {
        "jtraj": lambda: jtraj(q0, qf, t, qd0=[0.1, 0, -0.2], qd1=[0, 0.4, 0]),
        "quintic": lambda: quintic(0.2, 1.5, t, qd0=-0.3, qdf=0.2),
        "quintic-steps": lambda: quintic(q0, qf, 2001),  # per step: h = 1
        "trapezoidal": lambda: trapezoidal(q0, qf, t),
        "trapezoidal-V": lambda: trapezoidal(0.2, 1.5, t, V=0.9),
    }[make]()
    h = float(tr.t[1] - tr.t[0])
    ok = np.ones(len(tr) - 2, dtype=bool)
    if make.startswith("trapezoidal"):  # qdd jumps where the blends meet the linear segment
        tb = np.atleast_1d(tr.info["tblend"])
        for b in tb[np.isfinite(tb)]:
            ok &= (np.abs(tr.t[1:-1] - b) > 1.5 * h) & (np.abs(tr.t[1:-1] - (tr.t[-1] - b)) > 1.5 * h)
    assert ok.sum() > 0.99 * len(ok)
    # central differences are exact to h^2 / 6 times the next derivative: 1e-5 of the scale here
    for y, dy in [(tr.q, tr.qd), (tr.qd, tr.qdd)]:
        scale = max(1.0, float(np.abs(dy).max()))
        np.testing.assert_allclose(central(y, h)[ok], dy[1:-1][ok], rtol=0, atol=1e-5 * scale)


def test_quintic_scalar_and_steps_as_rtb():
    tr = quintic(1.0, 2.0, 10)
    assert tr.name == "quintic" and not tr.istime and tr.q.shape == (10,) and tr.naxes == 1
    np.testing.assert_array_equal(tr.t, np.arange(10))  # an int: step numbers, as RTB's quintic
    s = np.arange(10) / 9
    np.testing.assert_allclose(tr.q, 1 + 10 * s**3 - 15 * s**4 + 6 * s**5, atol=1e-14)
    np.testing.assert_allclose(tr.qd, (30 * s**2 - 60 * s**3 + 30 * s**4) / 9, atol=1e-14)  # per step
    assert quintic([0, 1], [1, 3], 5).q.shape == (5, 2)


# -- trapezoidal --------------------------------------------------------------------------------
def test_trapezoidal_piecewise_structure_default_speed():
    t = np.linspace(0, 3, 301)
    tr = trapezoidal(1.0, 4.0, t)
    V, tb, a = 1.5 * 3 / 3, 1.0, 1.5  # V = 1.5 (qf - q0) / tf, tblend = tf / 3, a = V / tb
    assert tr.name == "trapezoidal" and tr.q.shape == (301,)
    assert tr.info["V"] == pytest.approx(V) and tr.info["tblend"] == pytest.approx(tb)
    blend1, blend2 = t < tb - 1e-9, t > 3 - tb + 1e-9
    linear = ~blend1 & ~blend2 & (np.abs(t - tb) > 1e-9) & (np.abs(t - (3 - tb)) > 1e-9)
    np.testing.assert_allclose(tr.qdd[blend1], a)  # constant acceleration in the blends
    np.testing.assert_allclose(tr.qdd[blend2], -a)
    np.testing.assert_allclose(tr.qdd[linear], 0)
    np.testing.assert_allclose(tr.qd[linear], V)  # the speed V is reached and held
    assert tr.qd.max() == pytest.approx(V)
    np.testing.assert_allclose(tr.q[blend1], 1 + a / 2 * t[blend1] ** 2)  # parabola
    np.testing.assert_allclose(np.diff(tr.q[linear]), V * 0.01, rtol=1e-9)  # straight line
    assert tr.q[0] == 1.0 and tr.q[-1] == pytest.approx(4.0, abs=1e-14)
    assert tr.qd[0] == 0 and tr.qd[-1] == pytest.approx(0, abs=1e-12)


def test_trapezoidal_given_speed_per_axis_and_bounds():
    t = np.linspace(0, 2, 201)
    tr = trapezoidal([0.0, 1.0, 5.0], [1.0, -1.0, 5.0], t, V=[0.75, 1.5, 1.0])  # axis 2 does not move
    assert tr.q.shape == (201, 3)
    np.testing.assert_allclose(tr.info["V"], [0.75, -1.5, 0.0])  # V takes the sign of qf - q0
    np.testing.assert_allclose(tr.info["tblend"][:2], [2 / 3, 2 / 3])  # tb = (q0 - qf + V tf) / V
    np.testing.assert_allclose(tr.qd.min(axis=0)[1], -1.5)
    np.testing.assert_allclose(tr.q[-1], [1.0, -1.0, 5.0], atol=1e-14)
    np.testing.assert_array_equal(tr.q[:, 2], 5.0)
    # the bounds: |qf - q0| / tf < |V| <= 2 |qf - q0| / tf
    tri = trapezoidal(0.0, 1.0, t, V=1.0)  # the upper bound: a triangle, blends of tf / 2
    assert tri.info["tblend"] == pytest.approx(1.0) and tri.qd.max() == pytest.approx(1.0)
    with pytest.raises(ParameterError, match="too small"):
        trapezoidal(0.0, 1.0, t, V=0.4)
    with pytest.raises(ParameterError, match="too small"):
        trapezoidal(0.0, 1.0, t, V=0.5)  # exactly |qf - q0| / tf: no time to accelerate
    with pytest.raises(ParameterError, match=r"too large \(axis 1\)"):
        trapezoidal([0.0, 0.0], [1.0, 1.0], t, V=[0.8, 1.01])
    with pytest.raises(ParameterError, match="too small"):
        trapezoidal(0.0, 1.0, t, V=0.0)


def test_trapezoidal_steps_as_rtb():
    tr = trapezoidal(1, 2, 10)
    assert not tr.istime
    np.testing.assert_array_equal(tr.t, np.arange(10))
    np.testing.assert_allclose(
        tr.q, [1, 1.0277778, 1.1111111, 1.25, 1.4166667, 1.5833333, 1.75, 1.8888889, 1.9722222, 2], atol=1e-7
    )


# -- mstraj -------------------------------------------------------------------------------------
VIA = np.array([[0.0, 0.0], [1.0, 2.0], [3.0, 1.0], [2.0, 0.0]])


def test_mstraj_segment_durations_speed_and_duration():
    dt, tacc, qdmax = 0.125, 0.5, np.array([2.0, 1.0])
    tr = mstraj(VIA, dt, tacc, qdmax=qdmax)
    assert tr.name == "mstraj" and tr.q.shape == tr.qd.shape == tr.qdd.shape == (len(tr), 2)
    # segment 0: axis 1 needs 2 / 1 = 2 s, plus the half blend 0.25 s; segments 1, 2: 1 s + 0.5 s
    np.testing.assert_allclose(tr.info["segtime"], [2.25, 1.5, 1.5])
    np.testing.assert_array_equal(tr.info["slowest"], [1, 0, 1])
    np.testing.assert_allclose(tr.info["arrive"], np.cumsum([2.25, 1.5, 1.5]))
    assert tr.t[-1] == pytest.approx(5.25)  # the duration is the sum of the segment times
    np.testing.assert_allclose(np.diff(tr.t), dt)
    np.testing.assert_array_equal(tr.q[0], VIA[0])  # starts at the first row at rest
    np.testing.assert_allclose(tr.q[-1], VIA[-1], atol=1e-14)  # ends at the last at rest
    np.testing.assert_allclose(tr.qd[[0, -1]], 0, atol=1e-12)
    # linear parts (qdd = 0) move at dq / segtime, within qdmax; the slowest axis sets the time
    linear = np.all(tr.qdd == 0, axis=1)
    linear[0] = False
    assert linear.sum() > len(tr) // 2
    assert (np.abs(tr.qd[linear]) <= qdmax + 1e-12).all()
    speeds = {tuple(np.round(v, 12)) for v in tr.qd[linear]}
    expected = [np.diff(VIA, axis=0)[i] / tr.info["segtime"][i] for i in range(3)]
    assert speeds == {tuple(np.round(v, 12)) for v in expected}


def test_mstraj_passes_near_via_points_and_through_them_without_blends():
    dt, qdmax = 0.02, [1.0, 1.0]
    sharp = mstraj(VIA, dt, 0.0, qdmax=qdmax)  # tacc = 0: straight lines through every via point
    for w in VIA[1:]:
        assert np.linalg.norm(sharp.q - w, axis=1).min() < 1e-12
    smooth = mstraj(VIA, dt, 0.4, qdmax=qdmax)
    for w, v_in, v_out in zip(VIA[1:-1], np.diff(VIA, axis=0)[:-1], np.diff(VIA, axis=0)[1:], strict=True):
        miss = np.linalg.norm(smooth.q - w, axis=1).min()
        assert 1e-3 < miss < 0.2 * max(np.linalg.norm(v_in), np.linalg.norm(v_out))  # cuts the corner
    np.testing.assert_allclose(smooth.q[-1], VIA[-1], atol=1e-14)


def test_mstraj_derivatives_and_continuity():
    dt = 0.002
    tr = mstraj(VIA, dt, 0.5, qdmax=[2.0, 1.0], qd0=[0.3, 0.0])
    np.testing.assert_allclose(tr.qd[0], [0.3, 0.0])
    h = dt
    jerk = np.abs(np.diff(tr.qdd, axis=0)).max() / h
    np.testing.assert_allclose(central(tr.q, h), tr.qd[1:-1], rtol=0, atol=1.2 * h**2 / 6 * jerk)  # 3.3e-4
    # qdd is continuous (the blends start and end with zero acceleration) but the jerk jumps where a blend
    # meets a linear part, which central differences of qd blur by h |jerk| / 4: leave those samples out
    linear = np.all(tr.qdd == 0, axis=1)
    ok = linear[:-2] == linear[2:]
    assert (~ok).sum() <= 16  # two samples at each end of each of the 4 blends
    np.testing.assert_allclose(
        central(tr.qd, h)[ok], tr.qdd[1:-1][ok], rtol=0, atol=1e-3 * np.abs(tr.qdd).max()
    )
    assert np.abs(np.diff(tr.qd, axis=0)).max() < 20 * h  # no velocity jumps


def test_mstraj_tsegment_and_q0():
    tr = mstraj(VIA[1:], 0.1, 0.2, tsegment=[3.0, 2.0, 2.0], q0=VIA[0])
    np.testing.assert_allclose(tr.info["segtime"], [3.0, 2.0, 2.0])
    assert tr.t[-1] == pytest.approx(7.0)
    np.testing.assert_array_equal(tr.q[0], VIA[0])
    np.testing.assert_array_equal(tr.info["slowest"], [-1, -1, -1])
    np.testing.assert_allclose(mstraj(VIA, 0.1, 0.2, tsegment=[3.0, 2.0, 2.0]).q, tr.q)


def test_mstraj_bad_input():
    with pytest.raises(ParameterError, match="tacc must be >= 0"):
        mstraj(VIA, 0.1, -0.1, qdmax=1.0)
    with pytest.raises(ParameterError, match="dt must be"):
        mstraj(VIA, 0.0, 0.1, qdmax=1.0)
    with pytest.raises(ParameterError, match="exactly one of qdmax"):
        mstraj(VIA, 0.1, 0.1)
    with pytest.raises(ParameterError, match="exactly one of qdmax"):
        mstraj(VIA, 0.1, 0.1, qdmax=1.0, tsegment=[1, 1, 1])
    with pytest.raises(ParameterError, match="qdmax must be"):
        mstraj(VIA, 0.1, 0.1, qdmax=[1.0, 0.0])
    with pytest.raises(ParameterError, match="qdmax must be"):
        mstraj(VIA, 0.1, 0.1, qdmax=[1.0, 1.0, 1.0])
    with pytest.raises(ParameterError, match="tsegment must be 3"):
        mstraj(VIA, 0.1, 0.1, tsegment=[1.0, 1.0])
    with pytest.raises(ParameterError, match="too short"):
        mstraj(VIA, 0.1, 1.0, tsegment=[1.0, 1.0, 1.0])
    with pytest.raises(ParameterError, match="finite"):
        mstraj(np.array([[0.0, 0.0], [1.0, np.nan]]), 0.1, 0.1, qdmax=1.0)
    with pytest.raises(ParameterError, match="q0 must have shape"):
        mstraj(VIA, 0.1, 0.1, qdmax=1.0, q0=[0.0, 0.0, 0.0])
    with pytest.raises(ParameterError, match="at least 2 rows"):
        mstraj(VIA[:1], 0.1, 0.1, qdmax=1.0)
    with pytest.raises(ParameterError, match="tacc must be a number or 3"):
        mstraj(VIA, 0.1, [0.1, 0.2], qdmax=1.0)


# -- input checks shared by the generators --------------------------------------------------------
@pytest.mark.parametrize("fn", [quintic, jtraj, trapezoidal])
def test_bad_times_and_endpoints(fn):
    with pytest.raises(ParameterError, match="strictly increasing"):
        fn([0.0, 1.0], [1.0, 2.0], [0.0, 0.5, 0.5, 1.0])
    with pytest.raises(ParameterError, match="strictly increasing"):
        fn([0.0, 1.0], [1.0, 2.0], [0.0, 1.0, 0.5])
    with pytest.raises(ParameterError, match="finite"):
        fn([0.0, 1.0], [1.0, 2.0], [0.0, np.nan, 1.0])
    if fn is jtraj:  # jtraj's motion starts at time 0; quintic's and trapezoidal's at t[0] (as RTB 1.5)
        with pytest.raises(ParameterError, match="time >= 0"):
            fn([0.0, 1.0], [1.0, 2.0], [-1.0, 0.0, 1.0])
    with pytest.raises(ParameterError, match="at least 2"):
        fn([0.0, 1.0], [1.0, 2.0], 1)
    with pytest.raises(ParameterError, match="at least 2 times"):
        fn([0.0, 1.0], [1.0, 2.0], 2.0)
    with pytest.raises(ParameterError, match="one length"):
        fn([0.0, 1.0], [1.0, 2.0, 3.0], 10)
    with pytest.raises(ParameterError, match="q0 must be finite"):
        fn([0.0, np.nan], [1.0, 2.0], 10)
    with pytest.raises(ParameterError, match="qf must be finite"):
        fn([0.0, 0.0], [np.inf, 2.0], 10)


def test_bad_boundary_velocities():
    with pytest.raises(ParameterError, match="qd0 must be a number or 2"):
        jtraj([0, 1], [1, 2], 10, qd0=[1, 2, 3])
    with pytest.raises(ParameterError, match="qdf must be finite"):
        quintic(0, 1, 10, qdf=np.nan)
    with pytest.raises(ParameterError, match="V must be a number or 2"):
        trapezoidal([0, 1], [1, 2], 10, V=[1, 2, 3])


# -- t[0] > 0: the motion runs from t[0] (RTB 1.5) ------------------------------------------------
@pytest.mark.parametrize("fn", [quintic, trapezoidal])
def test_a_time_vector_starting_later_starts_the_motion_at_its_first_time(fn):
    """quintic and trapezoidal run from t[0] to t[-1], as RTB 1.5 (roboticstoolbox.tools.trajectory:
    ``tf = tv[-1] - tv[0]``, evaluated at ``tv - tv[0]``): the same samples as over t - t[0]."""
    tau = np.linspace(0, 2, 21)
    for start in (1.5, -3.0, 1e6):
        late, early = fn([0.2, -1.0], [1.0, 2.0], start + tau), fn([0.2, -1.0], [1.0, 2.0], tau)
        np.testing.assert_array_equal(late.t, start + tau)
        for a, b in ((late.q, early.q), (late.qd, early.qd), (late.qdd, early.qdd)):
            np.testing.assert_allclose(a, b, atol=1e-9 * max(1.0, start))  # t - t[0] rounds near 1e6
        np.testing.assert_array_equal(late.q[0], [0.2, -1.0])
        np.testing.assert_allclose(late.q[-1], [1.0, 2.0], atol=1e-14)


def test_jtraj_keeps_its_motion_from_time_zero():
    """RTB's jtraj scales by max(t) (normalised time t / t[-1]): a vector starting later samples the
    same polynomial from time 0, so its first sample is already on the way."""
    tr = jtraj([0.0], [1.0], np.array([2.0, 2.5, 3.0]))
    s = np.array([2.0, 2.5, 3.0]) / 3.0
    np.testing.assert_allclose(tr.q[:, 0], 10 * s**3 - 15 * s**4 + 6 * s**5, atol=1e-15)


# -- extreme inputs: finite samples or ParameterError, never NaN or inf (issue 36, item 5) ----------
def _outcome(fn, *args, **kwargs):
    """fn's Trajectory, or the ParameterError it raised; any warning (overflow, invalid) fails."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            return fn(*args, **kwargs)
        except ParameterError as exc:
            return exc


def _finite_trajectory(tr) -> None:
    if isinstance(tr, ParameterError):
        return
    for a in (tr.t, tr.q, tr.qd, tr.qdd):
        assert np.isfinite(a).all(), tr


def test_the_reported_inputs_give_finite_samples_or_raise():
    """trapezoidal(0, 1, [0, 1e-155]): acceleration 4.5e310 from t = 0; a quintic over 1e-170 s:
    accelerations up to 5.8e340 inside; endpoints +-1e308 over one second: velocity 3.75e308. At
    a quintic's two ends alone (the reported t = [0, 1e-170]) the samples are finite and exact: q0,
    qf, and the boundary velocities and accelerations, 0."""
    inner = [0.0, 0.25e-170, 1e-170]
    for make in (
        lambda: trapezoidal(0, 1, [0, 1e-155]),
        lambda: quintic(0, 1, inner),
        lambda: jtraj([0.0], [1.0], inner),
        lambda: jtraj([-1e308], [1e308], 50),
        lambda: quintic(-1e308, 1e308, [0.0, 0.25, 1.0]),
        lambda: trapezoidal(-1e308, 1e308, [0.0, 1.0]),
    ):
        with pytest.raises(ParameterError, match="exceed the range of a double"):
            make()
    for tr in (quintic(0, 1, [0, 1e-170]), jtraj([0.0], [1.0], [0, 1e-170])):
        np.testing.assert_array_equal(np.ravel(tr.q), [0.0, 1.0])
        assert not np.ravel(tr.qd).any() and not np.ravel(tr.qdd).any()


def test_extreme_but_representable_trajectories_come_out_finite_and_exact():
    """Positions near the range of a double are evaluated in units of a power of two: the samples
    are those of the same trajectory scaled down by 2**1000, times 2**1000, to the bit."""
    big = 2.0**1000
    t = np.linspace(0, 10, 41)
    for fn in (jtraj, quintic, trapezoidal):
        small = fn([-1.5, 0.25, 1.0], [1.5, -0.5, 1.0], t)
        huge = fn([-1.5 * big, 0.25 * big, big], [1.5 * big, -0.5 * big, big], t)
        for a, b in ((huge.q, small.q), (huge.qd, small.qd), (huge.qdd, small.qdd)):
            assert np.isfinite(a).all()
            np.testing.assert_array_equal(a, b * big)
    tr = jtraj([-1e308], [1e308], np.linspace(0, 10, 11))  # 2e308 apart: |qf - q0| is beyond a double
    assert np.isfinite(tr.q).all() and tr.q[0, 0] == -1e308 and tr.q[-1, 0] == 1e308
    assert abs(tr.q[5, 0]) < 1e293  # the middle, 0 up to rounding of 1e308
    assert tr.qd.max() == pytest.approx(15 / 8 * 2 * (1e308 / 10), rel=1e-12)  # 15/8 |qf - q0| / T
    still = quintic(3.0, 3.0, [0.0, 1e-300, 2e-300])  # no motion: zero over any duration
    assert (still.q == 3.0).all() and (still.qd == 0).all() and (still.qdd == 0).all()


def test_sizes_beyond_max_samples_are_refused():
    for make in (
        lambda: quintic(0, 1, 10**12),
        lambda: trapezoidal(0, 1, MAX_SAMPLES + 1),
        lambda: jtraj([0.0], [1.0], 10**20),
        lambda: mstraj(VIA, 0.1, 1e300, qdmax=1.0),
        lambda: mstraj(VIA, 5e-324, 0.5, qdmax=1.0),
        lambda: mstraj(VIA, 0.1, 0.5, qdmax=1e-300),
        lambda: mstraj(VIA, 1e-9, 0.5, tsegment=[1.0, 1.0, 1.0]),
    ):
        with pytest.raises(ParameterError, match="samples"):
            make()


def test_mstraj_far_via_points_and_huge_times():
    far = np.array([[-1e308, 0.0], [1e308, 1.0]])
    for kwargs in ({"qdmax": 1e300}, {"tsegment": [1.0]}):
        _finite_trajectory(_outcome(mstraj, far, 0.1, 0.2, **kwargs))
    with pytest.raises(ParameterError, match="double"):
        mstraj(far, 0.1, 0.2, tsegment=[1.0])  # 2e308 in one second
    _finite_trajectory(_outcome(mstraj, VIA, 1e300, 0.0, qdmax=1.0))  # times up to 3e300


_FLOATS = st.floats(allow_nan=False, allow_infinity=False)
_TIMES = st.lists(_FLOATS, min_size=2, max_size=6, unique=True).map(sorted)
_MAGNITUDES = st.sampled_from(
    [0.0, 5e-324, 1e-300, 1e-170, 1e-9, 1.0, 1e9, 1e154, 1e300, 1.7976931348623157e308]
)


@settings(max_examples=300, deadline=None)
@given(q0=_FLOATS, qf=_FLOATS, v0=_FLOATS, v1=_FLOATS, t=_TIMES, m=st.integers(2, 40))
def test_quintic_jtraj_and_trapezoidal_are_finite_or_refused(q0, qf, v0, v1, t, m):
    for tr in (
        _outcome(quintic, q0, qf, t, qd0=v0, qdf=v1),
        _outcome(quintic, q0, qf, m),
        _outcome(jtraj, [q0], [qf], [abs(x) for x in t] if t[0] < 0 else t, qd0=[v0], qd1=[v1]),
        _outcome(jtraj, [q0, qf], [qf, q0], m),
        _outcome(trapezoidal, q0, qf, t),
        _outcome(trapezoidal, q0, qf, m),
        _outcome(trapezoidal, q0, qf, t, V=v0),
    ):
        _finite_trajectory(tr)
        if not isinstance(tr, ParameterError):
            assert (np.ravel(tr.q[0]) == np.ravel(q0)).all() or tr.name == "jtraj"


@settings(max_examples=150, deadline=None)
@given(
    scale=_MAGNITUDES, dt=_MAGNITUDES, tacc=_MAGNITUDES, speed=_MAGNITUDES, sign=st.sampled_from([1.0, -1.0])
)
def test_mstraj_is_finite_or_refused(scale, dt, tacc, speed, sign):
    via = sign * scale * np.array([[0.0, 0.0], [1.0, -1.0], [-1.0, 0.5]])
    if dt > 0:
        _finite_trajectory(_outcome(mstraj, via, dt, tacc, qdmax=speed) if speed > 0 else ParameterError())
        _finite_trajectory(_outcome(mstraj, via, dt, tacc, tsegment=[max(speed, 1e-300)] * 2))


def test_ctraj_with_far_poses_and_extreme_times():
    A, B = np.eye(4), np.eye(4)
    A[:3, 3], B[:3, 3] = -1e308, 1e308
    for t in (20, [0.0, 1e-300, 1e300], [0.0, 5e-324]):
        P = ctraj(A, B, t)
        assert np.isfinite(P).all() and (P[0] == A).all() and (P[-1] == B).all()


# -- the Trajectory object ----------------------------------------------------------------------
def test_trajectory_is_frozen_and_read_only():
    tr = jtraj([0, 0], [1, 1], 5)
    with pytest.raises(dataclasses.FrozenInstanceError):
        tr.q = np.zeros((5, 2))  # type: ignore[misc]
    with pytest.raises(ValueError, match="read-only"):
        tr.q[0, 0] = 1.0
    with pytest.raises(TypeError):
        trapezoidal(0, 1, 5).info["V"] = 2  # type: ignore[index]
    assert "jtraj" in repr(tr) and "5 samples x 2 axes" in repr(tr)
    assert tr.s is tr.q and tr.sd is tr.qd and tr.sdd is tr.qdd


def test_plot_returns_a_figure_with_q_qd_qdd():
    pytest.importorskip("matplotlib")
    fig = mstraj(VIA, 0.1, 0.4, qdmax=1.0).plot()
    axes = fig.get_axes()
    assert len(axes) == 3
    assert [len(ax.get_lines()) for ax in axes] == [2, 2, 2]
    assert axes[-1].get_xlabel() == "t (s)"
    assert quintic(0, 1, 10).plot().get_axes()[-1].get_xlabel() == "k (step)"


# -- roboticstoolbox-python, where it is installed ---------------------------------------------
@pytest.fixture(scope="module")
def rtb():
    return pytest.importorskip("roboticstoolbox")


def test_rtb_quintic_jtraj_trapezoidal(rtb):
    q0, qf = np.array([0.1, -0.5, 2.0]), np.array([1.0, 0.5, -1.0])
    v0, v1 = np.array([0.1, 0, 0]), np.array([0, 0.2, 0])
    t = np.linspace(0, 2, 30)
    for ours, theirs in [
        (quintic(0.2, 1.5, 20), rtb.quintic(0.2, 1.5, 20)),
        (quintic(0.2, 1.5, t, qd0=0.3, qdf=-0.1), rtb.quintic(0.2, 1.5, t, qd0=0.3, qdf=-0.1)),
        (trapezoidal(0.2, 1.5, 20), rtb.trapezoidal(0.2, 1.5, 20)),
        (trapezoidal(1.5, 0.2, t, V=1.0), rtb.trapezoidal(1.5, 0.2, t, V=1.0)),
        (jtraj(q0, qf, t, qd0=v0, qd1=v1), rtb.jtraj(q0, qf, t, qd0=v0, qd1=v1)),
    ]:
        np.testing.assert_allclose(ours.t, theirs.t, atol=1e-12)
        for a, b in [(ours.q, theirs.q), (ours.qd, theirs.qd), (ours.qdd, theirs.qdd)]:
            np.testing.assert_allclose(a, b, atol=1e-9)
    ours, theirs = jtraj(q0, qf, 25), rtb.jtraj(q0, qf, 25)  # RTB's t differs (linspace(0, 25, 25))
    for a, b in [(ours.q, theirs.q), (ours.qd, theirs.qd), (ours.qdd, theirs.qdd)]:
        np.testing.assert_allclose(a, b, atol=1e-9)
    assert trapezoidal(0.2, 1.5, t).info["tblend"] == pytest.approx(rtb.trapezoidal(0.2, 1.5, t).tblend)


def test_rtb_mstraj(rtb):
    for kwargs in [{"qdmax": [2.0, 1.0]}, {"tsegment": np.array([3.0, 2.0, 2.0])}]:
        ours, theirs = mstraj(VIA, 0.125, 0.5, **kwargs), rtb.mstraj(VIA, 0.125, 0.5, **kwargs)
        np.testing.assert_allclose(ours.q[1:], theirs.q, atol=1e-12)  # RTB leaves out the start q0
        np.testing.assert_allclose(ours.info["arrive"], theirs.arrive, atol=1e-12)
