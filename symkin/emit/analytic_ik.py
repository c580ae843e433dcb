"""Lower a derived closed form (:class:`symkin.symbolic.analytic_ik.AnalyticIK`) to C, NumPy or
plain Python through the templates ``templates/c/analytic_ik*.j2`` and ``templates/python/analytic_ik.py.j2``
(both Python dialects).

The body is a nest of blocks, one per step: the step's coefficients (CSE'd), then the angle, its
cosine and sine (from the subproblem's own atan2/acos arguments, no extra trig calls), and, for a
two-branch step, a loop over the sign. Each leaf writes one candidate row into its fixed slot
(``sum_k i_k 2^(B-1-k)`` over the B branch indices, so leaves come in slot order) with a flag
saying whether a subproblem was clamped or singular (such rows are verified against the pose
before they are returned).

One writer (:func:`body`) spells the body in each dialect; the C body has the same steps, slots and
flags as the NumPy and Python bodies, with the trigonometry cut down where the exact coefficients allow it:

- subproblem 4 with constant ``A, B``: ``b = atan2(A, B)``, its cosine, sine and ``1 / sqrt(A^2 + B^2)``
  are folded in at generation time (``sk_sp4k``); with ``C = 0`` identically, ``d = pi/2``
  (``sk_sp4z``); ``acos`` is ``atan2(sqrt((1 - x)(1 + x)), x)``; one inline ``sk_atan2`` throughout;
- mirrored branches: when the second branch of a subproblem 4 is a sign pattern of the first
  (``b`` a multiple of pi/2 gives ``t' = -t`` or ``pi - t``; ``C = 0`` gives ``t' = t + pi``), every
  following subproblem 1 whose arguments ``(y, x)`` change only by signs under that pattern (checked
  exactly with sympy) takes its angle from the first branch (``-t``, ``pi - t`` or ``t +- pi``) with no
  atan2: the wrist flip of a spherical wrist, the ``q5`` and summed-angle flip of a UR arm. A flagged
  (singular or clamped) first branch is recomputed instead.
- the leaves come in slot order (the first two-branch step is the highest bit of the slot) and go
  straight into the filter (``sk_keep_``) with a mask of the two-branch steps that were nearly
  degenerate (``sin d`` or the prismatic root below the merge tolerance), so only rows that can be
  duplicates are compared.
"""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from symkin.core.names import c_string, comment_safe, identifier
from symkin.emit.printers import CPrinter, MathModulePrinter, NumPyPrinter
from symkin.emit.templates import render
from symkin.symbolic.analytic_ik import AnalyticIK, Step, cs_names, given_symbols, pose_symbols
from symkin.symbolic.cse import floatify
from symkin.symbolic.ik_geometry import is_zero, random_point, same_value, value_at

__all__ = ["render_analytic", "ik_prefix", "BACKEND_DIALECT", "body", "branch_mirror", "step_mirror"]

BACKEND_DIALECT = {"c": "c", "numpy": "numpy", "casadi": "python"}


def ik_prefix(robot_name: str) -> str:
    return f"symkin_{identifier(robot_name)}_ik"


@dataclass
class Out:
    lines: list[str]
    depth: int

    def emit(self, text: str) -> None:
        self.lines.append("    " * self.depth + text)


def cse_lines(exprs: list[sp.Expr], prefix: str) -> tuple[list[tuple[sp.Symbol, sp.Expr]], list[sp.Expr]]:
    flat = [floatify(e) for e in exprs]
    repl, reduced = sp.cse(flat, symbols=sp.numbered_symbols(prefix), order="none")
    return list(repl), list(reduced)


def used_later(plan: AnalyticIK) -> list[set[str]]:
    """Names of the symbols each step's successors use."""
    used: list[set[str]] = []
    acc: set[str] = set()
    for st in reversed(plan.steps):
        used.append(set(acc))
        for _, e in st.exprs:
            acc |= {str(s) for s in e.free_symbols}
    return used[::-1]


# -- mirrored branches (the C body) ------------------------------------------------------------

Pattern = tuple[int, int]  # signs of (cos, sin) of the second branch relative to the first


