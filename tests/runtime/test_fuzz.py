"""Property-based fuzzing of numeric inputs (issue 12): joint configurations of any dtype, byte
order, shape and value, IK options and targets, MMC parameters. Every call gives a correct result
(the numeric reference's, a verified IK solution, a finite joint velocity within its bounds) or a
SymkinError, the same on every backend. Example counts are bounded to keep CI fast."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import symkin
from symkin.errors import SymkinError
from symkin.runtime.control import MMC

FUZZ = settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
FEW = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])

ROBOT = symkin.load("panda")  # compiled (C, NumPy, CasADi, C MMC) by other tests of the session too
N = ROBOT.n
_KINS: dict[str, object] = {}


def kin(backend: str):
    if backend not in _KINS:
        _KINS[backend] = symkin.compile(ROBOT, backend=backend)
    return _KINS[backend]


VALUES = st.one_of(
    st.floats(-10, 10, allow_nan=False),
    st.sampled_from(
        [0.0, -0.0, math.nan, math.inf, -math.inf, 1e15, -1e15, 1.0000000000000002e15, 1e300, 5e-324]
    ),
)
DTYPES = st.sampled_from(["<f8", ">f8", "<f4", ">f4", "<i4", ">i8", "u1", "?", "<c16", "f2"])
SHAPES = st.sampled_from([(N,), (0, N), (1, N), (3, N), (N - 1,), (2, N + 1), (1, 1, N), ()])


@st.composite
def joint_arrays(draw):
    dtype = np.dtype(draw(DTYPES))
    shape = draw(SHAPES)
    with np.errstate(all="ignore"):
        a = np.array(draw(hnp.arrays(np.float64, shape, elements=VALUES))).astype(dtype)
    if draw(st.booleans()) and a.ndim == 2 and a.shape[0] > 1:
        a = a[::-1]  # negative strides
    return a


def _outcome(f, q):  # noqa: ANN001, ANN202
    try:
        return f(q)
    except SymkinError as exc:
        return exc


@FUZZ
@given(q=joint_arrays(), name=st.sampled_from(["fkine", "jacob0", "hessian0", "jacobe", "manipulability"]))
def test_any_q_gives_the_reference_answer_or_its_error_on_every_backend(q, name):
    want = _outcome(getattr(ROBOT, name), q)
    for backend in ("c", "numpy", "casadi"):
        got = _outcome(getattr(kin(backend), name), q)
        if isinstance(want, SymkinError):
            assert type(got) is type(want) and str(got) == str(want), (backend, got, want)
            continue
        assert not isinstance(got, BaseException), (backend, got)
        got, want_a = np.asarray(got), np.asarray(want)
        if name == "manipulability":  # sqrt(det) amplifies rounding at singularities: compare det
            got, want_a = got**2, want_a**2
        assert got.shape == want_a.shape and np.isfinite(got).all(), backend
        qmax = float(np.abs(np.asarray(q, dtype=float)).max(initial=0.0))
        tol = 1e-10 + 8 * N * qmax * 2.0**-53  # angle sums round (docs/guide/accuracy.md)
        scale = max(1.0, float(np.abs(want_a).max(initial=0.0)))
        assert np.abs(got - want_a).max(initial=0.0) <= tol * scale, backend


TARGET_Q = hnp.arrays(np.float64, (N,), elements=st.floats(-1.5, 1.5, allow_nan=False))


def _mostly(valid, *invalid):  # noqa: ANN001, ANN202
    """A valid value three times in four, else one of the invalid ones."""
    return st.one_of(valid, valid, valid, st.sampled_from(invalid))


@FEW
@given(
    q=TARGET_Q,
    ilimit=_mostly(st.integers(1, 60), 0, -2, 2**32 + 1, 2.5, True, "30"),
    slimit=_mostly(st.integers(1, 20), 0, 2**31, math.nan),
    tol=_mostly(st.floats(1e-10, 1e-3), 0.0, -1e-6, math.nan, math.inf),
    lam=_mostly(st.floats(0, 1), math.nan, -0.1, math.inf),
    solver=st.sampled_from(["c", "numpy"]),
    seed=st.integers(0, 2**64 - 1),
)
def test_ik_options_give_a_verified_solution_or_a_symkin_error(q, ilimit, slimit, tol, lam, solver, seed):
    Tep = ROBOT.fkine(q)
    try:
        res = kin("c").ik(Tep, ilimit=ilimit, slimit=slimit, tol=tol, lam=lam, backend=solver, seed=seed)
    except SymkinError:
        return
    assert np.isfinite(res.q).all() and res.iterations <= int(ilimit) * int(slimit)
    if res.success:  # every success is verified against its own target
        e = symkin.pose_error(ROBOT.fkine(res.q), Tep)
        assert np.linalg.norm(e) < 10 * tol + 1e-12
        assert ROBOT.within_limits(res.q)


POSE_ENTRIES = st.one_of(st.floats(-2, 2, allow_nan=False), st.sampled_from([math.nan, math.inf, 1e300]))


@FEW
@given(
    T=st.one_of(
        hnp.arrays(
            np.float64, st.sampled_from([(4, 4), (2, 4, 4), (0, 4, 4), (4, 3), (16,)]), elements=POSE_ENTRIES
        ),
        TARGET_Q.map(lambda q: ROBOT.fkine(q).astype(">f8")),
        TARGET_Q.map(lambda q: ROBOT.fkine(q) + 0j),
    ),
    solver=st.sampled_from(["c", "numpy"]),
)
def test_ik_targets_give_a_verified_result_or_a_symkin_error(T, solver):
    try:
        res = kin("c").ik(T, backend=solver, seed=0, slimit=3)
    except SymkinError:
        return
    T = np.asarray(T, dtype=float)
    if T.ndim == 2:
        res, T = res.__class__(res.q[None], np.array([res.success]), None, None, None, (res.reason,)), T[None]
    for q, ok, target in zip(res.q, np.atleast_1d(res.success), T):
        if ok:
            assert np.linalg.norm(symkin.pose_error(ROBOT.fkine(q), target)) < 1e-5


@FEW
@given(
    dt=_mostly(st.none() | st.floats(1e-4, 1), math.nan, math.inf, 0.0, -0.1),
    xi=_mostly(st.floats(0.01, 5), math.nan, math.inf, 0.0),
    rho_i=_mostly(st.floats(0.2, 1), math.nan, -1.0),
    rho_s=_mostly(st.floats(0, 0.15), -0.1, math.inf),
    lam=_mostly(st.floats(1e-4, 1), math.nan, 0.0),
    qd_max=_mostly(st.none() | st.floats(0.05, 3) | st.just(math.inf), math.nan, 0.0, -1.0),
    joint_limits=st.booleans(),
    backend=st.sampled_from(["python", "auto"]),
    q=TARGET_Q,
    nu=hnp.arrays(np.float64, (6,), elements=st.floats(-0.5, 0.5, allow_nan=False)),
)
def test_mmc_parameters_give_finite_bounded_steps_or_a_symkin_error(
    dt, xi, rho_i, rho_s, lam, qd_max, joint_limits, backend, q, nu
):
    k = kin("c") if backend == "auto" else ROBOT
    try:
        mmc = MMC(k, dt=dt, xi=xi, rho_i=rho_i, rho_s=rho_s, lam=lam, qd_max=qd_max,
                  joint_limits=joint_limits, backend=backend)  # fmt: skip
    except SymkinError:
        return
    q = np.clip(q, ROBOT.qlim[0], ROBOT.qlim[1])
    qd, info = mmc.step(q, nu)
    assert qd.shape == (N,) and np.isfinite(qd).all()
    assert info.status != "solved" or np.isfinite(info.residual)
    lower, upper = mmc.bounds(q)
    assert (qd >= lower - 1e-9).all() and (qd <= upper + 1e-9).all()
