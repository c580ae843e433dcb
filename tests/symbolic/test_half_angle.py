"""symkin.symbolic.half_angle: common factors of trigonometric polynomials modulo sin^2 + cos^2 = 1,
against sympy's own gcd of the polynomials written in sin(q/2), cos(q/2)."""

from __future__ import annotations

import numpy as np
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from symkin.symbolic.half_angle import HalfAngle

N = 2  # joints q0, q1 (revolute) and one length d0 (a prismatic joint)
S = sp.symbols(f"s0:{N}")
C = sp.symbols(f"c0:{N}")
D0 = sp.Symbol("d0")
Q = sp.symbols(f"q0:{N}")
DOM = sp.QQ[(*S, *C, D0)]
H = HalfAngle.of(N, DOM)
T = sp.symbols(f"t0:{N}")
U = sp.symbols(f"u0:{N}")

#: Trigonometric polynomials in s_j = sin q_j, c_j = cos q_j (some share roots: sin q0 and 1 - cos q0
#: both vanish at q0 = 0, sin q0 and 1 + cos q0 at q0 = pi).
BLOCKS = (
    S[0],
    C[0],
    1 - C[0],
    1 + C[0],
    S[1],
    C[1],
    S[0] * C[1] + C[0] * S[1],  # sin(q0 + q1)
    C[0] * C[1] - S[0] * S[1],  # cos(q0 + q1)
    2 * C[0] + S[1],
    3 * S[0] - 4 * C[0] + 1,
    D0,
    D0 + C[1],
)


def _pieces(polys: list[sp.Expr]) -> list[tuple[object, int]]:
    rings = [H.reduce(DOM.from_sympy(sp.expand(p))) for p in polys]
    common, source = H.common(rings)
    return H.group(common, source)


#: digits of the evaluations that compare two forms of a polynomial (both sides near a root cancel
#: heavily in double precision)
DIGITS = 40


def _value(expr: sp.Expr, q: np.ndarray, d0: float) -> sp.Float:
    values = {**{Q[j]: sp.Float(q[j], DIGITS) for j in range(N)}, D0: sp.Float(d0, DIGITS)}
    return expr.evalf(DIGITS, subs=values)


def _sympy_gcd(polys: list[sp.Expr]) -> sp.Expr:
    """The gcd by sympy of the polynomials written homogeneously in t_j = sin(q_j/2), u_j = cos(q_j/2):
    s = 2 t u, c = u^2 - t^2, each monomial times (t^2 + u^2)^k to the degree of the polynomial."""
    out = []
    for p in polys:
        P = sp.Poly(sp.expand(p), *S, *C, D0)
        deg = [max(m[j] + m[j + N] for m in P.monoms()) for j in range(N)]
        total = 0
        for m, coeff in P.terms():
            term = coeff * D0 ** m[2 * N]
            for j in range(N):
                b, a = m[j], m[j + N]
                term *= (2 * T[j] * U[j]) ** b * (U[j] ** 2 - T[j] ** 2) ** a
                term *= (T[j] ** 2 + U[j] ** 2) ** (deg[j] - a - b)
            total += term
        out.append(sp.expand(total))
    return sp.gcd_list(out)


def _at_half_angles(expr: sp.Expr, q: np.ndarray, d0: float) -> sp.Float:
    half = [sp.Float(q[j], DIGITS) / 2 for j in range(N)]
    values = {**{T[j]: sp.sin(half[j]) for j in range(N)}, **{U[j]: sp.cos(half[j]) for j in range(N)}}
    return expr.evalf(DIGITS, subs={**values, D0: sp.Float(d0, DIGITS)})


def _to_q(expr: sp.Expr) -> sp.Expr:
    return expr.xreplace({**{S[j]: sp.sin(Q[j]) for j in range(N)}, **{C[j]: sp.cos(Q[j]) for j in range(N)}})


