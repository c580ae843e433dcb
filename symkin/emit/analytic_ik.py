"""Lower a derived closed form (:class:`symkin.symbolic.analytic_ik.AnalyticIK`) to C, NumPy or
plain Python through the templates ``templates/{c,numpy,python}/analytic_ik*.j2``.

The body is a nest of blocks, one per step: the step's coefficients (CSE'd), then the angle, its
cosine and sine (from the subproblem's own atan2/acos arguments, no extra trig calls), and, for a
two-branch step, a loop over the sign. Each leaf writes one candidate row into its fixed slot
(``sum_k i_k 2^(B-1-k)`` over the B branch indices, so leaves come in slot order) with a flag
saying whether a subproblem was clamped or singular (such rows are verified against the pose
before they are returned).

The C body (:func:`body_c`) has the same steps, slots and flags as the NumPy and Python bodies, with
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

from symkin.core.names import c_string, comment_safe, identifier
from symkin.emit.ik_body import Out, cs_names, cse_lines, used_later
from symkin.emit.printers import CPrinter, MathModulePrinter, NumPyPrinter
from symkin.emit.templates import render
from symkin.symbolic.analytic_ik import AnalyticIK, Step, given_symbols, pose_symbols
from symkin.symbolic.cse import floatify
from symkin.symbolic.ik_geometry import is_zero, random_point, same_value, value_at

__all__ = ["render_analytic", "ik_prefix", "BACKEND_DIALECT", "body_c", "branch_mirror", "step_mirror"]

BACKEND_DIALECT = {"c": "c", "numpy": "numpy", "casadi": "python"}


def ik_prefix(robot_name: str) -> str:
    return f"symkin_{identifier(robot_name)}_ik"


def _body(plan: AnalyticIK, dialect: str) -> str:
    """The NumPy or plain-Python body: every step in order, a loop per two-branch step."""
    pr = NumPyPrinter() if dialect == "numpy" else MathModulePrinter()
    out = Out([], 1)
    later = used_later(plan)
    flag = "0"
    slot_terms: list[str] = []
    bit = 0
    for st, used in zip(plan.steps, later):
        v = st.var
        temps, values = cse_lines([e for _, e in st.exprs], f"{v}_x")
        for sym, e in temps:
            out.emit(f"{sym} = {pr.doprint(e)}")
        args = [pr.doprint(e) for e in values]
        free = (
            "0.0"
            if st.joint is None
            else (f"qf[..., {st.joint}]" if dialect == "numpy" else f"qf[{st.joint}]")
        )
        cn, sn = cs_names(v)
        need_cs = st.revolute and (cn in used or sn in used)
        if st.kind in ("sp4", "quad"):
            if st.kind == "sp4":
                names = ", ".join(f"{v}_{x}" for x in ("b", "d", "cb", "sb", "cd", "sd", "f"))
                out.emit(f"{names} = _sp4({args[0]}, {args[1]}, {args[2]}, {free})")
            else:
                out.emit(f"{v}_b, {v}_r, {v}_f = _quad({args[0]}, {args[1]})")
            out.emit(f"for {v}_i in (0, 1):")
            out.depth += 1
            out.emit(f"{v}_sg = 1.0 - 2.0 * {v}_i")
            if st.kind == "sp4":
                out.emit(f"{v} = {v}_b + {v}_sg * {v}_d")
                if need_cs:
                    out.emit(f"{cn} = {v}_cb * {v}_cd - {v}_sg * {v}_sb * {v}_sd")
                    out.emit(f"{sn} = {v}_sb * {v}_cd + {v}_sg * {v}_cb * {v}_sd")
            else:
                out.emit(f"{v} = -{v}_b + {v}_sg * {v}_r")
            out.emit(f"fl_{v} = {flag} | {v}_f")
            slot_terms.append(f"{v}_i")
            bit += 1
            flag = f"fl_{v}"
        elif st.kind == "sp1":
            out.emit(f"{v}, {cn}, {sn}, {v}_f = _sp1({args[0]}, {args[1]}, {free})")
            out.emit(f"fl_{v} = {flag} | {v}_f")
            flag = f"fl_{v}"
        elif st.kind == "sum":
            out.emit(f"{cn}, {sn} = {args[0]}, {args[1]}")
        else:  # lin
            out.emit(f"{v} = {args[0]}")
            if need_cs:
                fn = "np." if dialect == "numpy" else "math."
                out.emit(f"{cn}, {sn} = {fn}cos({v}), {fn}sin({v})")
    slot = " + ".join(f"{t} * {1 << (bit - 1 - b)}" for b, t in enumerate(slot_terms)) or "0"
    out.emit(f"_put(Q, F, {slot}, {flag}, ({', '.join(plan.outputs)},))")
    return "\n".join(out.lines)


# -- the C body --------------------------------------------------------------------------------

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


def _fk_code(plan: AnalyticIK, dialect: str) -> tuple[list[str], list[str]]:
    """Straight-line code for the 3x4 pose of q (for verifying flagged candidates)."""
    pr = CPrinter() if dialect == "c" else (NumPyPrinter() if dialect == "numpy" else MathModulePrinter())
    temps, values = cse_lines(list(plan.fk), "f")
    lines = []
    for sym, e in temps:
        lines.append(
            f"const double {sym} = {pr.doprint(e)};" if dialect == "c" else f"{sym} = {pr.doprint(e)}"
        )
    return lines, [pr.doprint(e) for e in values]


def _pose_lines(plan: AnalyticIK, dialect: str) -> list[str]:
    """The pose the steps solve for from the target as given, when the arm's constant ends were
    moved to the target (``plan.pose_map``; no lines otherwise)."""
    pr = CPrinter() if dialect == "c" else (NumPyPrinter() if dialect == "numpy" else MathModulePrinter())
    decl = "const double " if dialect == "c" else ""
    end = ";" if dialect == "c" else ""
    return [f"    {decl}{sym} = {pr.doprint(floatify(e))}{end}" for sym, e in plan.pose_map]


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
    fk_lines, fk_values = _fk_code(plan, dialect)
    joints = [(f"q{j}", f"c{j}", f"s{j}", plan.revolute[j]) for j in range(plan.n)]
    context = {
        "prefix": prefix,
        "n": plan.n,
        "S": plan.max_solutions,
        "check": plan.check,
        "revolute": [int(r) for r in plan.revolute],
        "pose": pose,
        "body": "\n".join(
            [*_pose_lines(plan, dialect), body_c(plan) if dialect == "c" else _body(plan, dialect)]
        ),
        "fk_lines": fk_lines,
        "fk_values": fk_values,
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
    return {f"{module}.py": render(f"{dialect}/analytic_ik.py.j2", module=module, **context)}
