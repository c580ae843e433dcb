"""``symkin bench reach``: reachability maps on Dask against plain batch IK, in one run.

Measures on the same map (a UR5 by default, 0.1 m voxels, 50 orientations as in the CLI, 64 blocks):

1. plain batch IK: one ``kin.ik`` call on every (voxel centre, orientation) target of the map, in
   this process (one core): the throughput the map's overhead is compared with;
2. the map on a local Dask cluster of 1 worker, then of 2 workers (clusters started before the
   timer): throughput, speed-up and throughput per core against (1);
3. the same map with another chunk size, compared bit for bit with (2) and (1);
4. with ``fault=True``: the map on 2 workers with one worker killed (SIGKILL) after the first
   blocks; the nanny restarts it, the scheduler reruns its tasks, the map is compared with (2).

and extrapolates the cost of a 1 cm map of the same robot from the measured time per IK problem.
The three are run ``repeat`` times, alternating, and the best wall times are kept. Wall times
suffer when other processes share the cores, so the CPU time of every process of the map (the
client with its scheduler thread, and the workers) is measured too and compared with the CPU
time of batch IK. The machine's load average is printed.
"""

from __future__ import annotations

import math
import os
import signal
import time
from typing import Any

import numpy as np

__all__ = ["run_reach", "format_reach", "ball_voxels"]


def ball_voxels(radius: float, resolution: float) -> int:
    """Number of grid points ``resolution * i`` (integer i) within ``radius`` of the origin."""
    h = math.ceil(radius / resolution - 1e-9)
    ax = np.arange(-h, h + 1) * resolution
    X, Y = np.meshgrid(ax, ax, indexing="ij")
    r2 = radius**2 - X**2 - Y**2
    zmax = np.floor(np.sqrt(np.maximum(r2, 0.0)) / resolution + 1e-9)
    return int(np.where(r2 >= 0, 2 * zmax + 1, 0).sum())


