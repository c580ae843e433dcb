"""LaTeX for models, written by hand (no sympy): an ETS as ``{}^0T_e = t_z(0.333) R_z(q_1) ...``.

The model's LaTeX text form (as ``str`` is its plain one), used by ``ETS._repr_latex_`` and
``Robot._repr_latex_`` and by the derivations above the model; it reads the model's objects by
their attributes and imports none of them (so the model imports it without a circle).

Joints are shown 1-based like the seed (``q_1 .. q_n``): symkin's joint ``q{j}`` (0-based index
``j``) is displayed as ``q_{j+1}``. A flipped joint reads ``R_y(-q_4)``.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from fractions import Fraction
from math import isqrt
from typing import Any

from symkin.core.rational import rational_text

__all__ = ["ets_latex", "et_latex", "const_latex", "robot_latex", "text_latex", "joint_latex", "display_name"]

AXIS_LATEX = {name: f"{name[0]}_{name[1]}" for name in ("tx", "ty", "tz", "Rx", "Ry", "Rz")}  # tx: t_x
_TEXT_ESCAPES = {
    "\\": r"\textbackslash{}",
    "{": r"\{",
    "}": r"\}",
    "_": r"\_",
    "%": r"\%",
    "&": r"\&",
    "#": r"\#",
    "$": r"\$",
    "^": r"\^{}",
    "~": r"\~{}",
}


def display_name(name: str) -> str:
    """A robot's name as shown in Markdown and LaTeX derivations: characters that would open math
    (``$``), code spans, escapes or new lines become ``?``."""
    return re.sub(r"[`$\\\x00-\x1f\x7f]", "?", name)


def text_latex(text: str) -> str:
    """Arbitrary text made safe inside ``\\text{...}`` or a LaTeX paragraph."""
    return "".join(_TEXT_ESCAPES.get(ch, ch) for ch in text)


def joint_latex(j: int) -> str:
    """The display name of symkin's 0-based joint ``j``: ``q_{j+1}``."""
    return f"q_{{{j + 1}}}"


def _rational_latex(r: Fraction) -> str:
    """A rational as a decimal when it terminates, else ``\\frac{n}{d}`` (sign in front)."""
    text = rational_text(abs(r))
    if "/" in text:
        num, den = text.split("/")
        text = f"\\frac{{{num}}}{{{den}}}"
    elif "e" in text:
        mant, exp = text.split("e")
        text = f"{mant} \\times 10^{{{int(exp)}}}"
    return ("-" if r < 0 else "") + text


def _surd_latex(s: Fraction) -> str:
    """A surd s (standing for sign(s) sqrt|s|) as LaTeX."""
    num, den = abs(s.numerator), s.denominator
    rn, rd = _isqrt_exact(num), _isqrt_exact(den)
    sign = "-" if s < 0 else ""
    if rn is not None and rd is not None:
        return sign + _rational_latex(Fraction(rn, rd))
    return f"{sign}\\sqrt{{{_rational_latex(abs(s))}}}"


def _isqrt_exact(k: int) -> int | None:
    r = isqrt(k)
    return r if r * r == k else None


def const_latex(c: Any) -> str:
    """An exact ETS constant ``a + b pi + atan2(y, x)`` as LaTeX, e.g. ``-\\frac{\\pi}{2}``."""
    parts: list[str] = []
    if c.atan2 is not None:
        y, x = c.atan2
        parts.append(f"\\operatorname{{atan2}}\\left({_surd_latex(y)}, {_surd_latex(x)}\\right)")
    if c.b != 0:
        num, den = abs(c.b.numerator), c.b.denominator
        top = "\\pi" if num == 1 else f"{num}\\pi"
        text = top if den == 1 else f"\\frac{{{top}}}{{{den}}}"
        parts.append(("-" if c.b < 0 else "") + text)
    if c.a != 0 or not parts:
        parts.append(_rational_latex(c.a))
    out = parts[0]
    for p in parts[1:]:
        out += " " + (f"- {p[1:]}" if p.startswith("-") else f"+ {p}")
    return out


def et_latex(e: Any, arg: str | None = None) -> str:
    """One elementary transform, e.g. ``R_z(q_{1})``; ``arg`` overrides the constant's text."""
    if e.joint is not None:
        inner = ("-" if e.flip else "") + joint_latex(e.joint)
    else:
        inner = arg if arg is not None else const_latex(e.const)  # type: ignore[arg-type]
    return f"{AXIS_LATEX[e.axis.name]}({inner})"


def ets_latex(ets: Any, lhs: str | None = "{}^{0}T_{e}", names: Mapping[int, str] | None = None) -> str:
    """The ETS as a product of elementary transforms (eq 1), without ``$`` delimiters.

    Args:
        ets: the sequence.
        lhs: the left-hand side (``None`` for the bare product).
        names: LaTeX for the argument of the constant at position ``k`` of the sequence (e.g.
            ``{0: "l_{1}"}``), shown instead of its value.
    """
    names = names or {}
    body = " ".join(et_latex(e, names.get(k)) for k, e in enumerate(ets)) or "I"
    return body if lhs is None else f"{lhs} = {body}"


def robot_latex(robot: Any) -> str:
    """A robot's name and ETS for Jupyter (``Robot._repr_latex_``), with ``$`` delimiters."""
    return f"$\\text{{{text_latex(robot.name)}}}:\\; {ets_latex(robot.ets)}$"
