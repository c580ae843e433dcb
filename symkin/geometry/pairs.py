"""Which shapes are checked against which: the model's bodies and the active pairs.

Every model is read as a tree (a :class:`symkin.Robot` through :meth:`symkin.Tree.from_robot`,
links ``base``, ``link1``.., ``ee``): one pipeline for chains and trees. A *body* is a set of links
joined by fixed joints; its id is the segment of the joint that moves it (-1 for the base body).
Self pairs skip shapes on one body, on adjacent bodies (one joint between them) and on links the
geometry lists as ``disabled``. Environment pairs are every shape against every obstacle.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.errors import GeometryError
from symkin.model.geometry import Capsule, Environment, Geometry, Sphere
from symkin.model.tree import Tree, as_tree

__all__ = ["Layout", "layout_of", "as_tree", "as_environment", "PAIR_KINDS"]

PAIR_KINDS = ("self", "sphere", "capsule", "box")


def as_environment(env: Any) -> Environment:
    """``env`` as an Environment: None (no obstacles), an Environment, or shapes (Sphere, Capsule, Box)."""
    if env is None:
        return Environment()
    if isinstance(env, Environment):
        return env
    from symkin.model.geometry import Box

    items = list(env) if isinstance(env, (list, tuple)) else [env]
    kinds: dict[type, list] = {Sphere: [], Capsule: [], Box: []}
    for x in items:
        if type(x) not in kinds:
            raise GeometryError(
                f"an environment holds Sphere, Capsule and Box obstacles (or is an Environment), "
                f"not {type(x).__name__}"
            )
        kinds[type(x)].append(x)
    return Environment(tuple(kinds[Sphere]), tuple(kinds[Capsule]), tuple(kinds[Box]))


@dataclass(frozen=True, eq=False)
class Layout:
    """A model's geometry laid out for evaluation.

    Attributes:
        tree: the model as a tree.
        shapes: the geometry's shapes, in order.
        segment: per shape, the segment whose link carries it (-1: the base link).
        body: per shape, its body id.
        self_pairs: (i, j) shape indices, i < j, checked against each other.
        point_index: per shape, the index of its first point in the stacked points (spheres have
            one point, capsules two).
    """

    tree: Tree
    shapes: tuple
    segment: tuple[int, ...]
    body: tuple[int, ...]
    self_pairs: tuple[tuple[int, int], ...]
    point_index: tuple[int, ...]

    @property
    def n_points(self) -> int:
        return sum(len(s.points) for s in self.shapes)

    def ancestors(self, segment: int) -> list[int]:
        """Segments from ``segment`` up to the base (itself first); [] for the base link."""
        out = []
        while segment >= 0:
            out.append(segment)
            segment = self.tree.segments[segment].parent
        return out

    def pair_labels(self, env: Environment) -> list[tuple[str, int, int]]:
        """What each distance is: ("self", i, j) for each self pair, then (kind, i, k) for each
        obstacle k of each kind (spheres, capsules, boxes) against every shape i, obstacle by
        obstacle: the order of ``distances``."""
        out = [("self", i, j) for i, j in self.self_pairs]
        for kind, items in (("sphere", env.spheres), ("capsule", env.capsules), ("box", env.boxes)):
            out += [(kind, i, k) for k in range(len(items)) for i in range(len(self.shapes))]
        return out

    def describe(self, label: tuple[str, int, int]) -> str:
        """A pair of :meth:`pair_labels` in words: ``"sphere 3 (link4) - capsule 9 (link6)"`` or
        ``"sphere 3 (link4) - obstacle box 0"``."""
        kind, i, j = label
        a = f"{type(self.shapes[i]).__name__.lower()} {i} ({self.shapes[i].link})"
        if kind == "self":
            return f"{a} - {type(self.shapes[j]).__name__.lower()} {j} ({self.shapes[j].link})"
        return f"{a} - obstacle {kind} {j}"


def _bodies(tree: Tree) -> tuple[dict[str, int], list[int], list[int]]:
    """link -> segment (-1 base); per segment its body; per segment its body's parent body."""
    seg_of = {tree.base_link: -1}
    body = []
    for k, seg in enumerate(tree.segments):
        seg_of[seg.link] = k
        if seg.slot is not None:
            body.append(k)
        else:
            body.append(-1 if seg.parent < 0 else body[seg.parent])
    parent_body = [(-1 if seg.parent < 0 else body[seg.parent]) for seg in tree.segments]
    return seg_of, body, parent_body


def layout_of(model: Any) -> Layout:
    """The :class:`Layout` of ``model``'s geometry (GeometryError when it has none), memoised."""
    tree = as_tree(model)
    cached = tree.__dict__.get("_collision_layout")
    if cached is not None:
        return cached
    geometry: Geometry | None = tree.geometry
    if geometry is None or not geometry.shapes:
        raise GeometryError(
            f"{tree.name} has no collision geometry: attach some with robot.with_geometry("
            "symkin.geometry.Geometry([...])) (built-in sphere models: panda, ur5, lbr_iiwa7, lbr_iiwa14)"
        )
    seg_of, body_of_seg, parent_body = _bodies(tree)
    segment = tuple(seg_of[s.link] for s in geometry.shapes)
    body = tuple(-1 if k < 0 else body_of_seg[k] for k in segment)
    link_of_body = {b: set() for b in set(body)}
    for s, b in zip(geometry.shapes, body):
        link_of_body[b].add(s.link)
    disabled = set(geometry.disabled)

    def adjacent(a: int, b: int) -> bool:
        return (a >= 0 and parent_body[a] == b) or (b >= 0 and parent_body[b] == a)

    pairs = []
    shapes = geometry.shapes
    for i in range(len(shapes)):
        for j in range(i + 1, len(shapes)):
            bi, bj = body[i], body[j]
            if bi == bj or adjacent(bi, bj):
                continue
            a, b = shapes[i].link, shapes[j].link
            if (min(a, b), max(a, b)) in disabled:
                continue
            pairs.append((i, j))
    index = np.cumsum([0] + [len(s.points) for s in shapes])[:-1]
    out = Layout(tree, shapes, segment, body, tuple(pairs), tuple(int(x) for x in index))
    object.__setattr__(tree, "_collision_layout", out)
    return out
