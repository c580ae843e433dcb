"""One rule for joint values and poses at every entry point, on every backend (issue 23, items 3 and
10-13): the same hostile input gives the rule's error (same class, same message) everywhere, or the
answer each entry point gives for the rule's float64 conversion of it.

The rule is symkin.model.robot.real_array (conversion: any byte order, precision up to long double,
object arrays of real numbers; complex, strings, objects and numbers beyond a double refused), then
as_batch / as_config / as_rows (shape, finite, |q| <= 1e15) for joint values and check_pose for poses.
The entry points: the reference model, compiled chains and trees on C, NumPy and CasADi, the
numerical IK seeds (NumPy and C solvers), the closed form's q0 and T (C, NumPy, CasADi), the
free-joint closed form, the controllers (MMC on the Python and C paths, RRMC) and the servo loop.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

import symkin
from symkin import Tree
from symkin.core.arrays import MAX_JOINT_VALUE, as_batch, as_config
from symkin.errors import ConfigurationError, PoseError, RobotError, SymkinError
from symkin.runtime.control import MMC, rrmc
from symkin.runtime.ik import check_pose
from tests.model.tree_urdfs import QUADRUPED

BACKENDS = ("c", "numpy", "casadi")
Q_UR5 = np.array([0.3, -1.0, 1.2, 0.4, 0.5, 0.5])


def _unaligned(a: np.ndarray) -> np.ndarray:
    buf = np.zeros(a.nbytes + 1, dtype=np.uint8)
    out = np.frombuffer(buf.data, dtype=a.dtype, count=a.size, offset=1).reshape(a.shape)
    out[...] = a
    return out


def hostile_q(q: np.ndarray) -> dict[str, object]:
    """Inputs for a joint-value argument of n = len(q) joints, named."""
    n = len(q)
    big = np.r_[1e16, q[1:]]
    return {
        "float64": q.copy(),
        "big-endian": q.astype(">f8"),
        "long double": q.astype(np.longdouble),
        "float16": q.astype(np.float16),
        "float32 unaligned": _unaligned(q.astype(np.float32)),
        "float64 unaligned": _unaligned(q),
        "int32": np.round(q).astype(np.int32),
        "uint64": np.abs(np.round(q)).astype(np.uint64),
        "bools": q > 0,
        "list": q.tolist(),
        "object Fractions": np.array([Fraction(x).limit_denominator(100) for x in q], dtype=object),
        "Python int beyond int64": [2**70] + [0] * (n - 1),
        "10**400": [10**400] + [0] * (n - 1),
        "Fraction beyond a double": np.array([Fraction(10**400, 3)] + [0] * (n - 1), dtype=object),
        "long double 1e400": np.r_[np.longdouble("1e400"), q[1:].astype(np.longdouble)],
        "1e15 exactly": np.r_[MAX_JOINT_VALUE, q[1:]],
        "just beyond 1e15": np.r_[np.nextafter(MAX_JOINT_VALUE, np.inf), q[1:]],
        "1e16": big,
        "1e16 big-endian": big.astype(">f8"),
        "1e16 list": big.tolist(),
        "1e300": np.r_[q[:-1], 1e300],
        "nan": np.r_[q[:-1], np.nan],
        "inf": np.r_[np.inf, q[1:]],
        "-inf long double": np.r_[-np.inf, q[1:]].astype(np.longdouble),
        "empty batch": np.zeros((0, n)),
        "batch": np.stack([q, -q]),
        "batch with nan": np.stack([q, np.r_[q[:-1], np.nan]]),
        "wrong length": np.zeros(n + 1),
        "3-d": np.zeros((1, 1, n)),
        "scalar": 0.5,
        "ragged": [[0.0] * n, [0.0]],
        "complex": q + 0j,
        "complex list": [0.0] * (n - 1) + [1j],
        "strings": q.astype(str),
        "objects": np.array([object()] * n),
    }


def outcome(f, *args, **kwargs):  # noqa: ANN001, ANN002, ANN003, ANN201
    """f's result, or the SymkinError it raised (anything else propagates and fails the test)."""
    try:
        return f(*args, **kwargs)
    except SymkinError as exc:
        return exc


def arrays(result) -> list[np.ndarray]:  # noqa: ANN001
    """The arrays of a result: a tuple of arrays, an IKResult, an (qd, StepInfo) pair, a ServoResult."""
    if hasattr(result, "success") and hasattr(result, "q"):  # IKResult
        return [np.asarray(result.q), np.asarray(result.success)]
    if hasattr(result, "q") and hasattr(result, "qd"):  # ServoResult
        return [np.asarray(result.q), np.asarray(result.qd)]
    if isinstance(result, tuple):
        return [np.asarray(r) for r in result if isinstance(r, (np.ndarray, float, int, bool))]
    return [np.asarray(result)]


