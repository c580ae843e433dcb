"""Self pairs that no configuration within the joint limits brings into contact, proved by
branch and bound over the joints between the two links.

Many self pairs of a sphere model can never meet: a Panda's link 1 and link 3 are held apart by
the elbow whatever q2 and q3 are. MoveIt finds such pairs by sampling ("Never" in an SRDF);
sampling can miss the rare configuration that does touch. Here a pair is kept out of the fast
check only with a proof. The distance ``d(q)`` of two spheres depends on the joints on the path
between their links alone (the rest move both rigidly), and it is Lipschitz: turning revolute
joint j by dtheta moves a point x by at most ``|x - o_j| dtheta``, and ``|x - o_j|`` is at most the
lengths of the constant translations between joint j and x (rotations keep lengths), plus the
strokes of any prismatic joints in between. So on a box of joint values with centre c and
half-widths h, ``d >= d(c) - sum_j L_j h_j``. Boxes whose bound is not above ``margin`` are halved
along the joint that contributes most; a pair is proved when every box of the limits is, and
refused as soon as a box centre comes within ``margin`` (a configuration in the limits where the
pair nearly or really touches) or the work exceeds a budget. Only the (box, pair) entries still
open are evaluated: a small box holds few of a link pair's pairs.

The proof holds for q within ``tree.qlim``; the C kernel and the generated NumPy module check
the proved pairs too whenever a configuration is outside those limits (or NaN), so their verdicts
are exact for every q. :func:`reach_sphere` bounds where a shape can be at all, for the C batch's
per-link obstacle lists.
"""

from __future__ import annotations

import hashlib
from typing import Any

import numpy as np

from symkin.core.cache import load_verified, store_verified
from symkin.core.progress import bar
from symkin.core.version import __version__
from symkin.geometry.pairs import Layout
from symkin.model.geometry import Capsule

__all__ = ["proved_apart", "reach_sphere", "reach_everywhere"]

MARGIN = 1e-6  # m: proved pairs stay at least this far apart (far above rounding in the kernel)
BUDGET = 40_000  # box evaluations per pair of links before giving up on its unproved pairs
ENTRIES = 2_000_000  # (box, open pair) evaluations per pair of links, likewise (links with many
# spheres: a 300-sphere Panda needed 97 million without it, 13 s; with it 24 million, 4.5 s, and
# 15 242 of the 16 364 pairs the unbounded search proves)
_SAMPLES = 2048  # random configurations tried first (fixed seed: the same pairs every time)
_CROWD = 2048  # open boxes of one pair beyond which it is given up
_MAX_RANGE = 1e3  # a joint range wider than this (rad or m) is not boxed


def _path(layout: Layout, seg: int, stop: set[int]) -> list[int]:
    """Segments from ``seg`` up to (not including) the first one in ``stop``, deepest first."""
    return [k for k in layout.ancestors(seg) if k not in stop]


def _reach(tree: Any, path: list[int], lo: np.ndarray, hi: np.ndarray) -> list[float]:
    """Per segment of ``path`` (deepest first), a bound on the distance from its joint origin to
    the end of the path's last link frame: the translations after it and their strokes."""
    num, out, acc = tree._num, [], 0.0
    for k in path:
        acc += float(np.linalg.norm(num.B[k][:3, 3]))
        seg = tree.segments[k]
        slot = None if seg.slot is None else tree.slots[seg.slot]
        out.append(acc)
        if slot is not None and not slot.revolute:  # the stroke of this prismatic joint
            m, o = float(slot.multiplier), float(slot.offset)
            acc += max(abs(m * lo[slot.joint] + o), abs(m * hi[slot.joint] + o))
        acc += float(np.linalg.norm(num.A[k][:3, 3]))
    return out


def _lipschitz(tree: Any, path: list[int], reach: list[float], extra: float, n: int) -> np.ndarray:
    """(n,) bound of |d x / d q_k| for a point ``extra`` away from the path's last link frame."""
    L = np.zeros(n)
    for k, r in zip(path, reach):
        seg = tree.segments[k]
        if seg.slot is None:
            continue
        slot = tree.slots[seg.slot]
        L[slot.joint] += abs(float(slot.multiplier)) * ((r + extra) if slot.revolute else 1.0)
    return L


def _relative_walk(tree: Any, path: list[int], Q: np.ndarray) -> np.ndarray:
    """(N, 4, 4) pose of the last link of ``path`` (deepest first) in the frame of the link the
    path hangs from, at joint values Q (N, n)."""
    T = np.broadcast_to(np.eye(4), (Q.shape[0], 4, 4))
    for k in reversed(path):
        T = T @ tree._num.transform(Q, k)
    return T


