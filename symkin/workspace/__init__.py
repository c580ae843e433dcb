"""Workspace maps and datasets beyond one machine, on Dask (the ``scale`` extra: dask, zarr).

- :func:`reachability`: per voxel of the reachable ball, the fraction of a fixed set of
  orientations IK solves, the best manipulability, and optionally one solution per orientation;
- :func:`samples`: (q, pose) datasets for learning.

Both split the work into blocks that run as Dask tasks (a local cluster by default, or
``scheduler="tcp://host:8786"``), write Zarr stores that a stopped run resumes from, and give the
same result bit for bit whatever the number of workers or the chunk size.
"""

from symkin.workspace.datasets import Dataset, open_dataset, samples
from symkin.workspace.grid import reach_ball, so3_uniform
from symkin.workspace.maps import MAP_IK_DEFAULTS, ReachMap, open_map, reachability
from symkin.workspace.plot import plot_slice

__all__ = [
    "MAP_IK_DEFAULTS",
    "Dataset",
    "ReachMap",
    "open_dataset",
    "open_map",
    "plot_slice",
    "reach_ball",
    "reachability",
    "samples",
    "so3_uniform",
]
