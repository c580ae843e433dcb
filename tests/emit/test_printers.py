"""The NumPy backend's printers: ``-a + b`` printed as ``b - a`` must give the same IEEE result."""

from __future__ import annotations

import math

import numpy as np
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from symkin.emit.printers import MathPrinter, NumPyKinPrinter, NumPyPrinter

X = sp.symbols("x0:4")
SUMS = [
    -X[0] * X[1] + X[2] * X[3],
    -X[0] + X[1],
    -sp.Float(0.0823) * X[0] * X[3] + X[1],
    -(X[0] ** 2) + sp.sin(X[1]),
    -(X[0] + X[1]) * X[2] + X[3],
    -X[0] * X[1] + X[2] + X[3],  # three terms: order kept
    -X[0] - X[1],  # both negated: kept
]


def _same(a: float, b: float) -> bool:
    return (math.isnan(a) and math.isnan(b)) or np.float64(a).tobytes() == np.float64(b).tobytes()


floats = st.one_of(
    st.floats(-1e3, 1e3, allow_nan=False),
    st.sampled_from([0.0, -0.0, 1e-310, -1e-310, math.inf, -math.inf, 1e300, -1e300]),
)


def test_two_term_sums_with_a_negated_first_term_are_printed_as_differences():
    printed = [MathPrinter().doprint(e) for e in SUMS]
    assert printed[0] == "x2*x3 - x0*x1"
    assert printed[1] == "x1 - x0"
    assert printed[2] == "x1 - 0.0823*x0*x3"
    assert printed[3] == "sin(x1) - (x0*x0)"
    assert printed[5] == NumPyPrinter().doprint(SUMS[5]) == "-x0*x1 + x2 + x3"
    assert printed[6] == "-x0 - x1"


@settings(max_examples=300, deadline=None)
@given(values=st.lists(floats, min_size=4, max_size=4))
def test_rewritten_sums_round_exactly_like_the_plain_ones(values):
    # the same bits (signed zeros and infinities included; a NaN from both, its sign bit aside) from
    # the rewritten and the plain text, with numpy arrays (batch code) and with Python floats (one
    # configuration)
    env_np = {"np": np, **{str(x): np.array([v]) for x, v in zip(X, values)}}
    env_py = {"sin": math.sin, **{str(x): v for x, v in zip(X, values)}}
    with np.errstate(all="ignore"):
        for e in SUMS:
            plain = NumPyPrinter().doprint(e)
            a = eval(plain, env_np)  # noqa: S307 - printed from the fixed expressions above
            b = eval(NumPyKinPrinter().doprint(e), env_np)  # noqa: S307
            assert _same(a[0], b[0]), (plain, values)
            try:
                c = eval(plain.replace("np.sin", "sin"), env_py)  # noqa: S307
            except (ValueError, OverflowError):  # math.sin(inf): the same error from both
                continue
            d = eval(MathPrinter().doprint(e), env_py)  # noqa: S307
            assert _same(c, d), (plain, values)
