"""Collision geometry: shapes on a robot's links, obstacles, which pairs are checked, where they come
from, and the NumPy reference of the queries the compiled kernel answers (:mod:`symkin.runtime.collision`).

- :class:`Sphere`, :class:`Capsule` (robot and obstacles), :class:`Box` (obstacles),
  :class:`Geometry` (a robot's shapes and disabled link pairs), :class:`Environment`.
- Sources: :func:`geometry_from_urdf` (``<collision>``), :func:`read_srdf` and
  :func:`srdf_disabled` (disabled pairs; :func:`disabled_pairs` and :func:`write_srdf` write an
  SRDF of the pairs that need no check), :func:`fit_spheres` (n spheres holding a mesh or points),
  :func:`cover_spheres` (the fewest spheres covering a body's surface exactly within an outward
  excess), :func:`fit_urdf` and :func:`fit_builtin` (covering models of a URDF's meshes, of a
  built-in arm's real meshes), :func:`builtin_geometry` (the built-in arms' sphere models,
  attached by :func:`symkin.load`).
- :func:`layout_of`: the model's bodies and active pairs; :func:`proved_apart`: the self pairs no
  configuration within the joint limits brings into contact (a proof, not a sample), and
  :func:`reach_sphere`: where a shape can be at all; the compiled batch check skips both.
- :func:`points`, :func:`distances`, :func:`distance_jacobians`, :func:`in_collision`: the reference.
- :mod:`symkin.geometry.distance`: signed distances of sphere, capsule and box pairs.
"""

from symkin.geometry.clearance import proved_apart, reach_sphere
from symkin.geometry.cover import Surface, cover_spheres
from symkin.geometry.fit import fit_spheres
from symkin.geometry.mesh_fit import MeshFit, coverage, fit_builtin, fit_urdf
from symkin.geometry.pairs import Layout, as_environment, layout_of
from symkin.geometry.reference import distance_jacobians, distances, in_collision, points
from symkin.geometry.srdf import disabled_pairs, read_srdf, srdf_disabled, write_srdf
from symkin.geometry.urdf import geometry_from_urdf
from symkin.model.builtin_geometry import builtin_geometry
from symkin.model.geometry import Box, Capsule, Environment, Geometry, Sphere

__all__ = [
    "Box",
    "Capsule",
    "Environment",
    "Geometry",
    "Layout",
    "MeshFit",
    "Sphere",
    "Surface",
    "as_environment",
    "builtin_geometry",
    "cover_spheres",
    "coverage",
    "distance_jacobians",
    "distances",
    "fit_builtin",
    "fit_spheres",
    "fit_urdf",
    "geometry_from_urdf",
    "in_collision",
    "layout_of",
    "points",
    "proved_apart",
    "reach_sphere",
    "read_srdf",
    "srdf_disabled",
    "disabled_pairs",
    "write_srdf",
]
