"""The elementary transform sequence (Haviland and Corke, Manipulator Differential Kinematics, Part 1,
2023, eqs 1-4, Fig. 2).

An ETS is a product of elementary transforms tx, ty, tz (translations) and Rx, Ry, Rz (rotations),
each either a constant or a joint variable. Constants are kept exact: a constant is
``a + b*pi (+ atan2(y, x))`` with rational ``a``, ``b``, ``y``, ``x``, so ``pi/2``, ``90deg`` and
``0.333`` stay exact and a rotation by a multiple of pi/2 is recognised as a signed permutation.

Text form (round-trips through :meth:`ETS.parse` and ``str``)::

    tz(0.333) Rz(q0) Rx(-pi/2) Rz(q1) * Rx(90deg) ⊕ tz(0.316) Rz(-q2)

Tokens are separated by whitespace, ``*`` or ``⊕``. A joint is ``q``, ``qN``, ``-q`` or ``-qN``
(flipped: positive joint motion is a negative rotation/translation about/along the axis; ``qN``
names the 0-based joint index, plain ``q`` numbers joints in order of appearance).
"""

from __future__ import annotations

import ast
import math
import numbers
import re
import sys
from collections.abc import Iterator
from dataclasses import dataclass
from enum import Enum
from fractions import Fraction
from typing import Any

from symkin.core.rational import rational_text
from symkin.errors import ETSParseError, RobotError

__all__ = ["Axis", "Const", "ET", "ETS", "rational_text", "surd", "tx", "ty", "tz", "Rx", "Ry", "Rz"]


class Axis(Enum):
    """The six elementary transforms of Fig. 2."""

    tx = "tx"
    ty = "ty"
    tz = "tz"
    Rx = "Rx"
    Ry = "Ry"
    Rz = "Rz"

    @property
    def is_rotation(self) -> bool:
        return self.value[0] == "R"

    @property
    def index(self) -> int:
        """0 for x, 1 for y, 2 for z."""
        return "xyz".index(self.value[1])


# ---------------------------------------------------------------------------------------------
# Exact constants


def _surd_value(s: Fraction) -> float:
    """A surd ``s`` stands for sign(s) * sqrt(|s|) (so a rational r is the surd r*|r|)."""
    return math.copysign(math.sqrt(abs(s)), s)


def surd(r: Fraction) -> Fraction:
    """The surd standing for the rational ``r``."""
    return r * abs(r)


def _surd_text(s: Fraction) -> str:
    num, den = abs(s.numerator), s.denominator
    rn, rd = math.isqrt(num), math.isqrt(den)
    if rn * rn == num and rd * rd == den:
        return rational_text(Fraction(rn, rd) * (1 if s >= 0 else -1))
    return ("-" if s < 0 else "") + f"sqrt({rational_text(abs(s))})"


@dataclass(frozen=True)
class Const:
    """An exact real constant ``a + b*pi + atan2(y, x)`` (the atan2 term only when ``atan2`` is set).

    The atan2 arguments are surds: ``atan2 = (sy, sx)`` stands for
    ``atan2(sign(sy) sqrt|sy|, sign(sx) sqrt|sx|)``, so a rotation taking z onto any axis with
    rational components is exact (its angles need square roots). Use :func:`surd` for rationals.
    """

    a: Fraction = Fraction(0)
    b: Fraction = Fraction(0)
    atan2: tuple[Fraction, Fraction] | None = None

    @staticmethod
    def of(value: float | int | Fraction | str | Const) -> Const:
        """An exact constant from a number (a float is taken as the decimal it prints as) or text."""
        if isinstance(value, Const):
            return value
        if isinstance(value, str):
            return _parse_const(value, value, 0)
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise TypeError(f"a constant must be a number or text, not {type(value).__name__}")
        if isinstance(value, (int, Fraction, numbers.Integral)):
            r = Fraction(int(value)) if isinstance(value, numbers.Integral) else value
            if abs(r) > _DBL_MAX:
                raise RobotError(f"a constant must be within the range of a double, not {value}")
            return Const(r)
        x = float(value)
        if not math.isfinite(x):
            raise RobotError(f"a constant must be finite, not {value}")
        return Const(Fraction(repr(x)))

    @staticmethod
    def pi_times(b: Fraction | int) -> Const:
        return Const(Fraction(0), Fraction(b))

    @property
    def value(self) -> float:
        v = float(self.a) + float(self.b) * math.pi
        if self.atan2 is not None:
            v += math.atan2(_surd_value(self.atan2[0]), _surd_value(self.atan2[1]))
        return v

    @property
    def is_zero(self) -> bool:
        return self.a == 0 and self.b == 0 and self.atan2 is None

    @property
    def quarter_turns(self) -> int | None:
        """k when the constant is exactly k*pi/2 (a signed-permutation rotation), else None."""
        if self.a != 0 or self.atan2 is not None:
            return None
        k = self.b * 2
        return int(k) % 4 if k.denominator == 1 else None

    def __neg__(self) -> Const:
        at = None if self.atan2 is None else (-self.atan2[0], self.atan2[1])
        if at is not None and at[0] == 0 and at[1] < 0:  # -atan2(0, -x) = -pi, not atan2(0, -x) = pi
            return Const(-self.a, -self.b - 2, at)
        return Const(-self.a, -self.b, at)

    def __add__(self, other: Const) -> Const:
        if self.atan2 is not None and other.atan2 is not None:
            raise RobotError("the sum of two atan2 constants is not representable")
        return Const(self.a + other.a, self.b + other.b, self.atan2 or other.atan2)

    def __str__(self) -> str:
        parts: list[str] = []
        if self.atan2 is not None:
            parts.append(f"atan2({_surd_text(self.atan2[0])},{_surd_text(self.atan2[1])})")
        if self.b != 0:
            num, den = abs(self.b.numerator), self.b.denominator
            text = "pi" if num == 1 else f"{num}*pi"
            if den != 1:
                text += f"/{den}"
            parts.append(("-" if self.b < 0 else "") + text)
        if self.a != 0 or not parts:
            parts.append(rational_text(self.a))
        out = parts[0]
        for p in parts[1:]:
            out += p if p.startswith("-") else "+" + p
        return out