def _prove(
    layout: Layout, pairs: list[tuple[int, int]], lo: np.ndarray, hi: np.ndarray
) -> set[tuple[int, int]]:
    """The pairs of one pair of links (spheres) proved apart over the box [lo, hi]."""
    tree = layout.tree
    a, b = layout.segment[pairs[0][0]], layout.segment[pairs[0][1]]
    common = set(layout.ancestors(a)) & set(layout.ancestors(b))
    pa, pb = _path(layout, a, common), _path(layout, b, common)
    ra, rb = _reach(tree, pa, lo, hi), _reach(tree, pb, lo, hi)
    xa = np.array([layout.shapes[i].points[0] for i, _ in pairs])
    xb = np.array([layout.shapes[j].points[0] for _, j in pairs])
    L = np.array(
        [
            _lipschitz(tree, pa, ra, float(np.linalg.norm(x)), tree.n)
            + _lipschitz(tree, pb, rb, float(np.linalg.norm(y)), tree.n)
            for x, y in zip(xa, xb)
        ]
    )  # (pairs, n)
    dims = np.flatnonzero(L.any(axis=0))
    width = hi[dims] - lo[dims]
    if len(dims) and (~np.isfinite(width) | (width > _MAX_RANGE)).any():
        return set()
    ua, ia = np.unique(xa, axis=0, return_inverse=True)
    ub, ib = np.unique(xb, axis=0, return_inverse=True)
    ua, ub, ia, ib = ua.T, ub.T, ia.ravel(), ib.ravel()
    R = np.array([layout.shapes[i].radius + layout.shapes[j].radius for i, j in pairs])

    def points(Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:  # (N, 3, points) of both links at Q
        Ta, Tb = _relative_walk(tree, pa, Q), _relative_walk(tree, pb, Q)
        return Ta[:, :3, :3] @ ua + Ta[:, :3, 3:], Tb[:, :3, :3] @ ub + Tb[:, :3, 3:]

    # configurations where a pair (nearly) touches refute it at once: a fixed set of random ones
    Q = np.zeros((_SAMPLES, tree.n))
    Q[:, dims] = lo[dims] + width * np.random.default_rng(0).random((_SAMPLES, len(dims)))
    ca, cb = points(Q)
    e = ca[:, :, ia] - cb[:, :, ib]
    alive = (np.sqrt(np.einsum("Nrk,Nrk->Nk", e, e)) - R >= MARGIN).all(axis=0)
    centre = np.zeros((1, tree.n))
    centre[0, dims] = 0.5 * (lo[dims] + hi[dims])
    half = np.zeros((1, len(dims)))  # along the joints that move the pairs (dims)
    half[0] = 0.5 * width
    Ld = np.ascontiguousarray(L[:, dims])
    # the open entries: (box eb[e], live pair ep[e]) not yet proved on that box; only they are
    # evaluated (a box holds few open pairs once it is small)
    ep = np.flatnonzero(alive)
    eb = np.zeros(len(ep), dtype=np.intp)
    spent = entries = 0
    while len(centre) and alive.any():
        spent += len(centre)
        entries += len(ep)
        if spent > BUDGET or entries > ENTRIES:
            alive[ep] = False
            break
        ca, cb = points(centre)
        ca, cb = ca.transpose(0, 2, 1).copy(), cb.transpose(0, 2, 1).copy()  # (N, points, 3)
        e = ca[eb, ia[ep]] - cb[eb, ib[ep]]  # (entries, 3)
        d = np.sqrt(np.einsum("kr,kr->k", e, e)) - R[ep]
        alive[ep[d < MARGIN]] = False
        keep = alive[ep] & (d - np.einsum("kj,kj->k", half[eb], Ld[ep]) < MARGIN)
        eb, ep = eb[keep], ep[keep]
        crowded = np.bincount(ep, minlength=len(pairs)) > _CROWD  # near contacts need ever more boxes
        alive &= ~crowded
        keep = ~crowded[ep]
        eb, ep = eb[keep], ep[keep]
        used = np.bincount(eb, minlength=len(centre)) > 0  # the boxes with open entries, renumbered
        eb = (np.cumsum(used) - 1)[eb]
        centre, half = centre[used], half[used]
        if not len(ep):
            break
        # halve each box along the joint contributing most to its open pairs' bound
        weight = np.stack([np.bincount(eb, Ld[ep, j], len(centre)) for j in range(len(dims))], axis=1)
        k = np.argmax(half * weight, axis=1)
        rows = np.arange(len(centre))
        half[rows, k] *= 0.5
        lower, upper = centre.copy(), centre.copy()
        lower[rows, dims[k]] -= half[rows, k]
        upper[rows, dims[k]] += half[rows, k]
        centre = np.concatenate([lower, upper])
        half = np.concatenate([half, half])
        eb, ep = np.concatenate([eb, eb + len(rows)]), np.concatenate([ep, ep])
    return {p for p, ok in zip(pairs, alive) if ok}


def proved_apart(layout: Layout) -> frozenset[tuple[int, int]]:
    """The self pairs of ``layout`` (two spheres) that no q within ``layout.tree.qlim`` brings
    closer than :data:`MARGIN`, proved by the branch and bound of this module. Pairs with a
    capsule are not tried. Memoised on the layout and kept in the compile cache
    (``clearance/<key>.json``, verified by the sha256 of its key and content: a file that does not
    verify or names other pairs is recomputed, never trusted)."""
    cached = layout.__dict__.get("_proved_apart")
    if cached is not None:
        return cached
    key = _key(layout)
    result = _pairs(load_verified("clearance", key), layout)
    if result is None:
        result = _compute(layout)
        store_verified("clearance", key, sorted(result))
    object.__setattr__(layout, "_proved_apart", result)
    return result


def _key(layout: Layout) -> str:
    """sha256 of what the proof depends on: the tree, its limits, the geometry, this module's
    constants and symkin's version."""
    tree = layout.tree
    h = hashlib.sha256()
    h.update(
        f"{tree.key}|{tree.geometry.fingerprint()}|{MARGIN}|{BUDGET}|{ENTRIES}|{_SAMPLES}|{_CROWD}|{__version__}".encode()
    )
    h.update(np.ascontiguousarray(tree.qlim, dtype="<f8").tobytes())
    return h.hexdigest()


def _pairs(stored: Any, layout: Layout) -> frozenset[tuple[int, int]] | None:
    """The verified cache entry ``stored`` as pairs, or None when it is not pairs of ``layout``."""
    try:
        pairs = frozenset((int(i), int(j)) for i, j in stored)
    except (TypeError, ValueError):
        return None
    return pairs if pairs <= set(layout.self_pairs) else None


def _compute(layout: Layout) -> frozenset[tuple[int, int]]:
    lo, hi = (np.asarray(x, dtype=float) for x in layout.tree.qlim)
    groups: dict[tuple[str, str], list[tuple[int, int]]] = {}
    for i, j in layout.self_pairs:
        if isinstance(layout.shapes[i], Capsule) or isinstance(layout.shapes[j], Capsule):
            continue
        groups.setdefault((layout.shapes[i].link, layout.shapes[j].link), []).append((i, j))
    out: set[tuple[int, int]] = set()
    # seconds on trees with many links (a quadruped's 11 000 pairs: about 10 s), once per model
    shown = len(groups) > 100
    for pairs in bar(groups.values(), progress=shown, desc="self pairs apart", unit="link pair"):
        out |= _prove(layout, pairs, lo, hi)
    return frozenset(out)


def reach_sphere(layout: Layout, segment: int, point: Any, radius: float) -> tuple[np.ndarray, float] | None:
    """A sphere (centre in the base frame, radius) holding the sphere (``point`` on ``segment``'s
    link, ``radius``) in every configuration within ``layout.tree.qlim``: centred on the origin of
    the first joint on the link's path (which no joint moves), as large as the translations and
    strokes from there to the point allow (rounded up). None when a stroke is unbounded."""
    tree = layout.tree
    lo, hi = (np.asarray(x, dtype=float) for x in tree.qlim)
    path = layout.ancestors(segment)
    moving = [k for k in path if tree.segments[k].slot is not None]
    if not moving:  # nothing moves the point: its own place
        L, _ = tree._walk(np.zeros((1, tree.n)))
        T = np.eye(4) if segment < 0 else L[0, segment]
        return T[:3, :3] @ np.asarray(point, dtype=float) + T[:3, 3], _up(float(radius))
    top = moving[-1]
    path = path[: path.index(top) + 1]
    reach = _reach(tree, path, lo, hi)[-1]
    slot = tree.slots[tree.segments[top].slot]
    if not slot.revolute:
        m, o = float(slot.multiplier), float(slot.offset)
        reach += max(abs(m * lo[slot.joint] + o), abs(m * hi[slot.joint] + o))
    R = reach + float(np.linalg.norm(point)) + float(radius)
    if not np.isfinite(R):
        return None
    _, P = tree._walk(np.zeros((1, tree.n)))
    return P[0, top, :3, 3].copy(), _up(R)


def _up(r: float) -> float:
    """``r`` with room for the rounding of the points it must hold (a relative 1e-12)."""
    return r * (1.0 + 1e-12) + 1e-15


def reach_everywhere(layout: Layout, segment: int) -> bool:
    """Whether :func:`reach_sphere` of a shape on ``segment``'s link holds for every q, not only
    within the joint limits: no prismatic joint moves the link (rotations keep the lengths the
    sphere is made of; only a prismatic stroke comes from the limits)."""
    tree = layout.tree
    return all(
        tree.slots[tree.segments[k].slot].revolute
        for k in layout.ancestors(segment)
        if tree.segments[k].slot is not None
    )
