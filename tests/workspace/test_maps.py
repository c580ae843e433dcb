"""Reachability maps and datasets on Dask (the ``scale`` extra; skipped without it).

The map of a planar 3-link arm is checked against the arm's closed-form workspace: the tool
position reaches the annulus l1 - l2 - l3 <= r <= l1 + l2 + l3, and the tool reaches position p
with heading phi exactly when the wrist p - l3 (cos phi, sin phi) lies in the 2-link annulus
|l1 - l2| <= |w| <= l1 + l2.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("zarr")
distributed = pytest.importorskip("distributed")

import symkin  # noqa: E402
from symkin.errors import WorkspaceError  # noqa: E402
from symkin.model.differential import manipulability_of  # noqa: E402
from symkin.workspace import open_dataset, open_map, reachability, samples  # noqa: E402
from symkin.workspace.run import local_cluster  # noqa: E402

L1, L2, L3 = 0.6, 0.25, 0.15
PLANAR = f"Rz(q) tx({L1}) Rz(q) tx({L2}) Rz(q) tx({L3})"
PHI = 0.1 + 2 * np.pi * np.arange(8) / 8  # headings of the orientation set (rotations about z)
ROWS = (0, 1, 5)  # vx, vy, wz: the planar Jacobian
SETTINGS = {
    "resolution": 0.1,
    "orientations": np.array(
        [[[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]] for a in PHI]
    ),
    "bounds": [[-1.1, 1.1], [-1.1, 1.1], [-0.01, 0.01]],  # the plane z = 0 of the arm
    "axes": ROWS,
    "seed": 5,
}


@pytest.fixture(scope="module")
def robot():
    return symkin.Robot.from_ets(PLANAR, name="planar3")


@pytest.fixture(scope="module")
def kin(robot):
    return symkin.compile(robot)


@pytest.fixture(scope="module")
def client():
    with local_cluster(2) as cluster, distributed.Client(cluster) as c:
        yield c


@pytest.fixture(scope="module")
def cluster_map(kin, client):
    return reachability(kin, solutions=True, chunk=5, scheduler=client, progress=False, **SETTINGS)


def test_planar_map_on_two_workers_matches_the_closed_form_workspace(cluster_map, robot):
    m = cluster_map
    assert m.complete and m.reach.shape == (21, 21, 1) and m.stats["computed"] == m.stats["blocks"] == 25
    p = m.centers[..., :2]
    r = np.linalg.norm(p, axis=-1)
    inner, outer = L1 - L2 - L3, L1 + L2 + L3
    assert (m.reach[r < inner - 1e-9] == 0).all() and (m.reach[r > outer + 1e-9] == 0).all()
    assert (m.reach[(r > inner + 0.1) & (r < outer - 0.1)] > 0).all()
    # per orientation: solved exactly where the wrist is in the 2-link annulus (away from its rims)
    heading = np.stack((np.cos(PHI), np.sin(PHI)), -1)
    wrist = np.linalg.norm(p[..., None, :] - L3 * heading, axis=-1)  # (21, 21, 1, 8)
    expected = (wrist >= abs(L1 - L2)) & (wrist <= L1 + L2) & (r[..., None] <= outer)
    rim = np.minimum(np.abs(wrist - abs(L1 - L2)), np.abs(wrist - (L1 + L2))) < 0.02
    solved = np.isfinite(m.solutions[...]).all(axis=-1)
    assert (solved == expected)[~rim].all()
    assert np.array_equal(m.reach, solved.mean(axis=-1))
    # every stored solution reaches its target (numeric ETS reference) within 1 um
    Q = m.solutions[...][solved]
    T = robot.fkine(Q)
    targets = np.broadcast_to(m.centers[..., None, :], (*solved.shape, 3))[solved]
    assert np.abs(T[:, :3, 3] - targets).max() < 1e-6
    heading_of = np.arctan2(T[:, 1, 0], T[:, 0, 0])
    want = np.broadcast_to(PHI, solved.shape)[solved]
    assert np.abs(np.angle(np.exp(1j * (heading_of - want)))).max() < 1e-6
    # best manipulability = max over the solutions of |det J| (vx, vy, wz rows; = l1 l2 |sin q2|)
    m_ref = manipulability_of(robot.jacob0(Q)[:, list(ROWS)])
    assert np.allclose(m_ref, L1 * L2 * np.abs(np.sin(Q[:, 1])), atol=1e-12)
    best = np.full(solved.shape, np.nan)
    best[solved] = m_ref
    with np.errstate(all="ignore"):
        best = np.nanmax(np.where(solved, best, -np.inf), axis=-1)
    best[~solved.any(-1)] = np.nan
    assert np.allclose(m.manipulability, best, rtol=1e-9, atol=0, equal_nan=True)
    assert m.attrs["robot"]["name"] == "planar3" and m.attrs["seed"] == 5
    assert m.attrs["symkin_version"] == symkin.__version__ and m.attrs["settings"]["resolution"] == 0.1


def test_same_map_bit_for_bit_with_one_worker_and_other_chunks(cluster_map, kin):
    with local_cluster(1) as cluster, distributed.Client(cluster) as c:
        one = reachability(kin, chunk=3, scheduler=c, progress=False, **SETTINGS)
    here = reachability(kin, chunk=8, scheduler="synchronous", progress=False, **SETTINGS)
    for other in (one, here):
        assert np.array_equal(other.reach, cluster_map.reach)
        assert np.array_equal(other.manipulability, cluster_map.manipulability, equal_nan=True)
        assert np.array_equal(other.centers, cluster_map.centers)


def test_an_interrupted_map_resumes_from_its_written_blocks(cluster_map, kin, tmp_path):
    path = tmp_path / "map.zarr"
    written = []

    def stop_after_three(index, result):
        written.append(index)
        if len(written) == 3:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        reachability(kin, chunk=5, output=path, scheduler="synchronous", on_block=stop_after_three,
                     progress=False, **SETTINGS)  # fmt: skip
    partial = open_map(path)
    assert not partial.complete
    resumed = reachability(kin, chunk=7, output=path, scheduler="synchronous", progress=False, **SETTINGS)
    assert resumed.stats["skipped"] == 3 and resumed.stats["computed"] == 22  # the store keeps chunk 5
    assert resumed.complete and np.array_equal(resumed.reach, cluster_map.reach)
    assert np.array_equal(resumed.manipulability, cluster_map.manipulability, equal_nan=True)
    again = reachability(kin, output=path, scheduler="synchronous", progress=False, **SETTINGS)
    assert again.stats["computed"] == 0 and np.array_equal(again.reach, cluster_map.reach)
    # a store holds one map: other settings are refused, overwrite replaces it
    with pytest.raises(WorkspaceError, match="seed"):
        reachability(kin, output=path, scheduler="synchronous", progress=False, **{**SETTINGS, "seed": 6})
    fresh = reachability(kin, output=path, scheduler="synchronous", progress=False, overwrite=True,
                         **{**SETTINGS, "resolution": 0.25})  # fmt: skip
    assert fresh.reach.shape == (9, 9, 1)
    # a store whose creation was interrupted (symkin's mark and arrays, no attributes yet) is made afresh
    import zarr

    from symkin.workspace.store import MARK

    half_made = tmp_path / "half.zarr"
    zarr.open_group(str(half_made), mode="w", attributes={MARK: 1}).create_array(
        "done", shape=(2,), dtype="bool"
    )
    remade = reachability(kin, output=half_made, scheduler="synchronous", progress=False, **SETTINGS)
    assert remade.complete and np.array_equal(remade.reach, cluster_map.reach)


def test_datasets_are_independent_of_chunks_and_append(robot, kin, client, tmp_path):
    whole = samples(kin, 1000, chunk=300, scheduler=client, progress=False, seed=2)
    assert whole.complete and len(whole) == 1000
    q = whole.q[...]
    assert ((q >= robot.qlim[0]) & (q <= robot.qlim[1])).all()
    assert np.abs(whole.pose[...] - robot.fkine(q)).max() < 1e-12  # numeric ETS reference
    path = tmp_path / "data.zarr"
    first = samples(kin, 400, chunk=128, output=path, scheduler="synchronous", progress=False, seed=2)
    assert np.array_equal(first.q[...], q[:400])
    grown = samples(kin, 1000, output=path, scheduler="synchronous", progress=False, seed=2)
    assert grown.stats["skipped"] == 3 and grown.stats["computed"] == 5  # block 3 (16 rows) is redone
    assert np.array_equal(open_dataset(path).q[...], q) and np.array_equal(grown.pose[...], whole.pose[...])
    with pytest.raises(WorkspaceError, match="already holds 1000"):
        samples(kin, 10, output=path, scheduler="synchronous", progress=False, seed=2)


def test_bad_settings_are_clear_errors(kin):
    bad = [
        {"resolution": -0.1},
        {"orientations": 0},
        {"orientations": np.ones((2, 3, 3))},
        {"bounds": [[5, 6], [0, 1], [0, 1]]},
        {"axes": (0, 7)},
        {"ik_options": {"seed": 1}},
        {"ik_options": {"slimit": 0}},
        {"scheduler": 42},
    ]
    for kwargs in bad:
        with pytest.raises((WorkspaceError, ValueError)):
            reachability(kin, **{"scheduler": "synchronous", "progress": False, **kwargs})
    import dask

    with (
        dask.config.set({"distributed.comm.timeouts.connect": "1s"}),
        pytest.raises(WorkspaceError, match="cannot reach the Dask scheduler"),
    ):
        reachability(kin, 0.5, 2, scheduler="tcp://127.0.0.1:1", progress=False)


def test_a_worker_killed_mid_run_does_not_change_the_map(cluster_map, kin, client):
    import os
    import signal

    pids = list(client.run(os.getpid).values())
    killed = []

    written: list[int] = []

    def kill_after_two(index, result):
        written.append(index)
        if len(written) == 2:
            os.kill(pids[0], signal.SIGKILL)  # the nanny restarts it; the scheduler reruns its tasks
            killed.append(pids[0])

    m = reachability(kin, chunk=4, scheduler=client, progress=False, on_block=kill_after_two, **SETTINGS)
    assert killed and m.complete and m.stats["computed"] == m.stats["blocks"] == 36
    assert np.array_equal(m.reach, cluster_map.reach)
    assert np.array_equal(m.manipulability, cluster_map.manipulability, equal_nan=True)


def test_position_only_map_of_a_spatial_arm_with_translational_manipulability():
    """IK weights ignore orientation (we = 1 1 1 0 0 0); manipulability of the translation rows
    comes from the compiled kinematics and is checked against the numeric reference."""
    robot = symkin.Robot.from_ets("Rz(q) tz(0.3) Ry(q) tx(0.4) Ry(q) tx(0.3)", name="spatial3")
    m = reachability(robot, 0.2, 2, axes="trans", ik_options={"we": (1, 1, 1, 0, 0, 0)}, solutions=True,
                     scheduler="synchronous", progress=False)  # fmt: skip
    solved = np.isfinite(m.solutions[...]).all(axis=-1)
    r = np.linalg.norm(m.centers - [0, 0, 0.3], axis=-1)
    assert (m.reach[r > 0.7 + 1e-9] == 0).all() and (m.reach[(r > 0.15) & (r < 0.6)] == 1).all()
    Q = m.solutions[...][solved]
    assert (
        np.abs(
            robot.fkine(Q)[:, :3, 3] - np.broadcast_to(m.centers[..., None, :], (*solved.shape, 3))[solved]
        ).max()
        < 1e-6
    )
    ref = np.full(solved.shape, -np.inf)
    ref[solved] = manipulability_of(robot.jacob0(Q)[:, :3])
    best = np.where(solved.any(-1), ref.max(-1), np.nan)
    # near a singularity sqrt(det) loses digits differently in C and in numpy.linalg.det: 1e-10
    assert np.allclose(m.manipulability, best, rtol=1e-9, atol=1e-10, equal_nan=True)
    assert np.nanmax(m.manipulability) > 0.05


def test_collision_free_map_counts_only_collision_free_solutions(robot, client):
    links = (("link1", L1), ("link2", L2), ("link3", L3))
    geometry = symkin.Geometry(
        tuple(symkin.Capsule((0, 0, 0), (length, 0, 0), 0.03, k) for k, length in links)
    )
    arm = robot.with_geometry(geometry)
    wall = symkin.Environment(spheres=(symkin.Sphere((0.45, 0.45, 0.0), 0.12),))
    common = dict(SETTINGS, solutions=True, scheduler="synchronous", progress=False)
    plain = reachability(arm, **common)
    free = reachability(arm, collision=wall, **common)
    assert (free.reach <= plain.reach + 1e-12).all()
    assert free.reach.sum() < plain.reach.sum()  # the wall takes reach away
    assert free.attrs["settings"]["collision"]["spheres"] == [[0.45, 0.45, 0.0, 0.12]]
    kin = symkin.compile(arm)
    Q = np.asarray(free.solutions)[np.isfinite(np.asarray(free.solutions)).all(axis=-1)]
    assert len(Q) and not kin.in_collision(Q, wall).any()
    Qp = np.asarray(plain.solutions)[np.isfinite(np.asarray(plain.solutions)).all(axis=-1)]
    assert kin.in_collision(Qp, wall).any()  # without collision=, some solutions go through the wall
    centre = np.linalg.norm(np.asarray(free.centers)[..., :2] - [0.45, 0.45], axis=-1) < 0.1
    assert (free.reach[centre] == 0).all()
    on_workers = reachability(arm, collision=wall, **dict(common, scheduler=client, chunk=5))
    assert np.array_equal(on_workers.reach, free.reach)  # the obstacles travel to the workers intact
    with pytest.raises(symkin.GeometryError, match="no collision geometry"):
        reachability(robot, collision=True, **common)


def test_the_local_cluster_listens_on_this_machine_only(client):
    """Issue 36, item 2: Dask's default dashboard address ":0" served the dashboard on every
    interface; the cluster of ``reach`` and ``dataset`` listens on 127.0.0.1 only (scheduler,
    dashboard and workers)."""
    import ipaddress
    from urllib.parse import urlparse

    cluster = client.cluster
    sockets = getattr(cluster.scheduler.http_server, "_sockets", None)
    assert sockets, "no dashboard sockets to check"
    for sock in sockets.values():
        assert ipaddress.ip_address(sock.getsockname()[0]).is_loopback, sock.getsockname()
    addresses = [cluster.scheduler_address, *client.scheduler_info()["workers"]]
    assert all(urlparse(a).hostname == "127.0.0.1" for a in addresses), addresses
    assert urlparse(cluster.dashboard_link).hostname == "127.0.0.1"