def _targets(kin: Any, resolution: float, orientations: int, seed: int) -> np.ndarray:
    from symkin.workspace.grid import VoxelGrid, reach_ball, so3_uniform

    centre, radius = reach_ball(kin.robot)
    grid = VoxelGrid.of(centre, radius, resolution)
    C = grid.centers().reshape(-1, 3)
    C = C[grid.inside(C)]
    R = so3_uniform(orientations, seed)
    T = np.zeros((len(C), len(R), 4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = C[:, None]
    T[..., 3, 3] = 1.0
    return T.reshape(-1, 4, 4)


def _process_cpu() -> float:
    import psutil

    t = psutil.Process().cpu_times()
    return float(t.user + t.system)


def _worker_cpu(client: Any) -> float:
    """CPU seconds used so far by the client's worker processes, summed."""
    return float(sum(client.run(_process_cpu).values()))


def _cluster(workers: int) -> Any:
    from symkin.workspace.run import local_cluster

    return local_cluster(workers)


def _same(a: Any, b: Any) -> bool:
    return bool(
        np.array_equal(a.reach, b.reach)
        and np.array_equal(a.manipulability, b.manipulability, equal_nan=True)
        and np.array_equal(a.centers, b.centers)
    )


def run_reach(
    robot: Any,
    resolution: float = 0.1,
    orientations: int = 50,
    seed: int = 0,
    fault: bool = False,
    progress: bool = True,
    repeat: int = 3,
) -> dict[str, Any]:
    """Run the benchmark (module docstring), ``repeat`` times alternating batch IK, 1 worker and 2
    workers; figures are the best of the repeats (medians alongside). Returns them as a dict."""
    import distributed

    from symkin.runtime.load import compile as compile_robot
    from symkin.workspace import reachability
    from symkin.workspace.grid import reach_ball
    from symkin.workspace.maps import MAP_IK_DEFAULTS

    kin = compile_robot(robot, backend="c")
    out: dict[str, Any] = {"robot": kin.name, "resolution": resolution, "orientations": orientations,
                           "cores": os.cpu_count(), "load_before": os.getloadavg()[0]}  # fmt: skip
    T = _targets(kin, resolution, orientations, seed)
    kin.ik(T[:100], seed=seed, **MAP_IK_DEFAULTS)  # warm the solver
    kwargs = {"seed": seed, "chunk": 8, "progress": False}
    times: dict[str, list[float]] = {"batch": [], "workers_1": [], "workers_2": []}
    cpu: dict[str, list[float]] = {key: [] for key in times}
    maps: dict[int, Any] = {}
    with _cluster(1) as c1, distributed.Client(c1) as one, _cluster(2) as c2, distributed.Client(c2) as two:
        for client in (one, two):
            client.run(lambda: compile_robot(kin.robot, backend="c") and None)  # load the kinematics
        for r in range(repeat):  # alternate the three, so a burst of load hits them alike
            c, t = time.process_time(), time.perf_counter()
            res = kin.ik(T, seed=seed, **MAP_IK_DEFAULTS)
            times["batch"].append(time.perf_counter() - t)
            cpu["batch"].append(time.process_time() - c)
            for workers, client in ((1, one), (2, two)):
                c, w = time.process_time(), _worker_cpu(client)
                m = reachability(kin, resolution, orientations, scheduler=client, **kwargs)
                maps[workers], st = m, m.stats or {}
                assert st["problems"] == len(T)
                times[f"workers_{workers}"].append(st["seconds"])
                cpu[f"workers_{workers}"].append(time.process_time() - c + _worker_cpu(client) - w)
            if progress:
                last = ", ".join(f"{k} {v[-1]:.2f} s" for k, v in times.items())
                print(f"  repeat {r + 1}/{repeat}: {last}", flush=True)
    out["batch_solved"] = float(res.success.mean())
    for key, values in times.items():
        best = min(values)
        out[key] = {"problems": len(T), "seconds": best, "median": float(np.median(values)),
                    "all": values, "rate": len(T) / best, "cpu_seconds": min(cpu[key]),
                    "cpu_all": cpu[key]}  # fmt: skip
    # CPU time is what other processes on a shared machine do not inflate (much): all the CPU of
    # the client, the scheduler (same process) and the workers, per problem, against batch IK
    for w in (1, 2):
        out[f"cpu_efficiency_{w}"] = out["batch"]["cpu_seconds"] / out[f"workers_{w}"]["cpu_seconds"]
        out[f"per_core_vs_batch_{w}"] = out[f"workers_{w}"]["rate"] / w / out["batch"]["rate"]
    out["blocks"] = (maps[1].stats or {})["blocks"]
    out["speedup_2_vs_1"] = out["workers_2"]["rate"] / out["workers_1"]["rate"]
    other = reachability(kin, resolution, orientations, seed=seed, chunk=6, workers=2, progress=False)
    out["identical_1_2_workers"] = _same(maps[1], maps[2])
    out["identical_chunk_8_6"] = _same(maps[2], other)
    if fault:
        out["fault"] = _fault_run(kin, resolution, orientations, kwargs, maps[2])
    # cost of a 1 cm map: measured seconds per problem (per core, 2 workers) x problems at 1 cm
    per_problem = out["workers_2"]["seconds"] * 2 / len(T)
    per_problem_median = out["workers_2"]["median"] * 2 / len(T)
    per_problem_cpu = out["workers_2"]["cpu_seconds"] / len(T)
    _, radius = reach_ball(kin.robot)
    voxels = ball_voxels(radius, 0.01)
    out["one_cm"] = {
        "radius": radius,
        "voxels": voxels,
        "seconds_per_problem": per_problem,
        "seconds_per_problem_median": per_problem_median,
        "core_hours": {K: voxels * K * per_problem / 3600 for K in (50, 100)},
        "core_hours_median": {K: voxels * K * per_problem_median / 3600 for K in (50, 100)},
        "cpu_seconds_per_problem": per_problem_cpu,
        "cpu_hours": {K: voxels * K * per_problem_cpu / 3600 for K in (50, 100)},
    }
    out["load_after"] = os.getloadavg()[0]
    return out


def _fault_run(kin: Any, resolution: float, orientations: int, kwargs: dict, reference: Any) -> dict:
    """The 2-worker map with one worker SIGKILLed after the first two blocks are written."""
    import distributed

    from symkin.workspace import reachability

    killed: list[int] = []
    with _cluster(2) as cluster, distributed.Client(cluster) as client:
        pids = list(client.run(os.getpid).values())

        def kill(index: int, result: dict) -> None:
            if len(killed) == 0 and index >= 0:
                seen.append(index)
                if len(seen) >= 2:
                    os.kill(pids[0], signal.SIGKILL)
                    killed.append(pids[0])

        seen: list[int] = []
        t = time.perf_counter()
        m = reachability(kin, resolution, orientations, scheduler=client, on_block=kill, **kwargs)
        seconds = time.perf_counter() - t
        after = sorted(client.run(os.getpid).values())
    return {"killed_pid": killed[0] if killed else None, "seconds": seconds, "complete": m.complete,
            "identical": _same(m, reference), "workers_after": len(after)}  # fmt: skip


def format_reach(r: dict[str, Any]) -> str:
    b, w1, w2 = r["batch"], r["workers_1"], r["workers_2"]
    lines = [
        f"symkin bench reach: {r['robot']}, {r['resolution']:g} m voxels, {r['orientations']} orientations, "
        f"{r['cores']} cores (load average {r['load_before']:.2f} before, {r['load_after']:.2f} after)",
        f"best of {len(b['all'])} runs (median in brackets); other processes on the machine slow them",
        f"plain batch IK, 1 core:  {b['problems']} problems in {b['seconds']:.2f} s ({b['median']:.2f}) = "
        f"{b['rate']:,.0f}/s ({r['batch_solved']:.1%} solved)",
        f"map, 1 Dask worker:      {w1['problems']} problems in {w1['seconds']:.2f} s ({w1['median']:.2f}) = "
        f"{w1['rate']:,.0f}/s ({r['blocks']} blocks)",
        f"map, 2 Dask workers:     {w2['problems']} problems in {w2['seconds']:.2f} s ({w2['median']:.2f}) = "
        f"{w2['rate']:,.0f}/s",
        f"speed-up 2 vs 1 workers: {r['speedup_2_vs_1']:.2f}x (goal >= 1.7x)",
        f"throughput per core vs plain batch IK: {r['per_core_vs_batch_1']:.0%} (1 worker), "
        f"{r['per_core_vs_batch_2']:.0%} (2 workers) (goal >= 80%)",
        f"CPU time (client + scheduler + workers) per problem, batch IK / map: {r['cpu_efficiency_1']:.0%} "
        f"(1 worker), {r['cpu_efficiency_2']:.0%} (2 workers); batch {b['cpu_seconds']:.2f} s, maps "
        f"{w1['cpu_seconds']:.2f} s, {w2['cpu_seconds']:.2f} s of CPU",
        f"same map bit for bit: 1 vs 2 workers {r['identical_1_2_workers']}, "
        f"chunk 8 vs 6 {r['identical_chunk_8_6']}",
    ]
    if "fault" in r:
        f = r["fault"]
        lines.append(
            f"worker killed mid-run (pid {f['killed_pid']}): complete {f['complete']}, "
            f"identical {f['identical']}, {f['seconds']:.2f} s, {f['workers_after']} workers after"
        )
    c = r["one_cm"]
    lines.append(
        f"1 cm map (extrapolated): {c['voxels']:,} voxels in the {c['radius']:.3f} m ball x K orientations "
        f"at {c['seconds_per_problem'] * 1e6:.1f} us per problem per core = "
        + ", ".join(f"{h:,.1f} core-hours for K = {K}" for K, h in c["core_hours"].items())
        + " (medians: "
        + ", ".join(f"{h:,.1f}" for h in c["core_hours_median"].values())
        + f"); from CPU time ({c['cpu_seconds_per_problem'] * 1e6:.1f} us per problem): "
        + ", ".join(f"{h:,.1f}" for h in c["cpu_hours"].values())
        + " CPU-hours"
    )
    return "\n".join(lines)
