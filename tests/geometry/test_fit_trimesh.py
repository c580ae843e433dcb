"""fit_spheres on real trimesh meshes (the ``geometry`` extra; skipped without trimesh): the spheres
contain the whole surface, checked on points sampled independently of the fit."""

from __future__ import annotations

import numpy as np
import pytest

trimesh = pytest.importorskip("trimesh")

from symkin.geometry import fit_spheres  # noqa: E402


@pytest.mark.parametrize(
    "mesh",
    [
        trimesh.creation.box(extents=(0.2, 0.1, 0.4)),  # 12 large triangles
        trimesh.creation.icosphere(subdivisions=2, radius=0.1),
        trimesh.creation.capsule(height=0.3, radius=0.05),
    ],
)
@pytest.mark.parametrize("n", [1, 3, 6])
def test_spheres_contain_the_whole_surface(mesh, n, tmp_path):
    spheres = fit_spheres(mesh, n, seed=2)
    assert len(spheres) == n
    V = trimesh.sample.sample_surface(mesh, 20_000, seed=7)[0]  # not the fit's own samples
    V = np.concatenate([V, mesh.vertices])
    outside = np.min([np.linalg.norm(V - c, axis=1) - r for c, r in spheres], axis=0)
    assert outside.max() <= 0
    path = tmp_path / "part.stl"
    mesh.export(path)
    again = fit_spheres(str(path), n, seed=2)  # a file read with trimesh
    assert len(again) == n


def test_more_spheres_hug_a_long_part_closer():
    capsule = trimesh.creation.capsule(height=0.4, radius=0.05)
    one, six = fit_spheres(capsule, 1), fit_spheres(capsule, 6)
    assert max(r for _, r in six) < 0.6 * one[0][1]