def test_sin_is_common_to_sin_and_its_square_written_in_cosines() -> None:
    # the iiwa's case: one minor carries s3, another (c3 - 1)(c3 + 1); the intersection of the factor
    # sets was empty
    (piece, power), *rest = _pieces([S[0] * C[1], (C[0] - 1) * (C[0] + 1) * S[1]])
    assert not rest and power == 1 and not H.odd(piece)
    assert (DOM.to_sympy(H.to_sc(piece)) / S[0]).is_nonzero  # sin q0 up to a constant


def test_a_root_at_zero_alone_is_a_half_angle_sine() -> None:
    (piece, power), *rest = _pieces([S[0], 1 - C[0]])  # common zero q0 = 0 only
    assert not rest and power == 1 and H.odd(piece)
    assert H.to_expr(piece, Q, (D0,)) == sp.sin(Q[0] / 2)
    (piece, power), *rest = _pieces([S[0] * S[1], (1 + C[0]) * C[1]])  # q0 = pi only
    assert not rest and H.to_expr(piece, Q, (D0,)) == sp.cos(Q[0] / 2)


def test_sums_of_angles_and_lengths_stay_whole() -> None:
    s01 = S[0] * C[1] + C[0] * S[1]
    pieces = _pieces([s01 * D0**2 * C[0], s01 * D0**3 * S[1]])
    got = {sp.trigsimp(_to_q(DOM.to_sympy(H.to_sc(p).primitive()[1]))): m for p, m in pieces}
    assert got in ({D0: 2, sp.sin(Q[0] + Q[1]): 1}, {D0: 2, -sp.sin(Q[0] + Q[1]): 1})


_PRODUCT = st.lists(st.tuples(st.integers(0, len(BLOCKS) - 1), st.integers(1, 2)), max_size=3)


def _product(items: list[tuple[int, int]]) -> sp.Expr:
    return sp.Mul(*[BLOCKS[i] ** e for i, e in items])


@settings(max_examples=25, deadline=None)
@given(_PRODUCT, st.lists(_PRODUCT, min_size=2, max_size=3), st.integers(0, 2**31))
def test_common_factors_are_the_gcd_of_the_half_angle_polynomials(
    shared: list[tuple[int, int]], own: list[list[tuple[int, int]]], seed: int
) -> None:
    polys = [_product(shared) * _product(mine) * (k + 2) for k, mine in enumerate(own)]
    if any(p.is_number for p in polys):
        return
    pieces = _pieces(polys)
    ours = sp.Mul(*[H.to_expr(p, Q, (D0,)) ** m for p, m in pieces])
    theirs = _sympy_gcd(polys)
    rng = np.random.default_rng(seed)
    ratios = []
    for _ in range(4):
        q, d0 = rng.uniform(-3, 3, N), float(rng.uniform(0.2, 2))
        ratios.append(float(_value(ours, q, d0) / _at_half_angles(theirs, q, d0)))
    assert np.ptp(ratios) <= 1e-9 * abs(ratios[0]) and abs(ratios[0]) > 1e-12, (pieces, theirs)


@settings(max_examples=25, deadline=None)
@given(
    st.lists(st.tuples(st.integers(0, len(BLOCKS) - 1), st.integers(1, 2)), max_size=5),
    st.integers(0, 2**32 - 1),
)
def test_one_polynomial_is_its_constant_times_its_factors(items: list[tuple[int, int]], seed: int) -> None:
    p = _product(items) * 3
    if p.is_number:
        return
    ring = H.reduce(DOM.from_sympy(sp.expand(p)))
    _, primes, source = H.divisors(ring)
    pieces = H.group(primes, source)
    assert not any(H.odd(piece) for piece, _ in pieces)  # one polynomial: every factor in s, c
    factors = {H.to_sc(piece): m for piece, m in pieces}
    constant = DOM.domain.to_sympy(H.scale(ring, factors))
    product = constant * sp.Mul(*[DOM.to_sympy(h) ** m for h, m in factors.items()])
    rng = np.random.default_rng(seed)
    for _ in range(3):
        q, d0 = rng.uniform(-3, 3, N), float(rng.uniform(0.2, 2))
        want, got = _value(_to_q(p), q, d0), _value(_to_q(product), q, d0)
        assert abs(float(got - want)) <= 1e-9 * max(1.0, abs(float(want)))
