"""What every derivation shares: the Derivation record, the ETS constants as sympy values, the
elementary transform matrices, the LaTeX printer with textbook abbreviations and the Markdown ->
LaTeX document writer."""

from __future__ import annotations

import itertools
import operator
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import sympy as sp

from symkin.errors import SymkinError
from symkin.model.ets import ET, ETS, Axis, Const, rational_text
from symkin.model.latex import text_latex
from symkin.model.robot import Robot
from symkin.symbolic.cse import count_ops
from symkin.symbolic.fold import MIX
from symkin.symbolic.kinematics import const_to_sympy

__all__ = [
    "CHECK_TEXT",
    "aligned",
    "hessian_pattern",
    "summary",
    "shared_context",
    "shown_sections",
    "FORMATS",
    "SECTIONS",
    "Constants",
    "Derivation",
    "Printer",
    "constants",
    "et_matrix",
    "generator",
    "products",
    "latex_document",
    "mp_function",
    "ops_of",
]

#: The parts of a written derivation, in order (``derive --sections fk,jacobian``). The heading and
#: the joint table are always written. In the program form a part that uses named quantities also
#: brings the parts that define them (``fk`` the link frames, ``jacobian`` the link frames and ``fk``).
SECTIONS = ("ets", "transforms", "links", "fk", "derivatives", "jacobian", "hessian", "checks")
_NEEDS_PROGRAM = {"fk": ("links",), "jacobian": ("links", "fk"), "hessian": ("links", "fk", "jacobian")}


def shown_sections(sections: Sequence[str] | str | None, program: bool = False) -> set[str]:
    """The parts to write: ``sections`` (names of :data:`SECTIONS`, or one string of them separated by
    commas or spaces; None: all), in the ``program`` form with the parts they need."""
    if sections is None:
        return set(SECTIONS)
    names = sections.replace(",", " ").split() if isinstance(sections, str) else list(sections)
    bad = [k for k in names if k not in SECTIONS]
    if bad or not names:
        raise SymkinError(f"unknown section(s) {bad or names}: choose from {', '.join(SECTIONS)}")
    return set(names).union(*(_NEEDS_PROGRAM.get(k, ()) for k in names if program))


DISPLAY_MAX_OPS = 900  # larger expressions are not printed


def mp_function(
    lines: Sequence[tuple[sp.Symbol, sp.Expr]], inputs: Sequence[sp.Symbol], outputs: list[sp.Expr]
) -> Any:
    """A straight-line program (``lines`` of named intermediates, only those ``outputs`` need) as
    one Python function of ``inputs`` returning the outputs, evaluated with mpmath (joint symbols
    ``q_k``, constants ``l_k`` and intermediates ``tk`` are valid Python names as they are)."""
    import mpmath
    from sympy.printing.pycode import MpmathPrinter

    from symkin.symbolic.program import needed_lines

    printer = MpmathPrinter({"fully_qualified_modules": True})
    needed = set(needed_lines(lines, outputs))
    body = [f"    {s} = {printer.doprint(e)}" for i, (s, e) in enumerate(lines) if i in needed]
    src = (
        f"def f({', '.join(str(s) for s in inputs)}):\n"
        + "\n".join(body)
        + f"\n    return [{', '.join(printer.doprint(e) for e in outputs)}]\n"
    )
    scope: dict[str, Any] = {"mpmath": mpmath}
    exec(compile(src, "<symkin program>", "exec"), scope)  # noqa: S102 - our own printed code
    return scope["f"]


def ops_of(expr: Any) -> int:
    """Operations of an expression, memoised over shared subexpressions (no recursion)."""
    return count_ops(sp.sympify(expr)).total


FORMATS = ("markdown", "latex")


