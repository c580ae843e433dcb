"""Collision distances of a model's geometry in JAX or PyTorch: shape points from the generated
collision module (:func:`symkin.emit.collision.render_collision_tensor`), the pair distances of
:mod:`symkin.runtime.diff.distance`, their joint gradients by automatic differentiation, and a
penalty usable in a loss.

Distances come in the order of :meth:`symkin.geometry.pairs.Layout.pair_labels`: the self pairs
(shapes on different bodies, not adjacent, not disabled), then every shape against each obstacle
sphere, capsule and box, as the NumPy reference (:mod:`symkin.geometry.reference`) and the C
kernel give them.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symkin.geometry.pairs import as_environment, layout_of
from symkin.geometry.reference import Tables
from symkin.runtime.diff import distance as dist
from symkin.runtime.diff.ops import ops_of

__all__ = ["DiffCollision"]


class DiffCollision:
    """The collision queries of ``model``'s geometry on ``backend`` ("jax" or "torch")."""

    def __init__(self, model: Any, backend: str) -> None:
        from symkin.runtime.collision import collision_module

        self.layout = layout_of(model)  # GeometryError when the model has none
        self.ops = ops_of(backend)
        self.module = collision_module(self.layout, backend)
        self.n = self.layout.tree.n
        caps, first, radius, _ = Tables.of(self.layout).arrays
        self.caps, self.first, self.radius = caps, first, radius
        pairs = np.array(self.layout.self_pairs, dtype=int).reshape(-1, 2)
        groups, order = [], []
        for ci in (False, True):
            for cj in (False, True):
                m = np.nonzero((caps[pairs[:, 0]] == ci) & (caps[pairs[:, 1]] == cj))[0]
                if m.size:
                    groups.append((ci, cj, pairs[m, 0], pairs[m, 1]))
                    order += m.tolist()
        self.self_groups = groups
        self.self_order = np.argsort(np.array(order, dtype=int)).tolist()  # back to the pairs' order
        self.shape_kinds = [(False, np.nonzero(~caps)[0]), (True, np.nonzero(caps)[0])]
        self.shape_order = np.argsort(np.concatenate([i for _, i in self.shape_kinds])).tolist()

    def points(self, q: Any) -> Any:
        """Base-frame shape points (..., P, 3) of q (..., n)."""
        return self.module.points(q)

    def labels(self, env: Any = None) -> list[tuple[str, int, int]]:
        """What each distance is: ("self", i, j) or (obstacle kind, shape i, obstacle k)."""
        return self.layout.pair_labels(as_environment(env))

    def _ends(self, X: Any, idx: np.ndarray, cap: bool) -> tuple[Any, Any]:
        i = self.first[idx].tolist()
        return X[..., i, :], (X[..., (self.first[idx] + 1).tolist(), :] if cap else None)

    def _self(self, X: Any) -> list[Any]:
        ops = self.ops
        parts = []
        for ci, cj, I, J in self.self_groups:
            (A, A2), (B, B2) = self._ends(X, I, ci), self._ends(X, J, cj)
            ra, rb = ops.const(self.radius[I], X), ops.const(self.radius[J], X)
            if ci and cj:
                parts.append(dist.capsule_capsule(ops, A, A2, ra, B, B2, rb))
            elif ci:
                parts.append(dist.capsule_sphere(ops, A, A2, ra, B, rb))
            elif cj:
                parts.append(dist.capsule_sphere(ops, B, B2, rb, A, ra))
            else:
                parts.append(dist.sphere_sphere(ops, A, ra, B, rb))
        if not parts:
            return []
        return [ops.xp.concatenate(parts, -1)[..., self.self_order]]

    def _obstacles(self, X: Any, env: Any) -> list[Any]:
        ops, xp = self.ops, self.ops.xp
        out = []
        arrays = env.arrays()
        for kind in ("spheres", "capsules", "boxes"):
            O = arrays[kind]
            if not len(O):
                continue
            P = ops.const(O, X)[:, None]  # (O, 1, k): broadcast against the shapes (..., 1, K)
            parts = []
            for cap, idx in self.shape_kinds:
                if not idx.size:
                    continue
                A, B = self._ends(X, idx, cap)
                A, B = A[..., None, :, :], (None if B is None else B[..., None, :, :])
                r = ops.const(self.radius[idx], X)
                if kind == "spheres":
                    c, ro = P[..., :3], P[..., 3]
                    d = (
                        dist.capsule_sphere(ops, A, B, r, c, ro)
                        if cap
                        else dist.sphere_sphere(ops, A, r, c, ro)
                    )
                elif kind == "capsules":
                    a, b, ro = P[..., :3], P[..., 3:6], P[..., 6]
                    d = (
                        dist.capsule_capsule(ops, A, B, r, a, b, ro)
                        if cap
                        else dist.capsule_sphere(ops, a, b, ro, A, r)
                    )
                else:
                    c, h, R = P[..., :3], P[..., 3:6], P[..., 6:].reshape((len(O), 1, 3, 3))
                    d = (
                        dist.capsule_box(ops, A, B, r, c, h, R)
                        if cap
                        else dist.sphere_box(ops, A, r, c, h, R)
                    )
                parts.append(d)
            d = xp.concatenate(parts, -1)[..., self.shape_order]  # (..., O, S)
            out.append(d.reshape(tuple(d.shape[:-2]) + (-1,)))
        return out

    def distances(self, q: Any, env: Any = None) -> Any:
        """Signed distances (..., M) of every active pair of q (..., n), negative where shapes overlap."""
        X = self.points(q)
        parts = self._self(X) + self._obstacles(X, as_environment(env))
        if not parts:
            return self.ops.xp.zeros_like(q[..., :0])
        return self.ops.xp.concatenate(parts, -1)

    def distance_jacobians(self, q: Any, env: Any = None) -> tuple[Any, Any]:
        """Signed distances (..., M) and their gradients (..., M, n) (forward-mode autodiff of
        :meth:`distances`, one configuration at a time by ``vmap``)."""
        env = as_environment(env)
        ops = self.ops
        D = self.distances(q, env)
        Qf = q.reshape((-1, self.n))

        def one(x: Any) -> Any:
            return self.distances(x, env)

        if ops.name == "jax":
            J = ops.jax.vmap(ops.jax.jacfwd(one))(Qf)  # type: ignore[attr-defined]
        else:
            import torch.func

            J = torch.func.vmap(torch.func.jacfwd(one))(Qf)
        return D, J.reshape(tuple(D.shape) + (self.n,))

    def in_collision(self, q: Any, env: Any = None) -> Any:
        """Whether any active pair overlaps, (...) booleans."""
        return (self.distances(q, env) < 0.0).any(-1)

    def cost(self, q: Any, env: Any = None, margin: float = 0.0) -> Any:
        """The penalty sum over pairs of max(margin - d, 0)^2, (...): zero when every pair is at
        least ``margin`` apart, smooth (its gradient continuous) in q elsewhere; for a loss."""
        d = self.distances(q, env)
        gap = self.ops.xp.where(d < margin, margin - d, 0.0)
        return (gap * gap).sum(-1)
