"""Code printers for the backends (subclasses of sympy's printers).

All printers write numbers as correctly rounded double literals (``repr(float(x))``) and small
integer powers as products, so the emitted code does exactly the arithmetic that was counted.
"""

from __future__ import annotations

import sympy as sp
from sympy.printing.c import C99CodePrinter
from sympy.printing.precedence import precedence
from sympy.printing.pycode import PythonCodePrinter

__all__ = [
    "CPrinter",
    "FloatCPrinter",
    "NumPyPrinter",
    "MathModulePrinter",
    "NumPyKinPrinter",
    "MathPrinter",
    "CasADiPrinter",
    "JaxPrinter",
    "TorchPrinter",
    "float_literal",
]


def float_literal(x: float) -> str:
    """A double literal that round-trips exactly: ``0.333``, ``2.0``, ``1e-20``."""
    text = repr(float(x))
    if text in ("inf", "-inf", "nan"):
        raise ValueError(f"non-finite constant {text} in generated code")
    if "." not in text and "e" not in text:
        text += ".0"
    return text


def _pow(printer, expr: sp.Pow, sqrt: str, one: str = "1.0") -> str:  # noqa: ANN001
    base, exp = expr.base, expr.exp
    b = printer.parenthesize(base, 60) if not base.is_Atom else printer._print(base)
    if exp.is_Integer and 1 <= int(exp) <= 4:
        return "(" + "*".join([b] * int(exp)) + ")"
    if exp.is_Integer and -4 <= int(exp) <= -1:
        return f"({one}/(" + "*".join([b] * -int(exp)) + "))"
    if exp == sp.Rational(1, 2):
        return f"{sqrt}({printer._print(base)})"
    raise ValueError(f"unsupported power {expr} in generated code")


class _DoubleLiterals:
    """Numbers as correctly rounded double literals (mixed into each printer)."""

    def _print_Rational(self, expr: sp.Rational) -> str:
        return float_literal(float(expr))

    def _print_Integer(self, expr: sp.Integer) -> str:
        return float_literal(int(expr))

    def _print_Float(self, expr: sp.Float) -> str:
        return float_literal(float(expr))


class _Calls:
    """Powers as products (:func:`_pow`), square roots, sines and cosines as calls of the names
    :meth:`_fn` gives them in the generated code (mixed into each printer)."""

    one = "1.0"  # the literal 1 of negative powers

    def _fn(self, name: str) -> str:
        """The generated code's name of the function ``name`` (``sqrt``, ``sin`` or ``cos``)."""
        return name

    def _print_Pow(self, expr: sp.Pow, rational: bool = False) -> str:
        return _pow(self, expr, self._fn("sqrt"), one=self.one)

    def _print_sin(self, expr: sp.sin) -> str:
        return f"{self._fn('sin')}({self._print(expr.args[0])})"  # type: ignore[attr-defined]

    def _print_cos(self, expr: sp.cos) -> str:
        return f"{self._fn('cos')}({self._print(expr.args[0])})"  # type: ignore[attr-defined]


class CPrinter(_DoubleLiterals, _Calls, C99CodePrinter):
    """C99 with exact double literals and multiplications for small powers; sin and cos as the
    template's ``sk_sin``/``sk_cos`` (the inline kernels of ``c/_sincos.c.j2``, or libm's with
    ``--libm``)."""

    def _fn(self, name: str) -> str:
        return name if name == "sqrt" else f"sk_{name}"


class FloatCPrinter(CPrinter):
    """Single-precision C: ``f``-suffixed literals (the double rounded to float by the compiler),
    ``sqrtf``; ``sk_sin``/``sk_cos`` map to ``sinf``/``cosf`` in the template."""

    one = "1.0f"

    def _print_Rational(self, expr: sp.Rational) -> str:
        return float_literal(float(expr)) + "f"

    def _print_Integer(self, expr: sp.Integer) -> str:
        return float_literal(int(expr)) + "f"

    def _print_Float(self, expr: sp.Float) -> str:
        return float_literal(float(expr)) + "f"

    def _fn(self, name: str) -> str:
        return "sqrtf" if name == "sqrt" else super()._fn(name)


class _PyLikePrinter(_DoubleLiterals, _Calls, PythonCodePrinter):
    module = "np"

    def _fn(self, name: str) -> str:
        return f"{self.module}.{name}"


class NumPyPrinter(_PyLikePrinter):
    """Elementwise NumPy expressions (``np.cos``) for the batched Python backend."""


class MathModulePrinter(NumPyPrinter):
    """Scalar Python with the math module (``math.cos``): the closed-form IK's code for one
    configuration."""

    module = "math"


class _PositiveFirst:
    """``-a + b`` (two terms, the first negated) printed as ``b - a``: the same IEEE result
    (x + (-y) == x - y, and addition commutes, signed zeros included), one negation less. Sums of
    three or more terms keep their order, which decides their rounding. Otherwise sympy's
    ``StrPrinter._print_Add``, each term printed once."""

    def _print_Add(self, expr: sp.Add, order: str | None = None) -> str:
        terms = self._as_ordered_terms(expr, order=order)  # type: ignore[attr-defined]
        prec = precedence(expr)
        signed = []
        for term in terms:
            t = self._print(term)  # type: ignore[attr-defined]
            sign = "+"
            if t.startswith("-") and not term.is_Add:
                sign, t = "-", t[1:]
            if precedence(term) < prec or term.is_Add:
                t = f"({t})"
            signed.append((sign, t))
        if len(signed) == 2 and signed[0][0] == "-" and signed[1][0] == "+":
            return f"{signed[1][1]} - {signed[0][1]}"
        text = " ".join(f"{sign} {t}" for sign, t in signed)
        return text[2:] if text.startswith("+ ") else "-" + text[2:]


class NumPyKinPrinter(_PositiveFirst, NumPyPrinter):
    """The NumPy backend's batch code: :class:`NumPyPrinter` with ``-a + b`` as ``b - a``."""


class MathPrinter(_PositiveFirst, _PyLikePrinter):
    """Scalar Python for one configuration: ``cos``, ``sin`` and ``sqrt`` as imported from ``math``
    into the generated module (a global each: faster than ``math.cos`` per call), ``-a + b`` as
    ``b - a``."""

    def _fn(self, name: str) -> str:
        return name


class CasADiPrinter(_PyLikePrinter):
    """CasADi SX expressions (``ca.cos``)."""

    module = "ca"


class JaxPrinter(_PositiveFirst, _PyLikePrinter):
    """``jax.numpy`` expressions (``jnp.cos``) on arrays of any batch shape; numbers stay Python
    floats, which JAX treats as weakly typed (the array's float32 or float64 is kept)."""

    module = "jnp"


class TorchPrinter(_PositiveFirst, _PyLikePrinter):
    """``torch`` expressions (``torch.cos``) on tensors of any batch shape; numbers stay Python
    floats, so the tensor's dtype and device are kept."""

    module = "torch"
