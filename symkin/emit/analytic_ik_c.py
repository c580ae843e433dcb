"""The C body of a derived closed form: specialised subproblems and mirrored branches.

Same steps, slots and flags as the NumPy and Python bodies (:mod:`symkin.emit.analytic_ik`), with
the trigonometry cut down where the exact coefficients allow it:

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

import sympy as sp

from symkin.emit.ik_body import Out, cs_names, cse_lines, used_later
from symkin.emit.printers import CPrinter
from symkin.symbolic.analytic_ik import AnalyticIK, Step
from symkin.symbolic.ik_geometry import is_zero, random_point, same_value, value_at

__all__ = ["body_c", "branch_mirror", "step_mirror"]

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


def _sp4_call(st: Step, args: list[str], free: str, pr: CPrinter) -> str:
    v = st.var
    e = dict(st.exprs)
    A, B, C = e["A"], e["B"], e["C"]
    if not (A.free_symbols | B.free_symbols):
        r = sp.sqrt(A**2 + B**2)
        if float(sp.N(r, 30)) > 1e-9:
            ir, b = (float(sp.N(x, 30)) for x in (1 / r, sp.atan2(A, B)))
            cb, sb = (float(sp.N(x, 30)) for x in (B / r, A / r))
            return f"sk_sp4k({args[2]}, {ir!r}, {b!r}, {cb!r}, {sb!r}, &{v}_)"
    if C == 0:
        return f"sk_sp4z({args[0]}, {args[1]}, {free}, &{v}_)"
    return f"sk_sp4({args[0]}, {args[1]}, {args[2]}, {free}, &{v}_)"


def _free(st: Step) -> str:
    return f"qf[{st.joint}]" if st.joint is not None else "0.0"


def body_c(plan: AnalyticIK) -> str:
    """The C statements of ``raw_`` between reading the pose and counting the candidates."""
    pr = CPrinter()
    out = Out([], 1)
    later = used_later(plan)
    steps = plan.steps
    flag = "0"
    slot_terms: list[str] = []
    deg_terms: list[str] = []
    bit = 0
    closers = 0
    k = 0
    while k < len(steps):
        st, used = steps[k], later[k]
        v = st.var
        temps, values = cse_lines([e for _, e in st.exprs], f"{v}_x")
        for sym, e in temps:
            out.emit(f"const double {sym} = {pr.doprint(e)};")
        args = [pr.doprint(e) for e in values]
        cn, sn = cs_names(v)
        need_cs = st.revolute and (cn in used or sn in used)
        if st.kind in ("sp4", "quad"):
            region = _region(steps, k)
            if st.kind == "sp4":
                out.emit(f"sk_sp4_t {v}_;")
                out.emit(f"if ({_sp4_call(st, args, _free(st), pr)}) {{")
            else:
                out.emit(f"sk_quad_t {v}_;")
                out.emit(f"if (sk_quad({args[0]}, {args[1]}, &{v}_)) {{")
            out.depth += 1
            if region:
                out.emit(f"int {v}_mir = 0; /* the second branch mirrors the first */")
                for m, _ in region:
                    out.emit(f"double {_store(steps[m], later[m])};")
            out.emit(f"for (int {v}_i = 0; {v}_i < 2; ++{v}_i) {{")
            out.depth += 1
            out.emit(f"const double {v}_sg = {v}_i ? -1.0 : 1.0;")
            if st.kind == "sp4":
                out.emit(f"const double {v} = {v}_.b + {v}_sg * {v}_.d;")
                if need_cs or region:
                    out.emit(f"const double {cn} = {v}_.cb * {v}_.cd - {v}_sg * {v}_.sb * {v}_.sd;")
                    out.emit(f"const double {sn} = {v}_.sb * {v}_.cd + {v}_sg * {v}_.cb * {v}_.sd;")
                deg_terms.append(f"({v}_.sd <= SK_DUP)" if st.joint is not None else "1")
            else:
                out.emit(f"const double {v} = -{v}_.b + {v}_sg * {v}_.r;")
                deg_terms.append(f"({v}_.r <= SK_DUP)")
            out.emit(f"const int fl_{v} = {flag} | {v}_.flag;")
            flag = f"fl_{v}"
            closers += 2
            slot_terms.append(f"{v}_i")
            bit += 1
            if region:
                flag = _emit_region(out, pr, steps, later, k, region, flag)
                k = region[-1][0] + 1
            else:
                k += 1
            continue
        if st.kind == "sp1":
            out.emit(f"sk_ang_t {v}_;")
            out.emit(f"{'sk_sp1' if need_cs else 'sk_sp1a'}({args[0]}, {args[1]}, {_free(st)}, &{v}_);")
            out.emit(f"const double {v} = {v}_.t;")
            if need_cs:
                out.emit(f"const double {cn} = {v}_.c, {sn} = {v}_.s;")
            out.emit(f"const int fl_{v} = {flag} | {v}_.flag;")
            flag = f"fl_{v}"
        elif st.kind == "sum":
            out.emit(f"const double {cn} = {args[0]}, {sn} = {args[1]};")
        else:  # lin
            out.emit(f"const double {v} = {args[0]};")
            if need_cs:
                out.emit(f"const double {cn} = cos({v}), {sn} = sin({v});")
        k += 1
    nb = bit
    slot = " + ".join(f"{t} * {1 << (nb - 1 - b)}" for b, t in enumerate(slot_terms)) or "0"
    deg = " | ".join(f"({t} << {nb - 1 - b})" for b, t in enumerate(deg_terms)) or "0"
    qs = ", ".join(plan.outputs)
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


def _names(st: Step, used: set[str]) -> list[str]:
    cn, sn = cs_names(st.var)
    return [st.var] + ([cn, sn] if st.revolute and (cn in used or sn in used) else [])


def _store(st: Step, used: set[str]) -> str:
    return ", ".join(f"{x}_m = 0.0" for x in _names(st, used))


def _emit_region(
    out: Out,
    pr: CPrinter,
    steps: tuple[Step, ...],
    later: list[set[str]],
    k: int,
    region: list[tuple[int, Pattern]],
    flag: str,
) -> str:
    """The mirrored subproblem-1 steps inside the branch loop of step k; returns the flag chain."""
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
        temps, values = cse_lines([e for _, e in st.exprs], f"{st.var}_x")
        out.emit("{")
        out.depth += 1
        for sym, e in temps:
            out.emit(f"const double {sym} = {pr.doprint(e)};")
        args = [pr.doprint(e) for e in values]
        names = _names(st, later[m])
        out.emit(f"sk_ang_t {st.var}_;")
        call = "sk_sp1" if len(names) == 3 else "sk_sp1a"
        out.emit(f"{call}({args[0]}, {args[1]}, {_free(st)}, &{st.var}_);")
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