def branch_mirror(st: Step) -> Pattern | None:
    """How the second branch ``t = b - d`` of a subproblem 4 relates to the first ``b + d``, as
    signs of (cos t, sin t), or None when it is no sign pattern."""
    if st.kind != "sp4":
        return None
    e = dict(st.exprs)
    A, B, C = e["A"], e["B"], e["C"]
    if not (A.free_symbols | B.free_symbols):
        if is_zero(A) and not is_zero(B):
            return (1, -1)  # b = 0 or pi: t' = -t
        if is_zero(B) and not is_zero(A):
            return (-1, 1)  # b = +-pi/2: t' = pi - t
        return None
    if C == 0:
        return (-1, -1)  # d = pi/2: t' = t - pi
    return None


def _sign_under(expr: sp.Expr, sigma: dict[sp.Symbol, sp.Expr]) -> int | None:
    """+1 or -1 when ``expr`` with ``sigma`` (symbols to +-themselves) substituted is +-``expr``, else
    None. Decided at two random points first (:func:`value_at`: no expansion, which for the
    coefficients of an arm with general axes has thousands of terms), then, for an exact ``expr``
    (no Floats), confirmed by expanding."""
    syms = expr.free_symbols
    flip = {s: sigma[s] / s for s in syms if s in sigma}  # type: ignore[operator]
    signs = set()
    try:
        for seed in (1, 2):
            point = random_point(syms, seed)
            a = value_at(expr, point)
            b = value_at(expr, {s: v * flip.get(s, 1) for s, v in point.items()})
            if same_value(a, b):
                signs.add(1)
            elif same_value(a, b, -1):
                signs.add(-1)
            else:
                return None
    except (ArithmeticError, ValueError):  # not defined at those points: decided by expanding
        signs = {1, -1}
    if len(signs) == 1 and expr.has(sp.Float):
        return signs.pop()
    moved = expr.subs(sigma, simultaneous=True)
    return next((sign for sign in sorted(signs, reverse=True) if sp.expand(moved - sign * expr) == 0), None)


def step_mirror(st: Step, sigma: dict[sp.Symbol, sp.Expr], angles: set[sp.Symbol]) -> Pattern | None:
    """The (cos, sin) signs of a subproblem 1 in the mirrored branch, when its arguments change
    only by signs under the substitution ``sigma`` (and use no mirrored angle itself)."""
    if st.kind != "sp1":
        return None
    e = dict(st.exprs)
    signs = []
    for key in ("x", "y"):
        expr = e[key]
        if expr.free_symbols & angles:
            return None
        sign = _sign_under(expr, sigma)
        if sign is None:
            return None
        signs.append(sign)
    return (signs[0], signs[1])


def _angle(t: str, pattern: Pattern) -> str:
    return {
        (1, 1): t,
        (1, -1): f"-{t}",
        (-1, 1): f"3.141592653589793 - {t}",
        (-1, -1): f"{t} - copysign(3.141592653589793, {t})",
    }[pattern]


def _sym(name: str) -> sp.Symbol:
    return sp.Symbol(name, real=True)


def _region(steps: tuple[Step, ...], k: int) -> list[tuple[int, Pattern]]:
    """The subproblem-1 steps after the two-branch step k that the mirror covers, with patterns."""
    first = branch_mirror(steps[k])
    if first is None:
        return []
    cn, sn = cs_names(steps[k].var)
    sigma: dict[sp.Symbol, sp.Expr] = {_sym(cn): first[0] * _sym(cn), _sym(sn): first[1] * _sym(sn)}
    angles = {_sym(steps[k].var)}
    out = []
    for m in range(k + 1, len(steps)):
        pat = step_mirror(steps[m], sigma, angles)
        if pat is None:
            break
        out.append((m, pat))
        cn, sn = cs_names(steps[m].var)
        sigma[_sym(cn)] = pat[0] * _sym(cn)
        sigma[_sym(sn)] = pat[1] * _sym(sn)
        angles.add(_sym(steps[m].var))
    return out


# -- the body: one writer, the spelling per dialect ----------------------------------------------


@dataclass(frozen=True)
class _Lang:
    """How a dialect spells the body's statements; the steps, slots and flags are the same in all.
    C keeps a subproblem's results in a struct ``v_`` that its helper fills (and opens a block when
    the helper can fail), Python unpacks the tuple its helper returns into names ``v_<field>``."""

    printer: type
    free: str = "qf[{}]"  # the given value of joint {} (the angle of a singular subproblem)
    trig: str = "math."  # the prefix of cos and sin
    decl: str = "{} = {}"  # a new variable {} = {} (a double; in C a flag is an int)
    field: str = "{}_{}"  # result {1} of the helper of step {0}
    loop: str = "for {}_i in (0, 1):"  # over the two branches of step {0}
    sign: str = "1.0 - 2.0 * {}_i"  # the branch's sign
    c: bool = False  # blocks in braces, flags declared int


