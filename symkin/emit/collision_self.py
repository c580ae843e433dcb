"""The self pair checks of the FKCC kernel (:mod:`symkin.emit.collision`): per pair of links, their
bounding spheres, then each shape pair, a sphere with several partners on the other link first tried
against that link's bound; written as straight-line C (scalar and four-lane) or, past
:data:`UNROLL_PAIRS` pairs, as the rows of C tables that loops walk (the same tests with the same
numbers in the same order, so the same verdicts).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["UNROLL_PAIRS", "SPHERE_FIRST", "LinkPair", "plan_self", "self_code", "self_tables", "c_number"]


def c_number(x: float) -> str:
    """A C (and Python) double literal that reads back exactly."""
    r = repr(float(x))
    return r if ("e" in r or "." in r or "n" in r) else r + ".0"


_num = c_number

# Self pairs are written out as straight-line code up to this many (the Panda's 600, VAMP's 1 050),
# past it as tables that loops walk: the compiler's time grows with the straight-line code (3 288
# pairs: 8 s against 0.9 s as tables; 29 204: 103 s against 2.5 s) and the loops check as fast
# (within a few per cent either way; docs/guide/performance.md)
UNROLL_PAIRS = 1500
SPHERE_FIRST = 3  # a sphere with this many partners on the other link is first tried on its bound


def _sphere_first(
    pairs: list[tuple[int, int]], link_of: dict[int, int], a: int, bounds: list, is_cap: list[bool]
) -> tuple[list[tuple[int, tuple[int, str], list[int]]], list[tuple[int, int]]]:
    """The self pairs of link ``a`` and one other link, planned: (firsts, rest). ``firsts``: the
    spheres, on the side with fewer spheres, that have at least SPHERE_FIRST partners, each with
    the other link's bound and its partners; such a sphere is tested against that bounding sphere
    first (missing it, it misses every shape inside). ``rest``: the pairs to test one by one, in
    their order. Links with capsules keep every pair in ``rest``."""
    if any(is_cap[i] or is_cap[j] for i, j in pairs):
        return [], list(pairs)
    split = [(i, j) if link_of[i] == a else (j, i) for i, j in pairs]  # (on link a, on the other)
    side = 0 if len({p[0] for p in split}) <= len({p[1] for p in split}) else 1
    partners: dict[int, list[int]] = {}
    for p in split:
        partners.setdefault(p[side], []).append(p[1 - side])
    firsts = [(o, bounds[link_of[js[0]]], js) for o, js in partners.items() if len(js) >= SPHERE_FIRST]
    done = {o for o, _, _ in firsts}
    return firsts, [(i, j) for i, j in pairs if i not in done and j not in done]


@dataclass(frozen=True)
class LinkPair:
    """The self pairs of two links, planned (:func:`plan_self`): the links' bounding spheres (points pa,
    pb; radii ra, rb; rr the squared sum, C numbers), the first spheres (sphere point, the other
    link's bound point, squared radius sum, and its partners: (point, squared radius sum)) and the
    pairs tested one by one (capsule?, then points (two spheres) or shapes (a capsule), squared
    radius sum)."""

    pa: int
    ra: str
    pb: int
    rb: str
    rr: str
    firsts: tuple[tuple[int, int, str, tuple[tuple[int, str], ...]], ...]
    rest: tuple[tuple[bool, int, int, str], ...]


def plan_self(groups: dict, plan: tuple) -> list[LinkPair]:
    """The self checks of ``groups`` ((link a, link b) -> shape pairs; ``plan``: bounds, link of
    each shape, first points, radii, which are capsules), in order: per pair of links, their
    bounding spheres, then each shape pair (two spheres: squared distance against the constant
    squared radius sum); a sphere with SPHERE_FIRST or more partners on the other link meets that
    link's bound first."""
    bounds, link_of, first, radius, is_cap = plan
    out = []

    def rr(x: float, y: float) -> str:
        return _num((x + y) * (x + y))

    for (a, b), pairs in sorted(groups.items()):
        (pa, ra), (pb, rb) = bounds[a], bounds[b]
        firsts, rest = _sphere_first(pairs, link_of, a, bounds, is_cap)
        out.append(
            LinkPair(
                pa, ra, pb, rb, rr(float(ra), float(rb)),
                tuple(
                    (first[o], bound[0], _num((radius[o] + float(bound[1])) ** 2),
                     tuple((first[j], rr(radius[o], radius[j])) for j in inner))
                    for o, bound, inner in firsts
                ),
                tuple(
                    (True, i, j, "0.0") if is_cap[i] or is_cap[j]
                    else (False, first[i], first[j], rr(radius[i], radius[j]))
                    for i, j in rest
                ),
            )
        )  # fmt: skip
    return out


# The self checks' C lines, scalar (return 1 on a hit) and four-lane (spheres only: a lane already
# hit needs nothing more, a test runs only for the lanes whose bounds meet and ``mask`` names): a
# pair of links' bounds, a sphere against the other link's bound, then a shape pair inside that
# test and one on its own.
_SELF_LINES = {
    False: {
        "link": "if (skc_spheres_overlap(X[{pa}], {ra}, X[{pb}], {rb})) {{",
        "first": "    if (sphere_hit({a}, {b}, {rr})) {{",
        "inner": "        if (sphere_hit({a}, {b}, {rr})) return 1;",
        "pair": "    if (sphere_hit({a}, {b}, {rr})) return 1;",
        "end": "}}",
    },
    True: {
        "link": "need = {mask}~hit & hit2(X[{pa}], X[{pb}], {rr});\nif (skv_any_(need)) {{",
        "first": "    near = need & hit2({a}, {b}, {rr});\n    if (skv_any_(near)) {{",
        "inner": "        hit |= near & hit2({a}, {b}, {rr});",
        "pair": "    hit |= need & hit2({a}, {b}, {rr});",
        "end": "    if (skv_all_(hit)) return hit;\n}}",
    },
}


def self_code(planned: list[LinkPair], lanes: bool = False, mask: str = "") -> list[str]:
    """The self checks of :func:`plan_self` as straight-line C (:data:`_SELF_LINES`); ``mask``: four
    lanes only, a mask of the lanes to test (``outside & ``)."""
    form = _SELF_LINES[lanes]
    code = []

    def add(kind: str, **values: Any) -> None:
        code.extend(form[kind].format(**values).split("\n"))

    for g in planned:
        add("link", pa=g.pa, ra=g.ra, pb=g.pb, rb=g.rb, rr=g.rr, mask=mask)
        for xo, xb, rr_o, inner in g.firsts:
            add("first", a=f"X[{xo}]", b=f"X[{xb}]", rr=rr_o)
            for x, rr in inner:
                add("inner", a=f"X[{xo}]", b=f"X[{x}]", rr=rr)
            code.append("    }")
        for cap, i, j, rr in g.rest:
            if cap:  # scalar code only (the lanes take spheres only)
                code.append(f"    if (overlaps(X, {i}, {j}, 0, NULL)) return 1;")
            else:
                add("pair", a=f"X[{i}]", b=f"X[{j}]", rr=rr)
        add("end")
    return code


def self_tables(planned: list[LinkPair]) -> dict[str, list[str]]:
    """The self checks of :func:`plan_self` as rows of the C tables the loops of ``self_hit`` and
    ``self_hit4`` walk (the same tests with the same numbers, in the same order): ``groups``
    ``{pa, pb, f0, f1, r0, r1, ra, rb, rr}``, ``firsts`` ``{xo, xb, i0, i1, rr}``, ``inner``
    ``{x, rr}``, ``pairs`` ``{a, b, capsule, rr}``."""
    rows: dict[str, list[str]] = {"groups": [], "firsts": [], "inner": [], "pairs": []}
    for g in planned:
        f0, r0 = len(rows["firsts"]), len(rows["pairs"])
        for xo, xb, rr_o, inner in g.firsts:
            i0 = len(rows["inner"])
            rows["inner"] += [f"{{{x}, {rr}}}" for x, rr in inner]
            rows["firsts"].append(f"{{{xo}, {xb}, {i0}, {len(rows['inner'])}, {rr_o}}}")
        rows["pairs"] += [f"{{{i}, {j}, {int(cap)}, {rr}}}" for cap, i, j, rr in g.rest]
        rows["groups"].append(
            f"{{{g.pa}, {g.pb}, {f0}, {len(rows['firsts'])}, {r0}, {len(rows['pairs'])}, "
            f"{g.ra}, {g.rb}, {g.rr}}}"
        )
    return rows
