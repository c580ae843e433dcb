"""Derivations of long chains: the kinematics as named intermediates, link frame by link frame.

Beyond about seven joints the multiplied-out link frames, pose and Jacobian have far more terms
than a reader can use (a generic 12-joint chain: about 2 million nodes). The derivation then
follows the O(n) algorithm of Haviland and Corke (Manipulator Differential Kinematics, Part 1,
2023, eqs 31-34) the way :mod:`symkin.symbolic.program` computes it: each link frame from the
previous one, every new quantity named (``zeta_k``), the Jacobian columns as cross products of
named axes and origins, and the Hessian by its rule. The results are checked at random points,
to 30 digits, against the literal products of the elementary transforms (eqs 1, 5, 26-28) and
against central differences of the Jacobian.
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from typing import Any

import mpmath
import sympy as sp

from symkin.model.ets import ETS
from symkin.model.latex import ets_latex
from symkin.model.robot import Robot
from symkin.symbolic.program import KinematicProgram, derive_program

__all__ = ["program_derivation", "program_context", "LINES_PER_BLOCK"]

LINES_PER_BLOCK = 12  # assignments per displayed equation block
_XYZ = "xyz"


def program_derivation(robot: Robot, symbolic_constants: bool) -> Any:
    """The :class:`symkin.derive.chain.Derivation` of ``robot`` in program form (see the module)."""
    from symkin.derive.common import Derivation, constants, et_matrix

    ets = robot.ets
    n = ets.n
    q = tuple(sp.Symbol(f"q_{j + 1}", real=True) for j in range(n))
    C = constants(ets, symbolic_constants)
    kp = derive_program(C.ets, q, C.constant, robot.name, hessians=True)
    eta = [e.sign * q[e.joint] if e.joint is not None else C.eta[k] for k, e in enumerate(ets)]
    E = [et_matrix(e.axis, eta[k]) for k, e in enumerate(ets)]
    checks = _checks(kp, ets, eta, q, dict(C.values))
    im = sp.ImmutableMatrix
    position = {j: k for k, j in enumerate(kp.order)}
    assert kp.H0 is not None
    return Derivation(
        robot,
        q,
        dict(C.values),
        tuple(map(im, E)),
        im(kp.T),
        tuple(im(kp.links[position[j]]) for j in range(n)),
        (),
        (),
        im(kp.J0),
        im(kp.J0),
        tuple(map(im, kp.H0)),
        True,
        checks,
        form="program",
        intermediates=kp.lines,
        sections=kp.marks,
    )


# ---------------------------------------------------------------------------------------------
# Checks at random points, 30 digits


def _checks(
    kp: KinematicProgram, ets: ETS, eta: list[sp.Expr], q: tuple[sp.Symbol, ...], values: dict
) -> dict[str, str]:
    """Compare the program with the literal products of eqs 1, 5 and 26-28, and its Hessian with
    central differences of its Jacobian along a random direction, at 3 random points to 30 digits."""
    from symkin.derive.common import et_matrix, generator, mp_function, products

    n = len(q)
    consts = list(values)
    assert kp.H0 is not None
    outs = [*kp.T, *(x for L in kp.links for x in L), *kp.J0, *(x for H in kp.H0 for x in H)]
    rng = random.Random(1)
    worst = {"eq 1: T": 0.0, "eq 5: link frames": 0.0, "eqs 26-28 and 31-34: J0": 0.0, "eq 20: H0": 0.0}

    def diff(key: str, a: Sequence[Any], b: Sequence[Any]) -> None:  # the largest |a - b| so far
        worst[key] = max(worst[key], float(max((abs(x - y) for x, y in zip(a, b)), default=0)))

    with mpmath.workdps(30):
        f = mp_function(kp.lines, list(q) + consts, outs)
        fj = mp_function(kp.lines, list(q) + consts, list(kp.J0))
        cvals = [mpmath.mpf(sp.N(values[c], 40)) for c in consts]
        mu = {e.joint: k for k, e in enumerate(ets) if e.joint is not None}
        for _ in range(3):
            qv = [mpmath.mpf(rng.randint(100, 2000)) / 1000 for _ in q]
            sub = dict(zip(q, qv)) | dict(zip(consts, cvals))
            values = [mpmath.mpf(sp.N(x.xreplace(sub), 40)) for x in eta]
            E = [et_matrix(e.axis, v, mpmath) for e, v in zip(ets, values)]
            prefix, suffix = products(E, mpmath.eye(4))
            got = f(*qv, *cvals)
            T = prefix[-1]
            k = 16
            diff("eq 1: T", got[:16], [T[r, c] for r in range(4) for c in range(4)])
            for j in kp.order:  # chain order
                P = prefix[mu[j] + 1]
                diff("eq 5: link frames", got[k : k + 16], [P[r, c] for r in range(4) for c in range(4)])
                k += 16
            J = got[k : k + 6 * n]
            k += 6 * n
            for j in range(n):
                e = ets[mu[j]]
                dT = prefix[mu[j]] * (e.sign * generator(e.axis, mpmath)) * E[mu[j]] * suffix[mu[j] + 1]
                S = dT[:3, :3] * T[:3, :3].T
                col = [dT[0, 3], dT[1, 3], dT[2, 3], S[2, 1], S[0, 2], S[1, 0]]
                diff("eqs 26-28 and 31-34: J0", [J[r * n + j] for r in range(6)], col)
            # eq 20 along a random direction v: sum_i v_i H_i = dJ(q + h v)/dh, by central differences
            H = got[k:]
            v = [mpmath.mpf(rng.randint(-1000, 1000)) / 1000 for _ in q]
            h = mpmath.mpf(10) ** -12
            Ju = fj(*[a + h * b for a, b in zip(qv, v)], *cvals)
            Jd = fj(*[a - h * b for a, b in zip(qv, v)], *cvals)
            fd = [(a - b) / (2 * h) for a, b in zip(Ju, Jd)]
            Hv = [sum(v[i] * H[i * 6 * n + m] for i in range(n)) for m in range(6 * n)]
            diff("eq 20: H0", Hv, fd)
    # central differences with step 1e-12 at 30 digits are exact to about 1e-18
    bound = {"eq 20: H0": 1e-15}
    return {k: ("numeric" if v < bound.get(k, 1e-20) else "failed") for k, v in worst.items()}


# ---------------------------------------------------------------------------------------------
# The written derivation


def program_context(D: Any) -> tuple[dict[str, Any], str]:
    """The template context of ``derive/program.md.j2`` and the LaTeX summary for Jupyter."""
    from symkin.derive.common import Printer, constants, shared_context

    q, n, ets = D.q, len(D.q), D.robot.ets
    C = constants(ets, bool(D.constants))
    mu = {e.joint: k for k, e in enumerate(ets) if e.joint is not None}
    P = Printer(q, D.intermediates)
    lines = list(D.intermediates)
    ends = dict(D.sections)
    ctx: dict[str, Any] = {**shared_context(D, P, C), "nodes": len(lines)}
    order = [e.joint for e in ets if e.joint is not None]
    steps = []
    start = 0
    previous = 0
    for k, j in enumerate(order):
        end = ends[f"link {k}"]
        factors = " ".join(f"E_{{{i + 1}}}" for i in range(previous, mu[j] + 1))
        lhs = f"{{}}^{{0}}T_{{{j + 1}}}"
        before = "" if k == 0 else f"{{}}^{{0}}T_{{{order[k - 1] + 1}}}\\, "
        steps.append(
            {
                "product": f"{lhs} = {before}{factors}",
                "lines": _blocks(P, lines[start:end]),
                "matrix": f"{lhs} = {P.matrix(D.links[j])}",
            }
        )
        start, previous = end, mu[j] + 1
    ctx["links"] = steps
    tail = " ".join(f"E_{{{i + 1}}}" for i in range(previous, len(ets)))
    last = f"{{}}^{{0}}T_{{{order[-1] + 1}}}"
    ctx["pose_product"] = f"{{}}^{{0}}T_{{e}} = {last}\\, {tail}" if tail else f"{{}}^{{0}}T_{{e}} = {last}"
    ctx["pose_lines"] = _blocks(P, lines[start : ends["T"]])
    ctx["pose"] = f"{{}}^{{0}}T_{{e}} = {P.matrix(D.T)}"
    ctx["jacobian_lines"] = _blocks(P, lines[ends["T"] : ends["J0"]])
    ctx["columns"] = [f"J_{{{j + 1}}} = {P.matrix(sp.Matrix(D.J0[:, j]).T)}^\\top" for j in range(n)]
    pattern = sp.Matrix(n, n, lambda i, c: 0 if D.H0[i][:, c].is_zero_matrix else sp.Symbol("zzbullet"))
    P.names[sp.Symbol("zzbullet")] = r"\bullet"
    ctx["hessian"] = rf"\big(\partial J_j / \partial q_i \neq 0\big)_{{ij}} = {P.matrix(pattern)}"
    ctx["hessian_lines"] = ends["H"] - ends["Je"]
    ctx["legend"] = P.legend()
    T = D.T
    summary = [ets_latex(ets, r"{}^{0}T_{e} &", C.names)] + [f"{_XYZ[r]} &= {P(T[r, 3])}" for r in range(3)]
    return ctx, r"$$\begin{aligned} " + r" \\ ".join(summary) + r" \end{aligned}$$"


def _blocks(P: Any, lines: list[tuple[sp.Symbol, sp.Expr]]) -> list[str]:
    """Assignments as aligned blocks of at most :data:`LINES_PER_BLOCK` lines."""
    out = []
    for i in range(0, len(lines), LINES_PER_BLOCK):
        rows = [f"{P.names[s]} &= {P(e)}" for s, e in lines[i : i + LINES_PER_BLOCK]]
        out.append(r"\begin{aligned} " + r" \\ ".join(rows) + r" \end{aligned}")
    return out
