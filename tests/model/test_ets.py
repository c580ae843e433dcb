"""The ETS text form: exact constants, round trips, and errors that point at the offending token."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from symkin import ET, ETS, Axis, Const, ETSParseError
from symkin.model.ets import surd
from symkin.model.kinematics import const_matrix, et_matrix


def test_constants_stay_exact():
    e = ETS.parse("Rx(-pi/2) Rz(90deg) Ry(45°) tx(0.333) tz(1/3) Rz(0.5*pi) Ry(2*pi/3+0.1) tx(1e-3)")
    consts = [x.const for x in e]
    assert consts[0] == Const(b=Fraction(-1, 2))
    assert consts[1] == Const(b=Fraction(1, 2))
    assert consts[2] == Const(b=Fraction(1, 4))
    assert consts[3] == Const(Fraction(333, 1000))
    assert consts[4] == Const(Fraction(1, 3))
    assert consts[5] == Const(b=Fraction(1, 2))
    assert consts[6] == Const(Fraction(1, 10), Fraction(2, 3))
    assert consts[7] == Const(Fraction(1, 1000))
    assert consts[0].quarter_turns == 3 and consts[2].quarter_turns is None
    assert consts[6].value == pytest.approx(2 * math.pi / 3 + 0.1, abs=1e-15)


def test_quarter_turn_constants_are_exact_signed_permutations():
    for k in range(-4, 5):
        M = const_matrix(Axis.Rx, Const.pi_times(Fraction(k, 2)))
        assert set(np.unique(M)) <= {-1.0, 0.0, 1.0}
        np.testing.assert_allclose(M, et_matrix(Axis.Rx, k * math.pi / 2), atol=1e-15)


def test_joints_plain_indexed_and_flipped():
    e = ETS.parse("Rz(q) tx(1) Rz(-q) * ty(q) ⊕ Rx(-q3)")
    assert [x.joint for x in e if x.is_joint] == [0, 1, 2, 3]
    assert [x.flip for x in e if x.is_joint] == [False, True, False, True]
    assert e.n == 4 and e.structure == "RRPR"
    e2 = ETS.parse("Rz(q1) tx(1) Rz(q0)")
    assert [x.joint for x in e2 if x.is_joint] == [1, 0]


def test_atan2_surd_constants_round_trip():
    e = ETS.parse("Rz(atan2(3, sqrt(7))) Ry(atan2(-1, 2)) Rx(-atan2(1,1))")
    assert e[0].const.atan2 == (surd(Fraction(3)), Fraction(7))
    assert e[0].const.value == pytest.approx(math.atan2(3, math.sqrt(7)), abs=1e-15)
    assert e[2].const.value == pytest.approx(-math.pi / 4, abs=1e-15)
    assert ETS.parse(str(e)) == e


AXES = list(Axis)
consts = st.one_of(
    st.floats(-1e3, 1e3, allow_nan=False).map(Const.of),
    st.builds(
        lambda a, b: Const(Fraction(a, 7), Fraction(b, 12)), st.integers(-50, 50), st.integers(-48, 48)
    ),
    st.builds(
        lambda y, x: Const(atan2=(surd(Fraction(y, 3)), Fraction(x, 5))),
        st.integers(-9, 9),
        st.integers(1, 9),
    ),
)


@st.composite
def sequences(draw):
    items = []
    n = 0
    for _ in range(draw(st.integers(1, 12))):
        axis = draw(st.sampled_from(AXES))
        if draw(st.booleans()):
            items.append(ET(axis, joint=n, flip=draw(st.booleans())))
            n += 1
        else:
            items.append(ET(axis, const=draw(consts)))
    perm = draw(st.permutations(range(n)))
    k = iter(perm)
    return ETS(tuple(ET(e.axis, joint=next(k), flip=e.flip) if e.is_joint else e for e in items))


@given(sequences())
def test_text_round_trips(e):
    assert ETS.parse(str(e)) == e


@given(st.floats(-1e300, 1e300, allow_nan=False, allow_infinity=False))
def test_any_float_constant_round_trips_exactly(x):
    e = ETS((ET(Axis.tx, const=Const.of(x)),))
    back = ETS.parse(str(e))
    assert back == e and back[0].const.value == x


@pytest.mark.parametrize(
    ("text", "message", "column"),
    [
        ("tx(1) foo(2)", "unknown token 'foo(2)'", 6),
        ("tx(1) Rz(q0) Rz(q0)", "joint q0 appears twice", 13),
        ("tz(pi*pi)", "a product must have a plain number on one side", 3),
        ("tz(pi/pi)", "pi may appear only linearly", 3),
        ("tx(1) *", "ends with a separator", 6),
        ("* tx(1)", "unexpected '*'", 0),
        ("Rz(q1)", "q0 is missing", 0),
        ("tx(", "unclosed parenthesis", 2),
        ("tx()", "needs a constant or a joint", 0),
        ("tx(1e400)", "not finite", 3),
        ("Rz(import os)", "invalid constant", 3),
        ("Rz(__import__('os'))", "only numbers", 3),
        ("", "empty ETS", 0),
        ("tx(1/0)", "division by zero", 3),
    ],
)
def test_malformed_text_points_at_the_token(text, message, column):
    with pytest.raises(ETSParseError) as info:
        ETS.parse(text)
    assert message in str(info.value)
    assert info.value.position == column
    if text:
        lines = str(info.value).splitlines()
        assert lines[-1].index("^") - 2 == column  # the caret sits under the offending token


def test_ets_validation():
    with pytest.raises(ValueError, match="either a constant or a joint"):
        ET(Axis.tx)
    with pytest.raises(ValueError, match="0..1"):
        ETS((ET(Axis.Rz, joint=0), ET(Axis.Rz, joint=2)))
    with pytest.raises(TypeError):
        ETS.parse(3)  # type: ignore[arg-type]


def test_concatenation_renumbers_joints():
    a = ETS.parse("Rz(q0) tx(1)")
    b = ETS.parse("Rz(q0) tx(2)")
    c = a * b
    assert str(c) == "Rz(q0) tx(1) Rz(q1) tx(2)"
