"""Zarr stores of maps and datasets: symkin replaces only a store it wrote (issue 23, item 4), and a
damaged chunk is named on open and computed again on resume (item 5). Skipped without the scale
extra; everything runs with ``scheduler="synchronous"``."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

zarr = pytest.importorskip("zarr")

import symkin  # noqa: E402
from symkin.errors import WorkspaceError  # noqa: E402
from symkin.workspace import open_dataset, open_map, reachability, samples  # noqa: E402
from symkin.workspace.store import MARK  # noqa: E402

PLANAR = "Rz(q) tx(0.6) Rz(q) tx(0.25) Rz(q) tx(0.15)"
PHI = 0.1 + 2 * np.pi * np.arange(4) / 4
MAP = {
    "resolution": 0.1,
    "orientations": np.array(
        [[[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0], [0, 0, 1]] for a in PHI]
    ),
    "bounds": [[-1.1, 1.1], [-1.1, 1.1], [-0.01, 0.01]],  # the plane of the arm: 23 x 23 x 1 voxels
    "axes": (0, 1, 5),
    "seed": 5,
    "chunk": 5,
    "solutions": True,
    "scheduler": "synchronous",
    "progress": False,
}
DATA = {"seed": 2, "chunk": 30, "scheduler": "synchronous", "progress": False}


@pytest.fixture(scope="module")
def kin():
    return symkin.compile(symkin.Robot.from_ets(PLANAR, name="planar3"))


@pytest.fixture(scope="module")
def whole_map(kin):
    return reachability(kin, **MAP)


@pytest.fixture(scope="module")
def whole_data(kin):
    return samples(kin, 100, **DATA)


def files_of(folder: Path) -> dict[str, bytes]:
    return {p.relative_to(folder).as_posix(): p.read_bytes() for p in folder.rglob("*") if p.is_file()}


def user_folder(tmp_path: Path) -> Path:
    folder = tmp_path / "thesis"
    (folder / "figures").mkdir(parents=True)
    (folder / "chapter1.tex").write_text("\\chapter{Kinematics}\n")
    (folder / "figures" / "arm.png").write_bytes(b"\x89PNG not really")
    return folder


# ---- item 4: overwrite only a store symkin wrote ----------------------------------------------
@pytest.mark.parametrize("overwrite", [True, False])
def test_a_folder_of_user_files_is_refused_and_left_untouched(kin, tmp_path, overwrite):
    folder = user_folder(tmp_path)
    before = files_of(folder)
    with pytest.raises(WorkspaceError, match="not a symkin store .*chapter1.tex"):
        samples(kin, 100, output=folder, overwrite=overwrite, **DATA)
    with pytest.raises(WorkspaceError, match="not a symkin store"):
        reachability(kin, output=folder, overwrite=overwrite, **MAP)
    assert files_of(folder) == before


def test_a_file_is_refused_and_left_untouched(kin, tmp_path):
    path = tmp_path / "notes.txt"
    path.write_text("my notes")
    with pytest.raises(WorkspaceError, match="is a file"):
        samples(kin, 100, output=path, overwrite=True, **DATA)
    assert path.read_text() == "my notes"


def test_a_store_another_program_wrote_is_refused_and_left_untouched(kin, tmp_path):
    path = tmp_path / "theirs.zarr"
    theirs = zarr.open_group(str(path), mode="w", attributes={"kind": "dataset", "owner": "lab"})
    theirs.create_array("q", shape=(4, 3), dtype="f8")[...] = np.arange(12.0).reshape(4, 3)
    theirs.create_array("done", shape=(1,), dtype="i8")
    before = files_of(path)
    for overwrite in (True, False):
        with pytest.raises(WorkspaceError, match=f"did not write .*{MARK}"):
            samples(kin, 100, output=path, overwrite=overwrite, **DATA)
    assert files_of(path) == before


def test_a_store_of_symkin_holding_user_files_is_not_overwritten(kin, tmp_path):
    path = tmp_path / "data.zarr"
    samples(kin, 100, output=path, **DATA)
    (path / "notes.txt").write_text("keep me")
    before = files_of(path)
    with pytest.raises(WorkspaceError, match="did not write .*notes.txt"):
        samples(kin, 60, output=path, overwrite=True, **DATA)
    assert files_of(path) == before
    # resuming does not delete anything: it is allowed
    assert samples(kin, 100, output=path, **DATA).stats["computed"] == 0


def test_overwrite_replaces_a_store_of_symkin_and_an_empty_folder_is_used(kin, tmp_path, whole_data):
    empty = tmp_path / "empty"
    empty.mkdir()
    first = samples(kin, 100, output=empty, **DATA)
    assert first.complete and np.array_equal(first.q[...], whole_data.q[...])
    other = samples(kin, 60, output=empty, overwrite=True, **{**DATA, "seed": 3})
    assert len(other) == 60 and other.attrs["seed"] == 3 and other.attrs[MARK] == 1
    # a store written before the mark existed (kind and symkin_version, no mark) is still symkin's
    group = zarr.open_group(str(empty), mode="r+")
    group.attrs.put({k: v for k, v in group.attrs.items() if k != MARK})
    assert len(samples(kin, 30, output=empty, overwrite=True, **DATA)) == 30


def test_a_remote_prefix_of_other_objects_is_refused_and_left_untouched(kin):
    fsspec = pytest.importorskip("fsspec")
    fs = fsspec.filesystem("memory")
    fs.pipe("/symkin-test-23/thesis/chapter1.tex", b"\\chapter{Kinematics}")
    with pytest.raises(WorkspaceError, match="not a symkin store"):
        samples(kin, 100, output="memory://symkin-test-23/thesis", overwrite=True, **DATA)
    assert fs.cat("/symkin-test-23/thesis/chapter1.tex") == b"\\chapter{Kinematics}"
    fs.rm("/symkin-test-23", recursive=True)


# ---- item 5: damaged chunks ---------------------------------------------------------------------
def damage(path: Path) -> None:
    """Truncate a chunk file to half its bytes (what a full disk or a killed copy leaves)."""
    data = path.read_bytes()
    assert len(data) > 8
    path.write_bytes(data[: len(data) // 2])


def written_chunks(store: Path, array: str) -> list[Path]:
    return sorted(p for p in (store / array / "c").rglob("*") if p.is_file())


def test_a_damaged_map_chunk_is_named_on_open_and_recomputed_on_resume(kin, whole_map, tmp_path):
    path = tmp_path / "map.zarr"
    reachability(kin, output=path, **MAP)
    chunk = written_chunks(path, "reach")[3]
    damage(chunk)
    key = "reach/" + chunk.relative_to(path / "reach").as_posix()
    with pytest.raises(WorkspaceError, match=f"chunk {key} cannot be read .*damaged"):
        open_map(path)
    resumed = reachability(kin, output=path, **MAP)
    assert resumed.stats["damaged"] == 1 and resumed.stats["computed"] == 1
    assert np.array_equal(resumed.reach, whole_map.reach)
    assert np.array_equal(resumed.solutions[...], whole_map.solutions[...], equal_nan=True)
    assert open_map(path).complete
    # damaged solutions, manipulability: only their blocks are computed again
    damage(written_chunks(path, "solutions")[0])
    damage(written_chunks(path, "manipulability")[-1])
    resumed = reachability(kin, output=path, **MAP)
    assert resumed.stats["damaged"] == resumed.stats["computed"] == 2
    assert np.array_equal(resumed.manipulability, whole_map.manipulability, equal_nan=True)
    assert np.array_equal(resumed.solutions[...], whole_map.solutions[...], equal_nan=True)


def test_damaged_done_marks_and_grid_arrays_of_a_map(kin, whole_map, tmp_path):
    path = tmp_path / "map.zarr"
    reachability(kin, output=path, **MAP)
    damage(written_chunks(path, "done")[0])
    with pytest.raises(WorkspaceError, match="chunk done/c/0/0/0 cannot be read"):
        open_map(path)
    resumed = reachability(kin, output=path, **MAP)  # which blocks were written is lost: all again
    assert resumed.stats["computed"] == resumed.stats["blocks"] == 25
    assert np.array_equal(resumed.reach, whole_map.reach)
    damage(written_chunks(path, "centers")[0])
    damage(written_chunks(path, "rotations")[0])
    resumed = reachability(kin, output=path, **MAP)
    assert resumed.stats["computed"] == 0
    assert np.array_equal(resumed.centers, whole_map.centers)
    assert np.array_equal(resumed.rotations, whole_map.rotations)


def test_a_damaged_dataset_chunk_is_recomputed_on_resume(kin, whole_data, tmp_path):
    path = tmp_path / "data.zarr"
    samples(kin, 100, output=path, **DATA)
    damage(written_chunks(path, "q")[1])
    damage(written_chunks(path, "pose")[3])
    resumed = samples(kin, 100, output=path, **DATA)
    assert resumed.stats["damaged"] == resumed.stats["computed"] == 2
    assert np.array_equal(resumed.q[...], whole_data.q[...])
    assert np.array_equal(resumed.pose[...], whole_data.pose[...])
    damage(written_chunks(path, "done")[0])
    with pytest.raises(WorkspaceError, match="chunk done/c/0 cannot be read"):
        open_dataset(path)
    resumed = samples(kin, 100, output=path, **DATA)
    assert resumed.stats["computed"] == 4 and resumed.complete
    assert np.array_equal(resumed.q[...], whole_data.q[...])


# ---- issue 36, item 1: what is read back from a store is verified -------------------------------
def flip(path: Path, at: int | None = None) -> None:
    """One bit of one byte changed (the middle one unless ``at``): the file keeps its size."""
    data = bytearray(path.read_bytes())
    k = len(data) // 2 if at is None else at
    data[k] ^= 0x01
    path.write_bytes(bytes(data))


def test_a_flipped_byte_in_a_chunk_is_never_a_wrong_number(kin, whole_data, tmp_path):
    """Random joint values do not compress: a chunk holds them raw, and one flipped bit was a
    different q read back as if computed. Each chunk's CRC-32C makes it a damaged chunk: named on
    open, computed again on resume."""
    path = tmp_path / "data.zarr"
    samples(kin, 100, output=path, **DATA)
    chunk = written_chunks(path, "q")[1]
    flip(chunk, at=len(chunk.read_bytes()) - 40)  # inside the values, before the checksum
    with pytest.raises(WorkspaceError, match="chunk q/c/1/0 cannot be read"):
        _read_all(path)
    resumed = samples(kin, 100, output=path, **DATA)
    assert resumed.stats["damaged"] == resumed.stats["computed"] == 1
    assert np.array_equal(resumed.q[...], whole_data.q[...])


def _read_all(path: Path) -> None:
    """Read every array of the dataset at ``path`` as symkin does (WorkspaceError naming a chunk)."""
    from symkin.workspace.store import open_stored, read_array

    group = open_stored(path, "dataset")
    for name in ("q", "pose", "done"):
        read_array(group[name], str(path))


@pytest.mark.parametrize(
    "where, old, new",
    [
        ("zarr.json", '"seed": 2', '"seed": 3'),  # the attributes: another dataset's settings
        ("q/zarr.json", "[\n    100,", "[\n    101,"),  # the shape: a row that was never computed
        ("done/zarr.json", '"fill_value": 0', '"fill_value": 1'),  # unwritten marks read as written
    ],
)
def test_a_flipped_digit_in_the_metadata_is_refused(kin, tmp_path, where, old, new):
    path = tmp_path / "data.zarr"
    samples(kin, 100, output=path, **DATA)
    meta = path / where
    text = meta.read_text()
    assert text.count(old) == 1, text
    meta.write_text(text.replace(old, new))
    with pytest.raises(WorkspaceError, match="do not match their sha256"):
        open_dataset(path)
    with pytest.raises(WorkspaceError, match="do not match their sha256"):
        samples(kin, 100, output=path, **DATA)  # a resume is refused too: overwrite computes it again
    assert samples(kin, 100, output=path, overwrite=True, **DATA).complete


def test_a_flipped_fill_value_of_a_map_is_refused(kin, whole_map, tmp_path):
    """Voxels of blocks that reach nothing are never written: they read as the fill value, 0. One
    digit made them all reachable."""
    path = tmp_path / "map.zarr"
    reachability(kin, output=path, **MAP)
    meta = path / "reach" / "zarr.json"
    text = meta.read_text()
    assert text.count('"fill_value": 0.0') == 1
    meta.write_text(text.replace('"fill_value": 0.0', '"fill_value": 1.0'))
    with pytest.raises(WorkspaceError, match="do not match their sha256"):
        open_map(path)
