"""The C backend's inline sin/cos against mpmath, and `symkin check` at large angles (issue 12,
item 14). docs/guide/accuracy.md quotes the full sweep (1.66 M angles); this is a
bounded sample of the same kinds of angles, hardest cases included."""

from __future__ import annotations

import math

import mpmath
import numpy as np
import pytest

import symkin
from symkin.check.kinematics import LARGE_TURNS, check
from symkin.emit.c import lanes
from symkin.runtime.kinematics import KIN_METHODS, Kinematics

INLINE_MAX = 1.6e6  # beyond, the generated code calls libm


def _angles() -> np.ndarray:
    rng = np.random.default_rng(12)
    k = np.unique(np.r_[np.arange(1, 1500), rng.integers(1, int(INLINE_MAX / (math.pi / 2)), 1500)])
    with mpmath.workdps(40):
        near = np.array([float(mpmath.mpf(int(j)) * mpmath.pi / 2) for j in k])
    return np.concatenate(
        [
            near,  # the doubles nearest k pi/2: the reduction cancels up to ~60 bits
            -near[::5],
            np.nextafter(near[::5], np.inf),
            np.nextafter(near[::5], -np.inf),
            np.array([1122611.8112436021, 704433.8757214118, 1136352.49373431, 927765.2013272601]),
            rng.uniform(-INLINE_MAX, INLINE_MAX, 800),
            rng.uniform(-4.0, 4.0, 800),
            10.0 ** rng.uniform(-300, 0, 100) * rng.choice([-1, 1], 100),
            10.0 ** rng.uniform(6.3, 15, 200) * rng.choice([-1, 1], 200),  # libm, up to MAX_JOINT_VALUE
            [0.0, -0.0, 5e-324, -5e-324, INLINE_MAX, -INLINE_MAX, np.nextafter(INLINE_MAX, np.inf)],
        ]
    )


def _ulp_errors(x: np.ndarray, got: np.ndarray, f) -> np.ndarray:  # noqa: ANN001
    out = np.empty(len(x))
    with mpmath.workprec(200):
        for i, (xi, gi) in enumerate(zip(x.tolist(), got.tolist())):
            true = f(mpmath.mpf(xi))
            ulp = math.ulp(float(true)) if float(true) != 0 else 5e-324
            out[i] = float(abs(mpmath.mpf(gi) - true) / ulp)
    return out


def test_inline_sin_cos_are_within_one_ulp():
    kin = symkin.compile(symkin.Robot.from_ets("Rz(q)", name="rz_ulp"), backend="c")
    assert lanes.ready(kin.module, timeout=600)  # the batch below: four lanes
    x = _angles()
    T = kin.fkine(x[:, None])  # generated code: T[0, 0] = sk_cos(q0), T[1, 0] = sk_sin(q0)
    for name, got, f in (("sin", T[:, 1, 0], mpmath.sin), ("cos", T[:, 0, 0], mpmath.cos)):
        err = _ulp_errors(x, got, f)
        worst = int(np.argmax(err))
        assert err.max() < 1.0, f"{name}: {err.max():.3g} ulp at x = {x[worst]!r}"
    zeros = x == 0
    assert np.array_equal(np.signbit(T[zeros, 1, 0]), np.signbit(x[zeros]))  # sin(-0) = -0


def test_backends_agree_at_large_angles():
    robot = symkin.load("ur5")
    Q = np.random.default_rng(0).uniform(-1e15, 1e15, (200, 6))
    c, n = symkin.compile(robot, backend="c"), symkin.compile(robot, backend="numpy")
    assert np.abs(c.fkine(Q) - n.fkine(Q)).max() < 1e-12


def test_check_covers_large_angles():
    robot = symkin.load("planar3")
    kin = symkin.compile(robot, backend="numpy")
    report = check(robot, backends=[kin], samples=4)
    large = [r for r in report.rows if r.function.endswith("(large q)")]
    assert {r.function for r in large} == {"fkine (large q)", "jacob0 (large q)", "hessian0 (large q)"}
    assert report.ok
    # a backend whose argument reduction goes wrong at large angles passes everything else and
    # fails exactly those rows
    rev = np.array([e.is_revolute for e in robot.ets.joints])

    def bad(f):  # noqa: ANN001, ANN202
        def call(q):  # noqa: ANN001, ANN202
            q = np.asarray(q, dtype=float)
            return f(np.where(rev, q - 6.2831853 * np.round(q / 6.2831853), q))  # 2 pi to 8 digits

        return call

    broken = Kinematics(robot, "numpy", {m: bad(getattr(kin, m)) for m in KIN_METHODS}, kin.files)
    rows = check(robot, backends=[broken], samples=4).rows
    assert all(r.ok for r in rows if not r.function.endswith("(large q)"))
    assert not any(r.ok for r in rows if r.function.endswith("(large q)"))
    assert LARGE_TURNS >= 1000


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_check_passes_at_large_angles_on_a_builtin_robot(backend):
    robot = symkin.load("puma560")
    report = check(robot, backends=[backend], samples=4)
    assert all(r.ok for r in report.rows if r.function.endswith("(large q)")), report.format()


def test_scalar_sin_cos_are_within_one_ulp_and_the_lanes_bits():
    """The straight-line sk_sin and sk_cos themselves (the harness of symkin bench sincos), on the
    hard angles above (next to k pi/2, huge: libm, tiny, signed zeros): within 1 ulp of mpmath, and
    the same bits as sk_sincos_n_ (seven angles per call, as a configuration) and the four lanes."""
    from symkin.bench.sincos import harness

    lib = harness(7)
    x = _angles()
    x = np.ascontiguousarray(x[: len(x) // 28 * 28])
    out = {}
    for name in ("skb_scalar", "skb_config", "skb_lanes", "skb_libm"):
        if hasattr(lib, name):
            s, c = np.empty(len(x)), np.empty(len(x))
            getattr(lib, name)(x.ctypes.data, len(x), s.ctypes.data, c.ctypes.data)
            out[name] = (s, c)
    assert {"skb_scalar", "skb_config", "skb_lanes"} <= set(out)
    s, c = out["skb_scalar"]
    for name, got, f in (("sin", s, mpmath.sin), ("cos", c, mpmath.cos)):
        err = _ulp_errors(x, got, f)
        assert err.max() < 1.0, f"{name}: {err.max():.3g} ulp at x = {x[int(np.argmax(err))]!r}"
    for other in ("skb_config", "skb_lanes"):
        for a, b in zip(out[other], (s, c)):
            assert np.array_equal(a.view(np.uint64), b.view(np.uint64)), other
    assert not np.array_equal(s.view(np.uint64), out["skb_libm"][0].view(np.uint64))  # not glibc's
