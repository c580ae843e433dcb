"""Exact rationals as short text (leaf module)."""

from __future__ import annotations

from decimal import Decimal, localcontext
from fractions import Fraction

__all__ = ["rational_text"]


def rational_text(r: Fraction) -> str:
    """Shortest exact text for a rational: a float's repr when that is exact (``0.333``, ``1e+300``),
    else a terminating decimal, else ``n/d``."""
    if abs(r) < 1e308:
        short = repr(float(r))
        if Fraction(short) == r:
            return short[:-2] if short.endswith(".0") else short
    if r.denominator == 1:
        return str(r.numerator)
    d = r.denominator
    while d % 2 == 0:
        d //= 2
    while d % 5 == 0:
        d //= 5
    if d != 1:
        return f"{r.numerator}/{r.denominator}"
    with localcontext() as ctx:
        ctx.prec = 200
        text = str((Decimal(r.numerator) / Decimal(r.denominator)).normalize())
    return text.replace("E", "e").replace("e+", "e")