_LANGS = {
    "python": _Lang(MathModulePrinter),
    "numpy": _Lang(NumPyPrinter, free="qf[..., {}]", trig="np."),
    "c": _Lang(
        CPrinter,
        trig="",
        decl="const double {} = {};",
        field="{}_.{}",
        loop="for (int {0}_i = 0; {0}_i < 2; ++{0}_i) {{",
        sign="{}_i ? -1.0 : 1.0",
        c=True,
    ),
}

# what each subproblem helper returns (C: the members of its struct, in the order of the struct)
_FIELDS = {
    "sp4": ("b", "d", "cb", "sb", "cd", "sd", "flag"),
    "quad": ("b", "r", "flag"),
    "sp1": ("t", "c", "s", "flag"),
}
_STRUCT = {"sp4": "sk_sp4_t", "quad": "sk_quad_t", "sp1": "sk_ang_t"}


def _coefficients(out: Out, lang: _Lang, st: Step) -> list[str]:
    """The step's coefficients, CSE'd: the temporaries emitted; the printed arguments returned, then
    the given value of the step's joint (what a singular subproblem takes as its angle)."""
    pr = lang.printer()
    temps, values = cse_lines([e for _, e in st.exprs], f"{st.var}_x")
    for sym, e in temps:
        out.emit(lang.decl.format(sym, pr.doprint(e)))
    return [pr.doprint(e) for e in values] + [lang.free.format(st.joint) if st.joint is not None else "0.0"]


def _call(out: Out, lang: _Lang, st: Step, args: list[str], need_cs: bool = True) -> None:
    """Step ``st``'s subproblem helper (:func:`_helper`): C fills the struct ``v_``, inside
    ``if (...) {`` for the two-branch steps (their helpers return 0 when there is no solution; the
    caller closes the block); Python unpacks the tuple ``_<kind>`` returns."""
    v = st.var
    helper, args = _helper(st, args, lang.c, need_cs)
    if lang.c:
        out.emit(f"{_STRUCT[st.kind]} {v}_;")
        call = f"sk_{helper}({', '.join(args)}, &{v}_)"
        out.emit(f"{call};" if st.kind == "sp1" else f"if ({call}) {{")
    else:
        names = ", ".join(lang.field.format(v, x) for x in _FIELDS[st.kind])
        out.emit(f"{names} = _{st.kind}({', '.join(args)})")


