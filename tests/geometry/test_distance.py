"""Signed-distance primitives: symkin.geometry.distance (NumPy) against independent brute-force
references, the first-order property of the normals, degenerate and penetrating cases, and the C
header runtime/csrc/symkin_collide.h against the NumPy module.

The references do not use Ericson's formula nor the box SDF formula: a distance between a point,
a segment or a box face is the minimum of |w + u E1 + v E2| over (u, v) in [0, 1]^2 (a convex
function), found by dense sampling of each parameter and golden-section refinement inside the
bracket around the best sample (nested: the outer parameter minimises the inner minimum). Inside
a box the reference is the largest signed distance to its 6 face planes (world coordinates).
"""

from __future__ import annotations

import ctypes
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import symkin
from symkin.emit.c.build import compile_library, find_compiler, load_library
from symkin.errors import CompileError
from symkin.geometry import distance as gd

HEADER = Path(symkin.__file__).resolve().parent / "runtime" / "csrc" / "symkin_collide.h"
_G = (np.sqrt(5.0) - 1.0) / 2.0
TOL = 1e-9  # reference tolerance (absolute, the scenes are of size ~1)


# --- random scenes ------------------------------------------------------------------------------


def _rotations(rng: np.random.Generator, n: int) -> np.ndarray:
    q = rng.normal(size=(n, 4))
    w, x, y, z = (q / np.linalg.norm(q, axis=1, keepdims=True)).T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )


def _boxes(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return rng.uniform(-0.5, 0.5, (n, 3)), rng.uniform(0.2, 1.2, (n, 3)), _rotations(rng, n)


def _unit(rng: np.random.Generator, n: int) -> np.ndarray:
    u = rng.normal(size=(n, 3))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def _rodrigues(w: np.ndarray, angle: float) -> np.ndarray:
    K = np.zeros(w.shape[:-1] + (3, 3))
    K[..., 0, 1], K[..., 0, 2], K[..., 1, 2] = -w[..., 2], w[..., 1], -w[..., 0]
    K = K - np.swapaxes(K, -1, -2)
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * (K @ K)


def _rot(x: np.ndarray, Q: np.ndarray, o: np.ndarray) -> np.ndarray:
    return o + np.einsum("nij,nj->ni", Q, x - o)


# --- brute-force references ---------------------------------------------------------------------


def _min1(f, B: int, grid: int = 33, iters: int = 66) -> tuple[np.ndarray, np.ndarray]:
    """min over t in [0, 1] of a convex f, for B problems: f maps t (B, K) -> (B, K). Dense
    sampling, then golden-section search in the bracket of the best sample's neighbours."""
    tg = np.linspace(0.0, 1.0, grid)
    vals = f(np.broadcast_to(tg, (B, grid)))
    k = np.argmin(vals, axis=1)
    best_v, best_t = vals[np.arange(B), k], tg[k]
    lo, hi = tg[np.maximum(k - 1, 0)], tg[np.minimum(k + 1, grid - 1)]
    x1, x2 = hi - _G * (hi - lo), lo + _G * (hi - lo)
    f1, f2 = f(x1[:, None])[:, 0], f(x2[:, None])[:, 0]
    for _ in range(iters):
        left = f1 < f2
        hi, lo = np.where(left, x2, hi), np.where(left, lo, x1)
        xn = np.where(left, hi - _G * (hi - lo), lo + _G * (hi - lo))
        fn = f(xn[:, None])[:, 0]
        x1, x2 = np.where(left, xn, x2), np.where(left, x1, xn)
        f1, f2 = np.where(left, fn, f2), np.where(left, f1, fn)
    v, t = np.where(f1 < f2, f1, f2), np.where(f1 < f2, x1, x2)
    better = v < best_v
    return np.where(better, v, best_v), np.where(better, t, best_t)


def ref_min_norm1(w: np.ndarray, E: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """min over t in [0, 1] of |w + t E| (B problems): (value, t)."""
    return _min1(lambda t: np.linalg.norm(w[:, None] + t[..., None] * E[:, None], axis=-1), len(w))


def ref_min_norm2(w: np.ndarray, E1: np.ndarray, E2: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """min over (u, v) in [0, 1]^2 of |w + u E1 + v E2| (B problems, nested 1-D searches)."""
    B = len(w)

    def outer(u: np.ndarray) -> np.ndarray:
        K = u.shape[1]
        ww = (w[:, None] + u[..., None] * E1[:, None]).reshape(-1, 3)
        value, _ = ref_min_norm1(ww, np.repeat(E2, K, axis=0))
        return value.reshape(B, K)

    value, u = _min1(outer, B)
    _, v = ref_min_norm1(w + u[:, None] * E1, E2)
    return value, u, v


def ref_point_segment(p, a, b) -> np.ndarray:
    return ref_min_norm1(a - p, b - a)[0]


def ref_segment_segment(a1, b1, a2, b2) -> np.ndarray:
    return ref_min_norm2(a1 - a2, b1 - a1, -(b2 - a2))[0]


def _faces(center, h, R):
    """The 6 faces of each box as (origin, edge1, edge2) in world coordinates, (6, B, 3) each."""
    O, E1, E2 = [], [], []
    for k in range(3):
        i, j = (k + 1) % 3, (k + 2) % 3
        for sign in (1.0, -1.0):
            O.append(
                center
                + (sign * h[:, k, None]) * R[:, :, k]
                - h[:, i, None] * R[:, :, i]
                - h[:, j, None] * R[:, :, j]
            )
            E1.append(2 * h[:, i, None] * R[:, :, i])
            E2.append(2 * h[:, j, None] * R[:, :, j])
    return np.array(O), np.array(E1), np.array(E2)


def ref_box_outside(p, center, h, R) -> tuple[np.ndarray, np.ndarray]:
    """Distance from p to the box surface by search over the 6 face rectangles, and the closest point."""
    O, E1, E2 = _faces(center, h, R)
    B = len(p)
    value, u, v = ref_min_norm2((O - p).reshape(-1, 3), E1.reshape(-1, 3), E2.reshape(-1, 3))
    value = value.reshape(6, B)
    best = np.argmin(value, axis=0)
    pick = best * B + np.arange(B)
    closest = (
        O.reshape(-1, 3)[pick]
        + u[pick, None] * E1.reshape(-1, 3)[pick]
        + v[pick, None] * E2.reshape(-1, 3)[pick]
    )
    return value[best, np.arange(B)], closest


def ref_box_planes(p, center, h, R) -> tuple[np.ndarray, np.ndarray]:
    """Largest signed distance of p to the 6 face planes (= the SDF inside), and that face's normal."""
    normals, dists = [], []
    for k in range(3):
        for sign in (1.0, -1.0):
            nrm = sign * R[:, :, k]
            normals.append(nrm)
            dists.append(np.einsum("bi,bi->b", nrm, p - (center + h[:, k, None] * nrm)))
    dists, normals = np.array(dists), np.array(normals)
    best = np.argmax(dists, axis=0)
    return dists[best, np.arange(len(p))], normals[best, np.arange(len(p))]


def _box_edges(center, h, R):
    """The 12 edges of each box as (start, end), (12, B, 3) each."""
    A, Bs = [], []
    for k in range(3):
        i, j = (k + 1) % 3, (k + 2) % 3
        for si in (1.0, -1.0):
            for sj in (1.0, -1.0):
                mid = center + si * h[:, i, None] * R[:, :, i] + sj * h[:, j, None] * R[:, :, j]
                A.append(mid - h[:, k, None] * R[:, :, k])
                Bs.append(mid + h[:, k, None] * R[:, :, k])
    return np.array(A), np.array(Bs)


def ref_capsule_box_core(a, b, center, h, R) -> np.ndarray:
    """min over the segment of the box SDF, without the SDF formula: when the segment enters the
    box, the min of the largest signed face-plane distance along it (convex, piecewise linear);
    otherwise the min of the endpoints' distances and the distances to the 12 box edges (the
    closest pair of a segment and a box apart has an endpoint of the segment or a box edge)."""
    B = len(a)

    def planes(t: np.ndarray) -> np.ndarray:
        K = t.shape[1]
        p = (a[:, None] + t[..., None] * (b - a)[:, None]).reshape(-1, 3)
        rep = lambda x: np.repeat(x, K, axis=0)  # noqa: E731
        return ref_box_planes(p, rep(center), rep(h), rep(R))[0].reshape(B, K)

    inside, _ = _min1(planes, B)
    ea, eb = _box_edges(center, h, R)
    edges = ref_segment_segment(
        np.tile(a, (12, 1)), np.tile(b, (12, 1)), ea.reshape(-1, 3), eb.reshape(-1, 3)
    )
    ends = np.minimum(ref_box_outside(a, center, h, R)[0], ref_box_outside(b, center, h, R)[0])
    outside = np.minimum(ends, edges.reshape(12, B).min(axis=0))
    return np.where(inside < 0.0, inside, outside)


# --- checks -------------------------------------------------------------------------------------


def _check_witness(d, n, pa, pb, rA, rB, box: bool = False) -> None:
    """n unit; |pa - pb| = |d + rA + rB| (= d + rA + rB unless pa is inside a box);
    d = n.(pa - pb) - rA - rB."""
    core = d + rA + rB
    gap = np.linalg.norm(pa - pb, axis=-1)
    np.testing.assert_allclose(np.linalg.norm(n, axis=-1), 1.0, rtol=0, atol=1e-12)
    if box:
        np.testing.assert_allclose(gap, np.abs(core), rtol=0, atol=1e-12)
    else:
        assert (core >= -1e-15).all()
        np.testing.assert_allclose(gap, core, rtol=0, atol=1e-12)
    apart = gap > 1e-9
    np.testing.assert_allclose(np.einsum("...i,...i", n, pa - pb)[apart], core[apart], rtol=0, atol=1e-12)


def _on_box_surface(p, center, h, R) -> np.ndarray:
    return np.abs(gd.box_sdf(p, center, h, R)[0])


# --- segment and point queries against the references ---------------------------------------------


def _segment_scenes(rng: np.random.Generator, n: int):
    a1, b1, a2, b2 = (rng.uniform(-1.5, 1.5, (n, 3)) for _ in range(4))
    m = n // 10
    b2[:m] = a2[:m] + rng.uniform(-1.5, 1.5, (m, 1)) * (b1[:m] - a1[:m])  # parallel
    b1[m : 2 * m] = a1[m : 2 * m]  # zero-length segment 1
    b2[2 * m : 3 * m] = a2[2 * m : 3 * m]  # zero-length segment 2
    b1[3 * m : 3 * m + 5], b2[3 * m : 3 * m + 5] = a1[3 * m : 3 * m + 5], a2[3 * m : 3 * m + 5]  # both
    a2[4 * m : 5 * m] = a1[4 * m : 5 * m] + 0.7 * (b1[4 * m : 5 * m] - a1[4 * m : 5 * m])  # touching
    return a1, b1, a2, b2


def test_point_segment_against_sampling():
    rng = np.random.default_rng(1)
    p, a, b = (rng.uniform(-1.5, 1.5, (300, 3)) for _ in range(3))
    b[:20] = a[:20]
    t = gd.point_segment(p, a, b)
    assert t.shape == (300,) and ((t >= 0) & (t <= 1)).all()
    dist = np.linalg.norm(a + t[:, None] * (b - a) - p, axis=1)
    np.testing.assert_allclose(dist, ref_point_segment(p, a, b), rtol=0, atol=TOL)
    assert (t[:20] == 0).all()


def test_segment_closest_against_sampling():
    rng = np.random.default_rng(2)
    a1, b1, a2, b2 = _segment_scenes(rng, 300)
    s, t = gd.segment_closest(a1, b1, a2, b2)
    assert ((s >= 0) & (s <= 1) & (t >= 0) & (t <= 1)).all()
    dist = np.linalg.norm(a1 + s[:, None] * (b1 - a1) - a2 - t[:, None] * (b2 - a2), axis=1)
    np.testing.assert_allclose(dist, ref_segment_segment(a1, b1, a2, b2), rtol=0, atol=TOL)
    # zero-length segments take parameter 0
    assert (s[30:60] == 0).all() and (t[60:90] == 0).all()


def test_capsule_capsule_against_sampling():
    rng = np.random.default_rng(3)
    a1, b1, a2, b2 = _segment_scenes(rng, 300)
    r1, r2 = rng.uniform(0.05, 0.6, 300), rng.uniform(0.05, 0.6, 300)
    d, n, pa, pb = gd.capsule_capsule(a1, b1, r1, a2, b2, r2)
    np.testing.assert_allclose(d, ref_segment_segment(a1, b1, a2, b2) - r1 - r2, rtol=0, atol=TOL)
    assert (d < 0).sum() > 50 and (d > 0).sum() > 50  # both penetrating and separated cases
    _check_witness(d, n, pa, pb, r1, r2)
    assert ref_point_segment(pa, a1, b1).max() < 1e-12 and ref_point_segment(pb, a2, b2).max() < 1e-12


def test_capsule_sphere_against_sampling():
    rng = np.random.default_rng(4)
    a, b, c = (rng.uniform(-1.5, 1.5, (300, 3)) for _ in range(3))
    b[:30] = a[:30]
    c[30:40] = a[30:40] + 0.25 * (b[30:40] - a[30:40])  # centre on the segment: n = (0, 0, 1)
    r1, r2 = rng.uniform(0.05, 0.6, 300), rng.uniform(0.05, 0.6, 300)
    d, n, pa, pb = gd.capsule_sphere(a, b, r1, c, r2)
    np.testing.assert_allclose(d, ref_point_segment(c, a, b) - r1 - r2, rtol=0, atol=TOL)
    _check_witness(d, n, pa, pb, r1, r2)
    assert ref_point_segment(pa, a, b).max() < 1e-12 and (pb == c).all()
    np.testing.assert_allclose(n[30:40], np.tile([0.0, 0.0, 1.0], (10, 1)), atol=1e-15)
    np.testing.assert_allclose(d[30:40], -r1[30:40] - r2[30:40], atol=1e-15)
    # a zero-length capsule is a sphere
    ref = gd.sphere_sphere(a[:30], r1[:30], c[:30], r2[:30])
    for x, y in zip(gd.capsule_sphere(a[:30], b[:30], r1[:30], c[:30], r2[:30]), ref):
        np.testing.assert_array_equal(x, y)


def test_sphere_sphere():
    rng = np.random.default_rng(5)
    c1, c2 = rng.uniform(-1, 1, (200, 3)), rng.uniform(-1, 1, (200, 3))
    c2[:10] = c1[:10]
    r1, r2 = rng.uniform(0.05, 0.8, 200), rng.uniform(0.05, 0.8, 200)
    d, n, pa, pb = gd.sphere_sphere(c1, r1, c2, r2)
    np.testing.assert_allclose(d, np.sqrt(((c1 - c2) ** 2).sum(1)) - r1 - r2, rtol=0, atol=1e-14)
    _check_witness(d, n, pa, pb, r1, r2)
    assert (pa == c1).all() and (pb == c2).all()
    assert (n[:10] == [0.0, 0.0, 1.0]).all() and (d[:10] == -r1[:10] - r2[:10]).all()
    d, n, pa, pb = gd.sphere_sphere([0, 0, 0], 1.0, [1.5, 0, 0], 1.0)  # penetrating
    assert d == -0.5 and (n == [-1, 0, 0]).all() and (pb == [1.5, 0, 0]).all()


# --- boxes against the references ---------------------------------------------------------------


def _box_points(rng: np.random.Generator, n: int, inside: bool):
    center, h, R = _boxes(rng, n)
    if inside:
        local = rng.uniform(-1, 1, (n, 3)) * h
    else:  # outside: at least one coordinate beyond its face
        local = rng.uniform(-2.5, 2.5, (n, 3)) * h
        k = rng.integers(0, 3, n)
        local[np.arange(n), k] = (
            np.sign(local[np.arange(n), k] + 1e-300) * h[np.arange(n), k] * rng.uniform(1.05, 2.5, n)
        )
    return center + np.einsum("nij,nj->ni", R, local), center, h, R, local


def test_box_sdf_outside_against_surface_sampling():
    rng = np.random.default_rng(6)
    p, center, h, R, _ = _box_points(rng, 150, inside=False)
    d, n = gd.box_sdf(p, center, h, R)
    ref, closest = ref_box_outside(p, center, h, R)
    np.testing.assert_allclose(d, ref, rtol=0, atol=TOL)
    np.testing.assert_allclose(n, (p - closest) / ref[:, None], rtol=0, atol=1e-6)
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, rtol=0, atol=1e-12)


def test_box_sdf_inside_against_face_planes():
    rng = np.random.default_rng(7)
    p, center, h, R, _ = _box_points(rng, 400, inside=True)
    d, n = gd.box_sdf(p, center, h, R)
    ref, normal = ref_box_planes(p, center, h, R)
    assert (d < 0).all()
    np.testing.assert_allclose(d, ref, rtol=0, atol=1e-12)
    np.testing.assert_allclose(n, normal, rtol=0, atol=1e-12)


def test_box_sdf_known_values():
    center, h = np.array([0.5, -1.0, 2.0]), np.array([1.0, 2.0, 3.0])
    I = np.eye(3)
    cases = [  # local point, d, n (lowest axis on ties), whether n is unique
        ([1.0, 0.25, -0.5], 0.0, [1, 0, 0], True),  # on a face
        ([0.5, -2.0, 1.5], 0.0, [0, -1, 0], True),
        ([1.0, 2.0, 0.125], 0.0, [1, 0, 0], False),  # on an edge
        ([0.5, -2.0, 3.0], 0.0, [0, -1, 0], False),
        ([-1.0, -2.0, -3.0], 0.0, [-1, 0, 0], False),  # on a corner
        ([2.0, 3.0, 0.0], np.sqrt(2.0), np.array([1, 1, 0]) / np.sqrt(2.0), True),  # beside an edge
        ([2.0, 3.0, 4.0], np.sqrt(3.0), np.array([1, 1, 1]) / np.sqrt(3.0), True),  # beside a corner
        ([0.5, 0.25, 0.125], -0.5, [1, 0, 0], True),  # inside
        ([0.0, 0.0, 0.0], -1.0, [1, 0, 0], False),  # the centre
        ([0.0, 1.0, 2.0], -1.0, [1, 0, 0], False),  # equidistant from 3 faces
    ]
    for local, d_ref, n_ref, unique in cases:
        d, n = gd.box_sdf(center + np.array(local), center, h, I)
        assert d == pytest.approx(d_ref, abs=1e-15), local
        np.testing.assert_allclose(n, n_ref, atol=1e-15, err_msg=str(local))
        # a rotated box: the same distance; the same normal in its frame where it is unique
        Q = _rotations(np.random.default_rng(len(str(local))), 1)[0]
        d2, n2 = gd.box_sdf(center + Q @ np.array(local), center, h, Q)
        assert d2 == pytest.approx(d_ref, abs=1e-14)
        if unique:
            np.testing.assert_allclose(n2, Q @ n_ref, atol=1e-12)
    # the face point of an inside point: pa moved to its nearest face
    d, n, pa, pb = gd.sphere_box(center + [0.5, 0.25, 0.125], 0.25, center, h, I)
    assert d == -0.75 and (pb == center + [1.0, 0.25, 0.125]).all()


def test_box_surface_points_rotated():
    """Points on rotated faces, edges and corners: d ~ 0, n unit and in the normal cone."""
    rng = np.random.default_rng(8)
    n_pts = 300
    center, h, R = _boxes(rng, n_pts)
    local = rng.uniform(-1, 1, (n_pts, 3)) * h
    kind = np.arange(n_pts) % 3  # 1, 2 or 3 coordinates on the surface
    for j in range(3):
        on = kind >= j
        local[on, j] = np.where(rng.random(on.sum()) < 0.5, -1.0, 1.0) * h[on, j]
    p = center + np.einsum("nij,nj->ni", R, local)
    d, n = gd.box_sdf(p, center, h, R)
    assert np.abs(d).max() < 1e-14
    nl = np.einsum("nji,nj->ni", R, n)  # n in box coordinates
    np.testing.assert_allclose(np.linalg.norm(n, axis=1), 1.0, atol=1e-12)
    active = np.abs(np.abs(local) - h) == 0
    assert np.abs(nl[~active]).max() < 1e-12  # no component along an axis the point is not at the end of
    assert (nl[active] * np.sign(local[active]) > -1e-12).all()  # outward


def test_sphere_box_against_references():
    rng = np.random.default_rng(9)
    p_out, c_out, h_out, R_out, _ = _box_points(rng, 120, inside=False)
    p_in, c_in, h_in, R_in, _ = _box_points(rng, 120, inside=True)
    c, center, h, R = (
        np.concatenate(x) for x in ((p_out, p_in), (c_out, c_in), (h_out, h_in), (R_out, R_in))
    )
    r = rng.uniform(0.05, 0.8, len(c))
    d, n, pa, pb = gd.sphere_box(c, r, center, h, R)
    ref = np.concatenate(
        [ref_box_outside(p_out, c_out, h_out, R_out)[0], ref_box_planes(p_in, c_in, h_in, R_in)[0]]
    )
    np.testing.assert_allclose(d, ref - r, rtol=0, atol=TOL)
    _check_witness(d, n, pa, pb, r, 0.0, box=True)
    assert (pa == c).all() and _on_box_surface(pb, center, h, R).max() < 1e-12
    assert (d < 0).sum() > 120 and (d > 0).sum() > 50


def test_capsule_box_against_references():
    rng = np.random.default_rng(10)
    n_cases = 150
    center, h, R = _boxes(rng, n_cases)
    a, b = rng.uniform(-2.2, 2.2, (n_cases, 3)), rng.uniform(-2.2, 2.2, (n_cases, 3))
    b[:10] = a[:10]  # zero length
    r = rng.uniform(0.05, 0.5, n_cases)
    d, n, pa, pb = gd.capsule_box(a, b, r, center, h, R)
    ref = ref_capsule_box_core(a, b, center, h, R)
    np.testing.assert_allclose(d, ref - r, rtol=0, atol=TOL)
    assert (ref < 0).sum() > 30 and (ref > 0).sum() > 30  # segments through the box and beside it
    _check_witness(d, n, pa, pb, r, 0.0, box=True)
    assert ref_point_segment(pa, a, b).max() < 1e-12 and _on_box_surface(pb, center, h, R).max() < 1e-12
    # a zero-length capsule is a sphere
    ref_s = gd.sphere_box(a[:10], r[:10], center[:10], h[:10], R[:10])
    for x, y in zip(gd.capsule_box(a[:10], b[:10], r[:10], center[:10], h[:10], R[:10]), ref_s):
        np.testing.assert_array_equal(x, y)


# --- penetrating and degenerate cases with known answers -----------------------------------------


def test_capsule_capsule_known_cases():
    o, x2 = np.zeros(3), np.array([2.0, 0, 0])
    # crossing at height 0.25: penetration, n from B (above) toward A
    d, n, pa, pb = gd.capsule_capsule(o, x2, 0.25, [1, -1, 0.25], [1, 1, 0.25], 0.5)
    assert d == -0.5 and (n == [0, 0, -1]).all() and (pa == [1, 0, 0]).all() and (pb == [1, 0, 0.25]).all()
    # intersecting: coincident core points, n = (0, 0, 1)
    d, n, pa, pb = gd.capsule_capsule(o, x2, 0.25, [1, -1, 0], [1, 1, 0], 0.5)
    assert d == -0.75 and (n == [0, 0, 1]).all() and (pa == pb).all()
    # parallel, overlapping: Ericson's s = 0 rule: t clamps to 0, s = the projection of a2
    d, n, pa, pb = gd.capsule_capsule(o, x2, 0.25, [1, 0.5, 0], [3, 0.5, 0], 0.5)
    assert d == -0.25 and (n == [0, -1, 0]).all() and (pa == [1, 0, 0]).all() and (pb == [1, 0.5, 0]).all()
    # anti-parallel, apart
    d, n, pa, pb = gd.capsule_capsule(o, x2, 0.25, [3, 2, 0], [-1, 2, 0], 0.5)
    assert d == 1.25 and (n == [0, -1, 0]).all()
    # parallel without overlap: endpoint to endpoint
    d, n, pa, pb = gd.capsule_capsule(o, x2, 0.25, [3, 0, 0], [5, 0, 0], 0.5)
    assert d == pytest.approx(0.25) and (pa == x2).all() and (pb == [3, 0, 0]).all()
    # collinear overlapping: distance 0
    d, n, pa, pb = gd.capsule_capsule(o, x2, 0.25, [3, 0, 0], [1, 0, 0], 0.5)
    assert d == -0.75 and (n == [0, 0, 1]).all()
    # zero-length segments: a capsule of length 0 is a sphere
    ref = gd.sphere_sphere([0.5, 0.25, 0], 0.25, [1, 1, 1], 0.5)
    got = gd.capsule_capsule([0.5, 0.25, 0], [0.5, 0.25, 0], 0.25, [1, 1, 1], [1, 1, 1], 0.5)
    for x, y in zip(got, ref):
        np.testing.assert_array_equal(x, y)
    ref = gd.capsule_sphere(o, x2, 0.25, [1, 1, 1], 0.5)
    got = gd.capsule_capsule(o, x2, 0.25, [1, 1, 1], [1, 1, 1], 0.5)
    for x, y in zip(got, ref):
        np.testing.assert_array_equal(x, y)


def test_capsule_box_penetrating_known_cases():
    center, h, I = np.zeros(3), np.array([1.0, 2.0, 3.0]), np.eye(3)
    # along x through the centre: the deepest point is the centre, 1 deep
    d, n, pa, pb = gd.capsule_box([-5, 0, 0], [5, 0, 0], 0.125, center, h, I)
    assert d == pytest.approx(-1.125, abs=1e-14) and np.abs(pa).max() < 1e-12
    np.testing.assert_allclose(np.abs(n), [1, 0, 0], atol=1e-15)
    # along z: the SDF is flat (-1) for |z| < 2; the search stays inside the flat stretch, so the
    # normal is the x face's (+x, lowest axis), not the z face's at the stretch's edge
    d, n, pa, pb = gd.capsule_box([0, 0, -10], [0, 0, 10], 0.125, center, h, I)
    assert d == -1.125 and (n == [1, 0, 0]).all() and abs(pa[2]) < 1.9 and (pb == pa + [1, 0, 0]).all()
    d, n, pa, pb = gd.capsule_box([0, 0, 0], [0, 0, 10], 0.125, center, h, I)  # flat stretch at t = 0
    assert d == -1.125 and (n == [1, 0, 0]).all() and pa[2] < 1.9
    # one end inside near a face, the other far outside: the deepest point is that end
    d, n, pa, pb = gd.capsule_box([0.75, 0, 0], [5, 1, 0], 0.125, center, h, I)
    assert d == pytest.approx(-0.375, abs=1e-14) and np.allclose(pa, [0.75, 0, 0], atol=1e-14)
    assert (n == [1, 0, 0]).all()
    # beside the box, parallel to a face: distance 0.5
    d, n, pa, pb = gd.capsule_box([1.5, -1, -1], [1.5, 1, 1], 0.125, center, h, I)
    assert d == pytest.approx(0.375, abs=1e-14) and (n == [1, 0, 0]).all()
    # crossing an edge diagonally
    d, n, pa, pb = gd.capsule_box([2.0, 1.0, 0.0], [0.0, 3.0, 0.0], 0.0, center, h, I)
    assert d == pytest.approx(0.0, abs=1e-12) and np.allclose(pa, [1, 2, 0], atol=1e-7)


def test_capsule_box_kink_between_two_faces():
    """The documented exception to n.e = d': the deepest point of a capsule crossing a box where
    two faces are equally deep. d is differentiable there with the gradient
    (a1 n2 - a2 n1) / (a1 - a2) (a1 > 0 > a2 the faces' SDF slopes along the segment), and n is the
    unit normal of one of the two faces."""
    center, h, I = np.zeros(3), np.ones(3), np.eye(3)
    a, b = np.array([0.0, -2.0, 0.0]), np.array([0.8, 2.0, 0.0])  # x = 0.8 t, y = 4 t - 2
    d, n, pa, pb = gd.capsule_box(a, b, 0.0, center, h, I)
    assert d == pytest.approx(-2 / 3, abs=1e-14)  # at t = 5/12: x = -y = 1/3
    np.testing.assert_allclose(pa, [1 / 3, -1 / 3, 0], atol=1e-9)
    assert any(np.allclose(n, face, atol=1e-15) for face in ([1, 0, 0], [0, -1, 0]))
    grad = [
        (
            gd.capsule_box(a + e, b + e, 0.0, center, h, I)[0]
            - gd.capsule_box(a - e, b - e, 0.0, center, h, I)[0]
        )
        / 2e-6
        for e in 1e-6 * np.eye(3)
    ]
    # faces +x (slope 0.8) and -y (slope -4): (0.8 (0, -1, 0) + 4 (1, 0, 0)) / 4.8
    np.testing.assert_allclose(grad, [5 / 6, -1 / 6, 0.0], atol=1e-7)


def test_broadcasting_and_shapes():
    rng = np.random.default_rng(11)
    a = rng.uniform(-1, 1, (4, 5, 3))
    b = rng.uniform(-1, 1, (5, 3))
    c = rng.uniform(-1, 1, 3)
    r = rng.uniform(0.1, 0.3, (4, 1))
    center, h, R = np.zeros(3), np.array([0.5, 0.25, 0.75]), _rotations(rng, 1)[0]

    def pick(i: int, j: int) -> dict:
        return {"a": a[i, j], "b": b[j], "r": r[i, 0]}

    def cases(v: dict) -> list:
        return [
            (gd.sphere_sphere, (v["a"], v["r"], c, 0.5)),
            (gd.capsule_sphere, (v["a"], v["b"], v["r"], c, 0.5)),
            (gd.capsule_capsule, (v["a"], v["b"], v["r"], c, 2 * c, 0.5)),
            (gd.sphere_box, (v["a"], v["r"], center, h, R)),
            (gd.capsule_box, (v["a"], v["b"], v["r"], center, h, R)),
        ]

    for k, (fn, args) in enumerate(cases({"a": a, "b": b, "r": r})):
        d, n, pa, pb = fn(*args)
        assert d.shape == (4, 5) and n.shape == pa.shape == pb.shape == (4, 5, 3), fn.__name__
        for i, j in [(0, 0), (3, 4), (2, 1)]:  # the same values one case at a time
            fn1, args1 = cases(pick(i, j))[k]
            d1, n1, pa1, pb1 = fn1(*args1)
            assert d1.shape == () and n1.shape == pa1.shape == pb1.shape == (3,)
            np.testing.assert_array_equal(d1, d[i, j])
            np.testing.assert_array_equal(n1, n[i, j])
            np.testing.assert_array_equal(pa1, pa[i, j])
            np.testing.assert_array_equal(pb1, pb[i, j])
    # scalar radius with a batch only in the radii still gives full-shape outputs
    d, n, pa, pb = gd.sphere_sphere(c, np.array([0.1, 0.2]), -c, 0.5)
    assert d.shape == (2,) and n.shape == (2, 3)
    with pytest.raises(ValueError):
        gd.sphere_sphere(np.zeros(2), 1.0, np.zeros(3), 1.0)
    with pytest.raises(ValueError):
        gd.sphere_box(np.zeros(3), 1.0, np.zeros(3), np.ones(3), np.eye(4))
    with pytest.raises(ValueError):
        gd.capsule_capsule(np.zeros((2, 3)), np.zeros((3, 3)), 1.0, np.zeros(3), np.zeros(3), 1.0)


# --- the first-order property -------------------------------------------------------------------

EPS_FD = 1e-6


def _fd_check(d0, dp, dm, expected, min_kept: float = 0.8, skip=None) -> None:
    """Central differences (dp - dm) / 2 eps against ``expected`` where d is smooth (no kink:
    the second difference is at rounding level), except the cases ``skip``."""
    smooth = np.abs(dp - 2 * d0 + dm) < 1e-8
    if skip is not None:
        smooth &= ~skip
    assert smooth.mean() >= min_kept, f"only {smooth.mean():.0%} smooth cases"
    fd = (dp - dm) / (2 * EPS_FD)
    np.testing.assert_allclose(fd[smooth], expected[smooth], rtol=0, atol=1e-6)


def _pair_scenes(kind: str, rng: np.random.Generator, n: int):
    """(A args, B args, A points, B points): A points are moved to move A (the centre or the
    segment's ends), B points (or the box centre) likewise."""
    r1, r2 = rng.uniform(0.05, 0.4, n), rng.uniform(0.05, 0.4, n)
    p = [rng.uniform(-1.5, 1.5, (n, 3)) for _ in range(4)]
    if kind == "sphere_sphere":
        return [p[0], r1], [p[1], r2]
    if kind == "capsule_sphere":
        return [p[0], p[1], r1], [p[2], r2]
    if kind == "capsule_capsule":
        return [p[0], p[1], r1], [p[2], p[3], r2]
    center, h, R = _boxes(rng, n)
    if kind == "sphere_box":
        return [p[0], r1], [center, h, R]
    return [p[0], p[1], r1], [center, h, R]


KINDS = ["sphere_sphere", "capsule_sphere", "capsule_capsule", "sphere_box", "capsule_box"]


def _box_kinks(kind: str, B, pa) -> np.ndarray | None:
    """Capsule-box cases whose deepest point is where two faces are equally deep (see
    test_capsule_box_kink_between_two_faces): there d's gradient is not the unit normal."""
    if kind != "capsule_box":
        return None
    center, h, R = B
    x = np.einsum("nji,nj->ni", R, pa - center)
    q = np.abs(x) - h
    k = np.argmax(q, axis=1)
    top = np.sort(q, axis=1)
    two_axes = top[:, 2] - top[:, 1] < 1e-9
    opposite = np.abs(x[np.arange(len(x)), k]) < 1e-9  # +k and -k faces, as in a thin wall
    return (top[:, 2] < 0) & (two_axes | opposite)


def _move_points(args, box: bool, Q=None, o=None, e=None):
    """Rigidly move a shape: every point argument (the box centre too, not its half extents) and a
    box's rotation."""
    out = list(args)
    idx = [0] if box else [i for i, x in enumerate(args) if x.ndim == 2]
    for i in idx:
        out[i] = args[i] + e if e is not None else _rot(args[i], Q, o)
    if box and Q is not None:
        out[2] = Q @ args[2]
    return out


@pytest.mark.parametrize("kind", KINDS)
def test_first_order_translation(kind):
    rng = np.random.default_rng(300 + KINDS.index(kind))
    fn = getattr(gd, kind)
    A, B = _pair_scenes(kind, rng, 300)
    box = kind.endswith("box")
    d0, n, pa, pb = fn(*A, *B)
    u = _unit(rng, 300)
    skip = _box_kinks(kind, B, pa)
    kept = 0.5 if kind == "capsule_box" else 0.8  # random capsules often cross the box: kinks
    # move A: d' = n.u
    dp = fn(*_move_points(A, False, e=EPS_FD * u), *B)[0]
    dm = fn(*_move_points(A, False, e=-EPS_FD * u), *B)[0]
    _fd_check(d0, dp, dm, np.einsum("ni,ni->n", n, u), kept, skip)
    # move B: d' = -n.u
    dp = fn(*A, *_move_points(B, box, e=EPS_FD * u))[0]
    dm = fn(*A, *_move_points(B, box, e=-EPS_FD * u))[0]
    _fd_check(d0, dp, dm, -np.einsum("ni,ni->n", n, u), kept, skip)


@pytest.mark.parametrize("kind", KINDS)
def test_first_order_rotation(kind):
    """With pa, pb fixed to their bodies, d' = n.(pa' - pb') under rotations of A and of B."""
    rng = np.random.default_rng(400 + KINDS.index(kind))
    fn = getattr(gd, kind)
    A, B = _pair_scenes(kind, rng, 300)
    box = kind.endswith("box")
    d0, n, pa, pb = fn(*A, *B)
    w, o = _unit(rng, 300), rng.uniform(-1, 1, (300, 3))
    Qp, Qm = _rodrigues(w, EPS_FD), _rodrigues(w, -EPS_FD)
    skip = _box_kinks(kind, B, pa)
    kept = 0.5 if kind == "capsule_box" else 0.8  # random capsules often cross the box: kinks
    dp = fn(*_move_points(A, False, Q=Qp, o=o), *B)[0]
    dm = fn(*_move_points(A, False, Q=Qm, o=o), *B)[0]
    _fd_check(d0, dp, dm, np.einsum("ni,ni->n", n, np.cross(w, pa - o)), kept, skip)
    dp = fn(*A, *_move_points(B, box, Q=Qp, o=o))[0]
    dm = fn(*A, *_move_points(B, box, Q=Qm, o=o))[0]
    _fd_check(d0, dp, dm, -np.einsum("ni,ni->n", n, np.cross(w, pb - o)), kept, skip)


# --- hypothesis properties ----------------------------------------------------------------------

_coord = st.floats(-4.0, 4.0, allow_nan=False, allow_infinity=False)
_point = st.tuples(_coord, _coord, _coord).map(np.array)
_HYP = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@_HYP
@given(_point, _point, _point, _point)
def test_segment_closest_properties(a1, b1, a2, b2):
    s, t = gd.segment_closest(a1, b1, a2, b2)
    assert 0 <= s <= 1 and 0 <= t <= 1
    dist = np.linalg.norm(a1 + s * (b1 - a1) - a2 - t * (b2 - a2))
    # no pair of points of a grid, nor the end points' projections, is closer
    g = np.linspace(0, 1, 21)
    P = a1 + g[:, None] * (b1 - a1)
    Qs = a2 + g[:, None] * (b2 - a2)
    grid = np.linalg.norm(P[:, None] - Qs[None], axis=-1).min()
    scale = 1.0 + max(np.abs(x).max() for x in (a1, b1, a2, b2))
    # nearly parallel segments (below ~1e-7 rad) are taken as parallel: an error of up to length * angle
    assert dist <= grid + 1e-7 * scale
    # the same distance with the segments swapped or reversed
    s2, t2 = gd.segment_closest(b2, a2, a1, b1)
    dist2 = np.linalg.norm(b2 + s2 * (a2 - b2) - a1 - t2 * (b1 - a1))
    assert abs(dist - dist2) <= 1e-7 * scale


@_HYP
@given(_point, _point, st.floats(0.0, 1.0), st.floats(0.0, 1.0), st.floats(0.0, 1.0))
def test_box_sdf_properties(p, center, hx, hy, hz):
    h = np.array([hx, hy, hz])
    R = _rotations(np.random.default_rng(int(abs(p[0]) * 1e6) % 1000), 1)[0]
    d, n = gd.box_sdf(p, center, h, R)
    assert abs(np.linalg.norm(n) - 1) < 1e-12
    pb = p - d * n  # the nearest surface point
    local = R.T @ (pb - center)
    assert (np.abs(local) <= h + 1e-12 * (1 + np.abs(p).max())).all()
    assert abs(gd.box_sdf(pb, center, h, R)[0]) <= 1e-12 * (1 + np.abs(p).max())
    # Lipschitz 1 and the gradient property along n
    for step in (1e-3, -1e-3):
        d2 = gd.box_sdf(p + step * n, center, h, R)[0]
        assert abs(d2 - d) <= abs(step) + 1e-12
    # translation invariance
    shift = np.array([0.5, -0.25, 1.0])
    assert abs(gd.box_sdf(p + shift, center + shift, h, R)[0] - d) < 1e-12


@_HYP
@given(_point, _point, st.floats(0.0, 1.0), _point, st.floats(0.0, 1.0))
def test_capsule_sphere_symmetry(a, b, r1, c, r2):
    """A capsule against a sphere equals the capsule-capsule query with a zero-length segment and,
    swapped, a sphere A against the capsule with the normal reversed."""
    d, n, pa, pb = gd.capsule_sphere(a, b, r1, c, r2)
    d2, n2, pa2, pb2 = gd.capsule_capsule(a, b, r1, c, c, r2)
    assert abs(d - d2) < 1e-12 and np.allclose(pa, pa2, atol=1e-12) and np.allclose(pb, pb2, atol=1e-12)
    d3, n3, pa3, pb3 = gd.capsule_capsule(c, c, r2, a, b, r1)
    assert abs(d - d3) < 1e-12 and np.allclose(pa, pb3, atol=1e-12)
    if np.linalg.norm(pa - pb) > 1e-9:
        assert np.allclose(n, -n3, atol=1e-9)


# --- the C header against NumPy -----------------------------------------------------------------

C_SOURCE = r"""
#include "symkin_collide.h"

#define LOOP for (long i = 0; i < count; ++i)
#define V(x) (x + 3 * i)
#define OUT V(n), V(pa), V(pb)

void t_sphere_sphere(long count, const double *c1, const double *r1, const double *c2, const double *r2,
                     double *d, double *n, double *pa, double *pb)
{
    LOOP d[i] = skc_sphere_sphere(V(c1), r1[i], V(c2), r2[i], OUT);
}
void t_capsule_sphere(long count, const double *a1, const double *b1, const double *r1, const double *c2,
                      const double *r2, double *d, double *n, double *pa, double *pb)
{
    LOOP d[i] = skc_capsule_sphere(V(a1), V(b1), r1[i], V(c2), r2[i], OUT);
}
void t_capsule_capsule(long count, const double *a1, const double *b1, const double *r1, const double *a2,
                       const double *b2, const double *r2, double *d, double *n, double *pa, double *pb)
{
    LOOP d[i] = skc_capsule_capsule(V(a1), V(b1), r1[i], V(a2), V(b2), r2[i], OUT);
}
void t_sphere_box(long count, const double *c, const double *r, const double *center, const double *h,
                  const double *R, double *d, double *n, double *pa, double *pb)
{
    LOOP d[i] = skc_sphere_box(V(c), r[i], V(center), V(h), R + 9 * i, OUT);
}
void t_capsule_box(long count, const double *a, const double *b, const double *r, const double *center,
                   const double *h, const double *R, double *d, double *n, double *pa, double *pb)
{
    LOOP d[i] = skc_capsule_box(V(a), V(b), r[i], V(center), V(h), R + 9 * i, OUT);
}
void t_box_sdf(long count, const double *p, const double *center, const double *h, const double *R, double *d,
               double *n)
{
    LOOP d[i] = skc_box_sdf(V(p), V(center), V(h), R + 9 * i, V(n));
}
void t_segment_closest(long count, const double *a1, const double *b1, const double *a2, const double *b2,
                       double *s, double *t)
{
    LOOP skc_segment_closest(V(a1), V(b1), V(a2), V(b2), s + i, t + i);
}
void t_point_segment(long count, const double *p, const double *a, const double *b, double *t)
{
    LOOP t[i] = skc_point_segment(V(p), V(a), V(b));
}
void t_spheres_overlap(long count, const double *c1, const double *r1, const double *c2, const double *r2,
                       int *out)
{
    LOOP out[i] = skc_spheres_overlap(V(c1), r1[i], V(c2), r2[i]);
}
"""


@pytest.fixture(scope="module")
def clib() -> ctypes.CDLL:
    try:
        find_compiler()
    except CompileError:
        pytest.skip("no C compiler")
    sources = {"t.c": C_SOURCE, "symkin_collide.h": HEADER.read_text()}
    # the header must build warning-free under strict flags
    path = compile_library(
        sources, "sk_collide_test", extra_cflags=("-Wall", "-Wextra", "-Werror", "-Wpedantic")
    )
    return load_library(path)


def _c_call(lib: ctypes.CDLL, name: str, inputs, outputs):
    """Call ``t_<name>(count, *inputs, *outputs)``; ``outputs``: trailing shapes (int dtype when
    given as ("int", shape))."""
    count = len(inputs[0])
    ins = [
        np.ascontiguousarray(np.broadcast_to(np.asarray(x, float), (count,) + np.shape(x)[1:]))
        for x in inputs
    ]
    outs = []
    for shape in outputs:
        if isinstance(shape, tuple) and shape and shape[0] == "int":
            outs.append(np.zeros((count,) + shape[1], dtype=np.intc))
        else:
            outs.append(np.zeros((count,) + shape))
    fn = getattr(lib, f"t_{name}")
    fn.restype = None
    fn(ctypes.c_long(count), *[a.ctypes.data_as(ctypes.c_void_p) for a in ins + outs])
    return outs


def _c_scenes(kind: str, rng: np.random.Generator, n: int = 2000):
    """Random pairs with degenerate rows mixed in (coincident, zero-length, parallel, on faces)."""
    A, B = _pair_scenes(kind, rng, n)
    m = n // 20
    if kind == "sphere_sphere":
        B[0][:m] = A[0][:m]
    elif kind == "capsule_sphere":
        A[1][:m] = A[0][:m]
        B[0][m : 2 * m] = A[0][m : 2 * m] + 0.375 * (A[1][m : 2 * m] - A[0][m : 2 * m])
    elif kind == "capsule_capsule":
        a1, b1, _ = A
        a2, b2, _ = B
        b1[:m] = a1[:m]
        b2[m : 2 * m] = a2[m : 2 * m]
        b2[2 * m : 3 * m] = a2[2 * m : 3 * m] + 0.5 * (b1[2 * m : 3 * m] - a1[2 * m : 3 * m])  # parallel
        a2[3 * m : 4 * m] = a1[3 * m : 4 * m] + 0.25 * (b1[3 * m : 4 * m] - a1[3 * m : 4 * m])  # touching
        b2[3 * m : 4 * m] = a2[3 * m : 4 * m] - 0.75 * (b1[3 * m : 4 * m] - a1[3 * m : 4 * m])  # collinear
    else:
        center, h, R = B
        R[:m] = np.eye(3)  # axis-aligned: points exactly on faces, edges, corners; flat stretches
        h[:m] = rng.integers(1, 5, (m, 3)) / 4
        center[:m] = rng.integers(-4, 5, (m, 3)) / 8
        A[0][:m] = center[:m] + rng.integers(-6, 7, (m, 3)) / 4 * h[:m]  # often exactly +-h
        if kind == "capsule_box":
            A[1][:m] = A[0][:m] + rng.integers(-8, 9, (m, 3)) / 4 * (rng.random((m, 3)) < 0.5)
            A[1][m : 2 * m] = A[0][m : 2 * m]  # zero length
    return A, B


def _assert_agree(got, want, what: str) -> None:
    got, want = np.asarray(got), np.asarray(want)
    assert got.shape == want.shape, what
    err = np.abs(got - want).max()
    assert err <= 1e-12, f"{what}: C and NumPy differ by {err:.3g}"


@pytest.mark.parametrize("kind", KINDS)
def test_c_matches_numpy(clib, kind):
    rng = np.random.default_rng(100 + KINDS.index(kind))
    A, B = _c_scenes(kind, rng)
    want = getattr(gd, kind)(*A, *B)
    got = _c_call(clib, kind, [*A, *B], [(), (3,), (3,), (3,)])
    for name, x, y in zip(("d", "n", "pa", "pb"), got, want):
        _assert_agree(x, y, f"{kind} {name}")
    assert (got[0] < 0).any() and (got[0] > 0).any()


def test_c_matches_numpy_helpers(clib):
    rng = np.random.default_rng(200)
    a1, b1, a2, b2 = _segment_scenes(rng, 2000)
    s, t = _c_call(clib, "segment_closest", [a1, b1, a2, b2], [(), ()])
    s_np, t_np = gd.segment_closest(a1, b1, a2, b2)
    _assert_agree(s, s_np, "segment_closest s")
    _assert_agree(t, t_np, "segment_closest t")
    (t,) = _c_call(clib, "point_segment", [a2, a1, b1], [()])
    _assert_agree(t, gd.point_segment(a2, a1, b1), "point_segment")
    p, center, h, R, _ = _box_points(rng, 2000, inside=False)
    p[:1000] = _box_points(rng, 1000, inside=True)[0]
    d, n = _c_call(clib, "box_sdf", [p, center, h, R], [(), (3,)])
    d_np, n_np = gd.box_sdf(p, center, h, R)
    _assert_agree(d, d_np, "box_sdf d")
    _assert_agree(n, n_np, "box_sdf n")
    c1, c2 = rng.uniform(-1, 1, (2000, 3)), rng.uniform(-1, 1, (2000, 3))
    r1, r2 = rng.uniform(0, 1, 2000), rng.uniform(0, 1, 2000)
    c2[:10] = c1[:10] + [1.0, 0.0, 0.0]  # touching exactly: not overlapping (d = 0, not < 0)
    r1[:10] = r2[:10] = 0.5
    c2[10:20], r1[10:20], r2[10:20] = c1[10:20] + [0.5, 0.0, 0.0], 0.5, 0.5  # overlapping
    (overlap,) = _c_call(clib, "spheres_overlap", [c1, r1, c2, r2], [("int", ())])
    assert (overlap.astype(bool) == (((c1 - c2) ** 2).sum(1) < (r1 + r2) ** 2)).all()
    d = gd.sphere_sphere(c1, r1, c2, r2)[0]
    assert (overlap.astype(bool) == (d < 0)).all()
    assert not overlap[:10].any() and overlap[10:20].all() and 0 < overlap.mean() < 1