@dataclass(frozen=True, eq=False)
class Derivation:
    """A robot's kinematics derived step by step. Matrices are sympy ``ImmutableMatrix``.

    Attributes:
        robot: the robot.
        q: joint symbols ``q_1 .. q_n``; ``q[j]`` is symkin's joint ``j`` (0-based).
        constants: symbol -> exact value of each symbolic link constant (empty unless
            ``symbolic_constants``); :meth:`numeric` substitutes them.
        E: the elementary transforms of the ETS as 4x4 matrices, in chain order (Fig. 2).
        T: end-effector pose 0T_e, 4x4 (eq 1).
        links: link frames 0T_j by joint index (eq 5).
        ee: the end-effector pose in each link frame, jT_e, by joint index.
        dT: dT/dq_j by joint index, 4x4 each (eq 26).
        J0: base-frame Jacobian 6xn, rows (v, omega), by eqs 27-28.
        J0_fast: the same by the fast form, eqs 31-34.
        H0: Hessian blocks, ``H0[i] = dJ0/dq_i`` 6xn (eq 20 of the manipulability paper).
        simplified: whether the results are the compact forms (else the literal products).
        checks: how each equality was established: ``"symbolic"`` or ``"numeric"``.
        fmt: the format of ``text``; text: the derivation as Markdown or a LaTeX document.
        markdown: the derivation as Markdown whatever ``fmt`` (what Jupyter shows).
        shown: the sections written (:data:`SECTIONS`).
        form: ``"expanded"`` (every result multiplied out) or ``"program"`` (long chains: the
            results are matrices over named intermediates, ``intermediates`` lists their
            definitions in order and :meth:`expand` substitutes them back; ``dT`` and ``ee`` are
            empty).
        intermediates: (symbol, expression) of each named intermediate (program form).
        sections: where the intermediates of each link frame, the pose, the Jacobian and the Hessian
            end (the marks of :class:`symkin.symbolic.program.TreeProgram`, the chain as a tree).
    """

    robot: Robot
    q: tuple[sp.Symbol, ...]
    constants: Mapping[sp.Symbol, sp.Expr]
    E: tuple[sp.ImmutableMatrix, ...]
    T: sp.ImmutableMatrix
    links: tuple[sp.ImmutableMatrix, ...]
    ee: tuple[sp.ImmutableMatrix, ...]
    dT: tuple[sp.ImmutableMatrix, ...]
    J0: sp.ImmutableMatrix
    J0_fast: sp.ImmutableMatrix
    H0: tuple[sp.ImmutableMatrix, ...]
    simplified: bool
    checks: Mapping[str, str]
    fmt: str = "markdown"
    text: str = ""
    latex_summary: str = field(default="", repr=False)
    form: str = "expanded"
    intermediates: tuple[tuple[sp.Symbol, sp.Expr], ...] = field(default=(), repr=False)
    sections: tuple[tuple[str, int], ...] = field(default=(), repr=False)
    markdown: str = field(default="", repr=False)
    shown: tuple[str, ...] = SECTIONS

    def numeric(self, expr: Any) -> Any:
        """``expr`` with the symbolic link constants replaced by their values."""
        return sp.sympify(expr).xreplace(dict(self.constants))

    def expand(self, expr: Any) -> Any:
        """``expr`` with the named intermediates of the program form substituted back, in terms of
        the joint symbols (large for long chains: that is why they are named)."""
        expr = sp.sympify(expr)
        for s, e in reversed(self.intermediates):
            if expr.has(s):
                expr = expr.xreplace({s: e})
        return expr

    def _repr_latex_(self) -> str:
        return self.latex_summary

    def _repr_markdown_(self) -> str:
        """The written derivation (Markdown with ``$$`` math) for Jupyter."""
        return self.markdown


@dataclass(frozen=True, eq=False)
class Constants:
    """The ETS handed to ``derive`` (symbolic translation constants replaced by unique
    placeholder constants), the value of each factor, and the names shown in the ETS."""

    ets: ETS
    eta: tuple[sp.Expr | None, ...]  # value of each constant factor, by position (None: a joint)
    names: dict[int, str]  # LaTeX argument by position, for symbolic constants
    values: dict[sp.Symbol, sp.Expr]
    factor: dict[sp.Symbol, int]  # the position of each symbol's factor in the ETS
    placeholders: dict[Const, sp.Expr]

    def constant(self, c: Const) -> sp.Expr:
        return self.placeholders[c] if c in self.placeholders else const_to_sympy(c)