def body(plan: AnalyticIK, dialect: str) -> str:
    """The statements of ``raw`` (NumPy, Python) or ``body_`` (C) between reading the pose and the
    end: the pose the steps solve for when the arm's constant ends were moved to the target
    (``plan.pose_map``), every step in order, a loop over the sign of each two-branch step, one leaf
    per slot."""
    lang = _LANGS[dialect]
    c = lang.c
    flag_decl = lang.decl.replace("double", "int")
    out = Out([], 1)
    for sym, e in plan.pose_map:
        out.emit(lang.decl.format(sym, lang.printer().doprint(floatify(e))))
    later = used_later(plan)
    steps = plan.steps
    flag = "0"
    slot_terms: list[str] = []
    deg_terms: list[str] = []
    closers = 0
    k = 0
    while k < len(steps):
        st, used = steps[k], later[k]
        v = st.var
        args = _coefficients(out, lang, st)
        cn, sn = cs_names(v)
        need_cs = st.revolute and (cn in used or sn in used)

        def f(x: str, v: str = v) -> str:
            return lang.field.format(v, x)

        if st.kind in ("sp4", "quad"):
            region = _region(steps, k) if c else []
            _call(out, lang, st, args)
            if c:
                out.depth += 1
            if region:
                out.emit(f"int {v}_mir = 0; /* the second branch mirrors the first */")
                for m, _ in region:
                    out.emit(f"double {_store(steps[m], later[m])};")
            out.emit(lang.loop.format(v))
            out.depth += 1
            out.emit(lang.decl.format(f"{v}_sg", lang.sign.format(v)))
            if st.kind == "sp4":
                out.emit(lang.decl.format(v, f"{f('b')} + {v}_sg * {f('d')}"))
                if need_cs or region:
                    out.emit(lang.decl.format(cn, f"{f('cb')} * {f('cd')} - {v}_sg * {f('sb')} * {f('sd')}"))
                    out.emit(lang.decl.format(sn, f"{f('sb')} * {f('cd')} + {v}_sg * {f('cb')} * {f('sd')}"))
                deg_terms.append(f"({f('sd')} <= SK_DUP)" if st.joint is not None else "1")
            else:
                out.emit(lang.decl.format(v, f"-{f('b')} + {v}_sg * {f('r')}"))
                deg_terms.append(f"({f('r')} <= SK_DUP)")
            out.emit(flag_decl.format(f"fl_{v}", f"{flag} | {f('flag')}"))
            flag = f"fl_{v}"
            closers += 2 if c else 0
            slot_terms.append(f"{v}_i")
            if region:
                flag = _emit_region(out, lang, steps, later, k, region, flag)
                k = region[-1][0] + 1
            else:
                k += 1
            continue
        if st.kind == "sp1":
            _call(out, lang, st, args, need_cs)
            out.emit(lang.decl.format(v, f("t")))
            if need_cs:
                out.emit(lang.decl.format(cn, f("c")))
                out.emit(lang.decl.format(sn, f("s")))
            out.emit(flag_decl.format(f"fl_{v}", f"{flag} | {f('flag')}"))
            flag = f"fl_{v}"
        elif st.kind == "sum":
            out.emit(lang.decl.format(cn, args[0]))
            out.emit(lang.decl.format(sn, args[1]))
        else:  # lin
            out.emit(lang.decl.format(v, args[0]))
            if need_cs:
                out.emit(lang.decl.format(cn, f"{lang.trig}cos({v})"))
                out.emit(lang.decl.format(sn, f"{lang.trig}sin({v})"))
        k += 1
    # the leaf: the row into its slot; C: into the filter (sk_keep_, with the mask of the nearly
    # degenerate two-branch steps) or into Q, F
    nb = len(slot_terms)
    slot = " + ".join(f"{t} * {1 << (nb - 1 - b)}" for b, t in enumerate(slot_terms)) or "0"
    qs = ", ".join(plan.outputs)
    if not c:
        out.emit(f"_put(Q, F, {slot}, {flag}, ({qs},))")
    else:
        deg = " | ".join(f"({t} << {nb - 1 - b})" for b, t in enumerate(deg_terms)) or "0"
        out.emit(f"const double q_[NQ] = {{{qs}}};")
        out.emit(f"const int slot_ = {slot};")
        out.emit("if (x) {")
        out.emit(f"    sk_keep_(x, slot_, {flag}, {deg}, q_);")
        out.emit("} else {")
        out.emit("    memcpy(Q + slot_ * NQ, q_, sizeof q_);")
        out.emit(f"    F[slot_] = {flag};")
        out.emit("}")
    for _ in range(closers):
        out.depth -= 1
        out.emit("}")
    return "\n".join(out.lines)


def _helper(st: Step, args: list[str], c: bool, need_cs: bool) -> tuple[str, list[str]]:
    """The subproblem helper of step ``st`` (without ``sk_`` or ``_``) and its arguments (``args``:
    the step's values, then the given value). C only: subproblem 4 with constant ``A, B`` folded in
    (``sk_sp4k``) or ``C = 0`` identically (``sk_sp4z``); subproblem 1 without cos and sin (``sk_sp1a``)."""
    if st.kind == "quad":
        return "quad", args[:2]
    if st.kind == "sp1":
        return ("sp1" if need_cs or not c else "sp1a"), args
    e = dict(st.exprs)
    A, B, C = e["A"], e["B"], e["C"]
    if c and not (A.free_symbols | B.free_symbols):
        r = sp.sqrt(A**2 + B**2)
        if float(sp.N(r, 30)) > 1e-9:
            ir, b = (float(sp.N(x, 30)) for x in (1 / r, sp.atan2(A, B)))
            cb, sb = (float(sp.N(x, 30)) for x in (B / r, A / r))
            return "sp4k", [args[2], repr(ir), repr(b), repr(cb), repr(sb)]
    if c and C == 0:
        return "sp4z", [args[0], args[1], args[3]]
    return "sp4", args


def _names(st: Step, used: set[str]) -> list[str]:
    cn, sn = cs_names(st.var)
    return [st.var] + ([cn, sn] if st.revolute and (cn in used or sn in used) else [])


def _store(st: Step, used: set[str]) -> str:
    return ", ".join(f"{x}_m = 0.0" for x in _names(st, used))


