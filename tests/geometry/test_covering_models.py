"""The stored covering models of the built-in arms against their real collision meshes (the URDFs
of example-robot-data and rtb-data: the ``meshes`` extra; skipped without it).

- Coverage: every one of 20 000 surface points drawn per mesh (plus its vertices; the Panda's
  fingers anywhere along their travel), independently of the fit, lies inside a sphere of its
  link: 100 %, not 99 %.
- Placement: the meshes sit on symkin's link frames where Pinocchio's own URDF reader and forward
  kinematics put them at random configurations (with the ``compare`` extra).
- The store: its figures within the excess, and one link refit from the meshes to the same spheres.
"""

from __future__ import annotations

import importlib.metadata
import json

import numpy as np
import pytest

import symkin
from symkin.model.builtin_geometry import COVERING, DEFAULT_EXCESS, STORE

pytest.importorskip("trimesh")


def _installed(dist: str) -> bool:
    try:
        importlib.metadata.distribution(dist)
    except importlib.metadata.PackageNotFoundError:
        return False
    return True


DIST = {"panda": "example-robot-data", "ur3": "example-robot-data", "ur5": "example-robot-data",
        "ur10": "example-robot-data", "lbr_iiwa14": "rtb-data"}  # fmt: skip
ROBOTS = [
    pytest.param(n, marks=pytest.mark.skipif(not _installed(DIST[n]), reason=f"needs {DIST[n]}"))
    for n in COVERING
]


@pytest.fixture(scope="module")
def parts():
    from symkin.geometry.mesh_fit import builtin_parts

    cache = {}

    def get(name):
        if name not in cache:
            cache[name] = builtin_parts(name)
        return cache[name]

    return get


@pytest.mark.parametrize("name", ROBOTS)
def test_every_mesh_point_is_inside_a_sphere_of_its_link(name, parts):
    from symkin.geometry.mesh_fit import coverage

    robot = symkin.load(name)
    meshes, slack, _ = parts(name)
    cov = coverage(robot.geometry, meshes, samples=20_000, seed=123)
    assert set(cov) >= {f"link{k}" for k in range(1, robot.n + 1)} | {"base"}
    for link, (fraction, worst, n) in cov.items():
        assert n >= 20_000
        assert fraction == 1.0 and worst <= 0, (name, link, fraction, worst)


@pytest.mark.parametrize("name", ROBOTS)
def test_meshes_land_where_pinocchio_puts_the_urdf_links(name, parts):
    """Each placed mesh, moved by symkin's link poses, against the same mesh file read again and
    moved by Pinocchio's forward kinematics of the URDF (its own parser) at random configurations."""
    pin = pytest.importorskip("pinocchio")
    from symkin.geometry.builtin_meshes import MESH_SOURCES, locate
    from symkin.geometry.meshes import box_triangles, read_mesh

    source = MESH_SOURCES[name]
    path, _ = locate(source)
    model = pin.buildModelFromUrdf(str(path))
    data = model.createData()
    robot = symkin.load(name)
    meshes, slack, _ = parts(name)
    B = np.eye(4)
    B[:2, :2] = [
        [np.cos(source.base_yaw), -np.sin(source.base_yaw)],
        [np.sin(source.base_yaw), np.cos(source.base_yaw)],
    ]
    # each URDF collision element: its raw vertices and its pose in the URDF link frame
    from xml.etree import ElementTree

    from symkin.model.transform import rpy_matrix

    raw = {}
    for lel in ElementTree.parse(path).getroot().findall("link"):
        for cel in lel.findall("collision"):
            g = cel.find("geometry")[0]
            o = cel.find("origin")
            xyz = [float(v) for v in (o.get("xyz", "0 0 0") if o is not None else "0 0 0").split()]
            rpy = [float(v) for v in (o.get("rpy", "0 0 0") if o is not None else "0 0 0").split()]
            if g.tag == "box":
                T = box_triangles(np.array([float(v) for v in g.get("size").split()]) / 2)
            else:
                T = read_mesh(
                    next(p.file for p in meshes if p.file.endswith(g.get("filename").split("/")[-1]))
                )
            M = rpy_matrix(xyz, rpy)
            raw.setdefault(lel.get("name"), []).append(T.reshape(-1, 3) @ M[:3, :3].T + M[:3, 3])
    seen = {}
    rng = np.random.default_rng(5)
    for q in robot.random_q(5, seed=2):
        opening = float(rng.uniform(0, 0.04))
        qp = np.zeros(model.nq)
        qp[: robot.n] = q
        if model.nq > robot.n:
            qp[robot.n :] = opening
        pin.framesForwardKinematics(model, data, qp)
        L = {
            "base": np.eye(4),
            "ee": robot.fkine(q),
            **{f"link{k + 1}": T for k, T in enumerate(robot.link_poses(q))},
        }
        seen.clear()
        for p in meshes:
            k = seen.get(p.urdf_link, 0)
            seen[p.urdf_link] = k + 1
            ours = p.triangles.reshape(-1, 3)
            if p.stroke is not None:
                ours = ours + opening / 0.04 * p.stroke
            ours = ours @ L[p.link][:3, :3].T + L[p.link][:3, 3]
            oMf = data.oMf[model.getFrameId(p.urdf_link)].homogeneous
            theirs = raw[p.urdf_link][k] @ (B @ oMf)[:3, :3].T + (B @ oMf)[:3, 3]
            err = np.linalg.norm(ours - theirs, axis=1).max()
            assert err <= slack.get(p.link, 0.0) + 1e-9, (name, p.urdf_link, err)


def test_store_holds_every_covering_model_within_its_excess():
    data = json.loads(STORE.read_text())
    assert data["max_excess"] == DEFAULT_EXCESS
    assert set(data["robots"]) == set(COVERING)
    for name, entry in data["robots"].items():
        robot = symkin.load(name)
        assert len(entry["spheres"]) == len(robot.geometry) == sum(r["spheres"] for r in entry["links"])
        for row in entry["links"]:
            # the bound r - d of every sphere, plus the storage rounding (< 3 um) and the slack
            assert row["excess_bound"] <= DEFAULT_EXCESS + row["slack"] + 3e-6, (name, row)
            assert 0 < row["excess_mean_sampled"] <= row["excess_max_sampled"] <= row["excess_bound"] + 1e-6


@pytest.mark.skipif(not _installed("example-robot-data"), reason="needs example-robot-data")
def test_a_refit_gives_the_stored_spheres():
    """The fit is deterministic: the UR5's last link (its smallest cover) refit from the meshes is
    the stored one."""
    from symkin.geometry.mesh_fit import builtin_parts, fit_parts

    meshes, slack, _ = builtin_parts("ur5")
    mine = [p for p in meshes if p.link == "link6"]
    spheres, rows = fit_parts(mine, DEFAULT_EXCESS, slack, progress=False)
    stored = [s for s in symkin.load("ur5").geometry.shapes if s.link == "link6"]
    assert len(spheres) == len(stored)
    for a, b in zip(spheres, stored):
        assert np.allclose(a.center, b.center, atol=1e-9) and abs(a.radius - b.radius) <= 1e-9
