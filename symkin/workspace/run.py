"""Running blocks as Dask tasks and writing their results as they complete.

``scheduler`` selects where the tasks run:

- ``None``: a ``distributed.LocalCluster`` started for the run, one single-threaded worker
  process per core (``workers=`` to choose), closed afterwards; it listens on this machine only
  (127.0.0.1: its scheduler, workers and dashboard, :func:`local_cluster`);
- ``"tcp://host:8786"`` (any scheduler address): an existing cluster, of one or many machines;
- a ``distributed.Client``: that client's cluster, left open;
- ``"synchronous"``: no Dask at all, the blocks run one after another in this process.

Each block is one task (``Client.submit``); the client collects the results with
``as_completed`` and writes them, so workers need no access to the store. A worker that dies
mid-task has its tasks rerun elsewhere by the scheduler (tasks are pure functions of their block).

A task costs the client and scheduler a few milliseconds of CPU (about 5 ms measured on the 2-core
development machine, whose scheduler shares the client's process), so blocks should hold seconds
of work: the default block edges (up to 16 voxels) give thousands of IK problems per task.
"""

from __future__ import annotations

import logging
import os
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from typing import Any

from symkin.errors import MissingExtraError, WorkspaceError
from symkin.workspace.store import SCALE_HINT

__all__ = ["client_for", "local_cluster", "require_scale", "run_blocks"]


def _distributed() -> Any:
    try:
        import distributed
    except ImportError:
        raise MissingExtraError(f"workspace maps and datasets need dask and zarr: {SCALE_HINT}") from None
    return distributed


def require_scale(scheduler: Any = None) -> None:
    """Raise MissingExtraError (naming ``symkin[scale]``) unless zarr, and dask unless
    ``scheduler="synchronous"``, are installed."""
    from symkin.workspace.store import zarr_module

    zarr_module()
    if not (isinstance(scheduler, str) and scheduler == "synchronous"):
        _distributed()


@contextmanager
def client_for(scheduler: Any = None, workers: int | None = None) -> Iterator[Any]:
    """A ``distributed.Client`` for ``scheduler`` (see the module docstring), or None for
    ``"synchronous"``. Clusters and clients made here are closed on exit."""
    if isinstance(scheduler, str) and scheduler == "synchronous":
        yield None
        return
    distributed = _distributed()
    if isinstance(scheduler, distributed.Client):
        yield scheduler
        return
    if scheduler is None:
        count = int(workers) if workers is not None else (os.cpu_count() or 1)
        if count < 1:
            raise WorkspaceError(f"workers must be >= 1, got {workers}")
        cluster = local_cluster(count)
        try:
            with distributed.Client(cluster) as client:
                yield client
        finally:
            cluster.close()
        return
    if not isinstance(scheduler, str):
        raise WorkspaceError(
            f"scheduler must be None, 'synchronous', an address like 'tcp://host:8786' or a "
            f"distributed.Client, not {type(scheduler).__name__}"
        )
    try:
        client = distributed.Client(scheduler)  # connect timeout: distributed.comm.timeouts.connect
    except (OSError, TimeoutError, ValueError) as exc:
        raise WorkspaceError(f"cannot reach the Dask scheduler at {scheduler}: {exc}") from None
    try:
        yield client
    finally:
        client.close()


def local_cluster(workers: int) -> Any:
    """A ``distributed.LocalCluster`` of ``workers`` single-threaded worker processes that listens
    on 127.0.0.1 only: Dask's default dashboard address ``":0"`` serves on every interface."""
    return _distributed().LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        host="127.0.0.1",
        dashboard_address="127.0.0.1:0",
        silence_logs=logging.ERROR,
    )


def run_blocks(
    fn: Callable[..., dict[str, Any]],
    args: tuple[Any, ...],
    todo: Sequence[int],
    write: Callable[[int, dict[str, Any]], None],
    client: Any,
    *,
    total: int,
    progress: bool | None = None,
    on_block: Callable[[int, dict[str, Any]], None] | None = None,
    desc: str = "blocks",
) -> dict[str, float]:
    """Run ``fn(*args, i)`` for each block ``i`` of ``todo`` and ``write(i, result)`` as each one
    completes (in completion order). ``progress`` (default: stderr is a terminal) shows a tqdm bar
    over all ``total`` blocks; ``on_block(i, result)`` is called after each write.

    Returns ``{"seconds": wall time, "task_seconds": sum of the tasks' own times, "problems": ...}``.
    """
    from tqdm import tqdm

    if progress is None:
        progress = sys.stderr.isatty()
    stats = {"seconds": 0.0, "task_seconds": 0.0, "problems": 0.0}
    t0 = time.perf_counter()
    bar = tqdm(total=total, initial=total - len(todo), disable=not progress, desc=desc, unit="block")

    def done(i: int, result: dict[str, Any]) -> None:
        write(i, result)
        stats["task_seconds"] += float(result.get("seconds", 0.0))
        stats["problems"] += float(result.get("problems", 0))
        bar.update(1)
        if on_block is not None:
            on_block(i, result)

    try:
        if client is None:
            for i in todo:
                done(i, fn(*args, i))
        else:
            distributed = _distributed()
            futures = {client.submit(fn, *args, i, pure=False): i for i in todo}
            try:
                for future in distributed.as_completed(futures):
                    done(futures[future], future.result())
                    future.release()
            except BaseException:
                client.cancel([f for f in futures if not f.done()])
                raise
    finally:
        bar.close()
        stats["seconds"] = time.perf_counter() - t0
    return stats