def _emit_region(
    out: Out,
    lang: _Lang,
    steps: tuple[Step, ...],
    later: list[set[str]],
    k: int,
    region: list[tuple[int, Pattern]],
    flag: str,
) -> str:
    """The mirrored subproblem-1 steps inside the branch loop of step k (C); returns the flag chain."""
    v = steps[k].var
    for m, _ in region:
        st = steps[m]
        out.emit(f"double {', '.join(_names(st, later[m]))};")
        out.emit(f"int {st.var}_fl;")
    out.emit(f"if ({v}_mir) {{")
    out.depth += 1
    for m, pat in region:
        st = steps[m]
        names = _names(st, later[m])
        out.emit(f"{st.var} = {_angle(st.var + '_m', pat)};")
        if len(names) == 3:
            cn, sn = names[1], names[2]
            out.emit(f"{cn} = {'-' if pat[0] < 0 else ''}{cn}_m, {sn} = {'-' if pat[1] < 0 else ''}{sn}_m;")
        out.emit(f"{st.var}_fl = 0;")
    out.depth -= 1
    out.emit("} else {")
    out.depth += 1
    for m, _ in region:
        st = steps[m]
        out.emit("{")
        out.depth += 1
        names = _names(st, later[m])
        _call(out, lang, st, _coefficients(out, lang, st), len(names) == 3)
        out.emit(f"{st.var} = {st.var}_.t, {st.var}_fl = {st.var}_.flag;")
        if len(names) == 3:
            out.emit(f"{names[1]} = {st.var}_.c, {names[2]} = {st.var}_.s;")
        out.depth -= 1
        out.emit("}")
    for m, _ in region:
        out.emit(", ".join(f"{x}_m = {x}" for x in _names(steps[m], later[m])) + ";")
    fl = " | ".join(f"{steps[m].var}_fl" for m, _ in region)
    out.emit(f"{v}_mir = !{v}_.flag && !({fl});")
    out.depth -= 1
    out.emit("}")
    for m, _ in region:
        var = steps[m].var
        out.emit(f"const int fl_{var} = {flag} | {var}_fl;")
        flag = f"fl_{var}"
    return flag


def render_analytic(plan: AnalyticIK, robot: object, backend: str, command: str) -> dict[str, str]:
    """The generated files of the closed form for ``backend`` ("c", "numpy" or "casadi", the last
    rendered as plain Python)."""
    from symkin.core.version import __version__

    dialect = BACKEND_DIALECT[backend]
    name = getattr(robot, "name", plan.name)
    prefix = ik_prefix(name)
    R, p = given_symbols() if plan.pose_map else pose_symbols()
    pose = [(str(R[i, j]), i * 4 + j) for i in range(3) for j in range(3)] + [
        (str(p[i]), i * 4 + 3) for i in range(3)
    ]
    lang = _LANGS[dialect]
    pr = lang.printer()
    fk_temps, fk_values = cse_lines(list(plan.fk), "f")  # the 3x4 pose of q, to verify flagged candidates
    joints = [(f"q{j}", f"c{j}", f"s{j}", plan.revolute[j]) for j in range(plan.n)]
    context = {
        "prefix": prefix,
        "n": plan.n,
        "S": plan.max_solutions,
        "check": plan.check,
        "revolute": [int(r) for r in plan.revolute],
        "pose": pose,
        "body": body(plan, dialect),
        "fk_lines": [lang.decl.format(sym, pr.doprint(e)) for sym, e in fk_temps],
        "fk_values": [pr.doprint(e) for e in fk_values],
        "joints": joints,
        "robot": identifier(name),
        "name_literal": c_string(name) if dialect == "c" else ascii(name),
        "kind": plan.structure.kind + (f" ({plan.structure.position})" if plan.structure.position else ""),
        "version": __version__,
        "command": comment_safe(command),
        "ets": comment_safe(str(getattr(robot, "ets", "")), limit=4000),
    }
    if dialect == "c":
        files = {
            f"{prefix}.h": render("c/analytic_ik.h.j2", **context),
            f"{prefix}.c": render("c/analytic_ik.c.j2", **context),
        }
        import hashlib

        digest = hashlib.sha256("".join(files[k] for k in sorted(files)).encode()).hexdigest()[:12]
        module = f"_{prefix}_{digest}"
        files[f"{prefix}_pymodule.c"] = render("c/analytic_ik_module.c.j2", module=module, **context)
        return files
    module = f"{prefix}"
    return {
        f"{module}.py": render("python/analytic_ik.py.j2", module=module, numpy=dialect == "numpy", **context)
    }
