"""Runs of constant transforms folded into one before the symbolic stage.

Between two joints a chain may hold many constant elementary transforms: each URDF joint's origin
is ``tx ty tz Rz(yaw) Ry(pitch) Rx(roll)``, and a run of fixed joints repeats that. Kept exact,
the symbolic walk multiplies the cos/sin of rational angles out into numeric expressions that
grow with every rotation (a 6-joint arm with four fixed joints of rpy ``0.1 0.2 0.3`` after it
did not compile in minutes). So a run holding two or more rotations that are not quarter turns
is folded, numerically, into one :class:`Fixed` transform, and so is any run longer than
:data:`MAX_RUN` (thousands of fixed links cost one transform, not a few named values each). Each
entry of the folded rotation and translation is exact (a rational) where the product is exact
(quarter turns, translations, the zeros and ones of a rotation about one axis) and a double
otherwise: the rotations by arbitrary angles are rounded once.

A short run with at most one such rotation is kept as it is: the walk handles it exactly at
about the same cost (a quarter turn is a column swap, one rotation is one cos/sin pair that
merges with the next joint's rotation about the same axis, ``cos(q1 + 3/10)``), and the code
generated for such chains (every built-in robot) does not change.

The closed-form IK folds the same runs with ``digits=``: the entries that are not exact are then
evaluated to that many significant digits (mpmath) instead of doubles, so its exact tests of
the geometry (which axes are parallel or meet, decided at 40 digits) see a folded run as they
would see its exact product.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Iterator, Sequence
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass
from fractions import Fraction
from functools import cached_property, lru_cache

import mpmath
import sympy as sp

from symkin.model.ets import ET, Const

__all__ = ["Fixed", "fold_constants"]

# exact rational, or where the value is not exact a double (or an mpmath number with ``digits=``)
Num = Fraction | float | mpmath.mpf
# The most constants one URDF joint puts between two joints: its origin (tx ty tz Rz Ry Rx) and
# the exact rotations that turn an oblique joint axis (two after the previous joint, two before
# this one). A longer run (fixed joints in a row) is folded even when exact: walked one transform
# at a time it costs a few named values per translation, folded three.
MAX_RUN = 10
MIX = {0: (1, 2), 1: (2, 0), 2: (0, 1)}  # rotation about axis i mixes columns (j, k)


def _mp(x: Num) -> mpmath.mpf:
    return mpmath.mpf(x.numerator) / x.denominator if isinstance(x, Fraction) else mpmath.mpf(x)


def _mul(a: Num, b: Num) -> Num:
    if not a or not b:
        return Fraction(0)
    if isinstance(a, Fraction) and isinstance(b, Fraction):
        return a * b
    if isinstance(a, float) or isinstance(b, float):
        return float(a) * float(b)
    return _mp(a) * _mp(b)


def _sum(terms: Iterable[Num]) -> Num:
    """Exact when every term is, else the correctly rounded sum of the terms (doubles), or their
    sum at the working precision (mpmath numbers)."""
    terms = [t for t in terms if t]
    if all(isinstance(t, Fraction) for t in terms):
        return sum(terms, Fraction(0))
    if any(isinstance(t, float) for t in terms):
        return math.fsum(terms)
    return mpmath.fsum(_mp(t) for t in terms)


@contextmanager
def _precision(digits: int | None) -> Iterator[None]:
    """mpmath's working precision for ``digits`` (a few guard digits over), or nothing for doubles."""
    with mpmath.workdps(digits + 10) if digits else nullcontext():
        yield


def _mp_value(c: Const) -> mpmath.mpf:
    """``a + b*pi + atan2(..)`` at mpmath's working precision."""
    v = _mp(c.a) + _mp(c.b) * mpmath.pi
    if c.atan2 is not None:
        sy, sx = (mpmath.sqrt(_mp(abs(s))) * (1 if s >= 0 else -1) for s in c.atan2)
        v += mpmath.atan2(sy, sx)
    return v


def _number(c: Const, digits: int | None = None) -> Num:
    if c.b == 0 and c.atan2 is None:
        return c.a
    return _mp_value(c) if digits else c.value


def _cos_sin(c: Const, digits: int | None) -> tuple[Num, Num]:
    if not digits:
        return math.cos(c.value), math.sin(c.value)
    v = _mp_value(c)
    return mpmath.cos(v), mpmath.sin(v)


def _sympy(x: Num, digits: int | None = None) -> sp.Expr:
    if isinstance(x, Fraction):
        return sp.Rational(x.numerator, x.denominator)
    return sp.Float(x, digits) if digits else sp.Float(x)


