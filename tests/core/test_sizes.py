"""Sizes a user asks for are checked before any allocation (symkin.core.sizes; issue 36, item 9):
``symkin dataset -n 10**20`` printed a MemoryError traceback, ``mstraj(..., tacc=1e300)`` an
OverflowError, and NumPy's "Maximum allowed size exceeded" came out of many others. Every size is
a symkin error naming it, whether it is beyond any integer a double holds or only beyond this
machine's memory (or its store's disk)."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin.core.sizes import MAX_COUNT, count, human_bytes, memory_bytes, room, stored
from symkin.errors import GeometryError, ParameterError, SymkinError, WorkspaceError


@pytest.mark.parametrize("value", [0, 1, 7, np.int64(7), np.uint8(7), 7.0, np.float32(7.0), 1e6, MAX_COUNT])
def test_a_count_is_an_integer_in_range(value):
    assert count(value, "n", minimum=0) == int(value)
    assert type(count(value, "n", minimum=0)) is int


@pytest.mark.parametrize(
    "value",
    [True, np.bool_(True), 7.5, float("nan"), float("inf"), "7", None, [7], -1, MAX_COUNT + 1, 10**20, 1e300],
)
def test_anything_else_is_refused_naming_the_size(value):
    with pytest.raises(ParameterError, match="the size"):
        count(value, "the size", minimum=0)


def test_the_error_class_is_the_callers():
    with pytest.raises(WorkspaceError):
        count(0, "n", error=WorkspaceError)
    with pytest.raises(GeometryError):
        room(float("inf"), "x", GeometryError)


def test_room_is_this_machines_memory():
    room(memory_bytes(), "all of it")
    for too_much in (memory_bytes() + 1, float("inf"), float("nan")):
        with pytest.raises(ParameterError, match="more than this machine's memory"):
            room(too_much, "the request")


def test_stored_is_the_disk_of_the_store_or_memory(tmp_path):
    import shutil

    total = shutil.disk_usage(tmp_path).total
    stored(tmp_path / "new" / "store.zarr", total, "a store")  # a path that does not exist yet
    with pytest.raises(ParameterError, match="whole disk"):
        stored(tmp_path / "new" / "store.zarr", total + 1, "a store")
    with pytest.raises(ParameterError, match="memory"):
        stored(None, memory_bytes() + 1, "in memory")
    stored("s3://bucket/store.zarr", 1e30, "a remote store")  # not checked


def test_human_bytes():
    assert human_bytes(512) == "512 B" and human_bytes(2**31) == "2.0 GiB" and "e+" in human_bytes(1e22)


# Every user size of the Python API, at 10**20 (beyond any count) and at a count that fits an
# integer but not this machine's memory (nor a C solver's int32 counter).
def _api(big: int) -> dict:
    from symkin.check.kinematics import check
    from symkin.geometry.fit import fit_spheres, mesh_points
    from symkin.runtime.ik import ik_trace
    from symkin.runtime.qrmc import QRMC
    from symkin.workspace.grid import so3_uniform

    robot = symkin.load("planar2")
    T = robot.fkine([0.1, 0.2])

    def kin():  # compiled when a case runs, not when the tests are collected
        return symkin.compile(robot, backend="numpy")

    cases = {
        "Robot.random_q": lambda: robot.random_q(big),
        "Kinematics.random_q": lambda: kin().random_q(big),
        "Tree.random_q": lambda: symkin.Tree.from_robot(robot).random_q(big),
        "jtraj samples": lambda: symkin.jtraj(np.zeros(2), np.ones(2), big),
        "quintic samples": lambda: symkin.quintic(0.0, 1.0, big),
        "trapezoidal samples": lambda: symkin.trapezoidal(0.0, 1.0, big),
        "ctraj samples": lambda: symkin.ctraj(np.eye(4), np.eye(4), big),
        "mstraj tacc": lambda: symkin.mstraj(np.array([[0, 0], [1, 1]]), 0.1, float(big), qdmax=1.0),
        "mstraj dt": lambda: symkin.mstraj(np.array([[0, 0], [1, 1]]), 1.0 / big, 0.1, qdmax=1.0),
        "mstraj qdmax": lambda: symkin.mstraj(np.array([[0, 0], [1, 1]]), 0.1, 0.1, qdmax=1.0 / big),
        "mstraj tsegment": lambda: symkin.mstraj(np.array([[0, 0], [1, 1]]), 0.1, 0.1, tsegment=[float(big)]),
        "mstraj segments": lambda: symkin.mstraj(np.zeros((3, 2)), 1.0 / big, 0.0, tsegment=[1.0, 1.0]),
        "motion_valid resolution": lambda: symkin.compile(symkin.load("ur5"), backend="numpy").motion_valid(
            np.zeros(6), np.ones(6), resolution=1.0 / big
        ),
        "ik_trace steps": lambda: ik_trace(kin(), T, [0.0, 0.0], big),
        "ik slimit": lambda: kin().ik(T, slimit=big),
        "ik ilimit": lambda: kin().ik(T, ilimit=big),
        "QRMC iterations": lambda: QRMC(kin(), iterations=big),  # a C int32: 10**20 was truncated
        "check samples": lambda: check(robot, backends=("numpy",), samples=big),
        "so3_uniform": lambda: so3_uniform(big),
        "mesh_points samples": lambda: mesh_points(_box_mesh(), samples=big),
        "fit_spheres samples": lambda: fit_spheres(_box_mesh(), 3, samples=big),
    }
    try:
        import zarr  # noqa: F401

        from symkin.workspace import reachability, samples

        here = {"scheduler": "synchronous", "backend": "numpy", "progress": False}
        cases |= {
            "dataset n": lambda: samples(robot, big, **here),
            "dataset chunk": lambda: samples(robot, 10, chunk=big, **here),
            "map orientations": lambda: reachability(robot, 0.5, big, **here),
            "map resolution": lambda: reachability(robot, 1.0 / big, 1, **here),
            "map radius": lambda: reachability(robot, 0.5, 1, radius=float(big), **here),
            "map chunk": lambda: reachability(robot, 0.5, 1, chunk=big, bounds=[[0, 0.5]] * 3, **here),
        }
    except ImportError:
        pass
    return cases


def _box_mesh():
    trimesh = pytest.importorskip("trimesh")
    return trimesh.creation.box((1.0, 1.0, 1.0))


def _beyond_memory() -> int:
    """More float64 values than bytes of memory, and beyond the C solvers' int32 counters."""
    return max(memory_bytes() // 8 + 1, 2**31)


@pytest.mark.parametrize("size", ["1e20", "memory"])
@pytest.mark.parametrize("what", list(_api(2)))
def test_every_size_of_the_api_is_bounded_with_a_symkin_error(what, size):
    big = 10**20 if size == "1e20" else _beyond_memory()
    call = _api(big)[what]
    if what in ("map chunk", "dataset chunk") and size == "memory":
        call()  # a block larger than the whole map or dataset is the whole: not an error
        return
    with pytest.raises(SymkinError) as info:
        call()
    message = str(info.value)
    words = ("integer", "memory", "disk", "too many voxels", "a trajectory may have")
    assert any(w in message for w in words), message


def test_read_bounded_reads_a_file_up_to_its_bound(tmp_path):
    from symkin.core.sizes import read_bounded

    path = tmp_path / "f"
    path.write_bytes(b"x" * 100)
    assert read_bounded(path, 100, "f") == b"x" * 100
    with pytest.raises(ParameterError, match="f is larger than 99 B"):
        read_bounded(path, 99, "f")


def test_read_text_reads_utf8_text_as_read_text_does_and_names_the_file_otherwise(tmp_path):
    from symkin.core.sizes import read_text

    path = tmp_path / "f.txt"
    path.write_bytes("\ufeffa\r\nb\rc°\n".encode())
    assert read_text(path, 100, "file 'f.txt'", GeometryError) == "a\nb\nc°\n"  # BOM dropped
    with pytest.raises(GeometryError, match=r"^cannot read file 'f.txt': the file is larger than 4 B"):
        read_text(path, 4, "file 'f.txt'", GeometryError)
    path.write_bytes(b"ok \xff")
    with pytest.raises(GeometryError, match=r"^file 'f.txt' is not UTF-8 text: invalid start byte at byte 3"):
        read_text(path, 100, "file 'f.txt'", GeometryError)
    with pytest.raises(GeometryError, match=r"^cannot read file 'g': No such file"):
        read_text(tmp_path / "g", 100, "file 'g'", GeometryError)
