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


def run(cache: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "SYMKIN_CACHE": str(cache)}
    env.pop("PYTHONDONTWRITEBYTECODE", None)  # Python writes its own bytecode caches, as by default
    return subprocess.run(
        [sys.executable, "-c", SCRIPT], capture_output=True, text=True, env=env, cwd=ROOT, timeout=900
    )


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
