"""Trigonometric polynomials factored uniquely, and their common factors, by the tangent half-angle.

A polynomial p in ``s_j = sin q_j``, ``c_j = cos q_j`` (and the lengths of prismatic joints) does
not factor uniquely modulo ``s_j^2 + c_j^2 = 1``: ``s_j^2 = (1 - c_j)(1 + c_j)``, so one minor of a
Jacobian may carry ``s_3`` and another ``(c_3 - 1)(c_3 + 1)``, and the intersection of their factor
sets misses the common ``sin q_3``. With ``t_j = tan(q_j / 2)``, ``s_j = 2 t_j / (1 + t_j^2)`` and
``c_j = (1 - t_j^2) / (1 + t_j^2)``, p is ``P(t) / prod_j (1 + t_j^2)^(d_j)`` (d_j its degree in
``s_j, c_j``) with P a polynomial over the rationals, where factorisation is unique. A root at
``q_j = pi`` (``t_j`` infinite) is the degree ``2 d_j - deg_{t_j} P`` that P lost (the power of
``u_j`` in P written homogeneously in ``(t_j, u_j)``). So the divisors of p form a multiset of
*primes*: the irreducible factors of P other than the ``1 + t_j^2`` (no real root), and the points
``q_j = pi``; a factor common to several polynomials takes each prime with its least multiplicity
(their greatest common divisor).

Written back: a product of primes of even degree in every ``t_j`` (the point at infinity counting
1) is a polynomial in ``s_j, c_j``, as ``t^a / (1 + t^2)^(e/2) = sin^a(q/2) cos^(e-a)(q/2)``, a
product of ``(1 - c)/2``, ``(1 + c)/2`` and ``s/2``; the primes are grouped so (``sin q_j`` is
``t_j`` with the point at infinity, ``cos q_j`` is ``(1 - t_j)(1 + t_j)``, ``sin(q_i + q_j)`` is
``(t_i + t_j)(1 - t_i t_j)``), and a prime left without a partner (``t_j`` alone: a root at
``q_j = 0`` only) is written in the sines and cosines of half angles (``sin(q_j / 2)``). See
Spong, Hutchinson and Vidyasagar, Robot Modeling and Control, 2006, sec 4.11, and Corke, Robotics,
Vision and Control, 3rd ed., 2023, sec 8.1.4, for singularities as the zeros of the minors of J.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass

import sympy as sp
from sympy.polys.rings import ring as poly_ring

from symkin.errors import SymkinError

__all__ = ["HalfAngle", "Prime", "Piece"]

#: A prime divisor: (irreducible polynomial in t, -1), or (1, j) for the root at q_j = pi.
Prime = tuple
#: A product of primes: (polynomial in t, {j: how many roots at q_j = pi}).
Piece = tuple


@dataclass(frozen=True, eq=False)
class HalfAngle:
    """The rings of one analysis: ``dom`` the polynomials in ``s_0..s_{n-1}, c_0..c_{n-1}`` and the
    prismatic lengths (over a field), ``tring`` those in ``t_0..t_{n-1}`` and the same lengths."""

    n: int
    dom: object
    tring: object

    @classmethod
    def of(cls, n: int, dom: object) -> HalfAngle:  # noqa: ANN102
        names = [f"t{j}" for j in range(n)] + [str(g) for g in dom.ring.gens[2 * n :]]  # type: ignore[attr-defined]
        tring, *_ = poly_ring(",".join(names), dom.domain)  # type: ignore[attr-defined]
        return cls(n, dom, tring)

    # -- s, c <-> t --------------------------------------------------------------------------

    def reduce(self, p):  # noqa: ANN001, ANN201
        """p with every s_j^2 replaced by 1 - c_j^2 (degree <= 1 in each s_j)."""
        n, gens = self.n, self.dom.ring.gens  # type: ignore[attr-defined]
        out = self.dom.zero  # type: ignore[attr-defined]
        for monom, coeff in p.terms():
            term = self.dom.ring.ground_new(coeff)  # type: ignore[attr-defined]
            for i, e in enumerate(monom):
                if e and i < n:
                    term *= gens[i] ** (e % 2) * (1 - gens[i + n] ** 2) ** (e // 2)
                elif e:
                    term *= gens[i] ** e
            out += term
        return out

    def to_t(self, p):  # noqa: ANN001, ANN201
        """(P, {j: d_j}): p = P(t) / prod (1 + t_j^2)^(d_j), d_j the degree of p in s_j, c_j."""
        n, tg = self.n, self.tring.gens  # type: ignore[attr-defined]
        degree = {j: max(m[j] + m[j + n] for m in p.monoms()) for j in range(n)}
        degree = {j: d for j, d in degree.items() if d}
        P = self.tring.zero  # type: ignore[attr-defined]
        for monom, coeff in p.terms():
            term = self.tring.ground_new(coeff)  # type: ignore[attr-defined]
            for j, d in degree.items():
                b, a, t = monom[j], monom[j + n], tg[j]
                term *= (2 * t) ** b * (1 - t**2) ** a * (1 + t**2) ** (d - a - b)
            for i, e in enumerate(monom[2 * n :]):
                term *= tg[n + i] ** e
            P += term
        return P, degree

    def to_sc(self, piece: Piece):  # noqa: ANN201
        """A piece of even degree in every t_j as a polynomial in s_j, c_j:
        ``g(t) / prod (1 + t_j^2)^(e_j / 2)``, ``t^a -> sin^a(q/2) cos^(e-a)(q/2)`` with
        ``sin^2(q/2) = (1 - c)/2``, ``cos^2(q/2) = (1 + c)/2``, ``sin(q/2) cos(q/2) = s/2``."""
        g, extra = piece
        n, gens = self.n, self.dom.ring.gens  # type: ignore[attr-defined]
        e = self._degrees(piece)
        half = self.dom.domain.convert(sp.Rational(1, 2))  # type: ignore[attr-defined]
        out = self.dom.zero  # type: ignore[attr-defined]
        for monom, coeff in g.terms():
            term = self.dom.ring.ground_new(coeff)  # type: ignore[attr-defined]
            for j, ej in e.items():
                a, b = monom[j], ej - monom[j]
                s, c = gens[j], gens[j + n]
                if a % 2:
                    term *= s * half
                    a, b = a - 1, b - 1
                term *= ((1 - c) * half) ** (a // 2) * ((1 + c) * half) ** (b // 2)
            for i, x in enumerate(monom[n:]):
                term *= gens[2 * n + i] ** x
            out += term
        return self.reduce(out)

    def to_expr(self, piece: Piece, qs: tuple[sp.Symbol, ...], lengths: tuple[sp.Symbol, ...]) -> sp.Expr:
        """Any piece as an expression in the sines and cosines of half angles (integer coefficients,
        the first positive): ``t^a / (1 + t^2)^(e/2) = sin^a(q/2) cos^(e-a)(q/2)`` for q in (-pi, pi]."""
        g, _ = piece
        g = g.primitive()[1]
        if g.LC < 0:
            g = -g
        e = self._degrees(piece)
        out = sp.Integer(0)
        for monom, coeff in g.terms():
            term = self.tring.domain.to_sympy(coeff)  # type: ignore[attr-defined]
            for j, ej in e.items():
                term *= sp.sin(qs[j] / 2) ** monom[j] * sp.cos(qs[j] / 2) ** (ej - monom[j])
            for i, x in enumerate(monom[self.n :]):
                term *= lengths[i] ** x
            out += term
        return out

    def _degrees(self, piece: Piece) -> dict[int, int]:
        g, extra = piece
        tg = self.tring.gens  # type: ignore[attr-defined]
        e = {j: g.degree(tg[j]) + extra.get(j, 0) for j in range(self.n)}
        return {j: d for j, d in e.items() if d}

    # -- divisors ----------------------------------------------------------------------------

    def divisors(self, p) -> tuple[object, dict[Prime, int], dict[Prime, int]]:  # noqa: ANN001
        """(rational constant, {prime: multiplicity}, {prime: k}) of a nonzero polynomial p in s, c;
        k numbers the rational factor of p the prime came from (the groups prefer primes of one)."""
        tg = self.tring.gens  # type: ignore[attr-defined]
        circles = {1 + t**2 for t in tg[: self.n]}
        mult: dict[Prime, int] = {}
        source: dict[Prime, int] = {}
        coeff, raw = p.factor_list()
        for k, (g, gmult) in enumerate(raw):
            P, degree = self.to_t(self.reduce(g))
            _, tf = P.factor_list()
            primes = [((f.monic(), -1), m) for f, m in tf if not f.is_ground and f.monic() not in circles]
            primes += [((self.tring.one, j), 2 * d - P.degree(tg[j])) for j, d in degree.items()]  # type: ignore[attr-defined]
            for prime, m in primes:
                if m:
                    mult[prime] = mult.get(prime, 0) + m * gmult
                    source.setdefault(prime, k)
        return coeff, mult, source

    def common(self, polys: list) -> tuple[dict[Prime, int], dict[Prime, int]]:
        """The greatest common divisor of nonzero polynomials in s, c, as ({prime: multiplicity},
        {prime: rational factor of the first polynomial it came from}): the first polynomial (pass the
        shortest) is factored, the others only divided by its primes."""
        _, common, source = self.divisors(polys[0])
        for p in polys[1:]:
            if not common:
                break
            common = self.restrict(common, p)
        return common, source

    def restrict(self, primes: dict[Prime, int], p) -> dict[Prime, int]:  # noqa: ANN001
        """The greatest common divisor of ``primes`` (a multiset) and a nonzero polynomial p in s, c:
        each prime with the least of its multiplicity and its multiplicity in p (found by exact
        division in t, no factorisation)."""
        tg = self.tring.gens  # type: ignore[attr-defined]
        P, degree = self.to_t(self.reduce(p))
        lost = {j: 2 * d - P.degree(tg[j]) for j, d in degree.items()}  # before P is divided
        out: dict[Prime, int] = {}
        for (f, j), cap in primes.items():
            m = 0
            if j >= 0:
                m = min(cap, lost.get(j, 0))
            else:
                while m < cap:
                    q, r = P.div(f)
                    if r:
                        break
                    P, m = q, m + 1
            if m:
                out[(f, j)] = m
        return out

    # -- grouping ----------------------------------------------------------------------------

    def group(self, primes: dict[Prime, int], source: dict[Prime, int]) -> list[tuple[Piece, int]]:
        """The primes grouped into factors, each with its power (see the module docstring): primes of
        even degree alone; ``sin q_j`` and ``cos q_j``; primes of odd degree paired with one of the
        same rational factor and the same odd joints, then with any of the same odd joints; what is
        left is one factor when its degrees are even, else one (half-angle) factor per prime."""
        count = {p: m for p, m in primes.items() if m}
        out: list[Piece] = []
        for p in sorted(count, key=_order):
            if not self.odd(_piece(p)):
                out += [_piece(p)] * count.pop(p)
        tg = self.tring.gens  # type: ignore[attr-defined]
        for j in range(self.n):
            t, one = tg[j], self.tring.one  # type: ignore[attr-defined]
            for a, b, piece in (((t, -1), (one, j), (t, {j: 1})), ((t - 1, -1), (t + 1, -1), (1 - t**2, {}))):
                k = min(count.get(a, 0), count.get(b, 0))
                out += [piece] * k
                for x in (a, b):
                    if x in count:
                        count[x] -= k
        by_source = sorted(count, key=lambda p: (source.get(p, -1), _order(p)))
        rest = [p for p in by_source for _ in range(count[p])]
        pool: list[Piece] = []
        for _, items in itertools.groupby(rest, key=lambda p: source.get(p, -1)):
            paired, left = self._pairs([_piece(p) for p in items])
            out += paired
            if left and not self.odd(_product(left)):
                out.append(_product(left))
            else:
                pool += left
        paired, left = self._pairs(pool)
        out += paired
        if left and not self.odd(_product(left)):
            out.append(_product(left))
        else:
            out += left
        powers: dict[tuple, tuple[Piece, int]] = {}
        for piece in out:
            key = (piece[0], tuple(sorted(piece[1].items())))
            powers[key] = (piece, powers[key][1] + 1 if key in powers else 1)
        return list(powers.values())

    def odd(self, piece: Piece) -> frozenset[int]:
        """The joints in which a piece has odd degree (the points at infinity counted)."""
        return frozenset(j for j, d in self._degrees(piece).items() if d % 2)

    def _pairs(self, pieces: list[Piece]) -> tuple[list[Piece], list[Piece]]:
        """Pieces of the same odd joints paired in order: (the pairs' products, the unpaired)."""
        paired, left = [], list(pieces)
        k = 0
        while k < len(left):
            key = self.odd(left[k])
            mate = next((i for i in range(k + 1, len(left)) if self.odd(left[i]) == key), None)
            if mate is None:
                k += 1
                continue
            other = left.pop(mate)
            paired.append(_product([left.pop(k), other]))
        return paired, left

    def scale(self, p, factors: dict) -> object:  # noqa: ANN001
        """The constant p / prod(h^m) of polynomials in s, c, evaluated exactly at rational points of
        the circles ``(c, s) = ((1 - t^2) / (1 + t^2), 2 t / (1 + t^2))``."""
        K = self.dom.domain  # type: ignore[attr-defined]
        n = self.n
        extra = len(self.dom.ring.gens) - 2 * n  # type: ignore[attr-defined]
        for k in range(1, 50):
            ts = [K.convert(sp.Rational(k + j, 3 * k + 2 * j + 7)) for j in range(n)]
            values = [2 * t / (1 + t * t) for t in ts] + [(1 - t * t) / (1 + t * t) for t in ts]
            values += [K.convert(sp.Rational(2 * k + j + 1, 5)) for j in range(extra)]
            den = K.one
            for h, m in factors.items():
                den *= h(*values) ** m
            if den:
                return p(*values) / den
        raise SymkinError("no point found to scale the factors of the determinant")  # not reached


def _piece(prime: Prime) -> Piece:
    f, j = prime
    return (f, {j: 1} if j >= 0 else {})


def _product(pieces: list[Piece]) -> Piece:
    f, extra = pieces[0][0], dict(pieces[0][1])
    for g, e in pieces[1:]:
        f = f * g
        for j, k in e.items():
            extra[j] = extra.get(j, 0) + k
    return (f, extra)


def _order(prime: Prime) -> tuple:
    f, j = prime
    return (j, len(f.terms()), str(f))
