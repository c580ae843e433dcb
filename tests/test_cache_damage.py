"""Every kind of file in the compile cache is verified, or rebuilt when damaged (issue 23, item 6;
issue 36, item 1).

A fresh process fills a private cache with every kind of entry symkin writes: a chain on the three
backends, its closed-form IK (C, NumPy, CasADi), the C IK solver, a tree, the C MMC step with its
OSQP sources, the collision kernel (C and NumPy) and its clearance proof. Then, one kind at a time,
every file of that kind is truncated to half its size (what a full disk or a killed copy leaves)
and the same script runs again in a new process: it must give the same numbers and no traceback.
A NumPy-backend module's bytecode was Python's own ``__pycache__`` file, which nothing checked:
``EOFError: marshal data too short``. And one digit (a byte of a binary file) flipped in every
file, which leaves JSON valid: the clearance proof was trusted and the kernels called a colliding
configuration free.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

SCRIPT = """
import json, numpy as np, symkin
r = symkin.Robot.from_ets("Rz(q0) tx(0.7) Rz(q1) tx(0.3)", name="damage_probe")
q = np.array([0.2, -0.4])
out = {}
for b in ("c", "numpy", "casadi"):
    k = symkin.compile(r, backend=b)
    out[b] = k.fkine(q).round(12).tolist()
    out[b + " ik_all"] = k.ik_all(r.fkine(q), q0=q).round(9).tolist()
k = symkin.compile(r)
out["ik"] = bool(k.ik(r.fkine(q), seed=0).success)
out["mmc"] = symkin.MMC(k).step(np.array([0.1, 0.2]), [0.5, 0.5, 0, 0, 0, 0.5])[0].round(9).tolist()
urdf = '''<?xml version="1.0"?><robot name="damage_tree"><link name="b"/><link name="l1"/><link name="l2"/>
<joint name="j1" type="revolute"><parent link="b"/><child link="l1"/><origin xyz="0.5 0 0"/>
<axis xyz="0 0 1"/><limit lower="-2" upper="2" velocity="1" effort="1"/></joint>
<joint name="j2" type="revolute"><parent link="b"/><child link="l2"/><origin xyz="0 0.5 0"/>
<axis xyz="0 1 0"/><limit lower="-2" upper="2" velocity="1" effort="1"/></joint></robot>'''
tree = symkin.Tree.from_urdf(urdf)
for b in ("c", "numpy", "casadi"):
    T = symkin.compile(tree, backend=b).fkine([0.3, 0.1], frame="l2")
    out["tree " + b] = np.asarray(T).round(12).tolist()
# spheres: the base's and link 2's first are 0.55 m apart whatever q (a proof in the cache); link 2's
# second overlaps the base's at q = 0 only
from symkin.geometry import Geometry, Sphere
r = r.with_geometry(Geometry((Sphere((0, 0, 0), 0.1, "base"), Sphere((0, 0, 0), 0.05, "link2"),
                              Sphere((-0.65, 0, 0), 0.05, "link2"))))
env = symkin.Environment(spheres=(symkin.Sphere((0.9, 0.3, 0), 0.1),))
for b in ("c", "numpy"):
    k = symkin.compile(r, backend=b)
    out["collide " + b] = [bool(k.in_collision(np.zeros(2))), bool(k.in_collision(q, env)),
                           k.distances(q, env).round(12).tolist()]