def check_same(label: str, f, x, rule) -> None:  # noqa: ANN001
    """f(x) is rule(x)'s error (class and message), or f(x) equals f(rule(x)) (the converted input)."""
    want = outcome(rule, x)
    got = outcome(f, x)
    if isinstance(want, SymkinError):
        assert isinstance(got, SymkinError), f"{label}: accepted what the rule refuses ({want})"
        assert (type(got), str(got)) == (type(want), str(want)), label
        return
    assert not isinstance(got, SymkinError), f"{label}: refused what the rule accepts: {got!r}"
    converted = np.ascontiguousarray(want[0] if isinstance(want, tuple) else want)
    if isinstance(want, tuple) and want[1]:  # as_batch: one configuration comes back as (1, n)
        converted = converted[0]
    for a, b in zip(arrays(got), arrays(f(converted)), strict=True):
        assert a.shape == b.shape and np.array_equal(a, b, equal_nan=True), label


# -- compiled objects (module scope: compiled once, shared through the compile cache) ----------
@pytest.fixture(scope="module")
def ur5():
    return symkin.load("ur5")


@pytest.fixture(scope="module")
def kins(ur5):
    return {b: symkin.compile(ur5, backend=b) for b in BACKENDS}


@pytest.fixture(scope="module")
def tree():
    return Tree.from_urdf(QUADRUPED)


@pytest.fixture(scope="module")
def tree_kins(tree):
    return {b: symkin.compile(tree, backend=b) for b in BACKENDS}


NAMES = sorted(hostile_q(Q_UR5))


@pytest.mark.parametrize("what", NAMES)
def test_kinematics_of_chains_and_trees_follow_the_rule(what, ur5, kins, tree, tree_kins):
    """q of the reference, of C, NumPy and CasADi chains (one configuration and batches) and trees."""
    x = hostile_q(Q_UR5)[what]
    rule = lambda v: as_batch(v, ur5.n, ur5.name)  # noqa: E731
    for name, kin in (("reference", ur5), *kins.items()):
        for method in ("fkine", "jacob0", "hessian0", "manipulability", "fkine_jacob0"):
            check_same(f"{what}: {name}.{method}", getattr(kin, method), x, rule)
    qt = tree.random_q(seed=3)
    xt = hostile_q(qt)[what]
    rule_t = lambda v: as_batch(v, tree.n, tree.name)  # noqa: E731
    for name, kin in (("tree reference", tree), *tree_kins.items()):
        check_same(f"{what}: {name}.fkine_all", kin.fkine_all, xt, rule_t)
        check_same(
            f"{what}: {name}.jacob0(frame)", lambda v, k=kin: k.jacob0(v, frame=tree.frames[-1]), xt, rule_t
        )


@pytest.mark.parametrize("what", NAMES)
def test_one_configuration_arguments_follow_the_rule(what, ur5, kins):
    """q0 of the numerical IK (NumPy and C solvers) and of the closed form (C, NumPy, CasADi), q of
    the controllers (MMC on the Python and the C path, RRMC), q0 of the servo loop (C and Python)."""
    x = hostile_q(Q_UR5)[what]
    T = ur5.fkine(Q_UR5 + 0.05)
    c = kins["c"]
    nu = np.array([0.01, 0.0, 0.0, 0.0, 0.0, 0.0])
    for arg, calls in (
        (
            "q0",
            {
                "ik numpy": lambda v: c.ik(T, q0=v, backend="numpy", seed=0, slimit=2),
                "ik c": lambda v: c.ik(T, q0=v, backend="c", seed=0, slimit=2),
                **{f"ik_all {b}": (lambda v, k=k: k.ik_all(T, q0=v)) for b, k in kins.items()},
                **{
                    f"analytic ik {b}": (lambda v, k=k: k.ik(T, method="analytic", q0=v))
                    for b, k in kins.items()
                },
                "servo c": lambda v: symkin.servo(c, v, T, max_steps=3),
                "servo python": lambda v: symkin.servo(ur5, v, T, max_steps=3, backend="python"),
            },
        ),
        (
            "q",
            {
                "mmc python": lambda v: MMC(ur5).step(v, nu),
                "mmc c": lambda v: MMC(c).step(v, nu),
                "rrmc": lambda v: rrmc(c, v, nu),
            },
        ),
    ):
        rule = lambda v, arg=arg: as_config(v, ur5.n, ur5.name, arg)  # noqa: E731
        for label, f in calls.items():
            check_same(f"{what}: {label}", f, x, rule)


