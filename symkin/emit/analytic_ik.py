"""Lower a derived closed form (:class:`symkin.symbolic.analytic_ik.AnalyticIK`) to C, NumPy or
plain Python through the templates ``templates/{c,numpy,python}/analytic_ik*.j2``.

The body is a nest of blocks, one per step: the step's coefficients (CSE'd), then the angle, its
cosine and sine (from the subproblem's own atan2/acos arguments, no extra trig calls), and, for a
two-branch step, a loop over the sign. Each leaf writes one candidate row into its fixed slot
(``sum_k i_k 2^(B-1-k)`` over the B branch indices, so leaves come in slot order) with a flag
saying whether a subproblem was clamped or singular (such rows are verified against the pose
before they are returned). The C body is :mod:`symkin.emit.analytic_ik_c`.
"""

from __future__ import annotations

from symkin.core.names import c_string, comment_safe, identifier
from symkin.emit.analytic_ik_c import body_c
from symkin.emit.ik_body import Out, cs_names, cse_lines, used_later
from symkin.emit.printers import CPrinter, NumPyPrinter
from symkin.emit.templates import render
from symkin.symbolic.analytic_ik import AnalyticIK, given_symbols, pose_symbols
from symkin.symbolic.cse import floatify

__all__ = ["render_analytic", "ik_prefix", "BACKEND_DIALECT"]

BACKEND_DIALECT = {"c": "c", "numpy": "numpy", "casadi": "python"}


class _MathPrinter(NumPyPrinter):
    """Scalar Python with the math module."""

    module = "math"


def ik_prefix(robot_name: str) -> str:
    return f"symkin_{identifier(robot_name)}_ik"


def _body(plan: AnalyticIK, dialect: str) -> str:
    """The NumPy or plain-Python body: every step in order, a loop per two-branch step."""
    pr = NumPyPrinter() if dialect == "numpy" else _MathPrinter()
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


def _fk_code(plan: AnalyticIK, dialect: str) -> tuple[list[str], list[str]]:
    """Straight-line code for the 3x4 pose of q (for verifying flagged candidates)."""
    pr = CPrinter() if dialect == "c" else (NumPyPrinter() if dialect == "numpy" else _MathPrinter())
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
    pr = CPrinter() if dialect == "c" else (NumPyPrinter() if dialect == "numpy" else _MathPrinter())
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