# A number followed by deg/°. Unambiguous (one way to split the digits) and anchored at the start
# of a number by the lookbehind, so substitution takes linear time in the length of the text.
_DEG = re.compile(r"(?<![\w.])((?:\d+(?:\.\d*)?|\.\d+)(?:[eE][-+]?\d+)?)\s*(deg|°)")
_DBL_MAX = Fraction(sys.float_info.max)
MAX_CONST_CHARS = 1000  # longest constant text accepted (a float's exact decimal has under 800)


def _parse_const(arg: str, text: str, pos: int) -> Const:
    """Parse ``arg`` (found at ``pos`` of ``text``) into an exact Const.

    Raises ETSParseError for anything else, including text over :data:`MAX_CONST_CHARS`
    characters, nesting too deep to evaluate and values beyond the range of a double.
    """
    shown = arg if len(arg) <= 60 else arg[:57] + "..."

    def fail(why: str) -> ETSParseError:
        return ETSParseError(f"invalid constant '{shown}': {why}", text, pos)

    if len(arg) > MAX_CONST_CHARS:
        raise fail(f"{len(arg)} characters, more than the {MAX_CONST_CHARS} allowed")
    src = _DEG.sub(r"(\1*pi/180)", arg.strip())
    try:
        tree = ast.parse(src, mode="eval")
    except (SyntaxError, ValueError) as exc:  # ValueError: an integer with too many digits
        raise fail("not a number, an expression in pi, or a number with deg/°") from exc
    except (RecursionError, MemoryError):
        raise fail("nested too deeply") from None
    try:
        c = _evaluate(tree, fail)
    except RecursionError:
        raise fail("nested too deeply") from None
    try:
        finite = math.isfinite(c.value)
    except OverflowError:
        finite = False
    if not finite:
        raise fail("its value cannot be computed in double precision (a number beyond about 1.8e308)")
    return c


def _is_call(node: ast.AST, name: str, nargs: int) -> bool:
    """Whether ``node`` is the call ``name(...)`` with ``nargs`` positional arguments and no keywords."""
    return (
        isinstance(node, ast.Call)
        and isinstance(node.func, ast.Name)
        and node.func.id == name
        and len(node.args) == nargs
        and not node.keywords
    )