def constants(ets: ETS, symbolic: bool) -> Constants:
    if not symbolic:
        eta = tuple(None if e.const is None else const_to_sympy(e.const) for e in ets)
        return Constants(ets, eta, {}, {}, {}, {})
    used = {e.const for e in ets if e.const is not None}
    scale = 10**40
    while any(Const(Fraction(i + 1, scale)) in used for i in range(len(ets))):
        scale += 1
    out: list[ET] = []
    eta: list[sp.Expr | None] = []
    names: dict[int, str] = {}
    values: dict[sp.Symbol, sp.Expr] = {}
    factor: dict[sp.Symbol, int] = {}
    placeholders: dict[Const, sp.Expr] = {}
    for pos, e in enumerate(ets):
        if e.const is None or e.axis.is_rotation or e.const.is_zero:
            out.append(e)
            eta.append(None if e.const is None else const_to_sympy(e.const))
            continue
        k = len(values) + 1
        sym = sp.Symbol(f"l_{k}", positive=True)
        value = const_to_sympy(e.const)
        sign = -1 if value.is_negative else 1
        values[sym] = sign * value
        factor[sym] = pos
        ph = Const(Fraction(pos + 1, scale))
        placeholders[ph] = sign * sym
        out.append(ET(e.axis, const=ph))
        eta.append(sign * sym)
        names[pos] = ("-" if sign < 0 else "") + f"l_{{{k}}}"
    return Constants(ETS(tuple(out)), tuple(eta), names, values, factor, placeholders)


def et_matrix(axis: Axis, eta: Any, lib: Any = sp) -> Any:
    """The elementary transform of Fig. 2 (a sympy matrix, or with ``lib=mpmath`` an mpmath one)."""
    M = lib.eye(4)
    i = axis.index
    if axis.is_rotation:
        j, k = MIX[i]
        M[j, j] = M[k, k] = lib.cos(eta)
        M[j, k], M[k, j] = -lib.sin(eta), lib.sin(eta)
    else:
        M[i, 3] = eta
    return M


def generator(axis: Axis, lib: Any = sp) -> Any:
    """[G] of eqs 20-25: dE/deta = [G] E (a sympy matrix, or with ``lib=mpmath`` an mpmath one)."""
    G = lib.zeros(4, 4)
    i = axis.index
    if axis.is_rotation:
        j, k = MIX[i]
        G[k, j], G[j, k] = 1, -1
    else:
        G[i, 3] = 1
    return G


def products(E: Sequence[Any], eye: Any) -> tuple[list[Any], list[Any]]:
    """The prefix products ``E_1 ... E_k`` (k = 0 .. M, the first ``eye``) and the suffix products
    ``E_k ... E_M`` (k = 1 .. M + 1, the last ``eye``) of the factors ``E``."""
    prefix = list(itertools.accumulate(E, operator.mul, initial=eye))
    suffix = list(itertools.accumulate(reversed(E), lambda acc, M: M * acc, initial=eye))
    return prefix, suffix[::-1]


