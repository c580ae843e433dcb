"""A slice of a reachability map as a PNG: reachability index and manipulability side by side."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from symkin.errors import MissingExtraError, WorkspaceError

__all__ = ["plot_slice"]

_AXIS = {"x": 0, "y": 1, "z": 2}


def plot_slice(rmap: Any, path: str | Path, axis: str = "z", at: float | None = None) -> Path:
    """Write the slice ``axis = at`` (metres, base frame; default: the plane through the ball's
    centre, snapped to the nearest voxel layer) of a :class:`ReachMap` as a PNG with two panels:
    the reachability index (fraction of orientations solved) and the best manipulability (eq 52,
    blank where no orientation was solved). Returns the path."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise MissingExtraError('plotting a map needs matplotlib: pip install "symkin[plot]"') from None
    if axis not in _AXIS:
        raise WorkspaceError(f"axis must be 'x', 'y' or 'z', not {axis!r}")
    k = _AXIS[axis]
    layer_values = np.moveaxis(rmap.centers[..., k], k, 0)[:, 0, 0]
    target = float(rmap.attrs["settings"]["centre"][k]) if at is None else float(at)
    if not np.isfinite(layer_values).any():
        raise WorkspaceError("the map has no written voxels to plot")
    i = int(np.nanargmin(np.abs(layer_values - target)))
    if abs(layer_values[i] - target) > rmap.resolution:
        lo, hi = np.nanmin(layer_values), np.nanmax(layer_values)
        raise WorkspaceError(f"{axis} = {target:g} m is outside the map ({lo:g} .. {hi:g} m)")
    reach = np.take(rmap.reach, i, axis=k)
    manip = np.take(rmap.manipulability, i, axis=k)
    centers = np.take(rmap.centers, i, axis=k)
    u, v = [a for a in range(3) if a != k]
    names = "xyz"
    h = rmap.resolution / 2
    extent = (
        np.nanmin(centers[..., u]) - h, np.nanmax(centers[..., u]) + h,
        np.nanmin(centers[..., v]) - h, np.nanmax(centers[..., v]) + h,
    )  # fmt: skip
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.8))
    robot = rmap.attrs["robot"]["name"]
    for ax, data, label, vmax in (
        (axes[0], reach, "reachability index", 1.0),
        (axes[1], manip, "best manipulability", None),
    ):
        im = ax.imshow(np.asarray(data).T, origin="lower", extent=extent, vmin=0.0, vmax=vmax,
                       cmap="viridis", interpolation="nearest")  # fmt: skip
        ax.set_xlabel(f"{names[u]} (m)")
        ax.set_ylabel(f"{names[v]} (m)")
        ax.set_title(label)
        ax.set_aspect("equal")
        fig.colorbar(im, ax=ax, shrink=0.85)
    K = len(rmap.rotations)
    fig.suptitle(f"{robot}: slice {names[k]} = {layer_values[i]:.3f} m, {rmap.resolution:g} m voxels, "
                 f"{K} orientations")  # fmt: skip
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