POSES = {
    "float64": lambda T: T,
    "big-endian": lambda T: T.astype(">f8"),
    "long double": lambda T: T.astype(np.longdouble),
    "Fortran order": np.asfortranarray,
    "unaligned": _unaligned,
    "list": lambda T: T.tolist(),
    "batch": lambda T: np.stack([T, T]),
    "big-endian batch": lambda T: np.stack([T, T]).astype(">f8"),
    "empty batch": lambda T: np.zeros((0, 4, 4)),
    "10**400": lambda T: [[10**400, 0, 0, 0]] + T.tolist()[1:],
    "nan": lambda T: np.where(np.eye(4, dtype=bool), np.nan, T),
    "complex": lambda T: T + 0j,
    "strings": lambda T: T.astype(str),
    "wrong shape": lambda T: T[:3],
    "not a rotation": lambda T: T * 2,
}


@pytest.mark.parametrize("what", sorted(POSES))
def test_target_poses_follow_the_rule(what, ur5, kins):
    """T of the numerical IK (NumPy and C solvers), of the closed form (C, NumPy, CasADi) and of the
    servo loop (C and Python; one pose only)."""
    T = POSES[what](ur5.fkine(Q_UR5))
    c = kins["c"]
    calls = {
        "ik numpy": lambda v: c.ik(v, backend="numpy", seed=0, slimit=2),
        "ik c": lambda v: c.ik(v, backend="c", seed=0, slimit=2),
        **{f"ik_all {b}": (lambda v, k=k: k.ik_all(v, q0=Q_UR5)) for b, k in kins.items()},
    }
    for label, f in calls.items():
        check_same(f"{what}: {label}", f, T, check_pose)

    def one_pose(v):  # noqa: ANN001, ANN202
        Tb, single = check_pose(v)
        if not single:
            raise PoseError(f"servo takes one target pose (4, 4), got shape {np.shape(v)}")
        return Tb, single

    q0 = Q_UR5 + 0.05
    for label, f in (
        ("servo c", lambda v: symkin.servo(c, q0, v, max_steps=3)),
        ("servo python", lambda v: symkin.servo(ur5, q0, v, max_steps=3, backend="python")),
    ):
        check_same(f"{what}: {label}", f, T, one_pose)


def test_the_rule_itself():
    """The decisions the tests above hold every entry point to."""
    n = 6
    ok = {"big-endian", "long double", "float16", "float32 unaligned", "float64 unaligned", "int32", "uint64",
          "bools", "list", "object Fractions", "1e15 exactly", "float64", "empty batch", "batch"}  # fmt: skip
    for what, x in hostile_q(Q_UR5).items():
        got = outcome(as_batch, x, n)
        if what in ok:
            assert not isinstance(got, SymkinError), (what, got)
            assert got[0].dtype == np.float64 and got[0].dtype.isnative
        else:
            assert isinstance(got, ConfigurationError), (what, got)
    for beyond in ([10**400] + [0] * 5, [Fraction(10**400, 3)] * n):
        with pytest.raises(ConfigurationError, match="beyond the range of a double"):
            as_batch(beyond, n)
    if np.finfo(np.longdouble).max > 1e400:  # x86: 80-bit long double
        with pytest.raises(ConfigurationError, match="beyond the range of a double"):
            as_batch(np.full(n, np.longdouble("1e400")), n)
    assert as_batch(np.zeros((0, n)), n)[0].shape == (0, n)


def test_big_endian_q0_gives_the_nearest_solution_on_every_backend(kins, ur5):
    """Issue 23 item 3: the C closed form read a '>f8' q0 as native doubles (a wrong "nearest"
    solution) and refused a '>f8' T."""
    T = ur5.fkine(Q_UR5)
    for kin in kins.values():
        sols = kin.ik_all(T)
        assert len(sols) > 1
        for s in sols:
            for q0 in (s.astype(">f8"), s.astype(np.longdouble), _unaligned(s)):
                assert np.abs(kin.ik_all(T, q0=q0)[0] - s).max() < 1e-9, kin.backend
                assert np.abs(kin.ik_all(T.astype(">f8"), q0=q0)[0] - s).max() < 1e-9, kin.backend
        batch = kin.ik_all(np.stack([T, T]).astype(">f8"), q0=np.stack(sols[:2]).astype(">f8"))
        assert np.abs(batch[:, 0] - sols[:2]).max() < 1e-9


