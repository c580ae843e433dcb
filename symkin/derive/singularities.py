"""Singular configurations, derived and checked: ``symkin derive --singularities``.

:func:`singularities` factors the Jacobian's determinant (:mod:`symkin.symbolic.singularities`),
then, for every factor f(q), checks numerically that the configurations where f = 0 are
singular and the others are not: it solves f = 0 for one joint (the others random), and the
smallest singular value of the numeric Jacobian (the O(n) reference of eqs 31-34 of Haviland and
Corke, Manipulator Differential Kinematics, Part 1, 2023, independent of sympy) must be below
:data:`SINGULAR_TOL` there and above it at random configurations. The geometric meaning of a
factor is recognised from the joint axes at those solutions (what holds there and at no random
configuration): two axes that become parallel or collinear (a wrist singularity when both are
among the last three joints), parallel axes that come to lie in one plane (an elbow: the arm
stretched out or folded back), a point (where two axes meet, or the end effector) that comes to
lie on an axis or in the plane of two axes (a shoulder singularity when the first axis is
involved), or two such points that come to coincide. Otherwise the text says that the joint twists
become dependent. Conversely, random lines through joint space must find no rank drop that no
factor explains (:mod:`symkin.derive.singular_lines`): the list is complete, not only correct.
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
import sympy as sp

from symkin.derive.common import FORMATS, Printer, latex_document
from symkin.derive.singular_lines import FACTOR_TOL, LINES, MAX_LINES, SINGULAR_TOL, LineCheck, line_check
from symkin.emit.templates import render
from symkin.errors import ParameterError, check_choice
from symkin.model.latex import display_name
from symkin.model.robot import Robot
from symkin.symbolic.singularities import MAX_TERMS, SingularFactor, SingularFactors, singular_factors

__all__ = ["Singularity", "SingularityReport", "singularities", "SINGULAR_TOL"]

_GEOMETRY_TOL = 1e-7  # m or rad: an incidence of axes and points that holds at a solution
_SOLUTIONS = 3
_RANDOM = 20
_UNEXPLAINED_SHOWN = 5  # configurations listed when rank drops along the lines are not explained
_STATEMENTS = 2  # incidences of points with axes and planes shown per factor
#: The roots of the factors of one joint, and as LaTeX.
_ROOTS = {
    "sin": (0.0, math.pi),
    "cos": (math.pi / 2, -math.pi / 2),
    "half-sin": (0.0,),
    "half-cos": (math.pi,),
}
_ROOTS_TEX = {"sin": r"0 \text{ or } \pi", "cos": r"\pm\pi/2", "half-sin": "0", "half-cos": r"\pi"}


@dataclass(frozen=True, eq=False)
class Singularity:
    """One singular family f(q) = 0, checked.

    Attributes:
        factor: the factor (:class:`symkin.symbolic.singularities.SingularFactor`).
        kind: ``"wrist"``, ``"elbow"``, ``"shoulder"``, ``"prismatic"`` or ``"other"``.
        meaning: what the arm looks like there (one sentence per recognised property).
        solutions: (k, n) configurations with f = 0 that the check used.
        sigma_at_solutions: the largest smallest-singular-value of J over those solutions.
        checked: whether every solution is singular (sigma below :data:`SINGULAR_TOL`); False when
            no real solution was found (then f = 0 has none, or none the sampling reached).
        rank: the largest rank of J (its rows used) over the solutions (singular values at least
            :data:`SINGULAR_TOL`); -1 without solutions.
        also: the 0-based indices of the earlier factors that vanish at every solution too (f = 0
            there is a root of higher order of the minors, as sin q_4 and cos(q_4 / 2) at q_4 = pi).
    """

    factor: SingularFactor
    kind: str
    meaning: tuple[str, ...]
    solutions: np.ndarray
    sigma_at_solutions: float
    checked: bool
    rank: int = -1
    also: tuple[int, ...] = ()


@dataclass(frozen=True, eq=False)
class SingularityReport:
    """The singularities of a robot: the factored determinant, each factor checked, and the text.

    Attributes:
        robot: the robot; analysis: the symbolic result.
        singularities: one :class:`Singularity` per factor, in the analysis' order.
        sigma_at_random: the smallest singular value of J at each of the random configurations.
        determinant_check: the largest relative difference between the symbolic determinant and
            ``det`` of the numeric J at the random configurations (square J only, else NaN).
        lines: the rank drops found along random lines through joint space, each of which must be
            a zero of a listed factor (:class:`symkin.derive.singular_lines.LineCheck`).
        fmt, text: the format and the written report (Markdown with $$ math, or a LaTeX document);
        markdown: the Markdown whatever ``fmt`` (what Jupyter shows).
    """

    robot: Robot
    analysis: SingularFactors
    singularities: tuple[Singularity, ...]
    sigma_at_random: np.ndarray
    determinant_check: float
    lines: LineCheck
    fmt: str = "markdown"
    text: str = ""
    markdown: str = field(default="", repr=False)

    @property
    def ok(self) -> bool:
        """Every factor's solutions are singular, no random configuration is, every rank drop along the
        random lines is a zero of a factor, and the determinant (square J) equals det of the numeric J."""
        det_ok = math.isnan(self.determinant_check) or self.determinant_check < 1e-9
        return (
            det_ok
            and all(s.checked for s in self.singularities)
            and bool((self.sigma_at_random > SINGULAR_TOL).all())
            and self.lines.ok
        )

    def _repr_markdown_(self) -> str:
        return self.markdown

    def summary(self) -> str:
        """A few plain-text lines: each condition (joints numbered from 1) and its check, the random
        configurations, the lines, and ``ok`` or ``NOT ok``."""
        A = self.analysis
        rename = {q: sp.Symbol(f"q{j + 1}") for j, q in enumerate(A.q)}
        minors = f"{A.minors} minor" + ("s" if A.minors != 1 else "")
        out = [f"{A.name}: {len(self.singularities)} conditions ({A.method}, {minors})"]
        for k, s in enumerate(self.singularities):
            cond = f"{sp.sstr(s.factor.expr.xreplace(rename))} = 0"
            if s.checked:
                check = f"singular, rank {s.rank} of {A.full_rank}, sigma_min <= {s.sigma_at_solutions:.1e}"
            elif len(s.solutions):
                check = f"NOT singular at its solutions (sigma_min {s.sigma_at_solutions:.1e})"
            else:
                check = "no real solution found"
            out.append(f"  {k + 1}  {cond}: {check}")
        out.append(f"random configurations: sigma_min >= {self.sigma_at_random.min(initial=math.inf):.3g}")
        L = self.lines
        out.append(
            f"lines: {L.lines} x {L.samples} samples, {len(L.drops)} rank drops, "
            + (f"{len(L.unexplained)} explained by no condition" if len(L.unexplained) else "all explained")
        )
        out.append("ok" if self.ok else "NOT ok")
        return "\n".join(out)


def singularities(
    robot: Robot | str,
    axes: str = "auto",
    fmt: Literal["markdown", "latex"] = "markdown",
    seed: int = 0,
    max_terms: int = MAX_TERMS,
    lines: int = LINES,
) -> SingularityReport:
    """The singular configurations of ``robot`` as factor conditions, checked numerically, and written
    up as Markdown or LaTeX (see the module docstring).

    ``axes``: the rows of J (``"auto"``, ``"all"``, ``"trans"``, ``"rot"``; see
    :func:`symkin.symbolic.singularities.singular_factors`); ``seed``: the random configurations
    of the checks; ``max_terms``: a minor whose determinant has more terms is not factored;
    ``lines``: how many random lines through joint space are searched for rank drops that no factor
    explains (:func:`symkin.derive.singular_lines.line_check`, 0 for none).
    """
    check_choice(fmt, FORMATS, "format")
    if not isinstance(lines, (int, np.integer)) or isinstance(lines, bool) or not 0 <= lines <= MAX_LINES:
        raise ParameterError(f"lines must be an integer from 0 to {MAX_LINES}, got {lines!r}")
    from symkin.model.resolve import resolve_robot

    robot = resolve_robot(robot)
    A = singular_factors(robot, axes=axes, max_terms=max_terms)
    rng = np.random.default_rng(seed)
    rows = list(A.rows)

    def sigma(Q: np.ndarray) -> np.ndarray:  # smallest singular value of J's rows, (N,)
        return np.linalg.svd(robot.jacob0(Q)[:, rows, :], compute_uv=False)[:, -1]

    Qr = robot.random_q(_RANDOM, seed=rng)
    sigma_random = sigma(Qr)
    det_check = math.nan
    if A.determinant is not None:
        f = sp.lambdify(A.q, A.determinant, "numpy")
        J = robot.jacob0(Qr)[:, rows, :]
        exact = np.linalg.det(J)
        got = np.array([float(f(*q)) for q in Qr])
        det_check = float(np.max(np.abs(got - exact)) / max(np.max(np.abs(exact)), 1e-300))
    geometry = _Geometry(robot, A)
    values = sp.lambdify(A.q, [f.expr for f in A.factors], "numpy")
    found = []
    for k, factor in enumerate(A.factors):
        Q = _solve(robot, A.q, factor, rng)
        sv = np.linalg.svd(robot.jacob0(Q)[:, rows, :], compute_uv=False) if len(Q) else np.zeros((0, 1))
        s = sv[:, -1]
        checked = bool(len(Q)) and bool((s < SINGULAR_TOL).all())
        kind, meaning = geometry.describe(factor, Q, Qr) if len(Q) else ("other", ())
        rank = int((sv >= SINGULAR_TOL).sum(axis=1).max(initial=-1))
        also = tuple(i for i in range(k) if len(Q) and _vanish(values, Q, i, Qr))
        found.append(Singularity(factor, kind, meaning, Q, float(s.max(initial=0.0)), checked, rank, also))
    line = line_check(robot, rows, A.q, [f.expr for f in A.factors], lines=lines, seed=rng)
    report = SingularityReport(robot, A, tuple(found), sigma_random, det_check, line)
    md = _markdown(report)
    return SingularityReport(
        robot, A, tuple(found), sigma_random, det_check, line, fmt,
        latex_document(md) if fmt == "latex" else md, md,
    )  # fmt: skip


def _vanish(values: Callable, Q: np.ndarray, i: int, Qr: np.ndarray) -> bool:
    """Whether factor i is 0 at every configuration of Q (relative to its size at the random Qr)."""
    at = np.array([float(values(*q)[i]) for q in Q])
    scale = max(max(abs(float(values(*q)[i])) for q in Qr), 1e-300)
    return bool((np.abs(at) <= FACTOR_TOL * scale).all())


# ---------------------------------------------------------------------------------------------
# Solving f = 0


def _solve(
    robot: Robot, q: Sequence[sp.Symbol], factor: SingularFactor, rng: np.random.Generator
) -> np.ndarray:
    """Up to 3 configurations with f = 0: f solved for one of its joints (bisection on a sign change
    over a scan of [-pi, pi], or [-2, 2] m for a prismatic joint, whatever its limits; else the
    minimum of |f| when it only touches 0), the others random within the joint limits. (0, n) when
    no root is found."""
    f = sp.lambdify(q, factor.expr, "numpy")
    out: list[np.ndarray] = []
    for attempt in range(60):
        if len(out) == _SOLUTIONS:
            break
        j = factor.joints[attempt % len(factor.joints)]
        base = robot.random_q(seed=rng)
        a, b = (-math.pi, math.pi) if robot.revolute[j] else (-2.0, 2.0)  # m, whatever the limits
        if factor.kind in _ROOTS:  # exact roots
            roots = _ROOTS[factor.kind]
            base[j] = roots[len(out) % len(roots)]
            out.append(base)
            continue
        root = _root(
            lambda x, base=base, j=j: float(f(*np.concatenate((base[:j], [x], base[j + 1 :])))), a, b
        )
        if root is not None:
            base[j] = root
            out.append(base)
    return np.array(out).reshape(-1, robot.n)


def _root(g: Callable[[float], float], a: float, b: float) -> float | None:
    xs = np.linspace(a, b, 721)
    ys = np.array([g(x) for x in xs])
    scale = max(float(np.abs(ys).max()), 1e-300)
    for k in range(len(xs) - 1):
        if ys[k] == 0.0:
            return float(xs[k])
        if ys[k] * ys[k + 1] < 0:
            lo, hi, flo = xs[k], xs[k + 1], ys[k]
            for _ in range(200):
                mid = 0.5 * (lo + hi)
                fm = g(mid)
                if fm == 0.0 or hi - lo < 1e-16:
                    return float(mid)
                if (fm < 0) == (flo < 0):
                    lo, flo = mid, fm
                else:
                    hi = mid
            return float(0.5 * (lo + hi))
    k = int(np.argmin(np.abs(ys)))  # a root of even multiplicity: golden-section search on |f|
    lo, hi = xs[max(k - 1, 0)], xs[min(k + 1, len(xs) - 1)]
    r = (math.sqrt(5) - 1) / 2
    for _ in range(120):
        x1, x2 = hi - r * (hi - lo), lo + r * (hi - lo)
        if abs(g(x1)) < abs(g(x2)):
            hi = x2
        else:
            lo = x1
    x = 0.5 * (lo + hi)
    return float(x) if abs(g(x)) < 1e-12 * scale else None


# ---------------------------------------------------------------------------------------------
# Geometric meaning


class _Geometry:
    """Joint axes (base frame) as numeric lines, and the incidences that a factor's solutions add."""

    def __init__(self, robot: Robot, A: SingularFactors) -> None:
        self.robot = robot
        self.n = robot.n
        self.revolute = [j for j, (rev, _, _) in enumerate(A.axis_exprs) if rev]
        exprs = [list(w) + list(o) for _, w, o in A.axis_exprs]
        self.f = sp.lambdify(A.q, exprs, "numpy")

    def lines(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        L = np.array(self.f(*q), dtype=float).reshape(self.n, 6)
        return L[:, :3], L[:, 3:]  # directions (unit), points

    def describe(self, factor: SingularFactor, Q: np.ndarray, Qr: np.ndarray) -> tuple[str, tuple[str, ...]]:
        def new(pred: Callable[[np.ndarray], bool]) -> bool:  # at every solution and no random q
            return all(pred(q) for q in Q) and not any(pred(q) for q in Qr[:8])

        tol, n, rev = _GEOMETRY_TOL, self.n, self.revolute
        said: list[str] = []
        kind = "other"
        last, first = set(range(max(n - 3, 0), n)), set(range(min(3, n)))
        sets = _parallel_sets(self, rev, Qr[:8], tol)  # axes parallel at every random q
        cls = {k: i for i, S in enumerate(sets) for k in S}
        seen: set[tuple[int, int]] = set()
        for i, j in sorted(itertools.combinations(rev, 2), key=lambda p: (p[1], -p[0])):
            if (cls[i], cls[j]) in seen or cls[i] == cls[j]:
                continue  # one statement per pair of parallel classes, with the nearest axes
            if new(lambda q, i=i, j=j: _parallel(*self.lines(q), i, j, tol)):
                seen.add((cls[i], cls[j]))
                both = "coincide" if all(_collinear(*self.lines(q), i, j, tol) for q in Q) else "are parallel"
                between = all(i < k < j for k in factor.joints)
                elbow = both == "coincide" and between and not ({i, j} <= last or {i, j} <= first)
                stretched = " (the arm is stretched out or folded back)" if elbow else ""
                said.append(f"the axes of joints {i + 1} and {j + 1} {both}{stretched}")
                if {i, j} <= last and n >= 5:
                    kind = "wrist"
                elif elbow and kind == "other":
                    kind = "elbow"
        for S in sets:
            if len(S) >= 3 and new(lambda q, S=S: _coplanar_parallel(*self.lines(q), S, tol)):
                names = ", ".join(str(k + 1) for k in S[:-1]) + f" and {S[-1] + 1}"
                said.append(
                    f"the parallel axes of joints {names} lie in one plane (the arm is stretched out or "
                    "folded back)"
                )
                kind = "elbow" if kind == "other" else kind
        points = self._points(rev, Qr[:8], tol)
        for (na, a), (nb, b) in itertools.combinations(points, 2):
            if new(lambda q, a=a, b=b: _same_point(a(q), b(q), tol)):
                said.append(f"{na} and {nb} coincide")
        if said:
            return kind, tuple(said)
        planes = self._planes(rev, Qr[:8], tol)
        on_axis: list[tuple[str, str]] = []  # (kind, statement)
        in_plane: list[tuple[str, str]] = []
        for pname, point in points:
            for a in rev:
                if new(lambda q, a=a, point=point: _on_line(point(q), *self.lines(q), a, tol)):
                    on_axis.append(
                        ("shoulder" if a == 0 else "other", f"{pname} lies on the axis of joint {a + 1}")
                    )
            for (a, b), plane in planes:
                if new(lambda q, point=point, plane=plane: _on_plane(point(q), plane(q), tol)):
                    stretched = cls[a] == cls[b]  # two parallel axes: the arm stretched out or folded back
                    in_plane.append((
                        "elbow" if stretched else ("shoulder" if a == 0 else "other"),
                        f"{pname} lies in the plane of the axes of joints {a + 1} and {b + 1}"
                        + (" (the arm is stretched out or folded back)" if stretched else ""),
                    ))  # fmt: skip
        for k, text in (on_axis + in_plane)[:_STATEMENTS]:
            said.append(text)
            kind = k if kind == "other" else kind
        if not said and not any(self.robot.revolute[j] for j in factor.joints):
            kind = "prismatic"  # a joint length f = 0: the joint's column and another align
        return kind, tuple(said)

    def _points(self, rev: list[int], Qr: np.ndarray, tol: float) -> list[tuple[str, Callable]]:
        """Named points: where two axes meet at every random q, and the end effector."""
        meets: list[tuple[set[int], Callable]] = []
        for i, j in itertools.combinations(rev, 2):
            if all(_meet(*self.lines(q), i, j, tol) is not None for q in Qr):
                point = functools.partial(self._meet_at, i, j)
                same = next((m for m in meets if all(_close(m[1](q), point(q), tol) for q in Qr)), None)
                if same is None:
                    meets.append(({i, j}, point))
                else:
                    same[0].update((i, j))
        out: list[tuple[str, Callable]] = []
        for axes, point in meets:
            names = sorted(k + 1 for k in axes)
            text = ", ".join(map(str, names[:-1])) + f" and {names[-1]}"
            out.append((f"the point where axes {text} meet", point))
        ee = self._end_effector
        for k, (name, point) in enumerate(out):
            if all(_close(ee(q), point(q), tol) for q in Qr):
                out[k] = (f"{name} (the end-effector origin)", point)
                break
        else:
            out.append(("the end-effector origin", ee))
        return out

    def _meet_at(self, i: int, j: int, q: np.ndarray) -> np.ndarray | None:
        return _meet(*self.lines(q), i, j, 1.0)

    def _end_effector(self, q: np.ndarray) -> np.ndarray:
        return self.robot.fkine(q)[:3, 3]

    def _planes(self, rev: list[int], Qr: np.ndarray, tol: float) -> list[tuple[tuple[int, int], Callable]]:
        """Planes spanned by two axes that are coplanar at every random q: (normal, point)."""
        out = []
        for a, b in itertools.combinations(rev, 2):
            if all(_plane(*self.lines(q), a, b, tol) is not None for q in Qr):
                out.append(((a, b), lambda q, a=a, b=b: _plane(*self.lines(q), a, b, 1.0)))
        return out


def _close(a: np.ndarray, b: np.ndarray, tol: float) -> bool:
    return bool(np.linalg.norm(a - b) < tol)


def _same_point(a: np.ndarray | None, b: np.ndarray | None, tol: float) -> bool:
    return a is not None and b is not None and _close(a, b, tol)


def _parallel(W: np.ndarray, P: np.ndarray, i: int, j: int, tol: float) -> bool:
    return bool(np.linalg.norm(np.cross(W[i], W[j])) < tol)


def _on_line(x: np.ndarray | None, W: np.ndarray, P: np.ndarray, a: int, tol: float) -> bool:
    return x is not None and bool(np.linalg.norm(np.cross(W[a], x - P[a])) < tol)


def _collinear(W: np.ndarray, P: np.ndarray, i: int, j: int, tol: float) -> bool:
    return _parallel(W, P, i, j, tol) and _on_line(P[j], W, P, i, tol)


def _meet(W: np.ndarray, P: np.ndarray, i: int, j: int, tol: float) -> np.ndarray | None:
    """Where axes i and j meet (None when they are parallel or skew by more than tol)."""
    c = np.cross(W[i], W[j])
    if np.linalg.norm(c) < 1e-6:
        return None
    d = P[j] - P[i]
    if abs(d @ c) / np.linalg.norm(c) > tol:
        return None
    t = np.cross(d, W[j]) @ c / (c @ c)
    return P[i] + t * W[i]


def _plane(W: np.ndarray, P: np.ndarray, a: int, b: int, tol: float) -> tuple[np.ndarray, np.ndarray] | None:
    """(unit normal, point) of the plane holding axes a and b, None when they are skew or collinear."""
    c = np.cross(W[a], W[b])
    if np.linalg.norm(c) < 1e-6:
        c = np.cross(W[a], P[b] - P[a])
        if np.linalg.norm(c) < 1e-6:
            return None
    elif abs((P[b] - P[a]) @ c) / np.linalg.norm(c) > tol:
        return None
    return c / np.linalg.norm(c), P[a]


def _on_plane(x: np.ndarray | None, plane: tuple[np.ndarray, np.ndarray] | None, tol: float) -> bool:
    """Whether x lies on the plane (unit normal, point); False when either is undefined there (two axes
    that meet at random configurations can be parallel at a solution, two coplanar ones collinear)."""
    if x is None or plane is None:
        return False
    normal, point = plane
    return bool(abs((x - point) @ normal) < tol)


def _parallel_sets(g: _Geometry, rev: list[int], Qr: np.ndarray, tol: float) -> list[list[int]]:
    """Maximal sets of axes parallel at every random configuration."""
    sets: list[list[int]] = []
    for j in rev:
        for S in sets:
            if all(_parallel(*g.lines(q), S[0], j, tol) for q in Qr):
                S.append(j)
                break
        else:
            sets.append([j])
    return sets


def _coplanar_parallel(W: np.ndarray, P: np.ndarray, S: list[int], tol: float) -> bool:
    """Whether parallel axes S lie in one plane: their points, projected along the common direction,
    are collinear."""
    w = W[S[0]]
    X = np.array([P[k] - (P[k] @ w) * w for k in S])
    X = X - X[0]
    return bool(np.linalg.svd(X, compute_uv=False)[1] < tol) if len(S) > 2 else True


# ---------------------------------------------------------------------------------------------
# The text


def _markdown(R: SingularityReport) -> str:
    from symkin.core.version import __version__
    from symkin.model.latex import ets_latex

    A, robot = R.analysis, R.robot
    n = robot.n
    q1 = tuple(sp.Symbol(f"q_{j + 1}", real=True) for j in range(n))
    rename = dict(zip(A.q, q1))
    P = Printer(q1)
    rows = {"all": "all six rows", "trans": "the translational rows", "rot": "the rotational rows"}[A.axes]
    pos, point = A.frame
    where = "the base frame" if pos == 0 else f"the frame after factor $E_{{{pos}}}$ of the ETS"
    items = []
    for k, s in enumerate(R.singularities):
        f = s.factor
        roots = _ROOTS_TEX.get(f.kind)
        cond = P(f.expr.xreplace(rename)) + " = 0"
        if roots:
            cond += rf" \;(q_{{{f.joints[0] + 1}}} = {roots})"
        power = f" (power {f.multiplicity})" if f.multiplicity > 1 else ""
        meaning = "; ".join(s.meaning) if s.meaning else "the joint twists become linearly dependent"
        if s.also:
            which = " and ".join(str(i + 1) for i in s.also)
            meaning += f" (where condition {which} holds too: a root of higher order)"
        if s.checked:
            sig = _sci(s.sigma_at_solutions)
            check = (
                f"singular (rank {s.rank} of {A.full_rank}): $\\sigma_{{min}} \\le {sig}$ at "
                f"{len(s.solutions)} solutions"
            )
            lo, hi = robot.qlim
            if not ((s.solutions >= lo - 1e-12) & (s.solutions <= hi + 1e-12)).all(axis=1).any():
                check += " (outside the joint limits)"
        elif len(s.solutions):
            check = f"NOT singular at the solutions ($\\sigma_{{min}} = {_sci(s.sigma_at_solutions)}$)"
        else:
            check = "no real solution found"
        items.append([str(k + 1), f"${cond}${power}", s.kind, meaning, check])
    det = ""
    if A.determinant is not None:
        det = P(A.determinant.xreplace(rename))
    ctx = {
        "robot": display_name(robot.name),
        "n": n,
        "structure": robot.ets.structure,
        "version": __version__,
        "joint_map": ", ".join(f"$q_{{{j + 1}}}$ is `q{j}`" for j in range(n)),
        "ets": ets_latex(robot.ets),
        "method": A.method,
        "method_tex": {
            "det(J)": r"$\det J$",
            "det(J J^T)": r"$\det(J J^\top)$",
            "det(J^T J)": r"$\det(J^\top J)$",
        }[A.method],
        "rows": rows,
        "m": len(A.rows),
        "where": where,
        "point": point if point == "end effector" else f"the origin of {point} (a point on its axis)",
        "determinant": det,
        "seconds": f"{A.seconds:.2f}",
        "minors": A.minors,
        "unfactored": A.unfactored,
        "max_terms": MAX_TERMS,
        "items": items,
        "legend": P.legend(),
        "random": len(R.sigma_at_random),
        "sigma_random": _sci(float(R.sigma_at_random.min(initial=math.inf))),
        "tol": _sci(SINGULAR_TOL),
        "det_check": "" if math.isnan(R.determinant_check) else _sci(R.determinant_check),
        "lines": R.lines.lines,
        "samples": R.lines.samples,
        "drops": len(R.lines.drops),
        "unexplained": [_configuration(q) for q in R.lines.unexplained[:_UNEXPLAINED_SHOWN]],
        "unexplained_count": len(R.lines.unexplained),
    }
    return render("derive/singularities.md.j2", **ctx)


def _configuration(q: np.ndarray) -> str:
    return "(" + ", ".join(f"{x:.4g}" for x in q) + ")"


def _sci(x: float) -> str:
    if not math.isfinite(x):
        return str(x)
    if x == 0:
        return "0"
    e = math.floor(math.log10(abs(x)))
    if -3 <= e <= 3:
        return f"{x:.3g}"
    return f"{x / 10**e:.2g} \\cdot 10^{{{e}}}"
