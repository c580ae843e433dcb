"""Emit forward kinematics + collision checks ("FKCC", after Thomason, Kingston and Kavraki, Motions
in Microseconds via Vectorized Sampling-Based Planning, ICRA 2024) as one C file per robot and
geometry.

The robot's constants are folded into straight-line code: each link pose is its parent's pose times
the segment's constant transform (terms with a 0 factor dropped, 1 factors not multiplied) times
the joint's rotation or translation; each shape point is its link's pose applied to the point.
The pair tests call the primitives of ``runtime/csrc/symkin_collide.h``. Functions (all double):

- ``skcoll_points(q, X)``: shape points in the base frame, (P, 3).
- ``skcoll_in_collision(q, S, ns, C, nc, B, nb)``: 1 when any active pair overlaps; stops at the
  first one found (environment first, then self pairs). The self pairs proved apart within the
  joint limits (:func:`symkin.geometry.proved_apart`) are tried only for q outside them; the batch
  tests each link only against the obstacle spheres within its reach sphere
  (:func:`symkin.geometry.reach_sphere`).
- ``skcoll_distances(q, S, ns, C, nc, B, nb, d, J)``: the signed distance of every active pair and,
  when ``J`` is not NULL, its gradient row (M, n).
- ``skcoll_distance_rows(q, S, ns, C, nc, B, nb, idx, k, J)``: the gradient rows (k, n) of the k
  pairs ``idx`` (indices into the distances; the MMC step's closest pairs).
- ``*_batch`` of each over N configurations (rows of Q).

Obstacles come packed as in :meth:`symkin.geometry.Environment.arrays`.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import numpy as np

from symkin.core.names import comment_safe, identifier
from symkin.core.version import __version__
from symkin.emit import collision_self
from symkin.emit.collision_self import c_number as _num
from symkin.emit.collision_self import plan_self, self_code
from symkin.emit.templates import render
from symkin.geometry.clearance import proved_apart, reach_everywhere, reach_sphere
from symkin.geometry.reference import Tables
from symkin.model.geometry import Capsule

__all__ = [
    "render_collision",
    "render_collision_numpy",
    "render_collision_casadi",
    "render_collision_tensor",
    "render_collision_python",
    "collision_module_name",
    "collision_tables",
]

# the distance primitives, shared with the C runtime (the MMC step with obstacle constraints)
COLLIDE_HEADER = Path(__file__).resolve().parent.parent / "runtime" / "csrc" / "symkin_collide.h"


def _py_num(x: float) -> str:
    """A Python float literal that reads back exactly, infinities as float("inf")."""
    return _num(x) if np.isfinite(x) else ('float("inf")' if x > 0 else 'float("-inf")')


# The straight-line link poses are written in three dialects: "c" (one configuration, double),
# "c4" (four configurations in the lanes of a v4) and "py" (NumPy: each entry an (N,) array).
Dialect = str


def _const(x: float, lang: Dialect) -> str:
    """A constant: a double literal, or four lanes of it (``SKV``) in the 4-lane code."""
    return f"SKV({_num(x)})" if lang == "c4" else _num(x)


def _stmt(text: str, lang: Dialect) -> str:
    return text if lang == "py" else text + ";"


# An entry of a pose as the emitter knows it: a number (known when the code is generated) or the
# name of the entry that holds it at run time ("T[3][5]").
Value = float | str
_ENTRY = re.compile(r"[A-Za-z_][A-Za-z_0-9]*\[\d+\](\[\d+\])?")  # the name of one entry


def _sum(parts: list[tuple[float | None, Value]]) -> tuple[Value | None, str]:
    """``sum(c * v)`` of (coefficient c or None for 1, value v) in order, terms with a zero value
    dropped: (the value when it is known without code: a number, or one entry unchanged; else None,
    and the expression's text)."""
    parts = [(c, v) for c, v in parts if not (isinstance(v, float) and v == 0.0)]
    if not parts:
        return 0.0, "0.0"
    if all(isinstance(v, float) for _, v in parts):
        total = None
        for c, v in parts:
            x = float(v) if c is None else c * float(v)  # type: ignore[arg-type]
            total = x if total is None else total + x
        return total, _num(total)  # type: ignore[arg-type]
    if len(parts) == 1 and parts[0][0] in (None, 1.0) and _ENTRY.fullmatch(str(parts[0][1])):
        return parts[0][1], str(parts[0][1])
    terms = []
    for c, v in parts:
        if isinstance(v, float):
            terms.append(_num(v if c is None else c * v))
        elif c is None or c == 1.0:
            terms.append(v)
        else:
            terms.append(f"-{v}" if c == -1.0 else f"{_num(c)} * {v}")
    return None, " + ".join(terms).replace("+ -", "- ")


def _is_identity(C: np.ndarray) -> bool:
    return bool(np.array_equal(C[:3, :4], np.eye(4)[:3]))


def _difference(x: str, y: str) -> str:
    """The text of ``x - y`` for term texts x, y ("" for zero; y may start with a minus)."""
    if not y:
        return x
    if not x:
        return y[1:] if y.startswith("-") else f"-{y}" if " " not in y else f"-({y})"
    return f"{x} + {y[1:]}" if y.startswith("-") else f"{x} - {y}"


def _factor(f: str, v: Value) -> str:
    """The text of ``f * v`` (f the name of a number: "c", "s"); "" when v is zero."""
    if isinstance(v, float):
        return "" if v == 0.0 else f if v == 1.0 else f"-{f}" if v == -1.0 else f"{f} * {_num(v)}"
    return f"{f} * {v}"


class _Poses:
    """Straight-line code of link poses (3x4 row-major, 12 entries each) with the numbers known at
    generation time folded in: an entry that is a number is not computed (a product with it is a
    number, a term with a zero dropped), an entry equal to another is not copied. ``keep``: every
    entry is also stored (the scalar and NumPy code hand T and PJ to the distance gradients); the
    four-lane code stores only what it computes."""

    def __init__(self, lang: Dialect, keep: bool) -> None:
        self.lang, self.keep = lang, keep
        self.lines: list[str] = []
        self.vals: dict[str, list[Value]] = {}

    def _set(self, dst: str, e: int, value: Value | None, text: str, out: list[Value]) -> None:
        if value is None or (isinstance(value, str) and value.startswith("M")):
            # computed here, or a temporary's entry (M<k>_ stays inside the function): stored
            self.lines.append(_stmt(f"{dst}[{e}] = {text}", self.lang))
            value = f"{dst}[{e}]"
        elif self.keep:
            self.lines.append(
                _stmt(
                    f"{dst}[{e}] = {_const(value, self.lang) if isinstance(value, float) else value}",
                    self.lang,
                )
            )
        out.append(value)

    def product(self, dst: str, src: str | None, C: np.ndarray) -> None:
        """``dst = src * C`` (C constant; src None: the identity)."""
        S = self.vals[src] if src is not None else [float(x) for x in np.eye(4)[:3].ravel()]
        out: list[Value] = []
        for i in range(3):
            for j in range(4):
                parts: list[tuple[float | None, Value]] = [
                    (float(C[m, j]), S[4 * i + m]) for m in range(3) if C[m, j] != 0.0
                ]
                if j == 3:
                    parts.append((None, S[4 * i + 3]))
                self._set(dst, 4 * i + j, *_sum(parts), out)
        self.vals[dst] = out

    def joint(self, dst: str, src: str, axis: int, revolute: bool, theta: str) -> None:
        """``dst = src * Rot_axis(theta)`` or ``src * Trans_axis(theta)``; "c4": four lanes (sin
        and cos by the branch-free ``skv_sin_``/``skv_cos_``: lane by lane the numbers of the
        scalar ``sk_sin``/``sk_cos``, the lanes those cannot compute marked in ``far``)."""
        S, lang = self.vals[src], self.lang
        out: list[Value] = list(S)
        if not revolute:  # the origin moves by theta along the axis: row i gains theta * S[i][axis]
            for i in range(3):
                e, x = 4 * i + 3, S[4 * i + axis]
                move = (
                    f"({theta}) * {x}"
                    if isinstance(x, str)
                    else None
                    if x == 0.0
                    else f"{_num(x)} * ({theta})"
                )
                value, text = _sum([(None, S[e])] + ([] if move is None else [(None, move)]))
                out[e] = value if value is not None else f"{dst}[{e}]"
                if value is None:
                    self.lines.append(_stmt(f"{dst}[{e}] = {text}", lang))
        else:
            j, k = [(1, 2), (2, 0), (0, 1)][axis]  # Rot_axis: e_j -> c e_j + s e_k, e_k -> -s e_j + c e_k
            self.lines += {
                "c": [f"{{ const double c = sk_cos({theta}), s = sk_sin({theta});"],
                "c4": [f"{{ const v4 th_ = {theta}, c = skv_cos_(th_, far), s = skv_sin_(th_, far);"],
                "py": [f"th_ = {theta}", "c, s = cos(th_), sin(th_)"],
            }[lang]
            for i in range(3):
                a, b = S[4 * i + j], S[4 * i + k]
                rows = (
                    (4 * i + j, " + ".join(t for t in (_factor("c", a), _factor("s", b)) if t)),
                    (4 * i + k, _difference(_factor("c", b), _factor("s", a))),
                )
                for e, text in rows:
                    if not text:
                        out[e] = 0.0
                        continue
                    self.lines.append(_stmt(f"{dst}[{e}] = {text.replace('+ -', '- ')}", lang))
                    out[e] = f"{dst}[{e}]"
            if lang != "py":
                self.lines.append("}")
        if self.keep:  # the entries the joint leaves as they were, stored too
            for e in range(12):
                if out[e] == S[e]:
                    v = S[e]
                    self.lines.append(
                        _stmt(f"{dst}[{e}] = {_const(v, lang) if isinstance(v, float) else v}", lang)
                    )
        self.vals[dst] = out


def _fk_lines(tree: Any, lang: Dialect) -> tuple[list[str], dict[str, list[Value]]]:
    """The straight-line link poses T (and PJ, before each joint) of ``tree`` and the value of each
    entry of each pose (:class:`_Poses`). "c4": the 4-lane code (``qv``, v4), which stores only the
    computed entries."""
    num = tree._num
    poses = _Poses(lang, keep=lang != "c4")
    q = "qv" if lang == "c4" else "q"
    for k, seg in enumerate(tree.segments):
        parent = None if seg.parent < 0 else f"T[{seg.parent}]"
        A, B = num.A[k], num.B[k]
        comment = f"segment {k}: link {comment_safe(seg.link, 60)}"
        poses.lines.append(f"# {comment}" if lang == "py" else f"/* {comment} */")
        if seg.slot is None:
            poses.product(f"T[{k}]", parent, A)
            continue
        s = tree.slots[seg.slot]
        sign = num.sign[k]
        mult, off = float(s.multiplier), float(s.offset)
        theta = f"{q}[{s.joint}]"
        if mult != 1.0:
            theta = f"{_num(mult)} * {theta}"
        if off != 0.0:
            theta = f"{theta} + {_num(off)}"
        if sign < 0:
            theta = f"-({theta})"
        poses.product(f"PJ[{k}]", parent, A)
        if _is_identity(B):
            poses.joint(f"T[{k}]", f"PJ[{k}]", num.axis[k], s.revolute, theta)
        else:  # the joint's pose in M<k>_, then the constant after it
            m = f"M{k}_"
            poses.lines.append(
                {"c": f"double {m}[12];", "c4": f"v4 {m}[12];", "py": f"{m} = [0.0] * 12"}[lang]
            )
            poses.joint(m, f"PJ[{k}]", num.axis[k], s.revolute, theta)
            poses.product(f"T[{k}]", m, B)
    return poses.lines, poses.vals


def _point_lines(
    points: list[tuple[int, list[str]]], lang: Dialect, vals: dict[str, list[Value]]
) -> list[str]:
    """``X[i][r]`` = link pose ``T[k]`` applied to each point (k, local coordinates), straight-line
    with the poses' known entries folded in (``vals`` of :func:`_fk_lines`; a point on the base link
    is its constant coordinates)."""
    lines = []
    for i, (k, local) in enumerate(points):
        T = vals[f"T[{k}]"] if k >= 0 else [float(x) for x in np.eye(4)[:3].ravel()]
        for r in range(3):
            parts: list[tuple[float | None, Value]] = [
                (float(local[c]), T[4 * r + c]) for c in range(3) if float(local[c]) != 0.0
            ]
            value, text = _sum([*parts, (None, T[4 * r + 3])])
            if isinstance(value, float):
                text = _const(value, lang)
            lines.append(_stmt(f"X[{i}][{r}] = {text}", lang))
    return lines


def _limits(qlim: np.ndarray) -> list[tuple[int, str | None, str | None]]:
    """Per joint with a finite limit: (index, lower or None, upper or None) as C numbers."""
    out = []
    for j, (lo, hi) in enumerate(zip(*np.asarray(qlim, dtype=float))):
        lo_s, hi_s = (_num(float(x)) if np.isfinite(x) else None for x in (lo, hi))
        if lo_s is not None or hi_s is not None:
            out.append((j, lo_s, hi_s))
    return out


def collision_tables(layout: Any) -> dict[str, Any]:
    """Everything the template needs, from a :class:`symkin.geometry.pairs.Layout`."""
    tree = layout.tree
    tables = Tables.of(layout)
    fk, vals = _fk_lines(tree, "c")
    fk4, vals4 = _fk_lines(tree, "c4")
    # per segment: has a joint, q index, multiplier, revolute, axis, sign (the distance gradients)
    joints = [
        (0, 0, 0.0, 0, 0, 1.0) if j is None else (1, j[0], j[1], int(j[2]), j[3], j[4]) for j in tables.joints
    ]
    points = [(k, [_num(x) for x in p]) for s, k in zip(layout.shapes, layout.segment) for p in s.points]
    # one bounding sphere per link (its shapes' points' box centre, the radius enclosing every shape):
    # in_collision tests a link's shapes only when its bounding sphere meets the obstacle or the
    # other link's bounding sphere; appended to the points after the shapes' own
    links = list(dict.fromkeys(s.link for s in layout.shapes))
    members: list[list[int]] = [[] for _ in links]
    for i, s in enumerate(layout.shapes):
        members[links.index(s.link)].append(i)
    bounds, reach = [], []
    for group in members:
        P = np.array([p for i in group for p in layout.shapes[i].points])
        c = 0.5 * (P.min(axis=0) + P.max(axis=0))
        r = max(np.linalg.norm(np.array(p) - c) + layout.shapes[i].radius
                for i in group for p in layout.shapes[i].points)  # fmt: skip
        r = float(np.nextafter(r, np.inf))  # rounding may not shrink the bound below a shape
        bounds.append((len(points), _num(r)))
        points.append((layout.segment[group[0]], [_num(x) for x in c]))
        # where the bound can be at all within the joint limits: the batch drops the obstacles
        # beyond it for the link (radius -1: no such bound)
        seg = layout.segment[group[0]]
        sphere = reach_sphere(layout, seg, c, r)
        reach.append(
            ([_num(x) for x in sphere[0]], _num(sphere[1]), int(reach_everywhere(layout, seg)))
            if sphere is not None
            else (["0.0", "0.0", "0.0"], "-1.0", 1)
        )
    link_of = {i: links.index(s.link) for i, s in enumerate(layout.shapes)}
    # self pairs proved apart within the joint limits are checked only for q outside them
    proved = proved_apart(layout)
    groups: dict[tuple[int, int], list[tuple[int, int]]] = {}
    groups_proved: dict[tuple[int, int], list[tuple[int, int]]] = {}
    for i, j in layout.self_pairs:
        a, b = sorted((link_of[i], link_of[j]))
        (groups_proved if (i, j) in proved else groups).setdefault((a, b), []).append((i, j))
    link_start, link_shapes = [0], []
    for group in members:
        link_shapes += group
        link_start.append(len(link_shapes))
    # in_collision's checks as straight-line code (_self_code, _self_code4; obstacles below)
    first = layout.point_index
    radius = [float(x.radius) for x in layout.shapes]
    is_cap = [isinstance(x, Capsule) for x in layout.shapes]
    sphere_code = []  # against obstacle sphere ob (centre ob, radius ro)
    for (pb, rb), group in zip(bounds, members):
        sphere_code.append(f"if (skc_spheres_overlap(X[{pb}], {rb}, ob, ro)) {{")
        for i in group:
            if is_cap[i]:
                sphere_code.append(f"    if (overlaps(X, {i}, -1, 1, ob)) return 1;")
            else:
                r_i = _num(radius[i])
                sphere_code.append(f"    if (skc_spheres_overlap(X[{first[i]}], {r_i}, ob, ro)) return 1;")
        sphere_code.append("}")
    point_code, point_code4 = _point_lines(points, "c", vals), _point_lines(points, "c4", vals4)
    # the 4-lane obstacle checks (spheres only): a lane already hit needs nothing more; a link is
    # tested only for the lanes whose bounding sphere meets the obstacle (as the scalar code)
    all_spheres = not any(is_cap)
    sphere_code4: list[str] = []
    plan = (bounds, link_of, first, radius, is_cap)
    planned, planned_proved = plan_self(groups, plan), plan_self(groups_proved, plan)
    looped = len(layout.self_pairs) > collision_self.UNROLL_PAIRS  # loops over tables past this size
    unrolled = all_spheres and not looped
    if all_spheres:  # link by link, the obstacles within its reach (idx[start[l]..start[l + 1]])
        for l, ((pb, rb), group) in enumerate(zip(bounds, members)):
            sphere_code4.append(f"for (int t = start[{l}]; t < start[{l + 1}]; ++t) {{")
            sphere_code4.append("    const double *ob = S + 4 * idx[t];")
            sphere_code4.append("    const double ro = ob[3];")
            sphere_code4.append(f"    need = ~hit & hit_obstacle(X[{pb}], {rb}, ob, ro);")
            sphere_code4.append("    if (skv_any_(need)) {")
            for i in group:
                r_i = _num(radius[i])
                sphere_code4.append(f"        hit |= need & hit_obstacle(X[{first[i]}], {r_i}, ob, ro);")
            sphere_code4.append("    }")
            sphere_code4.append("}")
            sphere_code4.append("if (skv_all_(hit)) return hit;")
    anc = [a for path in tables.ancestors for a in path]
    anc_start = np.cumsum([0] + [len(path) for path in tables.ancestors]).tolist()
    shapes = [
        (int(isinstance(s, Capsule)), layout.point_index[i], _num(s.radius), layout.segment[i])
        for i, s in enumerate(layout.shapes)
    ]
    return {
        "n": tree.n,
        "S": max(len(tree.segments), 1),
        "fk": fk,
        "joints": joints,
        "points": points,
        "point_code": point_code,
        "point_code4": point_code4,
        "fk4": fk4,
        "vector_pairs": all_spheres,
        "self_tables": looped,
        "self_code4": self_code(planned, lanes=True) if unrolled else [],
        "self_code4_proved": self_code(planned_proved, lanes=True, mask="outside & ") if unrolled else [],
        "self_rows": collision_self.self_tables(planned) if looped else {},
        "self_rows_proved": collision_self.self_tables(planned_proved) if looped else {},
        "has_proved": bool(planned_proved),
        "reach_limited": any(r[2] == 0 for r in reach),
        "limits": _limits(tree.qlim),
        "sphere_code4": sphere_code4,
        "shapes": shapes,
        "pairs": list(layout.self_pairs) or [(0, 0)],
        "npairs": len(layout.self_pairs),
        "nlinks": len(links),
        "bounds": bounds,
        "reach": reach,
        "link_start": link_start,
        "link_shapes": link_shapes,
        "self_code": [] if looped else self_code(planned),
        "self_code_proved": [] if looped else self_code(planned_proved),
        "sphere_code": sphere_code,
        "anc_start": anc_start,
        "anc": anc or [0],
    }


def render_collision(layout: Any) -> dict[str, str]:
    """The C sources of ``layout``'s FKCC kernel: ``{"skcoll.c": ..., "symkin_collide.h": ...}``."""
    tree = layout.tree
    text = render(
        "c/collision.c.j2",
        robot=comment_safe(tree.name, 80),
        ident=identifier(tree.name),
        version=__version__,
        nshapes=len(layout.shapes),
        nshape_points=layout.n_points,
        source=comment_safe(tree.geometry.source or "user geometry", 200),
        real="double",
        libm=False,
        **collision_tables(layout),
    )
    return {"skcoll.c": text, "symkin_collide.h": COLLIDE_HEADER.read_text()}


def collision_module_name(model_name: str) -> str:
    """The generated NumPy collision module's name: ``symkin_<robot>_collision``."""
    return f"symkin_{identifier(model_name)}_collision"


def _py_rows(rows: Any) -> str:
    """A tuple literal of tuples of floats, one row per line."""
    lines = "".join(
        f"        ({', '.join(_py_num(x) for x in row)}{',' * (len(row) == 1)}),\n" for row in rows
    )
    return "(\n" + lines + "    )"


def _py_tuple(items: list[str], indent: int = 8, width: int = 100) -> str:
    """A Python tuple literal of ``items`` (their source text), wrapped to ``width`` columns."""
    if not items:
        return "()"
    lines, line = [], ""
    for x in items:
        if line and indent + len(line) + len(x) + 2 > width:
            lines.append(line.rstrip())
            line = ""
        line += x + ", "
    lines.append(line.rstrip())
    pad = " " * indent
    return "(\n" + "".join(f"{pad}{x}\n" for x in lines) + " " * (indent - 4) + ")"


def render_collision_numpy(layout: Any, command: str = "symkin generate") -> dict[str, str]:
    """The generated NumPy collision module of ``layout``: ``{"symkin_<robot>_collision.py": ...}``,
    link poses and shape points as straight-line NumPy code vectorised over configurations, the
    geometry as literal :class:`symkin.geometry.reference.Tables`, the pair math from
    :func:`symkin.geometry.reference.evaluate_frames`."""
    return render_collision_python(layout, "numpy", command)


def render_collision_casadi(layout: Any, command: str = "symkin generate") -> dict[str, str]:
    """The generated CasADi collision module of ``layout``:
    ``{"symkin_<robot>_collision_casadi.py": ...}``, the same straight-line link poses and shape
    points on CasADi expressions; ``function(env)`` builds the distances' ``casadi.Function``
    (:func:`symkin.emit.casadi.collision.distances_function`)."""
    return render_collision_python(layout, "casadi", command)


def render_collision_tensor(layout: Any, backend: str, command: str = "symkin generate") -> dict[str, str]:
    """The generated JAX or PyTorch collision module of ``layout`` (``backend`` "jax" or "torch"):
    ``{"symkin_<robot>_collision_<backend>.py": ...}``, ``points(q)`` from the same straight-line
    link poses on arrays of any batch shape (the JAX module materialises each link pose on the CPU,
    as its kinematics module does), the geometry as literal Tables; the pair distances are
    :mod:`symkin.runtime.diff.distance`."""
    return render_collision_python(layout, backend, command)


def _segment_kept(fk: list[str]) -> list[str]:
    """The JAX link poses: each segment's pose ``T[k]`` passed through ``_keep_row`` once written."""
    out: list[str] = []
    last = None
    for line in fk:
        if line.startswith("# segment ") and last is not None:
            out.append(f"T[{last}] = _keep_row(T[{last}])")
        if line.startswith("# segment "):
            last = int(line.split()[2].rstrip(":"))
        out.append(line)
    if last is not None:
        out.append(f"T[{last}] = _keep_row(T[{last}])")
    return out


_LIBRARY = {"numpy": "NumPy", "casadi": "CasADi", "jax": "JAX", "torch": "PyTorch"}


def render_collision_python(layout: Any, backend: str, command: str = "symkin generate") -> dict[str, str]:
    """The generated collision module of ``layout`` on the Python ``backend`` (numpy, casadi, jax,
    torch; the ``render_collision_<backend>`` functions above)."""
    tree = layout.tree
    tables = Tables.of(layout)
    proved = proved_apart(layout)  # the generated in_collision skips them within the limits
    points = [(k, [_num(x) for x in p]) for s, k in zip(layout.shapes, layout.segment) for p in s.points]
    module = collision_module_name(tree.name) + ("" if backend == "numpy" else f"_{backend}")
    fk, vals = _fk_lines(tree, "py")
    text = render(
        f"{backend}/collision.py.j2",
        library=_LIBRARY[backend],
        module=module,
        robot=comment_safe(tree.name, 80),
        name_literal=ascii(tree.name),
        version=__version__,
        command=comment_safe(command, 200),
        source=comment_safe(tree.geometry.source or "user geometry", 200),
        n=tree.n,
        nseg=max(len(tree.segments), 1),
        nshapes=len(layout.shapes),
        npoints=layout.n_points,
        npairs=len(layout.self_pairs),
        tables={
            "caps": _py_tuple([str(x) for x in tables.caps]),
            "first": _py_tuple([str(x) for x in tables.first]),
            "radius": _py_tuple([_num(x) for x in tables.radius]),
            "segment": _py_tuple([str(x) for x in tables.segment]),
            "self_pairs": _py_tuple([f"({i}, {j})" for i, j in tables.self_pairs]),
            "joints": _py_tuple(
                [
                    "None" if j is None else f"({j[0]}, {_num(j[1])}, {j[2]}, {j[3]}, {_num(j[4])})"
                    for j in tables.joints
                ]
            ),
            "ancestors": _py_tuple([repr(tuple(x)) for x in tables.ancestors]),
            "proved": _py_tuple([f"({i}, {j})" for i, j in sorted(proved)]),
            "qlim": "None" if not proved else _py_rows(tree.qlim),
        },
        fk=_segment_kept(fk) if backend == "jax" else fk,
        point_code=_point_lines(points, "py", vals),
    )
    return {f"{module}.py": text}