def _evaluate(tree: ast.Expression, fail: Any) -> Const:
    """The exact value of a parsed constant expression (see :func:`_parse_const`)."""

    def surd_arg(node: ast.AST) -> Fraction:
        neg = False
        while isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            neg ^= isinstance(node.op, ast.USub)
            node = node.operand
        if _is_call(node, "sqrt", 1):
            r = num(node.args[0])
            if r < 0:
                raise fail("sqrt of a negative number")
            return -r if neg else r
        v = surd(num(node))
        return -v if neg else v

    def num(node: ast.AST) -> Fraction:
        c = ev(node)
        if c.b != 0 or c.atan2 is not None:
            raise fail("pi may appear only linearly")
        return c.a

    def ev(node: ast.AST) -> Const:
        if isinstance(node, ast.Constant) and type(node.value) in (int, float):
            if isinstance(node.value, float) and not math.isfinite(node.value):
                raise fail("not finite")
            return Const(
                Fraction(repr(node.value)) if isinstance(node.value, float) else Fraction(node.value)
            )
        if isinstance(node, ast.Name) and node.id == "pi":
            return Const(Fraction(0), Fraction(1))
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
            v = ev(node.operand)
            return -v if isinstance(node.op, ast.USub) else v
        if isinstance(node, ast.BinOp) and isinstance(node.op, (ast.Add, ast.Sub)):
            left, right = ev(node.left), ev(node.right)
            try:
                return left + (right if isinstance(node.op, ast.Add) else -right)
            except ValueError as exc:
                raise fail(str(exc)) from exc
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Mult):
            left, right = ev(node.left), ev(node.right)
            if left.b == 0 and left.atan2 is None:
                left, right = right, left
            if right.b != 0 or right.atan2 is not None:
                raise fail("a product must have a plain number on one side")
            if left.atan2 is not None and right.a != 1:
                raise fail("atan2 may only be added, not scaled")
            return Const(left.a * right.a, left.b * right.a, left.atan2)
        if isinstance(node, ast.BinOp) and isinstance(node.op, ast.Div):
            left, d = ev(node.left), num(node.right)
            if d == 0:
                raise fail("division by zero")
            if left.atan2 is not None and d != 1:
                raise fail("atan2 may only be added, not scaled")
            return Const(left.a / d, left.b / d, left.atan2)
        if _is_call(node, "atan2", 2):
            y, x = surd_arg(node.args[0]), surd_arg(node.args[1])
            if y == 0 and x == 0:
                raise fail("atan2(0, 0) is undefined")
            return Const(atan2=(y, x))
        raise fail("only numbers, pi, deg/°, atan2(y, x) (sqrt(r) allowed inside) and + - * / are allowed")

    return ev(tree.body)


# ---------------------------------------------------------------------------------------------
# Elementary transforms


@dataclass(frozen=True)
class ET:
    """One elementary transform: a constant, or joint ``joint`` (0-based), optionally flipped."""

    axis: Axis
    const: Const | None = None
    joint: int | None = None
    flip: bool = False

    def __post_init__(self) -> None:
        if not isinstance(self.axis, Axis):
            raise TypeError(f"axis must be an Axis, not {self.axis!r}")
        if (self.const is None) == (self.joint is None):
            raise RobotError("an ET is either a constant or a joint, exactly one of the two")
        if self.joint is not None and (not isinstance(self.joint, int) or self.joint < 0):
            raise RobotError(f"joint index must be a non-negative int, not {self.joint!r}")
        if self.const is not None and self.flip:
            raise RobotError("only joints can be flipped")

    @property
    def is_joint(self) -> bool:
        return self.joint is not None

    @property
    def is_revolute(self) -> bool:
        return self.is_joint and self.axis.is_rotation

    @property
    def is_prismatic(self) -> bool:
        return self.is_joint and not self.axis.is_rotation

    @property
    def sign(self) -> int:
        """-1 for a flipped joint, else +1."""
        return -1 if self.flip else 1

    @classmethod
    def const_(cls, axis: Axis | str, value: float | int | Fraction | str | Const) -> ET:
        return cls(Axis(axis), const=Const.of(value))

    def __str__(self) -> str:
        if self.joint is not None:
            return f"{self.axis.value}({'-' if self.flip else ''}q{self.joint})"
        return f"{self.axis.value}({self.const})"


# convenience constructors: tx(0.1), Rz(q=0), Rz(q=1, flip=True)
def _maker(axis: Axis):  # noqa: ANN202
    def make(
        value: float | int | Fraction | str | Const | None = None, *, q: int | None = None, flip: bool = False
    ) -> ET:
        if q is not None:
            if value is not None:
                raise RobotError("give a constant or q=, not both")
            return ET(axis, joint=q, flip=flip)
        if value is None:
            raise RobotError("give a constant value or a joint index q=")
        return ET(axis, const=Const.of(value))

    make.__name__ = axis.value
    make.__doc__ = (
        f"The elementary transform {axis.value}: a constant, or joint ``q`` (``flip`` for negative)."
    )
    return make


tx, ty, tz, Rx, Ry, Rz = (_maker(a) for a in Axis)

_TOKEN = re.compile(r"(tx|ty|tz|Rx|Ry|Rz)\s*\(")
_JOINT = re.compile(r"(-?)\s*q(\d{0,9})")  # fullmatch on the stripped argument: linear time