def test_batch_q0_must_have_one_row_per_target(kins, ur5):
    """q0 (N, n) of a batch: the C closed form took any array of N * n numbers (a (3, 4) q0 for two
    6-joint targets); now every backend and solver wants (n,) or (N, n)."""
    T = np.stack([ur5.fkine(Q_UR5)] * 2)
    bad = np.zeros((3, 4))
    errors = set()
    for kin in kins.values():
        for f in (lambda v, k=kin: k.ik_all(T, q0=v), lambda v, k=kin: k.ik(T, q0=v, seed=0, slimit=2)):
            with pytest.raises(ConfigurationError) as info:
                f(bad)
            errors.add(str(info.value))
        with pytest.raises(ConfigurationError, match="one row per target"):
            kin.ik_all(T, q0=np.zeros((3, 6)))
    assert len(errors) == 1, errors


@pytest.mark.parametrize("backend", BACKENDS)
def test_analytic_ik_of_no_targets_gives_q_of_shape_0_n(kins, backend):
    """Issue 23 item 13: q of shape (0,) for N = 0."""
    res = kins[backend].ik(np.zeros((0, 4, 4)), method="analytic")
    assert res.q.shape == (0, 6) and res.success.shape == (0,) and res.residual.shape == (0,)
    assert res.reason == ()
    assert kins[backend].ik_all(np.zeros((0, 4, 4))).shape[0] == 0


def test_free_joint_closed_form_follows_the_rule():
    """The free-joint closed form of a redundant arm: q0 and T by the rule, no targets -> (0, n)."""
    iiwa = symkin.compile("lbr_iiwa7")
    q = np.full(7, 0.3)
    T = iiwa.fkine(q)
    rule = lambda v: as_config(v, 7, iiwa.name, "q0")  # noqa: E731
    for what, x in hostile_q(q).items():
        if what in ("batch", "batch with nan"):
            continue  # one target takes one q0
        check_same(f"{what}: free joint", lambda v: iiwa.ik_all(T, free_joint=(0, 0.3), q0=v), x, rule)
    for what in ("big-endian", "long double", "complex", "10**400", "nan"):
        check_same(what, lambda v: iiwa.ik_all(v, free_joint=(0, 0.3)), POSES[what](T), check_pose)
    with pytest.raises(ConfigurationError, match="free joint 0"):
        iiwa.ik_all(T, free_joint=(0, [0.3, 1e16]))
    res = iiwa.ik(np.zeros((0, 4, 4)), method="analytic", free_joint=0)
    assert res.q.shape == (0, 7)


@pytest.mark.parametrize("backend", BACKENDS)
def test_valid_joint_values_with_a_large_sum_of_squares(kins, backend):
    """The NumPy scalar path takes q with sum q_j^2 <= 1e30 (each |q_j| <= 1e15, no function call);
    a valid q beyond that goes to the batch code, with the batch code's answer."""
    kin = kins[backend]
    q = np.full(6, 5e14)  # valid: each within 1e15, squares add up to 1.5e30
    assert np.array_equal(kin.fkine(q), kin.fkine(q[None])[0])
    assert np.isfinite(kin.jacob0(q)).all()


# -- the one pose rule at every function that takes a pose (issue 36, item 6) ---------------------
def _se3_forms() -> dict[str, object]:
    """spatialmath SE3 forms of a pose, where spatialmath is installed (the compare extra)."""
    try:
        from spatialmath import SE3
    except ImportError:
        return {}
    return {
        "SE3": lambda T: SE3(T, check=False),
        "SE3 of two poses": lambda T: SE3([SE3(T, check=False), SE3(T, check=False)]),
    }


MORE_POSES = {
    **POSES,
    "bottom row 1 0 0 1": lambda T: np.vstack([T[:3], [1.0, 0.0, 0.0, 1.0]]),
    "T[3, 3] = 2": lambda T: np.vstack([T[:3], [0.0, 0.0, 0.0, 2.0]]),
    "bottom row off by 1e-9": lambda T: np.vstack([T[:3], [0.0, 1e-9, 0.0, 1.0]]),
    "reflection": lambda T: T @ np.diag([1.0, 1.0, -1.0, 1.0]),
    "rotation off by 1e-5": lambda T: np.vstack([np.hstack([T[:3, :3] * (1 + 1e-5), T[:3, 3:]]), T[3:]]),
    "rotation off by 1e-8": lambda T: np.vstack([np.hstack([T[:3, :3] * (1 + 1e-8), T[:3, 3:]]), T[3:]]),
    "translation 1e300": lambda T: np.vstack([np.hstack([T[:3, :3], [[1e300], [-1e300], [0.0]]]), T[3:]]),
    **_se3_forms(),
}