@dataclass(frozen=True)
class Fixed:
    """A constant transform ``(R, t)`` standing for ``count`` elementary transforms.

    ``cols`` are the columns of R, ``t`` the translation; entries are rationals where exact and
    doubles otherwise, or with ``digits`` mpmath numbers to that many significant digits (module
    docstring). Not a joint: walks apply it as ``T <- T (R, t)``.
    """

    cols: tuple[tuple[Num, Num, Num], ...]
    t: tuple[Num, Num, Num]
    count: int
    digits: int | None = None

    is_joint = False

    @staticmethod
    def of(run: Sequence[ET], digits: int | None = None) -> Fixed:
        """The product of the constant elementary transforms ``run``, left to right (the entries
        that are not exact to ``digits`` significant digits, or doubles without it)."""
        with _precision(digits):
            return Fixed._of(run, digits)

    @staticmethod
    def _of(run: Sequence[ET], digits: int | None) -> Fixed:
        one, zero = Fraction(1), Fraction(0)
        cols: list[list[Num]] = [[one if i == j else zero for i in range(3)] for j in range(3)]
        t: list[Num] = [zero] * 3
        for e in run:
            if e.is_joint:
                raise ValueError(f"only constant transforms fold, not the joint {e}")
            i = e.axis.index
            if not e.axis.is_rotation:
                d = _number(e.const, digits)
                t = [_sum((p, _mul(d, x))) for p, x in zip(t, cols[i])]
                continue
            j, kk = MIX[i]
            cj, ck = cols[j], cols[kk]
            k = e.const.quarter_turns
            if k is not None:  # a signed swap of two columns
                cols[j], cols[kk] = ((cj, ck), (ck, [-x for x in cj]), ([-x for x in cj], [-x for x in ck]),
                                     ([-x for x in ck], cj))[k]  # fmt: skip
                continue
            c, s = _cos_sin(e.const, digits)
            cols[j] = [_sum((_mul(c, x), _mul(s, y))) for x, y in zip(cj, ck)]
            cols[kk] = [_sum((_mul(c, y), _mul(-s, x))) for x, y in zip(cj, ck)]
        return Fixed(tuple(tuple(c) for c in cols), tuple(t), len(run), digits)  # type: ignore[arg-type]

    def inverse(self) -> Fixed:
        """``(R^T, -R^T t)``: the run walked backwards, each transform inverted."""
        rows = tuple(tuple(self.cols[j][i] for j in range(3)) for i in range(3))  # columns of R^T
        with _precision(self.digits):
            t = tuple(-_sum(_mul(self.cols[i][r], self.t[r]) for r in range(3)) for i in range(3))
        return Fixed(rows, t, self.count, self.digits)  # type: ignore[arg-type]

    def apply(
        self, cols: Sequence[Sequence[sp.Expr]], p: Sequence[sp.Expr]
    ) -> tuple[list[list[sp.Expr]], list[sp.Expr]]:
        """The pose with rotation columns ``cols`` and origin ``p`` times this transform:
        ``(R_pose R, p + R_pose t)``, each entry a combination of ``cols`` (zero terms left out)."""
        R, t = self.exprs

        def combine(coef: Sequence[sp.Expr], start: Sequence[sp.Expr]) -> list[sp.Expr]:
            return [
                s + sum((coef[r] * cols[r][i] for r in range(3) if coef[r] != 0), sp.Integer(0))
                for i, s in enumerate(start)
            ]

        return [combine(c, [sp.Integer(0)] * 3) for c in R], combine(t, p)

    @cached_property
    def exprs(self) -> tuple[tuple[tuple[sp.Expr, ...], ...], tuple[sp.Expr, ...]]:
        """The columns of R and t as sympy numbers (Rational where exact, else Float)."""
        d = self.digits
        return tuple(tuple(_sympy(x, d) for x in c) for c in self.cols), tuple(_sympy(x, d) for x in self.t)

    def __str__(self) -> str:
        return f"Fixed({self.count} transforms)"


def _folds(run: Sequence[ET]) -> bool:
    """Whether a run of constants folds: longer than :data:`MAX_RUN`, or two or more rotations
    that are not quarter turns."""
    if len(run) > MAX_RUN:
        return True
    return sum(1 for e in run if e.axis.is_rotation and e.const.quarter_turns is None) >= 2


def fold_constants(elements: Iterable[ET], digits: int | None = None) -> tuple[ET | Fixed, ...]:
    """``elements`` with every maximal run of constant transforms that is longer than
    :data:`MAX_RUN` or holds two or more rotations by angles other than multiples of pi/2
    replaced by one :class:`Fixed` (cached: the strategy choice folds each chain twice), its
    inexact entries doubles or with ``digits`` that many significant digits."""
    return _fold(tuple(elements), digits)


@lru_cache(maxsize=16)
def _fold(elements: tuple[ET, ...], digits: int | None = None) -> tuple[ET | Fixed, ...]:
    out: list[ET | Fixed] = []
    run: list[ET] = []

    def end_run() -> None:
        if _folds(run):
            out.append(Fixed.of(run, digits))
        else:
            out.extend(run)
        run.clear()

    for e in elements:
        if e.is_joint:
            end_run()
            out.append(e)
        else:
            run.append(e)
    end_run()
    return tuple(out)