def _tokens(text: str) -> Iterator[tuple[str, str, int]]:
    """Yield (axis, argument, position) for each token of ETS text, or raise at the bad spot."""
    i, n = 0, len(text)
    expect_token = True
    while i < n:
        ch = text[i]
        if ch.isspace():
            i += 1
            continue
        if ch in "*⊕":
            if expect_token:
                raise ETSParseError(f"unexpected '{ch}': a transform must come before it", text, i)
            expect_token = True
            i += 1
            continue
        m = _TOKEN.match(text, i)
        if not m:
            bad = re.match(r"\S+", text[i:])
            word = bad.group(0) if bad else ch
            raise ETSParseError(f"unknown token '{word}': expected one of tx( ty( tz( Rx( Ry( Rz(", text, i)
        depth, j = 1, m.end()
        while j < n and depth:
            depth += {"(": 1, ")": -1}.get(text[j], 0)
            j += 1
        if depth:
            raise ETSParseError("unclosed parenthesis", text, m.end() - 1)
        yield m.group(1), text[m.end() : j - 1], i
        expect_token = False
        i = j
    if expect_token and n and text.strip() and text.strip()[-1] in "*⊕":
        raise ETSParseError("the text ends with a separator", text, len(text.rstrip()) - 1)


# ---------------------------------------------------------------------------------------------
# The sequence


@dataclass(frozen=True)
class ETS:
    """A sequence of elementary transforms; the product left to right is the end-effector pose (eq 1).

    Joint indices must be exactly ``0 .. n-1``, each used once (in any order along the chain).
    """

    ets: tuple[ET, ...]

    def __post_init__(self) -> None:
        object.__setattr__(self, "ets", tuple(self.ets))
        for e in self.ets:
            if not isinstance(e, ET):
                raise TypeError(f"an ETS holds ET objects, not {type(e).__name__}")
        idx = sorted(e.joint for e in self.ets if e.joint is not None)
        if idx != list(range(len(idx))):
            raise RobotError(f"joint indices must be 0..{len(idx) - 1}, each once; got {idx}")

    # -- text form ------------------------------------------------------------------------
    @classmethod
    def parse(cls, text: str) -> ETS:
        """Parse the text form (module docstring). Errors point at the offending token."""
        if not isinstance(text, str):
            raise TypeError(f"ETS text must be a str, not {type(text).__name__}")
        out: list[ET] = []
        njoint = 0
        seen: dict[int, int] = {}
        for name, arg, pos in _tokens(text):
            axis = Axis(name)
            argpos = pos + len(name) + 1
            jm = _JOINT.fullmatch(arg.strip())
            if jm:
                index = int(jm.group(2)) if jm.group(2) else njoint
                if index in seen:
                    raise ETSParseError(f"joint q{index} appears twice", text, pos)
                seen[index] = pos
                out.append(ET(axis, joint=index, flip=bool(jm.group(1))))
                njoint += 1
            else:
                if not arg.strip():
                    raise ETSParseError(f"{name}() needs a constant or a joint q", text, pos)
                if re.fullmatch(r"-?\s*q\d+", arg.strip()):
                    raise ETSParseError("joint index too large (at most 9 digits)", text, argpos)
                out.append(ET(axis, const=_parse_const(arg, text, argpos)))
        if not out:
            raise ETSParseError("empty ETS: expected at least one transform", text, 0)
        if sorted(seen) != list(range(njoint)):
            missing = sorted(set(range(njoint)) - set(seen))
            bad = max(seen)
            raise ETSParseError(
                f"joint indices must be 0..{njoint - 1}, each once; "
                f"q{missing[0]} is missing and q{bad} is out of range",
                text,
                seen[bad],
            )
        return cls(tuple(out))

    def __str__(self) -> str:
        return " ".join(str(e) for e in self.ets)

    def __repr__(self) -> str:
        return f"ETS.parse({str(self)!r})"

    def _repr_latex_(self) -> str:
        from symkin.model.latex import ets_latex

        return "$" + ets_latex(self) + "$"

    # -- structure ------------------------------------------------------------------------
    def __iter__(self) -> Iterator[ET]:
        return iter(self.ets)

    def __len__(self) -> int:
        return len(self.ets)

    def __getitem__(self, i: int) -> ET:
        return self.ets[i]

    def __mul__(self, other: ETS | ET) -> ETS:
        """Concatenate; the joints of ``other`` are renumbered after those of ``self``."""
        if isinstance(other, ET):
            other = ETS((other,)) if other.joint is None else ETS((ET(other.axis, joint=0, flip=other.flip),))
        if not isinstance(other, ETS):
            return NotImplemented
        shift = self.n
        moved = tuple(
            e if e.joint is None else ET(e.axis, joint=e.joint + shift, flip=e.flip) for e in other.ets
        )
        return ETS(self.ets + moved)

    @property
    def n(self) -> int:
        """Number of joints."""
        return sum(1 for e in self.ets if e.joint is not None)

    @property
    def joints(self) -> tuple[ET, ...]:
        """The joint transforms ordered by joint index."""
        return tuple(sorted((e for e in self.ets if e.joint is not None), key=lambda e: e.joint))

    @property
    def structure(self) -> str:
        """'R'/'P' per joint, by joint index."""
        return "".join("R" if e.axis.is_rotation else "P" for e in self.joints)
