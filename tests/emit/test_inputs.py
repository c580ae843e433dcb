"""Every backend takes and refuses the same inputs, with the same answers and the same errors
(issue 12, items 2, 8 and 13): byte order and layout of q, complex/object/string q, empty
batches, bad axes, non-ASCII and very long robot names."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin.core.names import IDENTIFIER_MAX, identifier
from symkin.errors import ConfigurationError, ParameterError
from symkin.runtime.kinematics import KIN_METHODS

BACKENDS = ("c", "numpy", "casadi")
METHODS = (*KIN_METHODS, "manipulability", "jacobm")


@pytest.fixture(scope="module")
def panda():
    return symkin.load("panda")


@pytest.fixture(scope="module")
def kins(panda):
    return {b: symkin.compile(panda, backend=b) for b in BACKENDS}


def _outs(value):
    return value if isinstance(value, tuple) else (value,)


def _unaligned(a: np.ndarray) -> np.ndarray:
    buf = np.zeros(a.nbytes + 1, dtype=np.uint8)
    out = np.frombuffer(buf.data, dtype=a.dtype, count=a.size, offset=1).reshape(a.shape)
    out[...] = a
    assert not out.flags.aligned
    return out


@pytest.mark.parametrize("backend", BACKENDS)
def test_any_byte_order_and_layout_of_q_gives_the_native_answer(kins, panda, backend):
    kin = kins[backend]
    q = panda.random_q(seed=1)
    Q = panda.random_q(5, seed=2)
    variants = {
        "big-endian": (q.astype(">f8"), Q.astype(">f8")),
        "float32": (q.astype(np.float32), Q.astype(np.float32)),
        "non-contiguous": (np.repeat(q, 2)[::2], np.asfortranarray(Q)),
        "unaligned": (_unaligned(q), _unaligned(Q)),
        "list": (q.tolist(), Q.tolist()),
    }
    for name in METHODS:
        f = getattr(kin, name)
        for what, (qv, Qv) in variants.items():
            want_q = np.asarray(qv, dtype=float)  # float32 rounds: compare at the converted values
            want_Q = np.asarray(Qv, dtype=float)
            pairs = ((f(qv), f(np.ascontiguousarray(want_q))), (f(Qv), f(np.ascontiguousarray(want_Q))))
            for got, want in pairs:
                for a, b in zip(_outs(got), _outs(want)):
                    assert np.array_equal(a, b), (backend, name, what)
    # and the big-endian answer is the reference's (it was off by 0.7 on the C backend)
    assert np.abs(kin.fkine(q.astype(">f8")) - panda.fkine(q)).max() < 1e-12


BAD_Q = {
    "complex": (np.zeros(7) + 1j, "q must be real numbers, not complex"),
    "complex list": ([0.0] * 6 + [1j], "q must be real numbers, not complex"),
    "complex with zero imaginary part": (np.zeros(7, dtype=complex), "q must be real numbers, not complex"),
    "strings": (np.array(["0.1"] * 7), "q must be an array of 7 numbers, not strings"),
    "objects": (np.array([object()] * 7), "q must be an array of 7 numbers"),
    "None": (None, "q must have shape (7,) or (N, 7)"),
    "3-d": (np.zeros((1, 1, 7)), "q must have shape (7,) or (N, 7)"),
    "nan": (np.full(7, np.nan), "joint values must be finite"),
}


@pytest.mark.parametrize("what", sorted(BAD_Q))
def test_bad_q_gets_the_same_error_on_every_backend(kins, panda, what):
    q, words = BAD_Q[what]
    messages = set()
    for kin in (panda, *kins.values()):
        for name in ("fkine", "jacob0", "manipulability"):
            with pytest.raises(ConfigurationError) as info:
                getattr(kin, name)(q)
            assert words in str(info.value), (kin, name)
            messages.add(str(info.value))
    assert len(messages) == 1, messages


def test_object_arrays_of_real_numbers_are_accepted_everywhere(kins, panda):
    from fractions import Fraction

    q = np.array([Fraction(1, 3)] * 7, dtype=object)
    want = panda.fkine(np.full(7, 1 / 3))
    for kin in kins.values():
        assert np.abs(kin.fkine(q) - want).max() < 1e-12


@pytest.mark.parametrize("backend", BACKENDS)
def test_empty_batches_give_empty_results(kins, panda, backend):
    kin = kins[backend]
    Q = np.zeros((0, 7))
    for name in (*METHODS, "cond"):
        got, want = getattr(kin, name)(Q), getattr(panda, name)(Q)
        for a, b in zip(_outs(got), _outs(want)):
            assert a.shape == b.shape and a.shape[0] == 0, (backend, name)


@pytest.mark.parametrize("solver", ["c", "numpy"])
def test_empty_ik_batch_gives_an_empty_result(kins, solver):
    res = kins["c"].ik(np.zeros((0, 4, 4)), backend=solver)
    assert res.q.shape == (0, 7) and res.success.shape == (0,) and len(res) == 0 and res.reason == ()


def test_cond_is_inf_at_a_singular_configuration(kins, panda):
    assert panda.cond(panda.qz) == np.inf  # J J^T is singular at qz (it was 2.8e16, rounding noise)
    q = panda.random_q(seed=3)
    for kin in kins.values():
        assert kin.cond(panda.qz) == np.inf
        assert kin.cond(q) == pytest.approx(panda.cond(q), rel=1e-9)
        c = kin.cond(np.stack([q, panda.qz]))
        assert c[0] == pytest.approx(panda.cond(q), rel=1e-9) and c[1] == np.inf


def test_bad_axes_give_the_same_error_on_every_backend(kins, panda):
    q = panda.qr
    for kin in (panda, *kins.values()):
        for name in ("manipulability", "jacobm", "cond"):
            with pytest.raises(ParameterError, match="axes must be one of"):
                getattr(kin, name)(q, axes="xyz")


def test_identifier_is_bounded_ascii_and_keeps_names_apart():
    for name in ("café", "cafè", "a" * 300, "a" * 300 + "b", "ロボット", "9lives", "x" * IDENTIFIER_MAX):
        ident = identifier(name)
        assert ident.isascii() and ident.isidentifier() and len(ident) <= IDENTIFIER_MAX, name
    assert identifier("café") != identifier("cafè")
    assert identifier("a" * 300) != identifier("a" * 300 + "b")
    assert identifier("panda") == "panda" and identifier("UR5 arm") == "ur5_arm"  # plain names unchanged


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", ["café", "é" * 3 + "x" * 250])
def test_non_ascii_and_long_names_compile_and_report_errors(backend, name):
    robot = symkin.Robot.from_ets("Rz(q) tx(1) Rz(q) tx(0.5)", name=name)
    kin = symkin.compile(robot, backend=backend)
    assert kin.name == name  # the display name is kept
    for fname, text in kin.files.items():
        assert fname.isascii() and len(fname) < 80 and text.isascii(), fname
    assert np.abs(kin.fkine([0.1, 0.2]) - robot.fkine([0.1, 0.2])).max() < 1e-12
    with pytest.raises(ConfigurationError) as info:  # the error path (UnicodeDecodeError in C before)
        kin.fkine([1.0, 2.0, 3.0])
    assert name[:20] in str(info.value)


def test_names_with_nul_or_lone_surrogates_are_refused():
    for bad in ("a\0b", "a\udcffb"):
        with pytest.raises(symkin.RobotError):
            symkin.Robot.from_ets("Rz(q)", name=bad)