def _pose_takers(ur5, kins):  # noqa: ANN001, ANN202
    """(label, function of one pose, the rule it follows) for every public function that takes a pose:
    the rule is as_poses with the function's name for the pose, its error class and whether it takes
    a stack. IK and the servo loop are checked above with check_pose."""
    from symkin.core.pose import as_poses
    from symkin.errors import ParameterError

    c = kins["c"]
    T_ok = ur5.fkine(Q_UR5)
    S = np.array([[0, 0, 1, 0, 0, 0], [0, 1, 0, -0.1, 0, 0]], dtype=float)

    def rule(what, error=PoseError, batch=True):  # noqa: ANN001, ANN202
        return lambda v: as_poses(v, what, error, batch)

    def path_rule(v):  # noqa: ANN001, ANN202
        P, single = as_poses(v, "poses")
        if single or len(P) == 0:
            raise ParameterError(f"poses must be a path of N >= 1 poses, shape (N, 4, 4), got {np.shape(v)}")
        return P, single

    return [
        ("velocity_transform", symkin.velocity_transform, rule("T")),
        ("wrench_transform", symkin.wrench_transform, rule("T")),
        ("pose_error Te", lambda v: symkin.pose_error(v, T_ok), rule("Te")),
        ("pose_error Tep", lambda v: symkin.pose_error(T_ok, v), rule("Tep")),
        ("p_servo Te", lambda v: symkin.p_servo(v, T_ok, frame="base"), rule("Te", batch=False)),
        ("p_servo Tep", lambda v: symkin.p_servo(T_ok, v, frame="ee"), rule("Tep", batch=False)),
        ("ctraj T0", lambda v: symkin.ctraj(v, T_ok, 5), rule("T0", batch=False)),
        ("ctraj T1", lambda v: symkin.ctraj(T_ok, v, 5), rule("T1", batch=False)),
        ("servo_path", lambda v: symkin.servo_path(c, v, Q_UR5).q, path_rule),
        ("with_tool", lambda v: ur5.with_tool(v).fkine(Q_UR5), rule("tool", RobotError, False)),
        ("with_base", lambda v: ur5.with_base(v).fkine(Q_UR5), rule("base", RobotError, False)),
        ("from_poe M", lambda v: symkin.Robot.from_poe(v, S).fkine([0.1, 0.2]), rule("M", RobotError, False)),
        ("ik with collision", lambda v: c.ik(v, collision=True, seed=0, slimit=2).q, rule("target")),
    ]


@pytest.mark.parametrize("what", sorted(MORE_POSES))
def test_every_function_taking_a_pose_follows_the_one_rule(what, ur5, kins):
    """The same hostile pose gives the same error (class and message, naming the argument) or the
    answer of its float64 conversion, at every function that takes a pose."""
    T = MORE_POSES[what](ur5.fkine(Q_UR5))
    for label, f, rule in _pose_takers(ur5, kins):
        if label == "from_poe M" and what == "translation 1e300":
            with pytest.raises(RobotError, match=r"within \+-1e\+150"):  # PoE's own bound, after the rule
                f(T)
            continue
        if label == "ik with collision" and not ur5.geometry:
            continue
        check_same(f"{what}: {label}", f, T, rule)


def test_the_pose_rule_refuses_what_the_issue_reported():
    """velocity_transform/wrench_transform accepted a bottom row [1 0 0 1] and T[3, 3] = 2; p_servo
    took any rotation; np.asarray of an SE3 of two poses is its first pose alone (kin.ik solved one)."""
    T = np.eye(4)
    for bottom in ([1.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 2.0]):
        T[3] = bottom
        for f in (symkin.velocity_transform, symkin.wrench_transform):
            with pytest.raises(PoseError, match=r"T has bottom row"):
                f(T)
    with pytest.raises(PoseError, match="Tep rotation is not orthonormal"):
        symkin.p_servo(np.eye(4), np.diag([2.0, 1.0, 1.0, 1.0]), frame="base")
    SE3 = pytest.importorskip("spatialmath").SE3
    two = SE3([SE3.Tx(0.4) * SE3.Rz(0.3), SE3.Ty(0.2)])
    assert symkin.velocity_transform(two).shape == (2, 6, 6)
    kin = symkin.compile("panda", backend="c")
    res = kin.ik(SE3([SE3(kin.fkine(kin.qr)), SE3(kin.fkine(kin.qz))]), seed=0)
    assert res.batch and len(res) == 2 and np.asarray(res.success).all()