print(json.dumps(out))
"""

# Every file in the cache is of one of these kinds (the test fails on a file of a new kind).
KINDS = {
    "generated sources": lambda p: p.parent.name == "gen" and p.suffix == ".json",
    "OSQP sources": lambda p: p.parent.name == "osqp" and p.suffix == ".json",
    "clearance proofs": lambda p: p.parent.name == "clearance" and p.suffix == ".json",
    "C library": lambda p: p.suffix == ".so",
    "C library checksum": lambda p: p.name.endswith(".so.sha256"),
    "C build key": lambda p: p.name.endswith(".so.build"),
    "C sources of an entry": lambda p: p.suffix in (".c", ".h"),
    "Python module": lambda p: p.suffix == ".py",
    "Python bytecode": lambda p: p.suffix == ".code",
}


def run(
    cache: Path, preamble: str = "", argv: tuple[str, ...] = (), **env: str
) -> subprocess.CompletedProcess:
    """SCRIPT (after ``preamble``) in a new process with ``cache`` as SYMKIN_CACHE, run through
    ``argv`` (such as ``unshare -m sh -c ...``) when given."""
    environ = {**os.environ, "SYMKIN_CACHE": str(cache), **env}
    environ.pop("PYTHONDONTWRITEBYTECODE", None)  # Python writes its own bytecode caches, as by default
    command = [*argv, sys.executable, "-c", preamble + SCRIPT]
    return subprocess.run(command, capture_output=True, text=True, env=environ, cwd=ROOT, timeout=900)


@pytest.fixture(scope="module")
def warm(tmp_path_factory) -> tuple[Path, dict]:
    cache = tmp_path_factory.mktemp("cache") / "symkin"
    res = run(cache)
    assert res.returncode == 0, res.stderr
    return cache, json.loads(res.stdout)


def test_every_file_in_the_cache_is_of_a_known_kind(warm):
    cache, _ = warm
    files = [p for p in cache.rglob("*") if p.is_file()]
    unknown = [str(p.relative_to(cache)) for p in files if not any(kind(p) for kind in KINDS.values())]
    assert not unknown, f"cache files of no known kind (add them to KINDS and verify them): {unknown}"
    assert not list(cache.rglob("__pycache__")), "Python's unverified bytecode cache was used"
    for name, kind in KINDS.items():
        assert any(kind(p) for p in files), f"the script made no {name} file"


@pytest.mark.parametrize("kind", list(KINDS))
def test_a_damaged_cache_file_is_verified_or_rebuilt(warm, tmp_path, kind):
    pristine, expected = warm
    cache = tmp_path / "symkin"
    shutil.copytree(pristine, cache)
    damaged = [p for p in cache.rglob("*") if p.is_file() and KINDS[kind](p)]
    for path in damaged:
        data = path.read_bytes()
        path.write_bytes(data[: len(data) // 2])
    res = run(cache)
    assert res.returncode == 0 and "Traceback" not in res.stderr, res.stderr
    assert json.loads(res.stdout) == expected
    again = run(cache)  # and the cache is whole again
    assert again.returncode == 0 and json.loads(again.stdout) == expected


def test_a_damaged_pycache_beside_a_generated_module_is_not_read(warm, tmp_path):
    """What an older symkin left (Python's bytecode of each generated module), truncated: it was
    read and raised ``EOFError: marshal data too short``; now it is never read."""
    import importlib.util
    import py_compile

    pristine, expected = warm
    cache = tmp_path / "symkin"
    shutil.copytree(pristine, cache)
    modules = list(cache.rglob("*.py"))
    for source in modules:
        pyc = Path(importlib.util.cache_from_source(str(source)))
        py_compile.compile(str(source), cfile=str(pyc), doraise=True)  # valid header: matches the source
        pyc.write_bytes(pyc.read_bytes()[: pyc.stat().st_size // 2])
    assert modules
    res = run(cache)
    assert res.returncode == 0 and "Traceback" not in res.stderr, res.stderr
    assert json.loads(res.stdout) == expected


def _flip(data: bytes) -> bytes:
    """``data`` with its last decimal digit changed (text: still valid JSON, still a number), or for
    a binary file (or text without digits) one bit of its middle byte."""
    digits = [i for i, c in enumerate(data) if 48 <= c <= 57]
    if b"\0" in data or not digits:
        k = len(data) // 2
        return data[:k] + bytes([data[k] ^ 0x01]) + data[k + 1 :]
    k = digits[-1]
    return data[:k] + str((data[k] - 48 + 1) % 10).encode() + data[k + 1 :]


def test_a_flipped_digit_in_any_cache_file_is_not_trusted(warm, tmp_path):
    """One digit flipped in every file of the cache at once: the same numbers (the clearance proof
    [[0, 1]] became [[0, 2]], the pair that collides at q = 0), and every file is whole again."""
    pristine, expected = warm
    cache = tmp_path / "symkin"
    shutil.copytree(pristine, cache)
    files = [p for p in cache.rglob("*") if p.is_file()]
    for path in files:
        path.write_bytes(_flip(path.read_bytes()))
    (proof,) = (cache / "clearance").glob("*.json")
    assert "[[0, 2]]" in proof.read_text()  # a pair of the layout, not proved
    res = run(cache)
    assert res.returncode == 0 and "Traceback" not in res.stderr, res.stderr
    assert json.loads(res.stdout) == expected
    stale = [str(p.relative_to(cache)) for p in files if not _whole(p, pristine / p.relative_to(cache))]
    assert not stale, f"damaged files left in the cache: {stale}"


def _whole(path: Path, original: Path) -> bool:
    """``path`` is ``original`` again, or for bytecode (marshal's output differs from one compile to
    the next) a valid file: the magic number, the sha256 of the module beside it and its own."""
    import hashlib
    import importlib.util

    data = path.read_bytes()
    if path.suffix != ".code":
        return data == original.read_bytes()
    source = path.with_name(path.name.split(".")[0] + ".py").read_bytes()
    head = importlib.util.MAGIC_NUMBER + hashlib.sha256(source).digest()
    return (
        data.startswith(head)
        and data[len(head) : len(head) + 32] == hashlib.sha256(data[len(head) + 32 :]).digest()
    )


# ---- issue 36, item 7: a full or unwritable cache costs speed, never an answer --------------------
# Every write into the cache (files, not folders) fails as on a full disk: Python's open and os.open
# (pathlib, tempfile.mkstemp) raise ENOSPC for a path under SYMKIN_CACHE; reading still works.
FULL = """
import builtins, errno, io, os
_cache = os.path.realpath(os.environ["SYMKIN_CACHE"])
def _full(path):
    try:
        p = os.path.realpath(os.fsdecode(path))
    except TypeError:
        return False
    if p == _cache or p.startswith(_cache + os.sep):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), p)