class Printer:
    """sympy -> LaTeX with textbook abbreviations ``c_{12} = cos(q_1 + q_2)`` and decimals; the
    intermediates of a program (``named``: (symbol, expression) in order) print as ``zeta_k``."""

    def __init__(self, q: Sequence[sp.Symbol], named: Sequence[tuple[sp.Symbol, sp.Expr]] = ()) -> None:
        self.index = {s: j + 1 for j, s in enumerate(q)}
        self.used: dict[sp.Symbol, tuple[str, str]] = {}  # abbreviation -> (latex, meaning)
        self.names: dict[sp.Symbol, str] = {s: f"\\zeta_{{{i}}}" for i, (s, _) in enumerate(named)}

    def _abbreviation(self, f: sp.Expr) -> sp.Symbol | None:
        idx = []
        for term, c in f.args[0].as_coefficients_dict().items():
            if c != 1 or term not in self.index:
                return None
            idx.append(self.index[term])
        idx.sort()
        kind = "c" if isinstance(f, sp.cos) else "s"
        sym = sp.Symbol(f"zz{kind}{'_'.join(map(str, idx))}")
        sub = ("" if len(self.index) < 10 else ",").join(map(str, idx))  # c_{12} or c_{1,2}, never both
        tex = f"{kind}_{{{sub}}}"
        arg = " + ".join(f"q_{{{i}}}" for i in idx)
        fn = "\\cos" if kind == "c" else "\\sin"
        meaning = f"{fn} {arg}" if len(idx) == 1 else f"{fn}({arg})"
        self.used[sym] = (tex, meaning)
        self.names[sym] = tex
        return sym

    def _fraction_of_angle(self, f: sp.Expr) -> sp.Symbol | None:
        """``sin(q_4 / 2)`` as ``\\sin(q_{4}/2)`` (the rationals below would print 0.5 q_4)."""
        c, q = f.args[0].as_coeff_Mul()
        if q not in self.index or not c.is_Rational or c.is_Integer:
            return None
        fn = "\\cos" if isinstance(f, sp.cos) else "\\sin"
        num = "" if c.p == 1 else ("-" if c.p == -1 else f"{c.p} ")
        sym = sp.Symbol(f"zzfrac{len(self.names)}")
        self.names[sym] = f"{fn}({num}q_{{{self.index[q]}}}/{c.q})"
        return sym

    def __call__(self, expr: Any) -> str:
        expr = sp.sympify(expr)
        ops = ops_of(expr)
        if ops > DISPLAY_MAX_OPS:
            return f"\\text{{(an expression of {ops} operations, not shown)}}"
        subs = {}
        for f in expr.atoms(sp.cos, sp.sin):
            a = self._abbreviation(f) or self._fraction_of_angle(f)
            if a is not None:
                subs[f] = a
        for pw in expr.atoms(sp.Pow):  # roots keep their exponent: sqrt(2), not 2^0.5
            if pw.exp.is_Rational and not pw.exp.is_Integer:
                sym = sp.Symbol(f"zzpow{len(self.names)}")
                self.names[sym] = sp.latex(pw)
                subs[pw] = sym
        for r in expr.atoms(sp.Rational):
            den = r.q
            while den % 2 == 0:
                den //= 2
            while den % 5 == 0:
                den //= 5
            if r.q > 1 and den == 1:  # every terminating decimal as a decimal, as in the ETS
                text = rational_text(Fraction(int(r.p), int(r.q)))
                subs[r] = sp.Float(text, max(15, len(text)))
        return sp.latex(expr.xreplace(subs), symbol_names=self.names)

    def matrix(self, M: sp.Matrix) -> str:
        rows = [" & ".join(self(M[r, c]) for c in range(M.cols)) for r in range(M.rows)]
        return "\\begin{pmatrix} " + " \\\\ ".join(rows) + " \\end{pmatrix}"

    def legend(self) -> str:
        items = sorted(self.used.items(), key=lambda kv: (kv[0].name[2], len(kv[0].name), kv[0].name))
        return ", ".join(f"${tex} = {meaning}$" for _, (tex, meaning) in items)


INLINE = re.compile(r"(\$[^$]*\$|`[^`]*`)")


def inline_latex(text: str) -> str:
    """Markdown text -> LaTeX: ``$math$`` kept, backquoted code in typewriter, the rest escaped."""
    out = []
    for part in INLINE.split(text):
        if part.startswith("$"):
            out.append(part)
        elif part.startswith("`"):
            out.append(f"\\texttt{{{text_latex(part[1:-1])}}}")
        else:
            out.append(text_latex(part))
    return "".join(out)


