"""``symkin reach`` and ``symkin dataset``: the scale extra's commands."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from symkin.cli.main import main

PLANAR = "Rz(q) tx(0.6) Rz(q) tx(0.25) Rz(q) tx(0.15)"


def test_reach_without_the_scale_extra_names_it_and_exits_2(monkeypatch, capsys, tmp_path):
    monkeypatch.setitem(sys.modules, "zarr", None)  # `import zarr` now fails as if not installed
    monkeypatch.setitem(sys.modules, "distributed", None)
    assert main(["reach", "ur5", "-o", str(tmp_path / "m.zarr")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'pip install "symkin[scale]"' in err[0]
    assert main(["dataset", "ur5", "-n", "10", "-o", str(tmp_path / "d.zarr")]) == 2
    assert 'pip install "symkin[scale]"' in capsys.readouterr().err
    assert main(["bench", "reach"]) == 2
    assert 'pip install "symkin[scale]"' in capsys.readouterr().err
    assert not (tmp_path / "m.zarr").exists()


def test_reach_and_dataset_commands_write_stores_and_a_plot(tmp_path, capsys):
    zarr = pytest.importorskip("zarr")
    pytest.importorskip("distributed")
    store, png = tmp_path / "map.zarr", tmp_path / "slice.png"
    args = ["reach", PLANAR, "--resolution", "0.25", "--orientations", "4", "-o", str(store),
            "--scheduler", "synchronous", "--axes", "0 1 5", "--plot", str(png)]  # fmt: skip
    assert main(args) == 0
    out = capsys.readouterr().out
    assert "9x9x9 voxels of 0.25 m, 4 orientations" in out and "plot written" in out
    assert png.stat().st_size > 10_000 and png.read_bytes()[:4] == b"\x89PNG"
    group = zarr.open_group(str(store), mode="r")
    assert {"reach", "manipulability", "centers"} <= set(group.array_keys())
    assert group["centers"].shape == (9, 9, 9, 3) and dict(group.attrs)["settings"]["orientations"] == 4
    reach = group["reach"][...]
    assert ((reach >= 0) & (reach <= 1)).all()
    assert main([*args[:-2], "--json"]) == 0  # resumes: nothing left to compute
    assert '"computed": 0' in capsys.readouterr().out
    assert main([*args[:-2], "--seed", "1"]) == 2  # another map in the same store
    assert "holds a different reachability" in capsys.readouterr().err
    assert main(["dataset", PLANAR, "-n", "100", "--chunk", "30", "-o", str(tmp_path / "d.zarr"),
                 "--scheduler", "synchronous"]) == 0  # fmt: skip
    assert "100 (q, pose) samples" in capsys.readouterr().out
    data = zarr.open_group(str(tmp_path / "d.zarr"), mode="r")
    assert data["q"].shape == (100, 3) and np.isfinite(data["pose"][...]).all()
    assert main(["reach", PLANAR, "-o", str(store), "--resolution", "0", "--scheduler", "synchronous"]) == 2
    assert "--resolution: must be a positive" in capsys.readouterr().err


def test_reach_collision_maps_only_collision_free_reach(tmp_path, capsys):
    zarr = pytest.importorskip("zarr")
    pytest.importorskip("distributed")
    base = ["reach", "ur5", "--resolution", "0.3", "--orientations", "2", "--slimit", "3", "--scheduler",
            "synchronous", "--bounds", "0.2 0.6 -0.3 0.3 0.0 0.4", "--json"]  # fmt: skip
    assert main([*base, "-o", str(tmp_path / "plain.zarr")]) == 0
    plain = zarr.open_group(str(tmp_path / "plain.zarr"), mode="r")["reach"][...]
    capsys.readouterr()
    wall = ["--collision", "--box", "0.4 0 0.2 0.3 0.4 0.25"]
    assert main([*base, "-o", str(tmp_path / "free.zarr"), *wall]) == 0
    group = zarr.open_group(str(tmp_path / "free.zarr"), mode="r")
    free = group["reach"][...]
    assert plain.sum() > 0 and free.sum() < plain.sum() and (free <= plain).all()
    assert dict(group.attrs)["settings"]["collision"]["boxes"][0][:6] == [0.4, 0, 0.2, 0.3, 0.4, 0.25]
    capsys.readouterr()
    assert main([*base, "-o", str(tmp_path / "x.zarr"), "--sphere", "0 0 0 0.1"]) == 2
    assert "add --collision" in capsys.readouterr().err
