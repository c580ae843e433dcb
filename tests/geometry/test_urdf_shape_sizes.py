"""Collision shapes of every size a URDF can say: a thin shape is covered by a bounded number of
spheres (never dropped, never a memory blow-up), a size that is negative, NaN, inf or beyond
MAX_SHAPE_SIZE is refused naming the link, and a mesh file that cannot be read is skipped with a
warning naming the file and the link (regressions of issue 36, items 3 and 11)."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import symkin
from symkin.errors import GeometryError
from symkin.geometry.fit import fit_spheres
from symkin.geometry.urdf import MAX_SHAPE_SPHERES, box_spheres, geometry_from_urdf


def urdf(shape: str, origin: str = "") -> str:
    return (
        '<robot name="r"><link name="base"/><link name="plate_link"><collision>'
        f"{origin}<geometry>{shape}</geometry></collision></link>"
        '<joint name="j1" type="revolute"><parent link="base"/><child link="plate_link"/>'
        '<axis xyz="0 0 1"/><limit lower="-1" upper="1"/></joint></robot>'
    )


def shapes_of(xml: str, tmp_path=None, **kw):
    if tmp_path is not None:
        path = tmp_path / "r.urdf"
        path.write_text(xml)
        xml = path
    tree = symkin.Tree.from_urdf(xml)
    return geometry_from_urdf(xml, tree, **kw)


def box_points(size, n=4000, seed=0):
    """Corners, face centres and random points of the box of side lengths ``size``."""
    h = np.asarray(size, dtype=float) / 2
    rng = np.random.default_rng(seed)
    signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)], float)
    faces = np.concatenate([np.eye(3), -np.eye(3)])
    return np.concatenate([signs * h, faces * h, (rng.random((n, 3)) * 2 - 1) * h])


THIN = ["0 1 1", "1e-300 1 1", "1e-12 1 1", "1 1e-200 0.5", "0.3 0.2 1e-9", "0 0 1", "1e-300 1e-300 1e-300"]


@pytest.mark.parametrize("size", THIN)
@pytest.mark.parametrize("budget", [1, 8, 64])
def test_thin_boxes_are_covered_by_a_bounded_number_of_spheres(size, budget):
    g = shapes_of(urdf(f'<box size="{size}"/>'), max_box_spheres=budget)
    assert 1 <= len(g.shapes) <= budget
    C = np.array([s.center for s in g.shapes])
    R = np.array([s.radius for s in g.shapes])
    P = box_points([float(v) for v in size.split()])
    inside = (np.linalg.norm(P[:, None] - C[None], axis=2) <= R + 1e-12).any(1)
    assert inside.all()


def test_a_plate_of_zero_and_of_tiny_thickness_get_the_same_cover():
    zero = box_spheres([0.0, 0.5, 0.5])
    tiny = box_spheres([1e-150, 0.5, 0.5])
    assert len(zero) == len(tiny) == 64
    np.testing.assert_allclose([r for _, r in zero], [r for _, r in tiny])


@pytest.mark.parametrize(
    "shape",
    [
        '<box size="1e300 1 1"/>',
        '<box size="2e4 1 1"/>',
        '<box size="-1 1 1"/>',
        '<box size="nan 1 1"/>',
        '<box size="inf 1 1"/>',
        '<box size="1 1"/>',
        '<sphere radius="-0.1"/>',
        '<sphere radius="nan"/>',
        '<sphere radius="-inf"/>',
        '<sphere radius="1e300"/>',
        '<cylinder radius="-1" length="1"/>',
        '<cylinder radius="0.1" length="-1"/>',
        '<cylinder radius="0.1" length="inf"/>',
        '<cylinder radius="1e20" length="1"/>',
        '<capsule radius="0.1" length="nan"/>',
        '<capsule radius="-0.1" length="1"/>',
    ],
)
def test_bad_sizes_are_refused_naming_the_link(shape):
    with pytest.raises(GeometryError, match="plate_link"):
        shapes_of(urdf(shape))


@pytest.mark.parametrize(
    "shape",
    ['<sphere radius="1e-300"/>', '<sphere radius="0"/>', '<cylinder radius="1e-300" length="1e-300"/>'],
)
def test_tiny_round_shapes_are_kept(shape):
    g = shapes_of(urdf(shape))
    assert len(g.shapes) == 1


@pytest.mark.parametrize("budget", [0, -1, MAX_SHAPE_SPHERES + 1, 10**12, 1.5, True])
def test_sphere_budgets_are_bounded(budget):
    with pytest.raises(GeometryError, match="max_box_spheres|between"):
        shapes_of(urdf('<box size="1e-12 1 1"/>'), max_box_spheres=budget)
    with pytest.raises(GeometryError):
        box_spheres([0.5, 0.5, 0.5], budget)


@pytest.mark.parametrize(
    "content",
    [
        b"",
        b"solid x\nfacet normal 0 0 1\nthis is not an stl\n",
        b"\x00" * 37,
        b"solid empty\nendsolid empty\n",
    ],
)
def test_unreadable_mesh_files_are_skipped_with_a_warning_naming_file_and_link(content, tmp_path):
    pytest.importorskip("trimesh")
    (tmp_path / "broken.stl").write_bytes(content)
    xml = urdf('<mesh filename="broken.stl"/>')
    with pytest.warns(UserWarning) as record:
        g = shapes_of(xml, tmp_path, mesh_spheres=4)
    text = " | ".join(str(w.message) for w in record)
    assert "broken.stl" in text and "plate_link" in text and "skipped" in text
    assert len(g.shapes) == 0 and "skipped on ['plate_link']" in g.source


def _cube(tmp_path):
    trimesh = pytest.importorskip("trimesh")
    trimesh.creation.box(extents=(0.1, 0.2, 0.3)).export(tmp_path / "cube.stl")


@pytest.mark.parametrize("scale", ["1e300 1 1", "nan 1 1", "1 inf 1", "2e4 1 1"])
def test_bad_mesh_scales_are_refused_naming_the_link(scale, tmp_path):
    _cube(tmp_path)
    with pytest.raises(GeometryError, match="plate_link"):
        shapes_of(urdf(f'<mesh filename="cube.stl" scale="{scale}"/>'), tmp_path, mesh_spheres=2)


@pytest.mark.parametrize("scale", ["0 1 1", "1e-300 1 1", "-1 1 1", "1e-12 1e-12 1e-12"])
def test_flat_tiny_and_mirrored_meshes_are_covered(scale, tmp_path):
    _cube(tmp_path)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        g = shapes_of(urdf(f'<mesh filename="cube.stl" scale="{scale}"/>'), tmp_path, mesh_spheres=3)
    assert 1 <= len(g.shapes) <= 3
    s = np.array([float(v) for v in scale.split()])
    P = box_points([0.1, 0.2, 0.3]) * s
    C = np.array([x.center for x in g.shapes])
    R = np.array([x.radius for x in g.shapes])
    assert (np.linalg.norm(P[:, None] - C[None], axis=2) <= R + 1e-12).any(1).all()


def test_fit_spheres_names_an_empty_mesh_file(tmp_path):
    pytest.importorskip("trimesh")
    (tmp_path / "empty.stl").write_bytes(b"")
    with pytest.raises(GeometryError, match="empty.stl"):
        fit_spheres(str(tmp_path / "empty.stl"), 3)