def latex_document(markdown: str) -> str:
    """The template's Markdown (``#`` title, ``##`` sections, ``###`` subsections, paragraphs, ``$$``
    blocks, pipe tables) as a standalone LaTeX document (amsmath only)."""
    body: list[str] = []
    title = ""
    table = False
    lines = iter(markdown.splitlines())
    for line in lines:
        if table and not line.startswith("|"):
            body += [r"\end{tabular}", r"\end{center}", ""]
            table = False
        if line.startswith("# "):
            title = inline_latex(line[2:])
        elif line.startswith(("## ", "### ")):
            level = "section" if line.startswith("## ") else "subsection*"
            body += [rf"\{level}{{{inline_latex(line.split(' ', 1)[1])}}}", ""]
        elif line == "$$":
            body += [r"\[", *iter(lines.__next__, "$$"), r"\]", ""]
        elif line.startswith("|") and not set(line) <= set("|-"):
            cells = [inline_latex(c.strip()) for c in line.strip().strip("|").split(" | ")]
            if not table:
                body += [r"\begin{center}", r"\begin{tabular}{" + "l" * len(cells) + "}"]
                table = True
            body.append(" & ".join(cells) + r" \\")
        elif line.strip() and not line.startswith("|"):
            body += [inline_latex(line), ""]
    head = [r"\documentclass[a4paper,10pt]{article}", r"\usepackage[margin=2cm]{geometry}",
            r"\usepackage{amsmath,amssymb}", r"\setcounter{MaxMatrixCols}{40}", r"\allowdisplaybreaks",
            rf"\title{{{title}}}", r"\date{}", r"\begin{document}", r"\maketitle", ""]  # fmt: skip
    return "\n".join(head + body + [r"\end{document}"]) + "\n"


CHECK_TEXT = {
    "symbolic": "the difference simplifies to 0",
    "numeric": "the difference vanishes at 3 random points to 30 digits (too large to expand symbolically)",
    "failed": "NOT equal",
}


def shared_context(D: Any, P: Printer, C: Constants) -> dict[str, Any]:
    """What the chain's and the program's written derivations both show: the robot, its ETS, the
    joints (each with its factor), the named constants, every factor as a matrix, the checks."""
    from symkin.core.version import __version__
    from symkin.model.latex import display_name, et_latex, ets_latex

    robot, n, ets = D.robot, len(D.q), D.robot.ets
    mu = {e.joint: k for k, e in enumerate(ets) if e.joint is not None}
    kinds = {True: "revolute", False: "prismatic"}
    return {
        "robot": display_name(robot.name),
        "n": n,
        "structure": ets.structure,
        "M": len(ets),
        "source": robot.source.rstrip(".") + ". " if robot.source else "",
        "version": __version__,
        "joint_map": ", ".join(f"$q_{{{j + 1}}}$ is `q{j}`" for j in range(n)),
        "ets": ets_latex(ets, names=C.names),
        "checks": "; ".join(f"{k}: {CHECK_TEXT[v]}" for k, v in D.checks.items()),
        "joints": [
            [
                f"$q_{{{j + 1}}}$",
                f"`q{j}`",
                f"`{display_name(robot.joint_names[j])}`",
                kinds[ets[mu[j]].is_revolute],
                f"$E_{{{mu[j] + 1}}} = {et_latex(ets[mu[j]])}$",
            ]
            for j in range(n)
        ],  # fmt: skip
        "constants": [
            [f"${sp.latex(s)}$", f"$E_{{{C.factor[s] + 1}}}$", f"${P(v)}$"] for s, v in C.values.items()
        ],
        "factors": [
            f"E_{{{k + 1}}} = {et_latex(e, C.names.get(k))} = {P.matrix(D.E[k])}" for k, e in enumerate(ets)
        ],
    }


def aligned(rows: Iterable[str]) -> str:
    """Rows ``lhs &= rhs`` as one aligned block."""
    return r"\begin{aligned} " + r" \\ ".join(rows) + r" \end{aligned}"


def summary(D: Any, P: Printer, C: Constants, *rows: str) -> str:
    """What Jupyter shows of a chain's derivation ``D``: its ETS and position (then ``rows``)."""
    from symkin.model.latex import ets_latex

    xyz = [f"{'xyz'[r]} &= {P(D.T[r, 3])}" for r in range(3)]
    return f"$${aligned([ets_latex(D.robot.ets, '{}^{0}T_{e} &', C.names), *xyz, *rows])}$$"


def hessian_pattern(P: Printer, H0: Sequence[Any]) -> str:
    """The pattern of the Hessian blocks ``H0``: a bullet where dJ_j/dq_i is not zero."""
    n, dot = len(H0), sp.Symbol("zzbullet")
    P.names[dot] = r"\bullet"
    pattern = sp.Matrix(n, n, lambda i, c: 0 if H0[i][:, c].is_zero_matrix else dot)
    return rf"\big(\partial J_j / \partial q_i \neq 0\big)_{{ij}} = {P.matrix(pattern)}"
