"""cover_spheres and the triangle arithmetic under it, on shapes with known answers: every surface
point (dense samples drawn apart from the fit, corners, a swept part at any place of its stroke)
inside a sphere, no sphere reaching farther out than the excess asked for (checked by sampling the
spheres' outer boundary against the exact solid), and distances / winding numbers against
independent computations."""

from __future__ import annotations

import numpy as np
import pytest

from symkin.errors import GeometryError
from symkin.geometry.cover import Surface, cover_spheres, outer_excess
from symkin.geometry.meshes import box_triangles
from symkin.geometry.triangles import closest_distance, pieces, sample_surface, subdivide, winding_number


def box_distance(P, h):
    """Exact distance from points to the surface of the box |x_i| <= h_i."""
    q = np.abs(P) - h
    outside = np.linalg.norm(np.maximum(q, 0), axis=1)
    inside = np.minimum(q.max(1), 0)
    return np.where(q.max(1) > 0, outside, -inside)


def covered(P, cover):
    D = np.linalg.norm(P[:, None] - cover.centres[None], axis=2) - cover.radii[None]
    return D.min(1)


def test_closest_distance_and_winding_on_a_box():
    h = np.array([0.1, 0.2, 0.05])
    T = box_triangles(h)
    rng = np.random.default_rng(0)
    P = rng.uniform(-0.4, 0.4, size=(3000, 3))
    np.testing.assert_allclose(closest_distance(P, T), box_distance(P, h), atol=1e-12)
    w = winding_number(P, T)
    inside = (np.abs(P) < h).all(1)
    np.testing.assert_allclose(w[inside], 1.0, atol=1e-9)
    np.testing.assert_allclose(w[~inside], 0.0, atol=1e-9)


def test_subdivide_keeps_the_surface_and_bounds_edges():
    T = box_triangles([0.3, 0.02, 0.1])
    S = subdivide(T, 0.01)
    E = np.linalg.norm(S - np.roll(S, 1, axis=1), axis=-1)
    assert E.max() <= 0.01
    area = lambda X: 0.5 * np.linalg.norm(np.cross(X[:, 1] - X[:, 0], X[:, 2] - X[:, 0]), axis=1).sum()  # noqa: E731
    assert area(S) == pytest.approx(area(T), rel=1e-12)
    P = pieces(T, 0.02, stroke=np.array([0.0, 0.05, 0.0]))
    assert P.shape[1:] == (6, 3) and np.allclose(P[:, 3:] - P[:, :3], P[0, 3] - P[0, 0])


SHAPES = {
    "box": lambda: box_triangles([0.04, 0.06, 0.12]),
    "plate": lambda: box_triangles([0.1, 0.08, 0.004]),
    "long bar": lambda: box_triangles([0.2, 0.02, 0.02]),
}


@pytest.mark.parametrize("shape", sorted(SHAPES))
@pytest.mark.parametrize("excess", [0.02, 0.04])
def test_cover_holds_every_surface_point_within_the_excess(shape, excess):
    T = SHAPES[shape]()
    cover = cover_spheres([Surface(T)], excess)
    P = np.concatenate([sample_surface(T, 30_000, seed=11), T.reshape(-1, 3)])
    assert covered(P, cover).max() <= 0  # every point, not 99 %
    assert cover.excess.max() <= excess * (1 + 1e-6) + 1e-9
    # the bound r - d holds against the exact solid: sample the union's outer boundary
    h = np.abs(T.reshape(-1, 3)).max(0)
    k = np.arange(300) + 0.5
    phi, theta = np.arccos(1 - 2 * k / 300), np.pi * (1 + 5**0.5) * k
    U = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], -1)
    X = (cover.centres[:, None] + cover.radii[:, None, None] * U[None]).reshape(-1, 3)
    out = np.linalg.norm(np.maximum(np.abs(X) - h, 0), axis=1)
    assert out.max() <= cover.excess.max() + 1e-9
    sampled = outer_excess(cover.centres, cover.radii, [Surface(T)])
    assert sampled.max() <= cover.excess.max() + 1e-9


def test_tighter_excess_takes_more_spheres():
    T = box_triangles([0.04, 0.04, 0.15])
    loose, tight = cover_spheres([Surface(T)], 0.04), cover_spheres([Surface(T)], 0.015)
    assert len(loose) < len(tight)


def test_a_swept_part_is_covered_along_its_whole_stroke():
    finger = box_triangles([0.01, 0.005, 0.02])
    stroke = np.array([0.0, 0.04, 0.0])
    cover = cover_spheres([Surface(finger, stroke)], 0.015)
    rng = np.random.default_rng(3)
    P = sample_surface(finger, 20_000, seed=4) + rng.random((20_000, 1)) * stroke
    P = np.concatenate([P, finger.reshape(-1, 3), finger.reshape(-1, 3) + stroke])
    assert covered(P, cover).max() <= 0


def test_a_flat_part_without_inside_is_covered():
    flat = box_triangles([0.06, 0.06, 0.0])  # zero thickness: no grid point inside, centroid spheres
    cover = cover_spheres([Surface(flat)], 0.02)
    assert covered(sample_surface(flat, 10_000, seed=2), cover).max() <= 0
    assert cover.excess.max() <= 0.02 + 1e-9


@pytest.mark.parametrize("excess", [0, -0.01, float("nan"), float("inf")])
def test_bad_excess_is_refused(excess):
    with pytest.raises(GeometryError, match="max_excess"):
        cover_spheres([Surface(box_triangles([0.1, 0.1, 0.1]))], excess)


def test_bad_surfaces_are_refused():
    with pytest.raises(GeometryError, match="no surface"):
        cover_spheres([], 0.01)
    with pytest.raises(GeometryError, match="shape"):
        cover_spheres([Surface(np.zeros((0, 3, 3)), name="empty")], 0.01)
    bad = box_triangles([0.1, 0.1, 0.1])
    bad[0, 0, 0] = np.nan
    with pytest.raises(GeometryError, match="NaN"):
        cover_spheres([Surface(bad)], 0.01)