_io_open, _os_open = io.open, os.open
def _open(file, mode="r", *args, **kwargs):
    if not isinstance(file, int) and any(c in mode for c in "wax+"):
        _full(file)
    return _io_open(file, mode, *args, **kwargs)
def _os_open_full(path, flags, *args, **kwargs):
    if flags & (os.O_WRONLY | os.O_RDWR | os.O_CREAT):
        _full(path)
    return _os_open(path, flags, *args, **kwargs)
builtins.open = io.open = _open
os.open = _os_open_full
"""


def _same_answers(res: subprocess.CompletedProcess, expected: dict) -> None:
    assert res.returncode == 0 and "Traceback" not in res.stderr, res.stderr
    assert json.loads(res.stdout) == expected


def test_a_full_cache_costs_speed_not_answers(warm, tmp_path):
    """Every artefact (kinematics on three backends, closed-form IK, the C IK and MMC extensions,
    OSQP sources, a tree, the collision kernel and its proof) with a cache that takes no file: C
    ``symkin.compile`` and the collision kernel raised ``OSError: [Errno 28]``."""
    _, expected = warm
    cache = tmp_path / "full"
    cache.mkdir()
    _same_answers(run(cache, FULL), expected)
    assert not [p for p in cache.rglob("*") if p.is_file()]  # nothing half-written left behind


def test_an_unwritable_cache_costs_speed_not_answers(warm, tmp_path):
    """SYMKIN_CACHE below a plain file: no folder can be made there (by root either)."""
    _, expected = warm
    (tmp_path / "file").write_text("not a folder")
    _same_answers(run(tmp_path / "file" / "cache"), expected)


def _can_mount_tmpfs() -> bool:
    import shutil as sh

    if sys.platform != "linux" or sh.which("unshare") is None:
        return False
    probe = subprocess.run(
        ["unshare", "-rm", "sh", "-c", "mount -t tmpfs -o size=64k tmpfs /mnt"], capture_output=True
    )
    return probe.returncode == 0


@pytest.mark.skipif(not _can_mount_tmpfs(), reason="needs unshare and a tmpfs in a user namespace")
def test_a_really_full_cache_costs_speed_not_answers(warm, tmp_path):
    """A real disk that fills up: a 400 KiB tmpfs (in a private mount namespace) as the cache, so
    some entries fit and the rest fail part way (a source file, the compiler's output)."""
    _, expected = warm
    cache = tmp_path / "tiny"
    cache.mkdir()
    mount = f'mount -t tmpfs -o size=400k tmpfs {cache} && exec "$@"'
    res = run(cache, argv=("unshare", "-rm", "sh", "-c", mount, "sh"))
    _same_answers(res, expected)


def test_the_compiler_failing_on_a_full_disk_builds_outside_the_cache(tmp_path, monkeypatch):
    """The disk fills while the compiler writes the library into the cache: it says "No space left
    on device" and the library is built in a temporary folder instead; a compile error of the
    sources is still a CompileError."""
    import ctypes
    import shlex

    from symkin.emit.c.build import compile_library, find_compiler
    from symkin.errors import CompileError

    real = shlex.join(find_compiler())
    cc = tmp_path / "cc-full"
    full = 'echo "ld: final link failed: No space left on device" >&2; exit 1'
    cc.write_text(f'#!/bin/sh\ncase "$PWD" in "$SYMKIN_CACHE"/*) {full};; esac\nexec {real} "$@"\n')
    cc.chmod(0o755)
    monkeypatch.setenv("SYMKIN_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("CC", str(cc))
    path = compile_library({"full.c": "int symkin_full(void) { return 36; }\n"}, "full_disk_probe")
    assert tmp_path / "cache" not in path.parents
    assert ctypes.CDLL(str(path)).symkin_full() == 36
    with pytest.raises(CompileError, match="the C compiler failed"):
        compile_library({"bad.c": "int symkin_bad(void) { return }\n"}, "full_disk_bad")


def test_neither_the_cache_nor_a_temporary_folder_writable_is_one_symkin_error(tmp_path, monkeypatch):
    """Not a bare OSError: a CompileError naming the cache and the temporary folder."""
    import tempfile

    from symkin.emit.c.build import compile_library
    from symkin.errors import CompileError
    from symkin.runtime.mmc_c import _generate_osqp

    (tmp_path / "file").write_text("not a folder")
    monkeypatch.setenv("SYMKIN_CACHE", str(tmp_path / "file" / "cache"))
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "file" / "tmp"))
    with pytest.raises(CompileError) as info:
        compile_library({"nowhere.c": "int symkin_nowhere(void) { return 1; }\n"}, "nowhere_probe")
    assert "symkin cache" in str(info.value) and str(tmp_path / "file" / "tmp") in str(info.value)
    with pytest.raises(CompileError, match="OSQP's generated sources into the temporary folder"):
        _generate_osqp(2, False, ())
