"""The compile caches (in memory, generated files, C libraries, NumPy modules) never serve another
robot's behaviour or stale code, and an awkward environment only costs speed (issue 12, items 1,
10, 11)."""

from __future__ import annotations

import importlib
import os
import shutil
import subprocess
import sys
import threading
from pathlib import Path

import numpy as np
import pytest

import symkin
from symkin.emit.numpy.backend import load_numpy

compile_mod = importlib.import_module("symkin.compiler.compile")

ETS3 = "Rz(q0) tx(0.4) Rz(q1) tx(0.3) Rz(q2) tx(0.1)"


def _arm(**kwargs):
    return symkin.Robot.from_ets(ETS3, name="arm3_cache", **kwargs)


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_robots_differing_only_in_limits_get_their_own_compiled_object(backend):
    A = _arm()
    B = _arm(qlim=[[-0.2] * 3, [0.2] * 3], qd_max=[0.1] * 3)
    kA, kB = symkin.compile(A, backend=backend), symkin.compile(B, backend=backend)
    assert kB is not kA
    assert kB.robot is B and np.array_equal(kB.qlim, B.qlim) and np.array_equal(kB.qd_max, B.qd_max)
    # IK: a target whose solutions lie outside B's limits is solved for A and refused for B
    q = np.array([1.0, -0.8, 0.5])
    assert kA.ik(A.fkine(q), seed=1).success
    res = kB.ik(A.fkine(q), seed=1)
    assert not res.success and "joint limits" in res.reason
    # MMC reads B's speed limits (it exceeded them with A's compiled object: 1.9 rad/s against 0.1)
    qd, _ = symkin.MMC(kB).step(np.array([0.1, 0.1, 0.1]), [0.5, 0.5, 0, 0, 0, 0.5])
    assert np.abs(qd).max() <= 0.1 + 1e-12


def test_equal_robots_share_one_compiled_object_and_every_attribute_counts():
    kin = symkin.compile(_arm(), backend="numpy")
    assert symkin.compile(_arm(), backend="numpy") is kin  # an equal but distinct Robot object
    variants = [
        _arm(configs={"home": [0.1, 0.2, 0.3]}),
        _arm(joint_names=("a", "b", "c")),
        _arm(qd_max=[1.0, 2.0, 3.0]),
        symkin.Robot(_arm().ets, name="arm3_cache", source="another source"),
    ]
    for robot in variants:
        other = symkin.compile(robot, backend="numpy")
        assert other is not kin and other.robot is robot


def test_generated_files_on_disk_are_per_robot_attributes():
    """The C header lists the joint limits: a robot differing only in them gets its own files,
    also from the on-disk cache (a fresh process would otherwise be served the other's)."""
    A = _arm()
    B = _arm(qlim=[[-0.2] * 3, [0.2] * 3], qd_max=[0.1] * 3, joint_names="abc")
    assert compile_mod.cache_key(A, "c") != compile_mod.cache_key(B, "c")
    assert compile_mod.cache_key(A, "c") == compile_mod.cache_key(_arm(), "c")
    files = compile_mod.cached_files(B, "c", compile_mod.cache_key(B, "c"), True)
    header = next(text for name, text in files.items() if name.endswith(".h"))
    assert "[-0.2, 0.2]" in header and "QMAX" in header


def test_disk_cache_key_covers_the_compiler_code(tmp_path, monkeypatch):
    robot = _arm()
    key = compile_mod.cache_key(robot, "c")
    monkeypatch.setattr(compile_mod, "compiler_digest", lambda: "changed")
    assert compile_mod.cache_key(robot, "c") != key
    monkeypatch.undo()
    # the digest covers the symbolic and emit sources: editing any of them changes it
    root = Path(compile_mod.__file__).resolve().parent.parent
    copy = tmp_path / "symkin"
    for part in compile_mod.COMPILER_SOURCES:
        src = root / part
        if src.is_dir():
            shutil.copytree(src, copy / part)
        else:
            (copy / part).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy(src, copy / part)
    before = compile_mod.sources_digest(copy)
    assert before == compile_mod.sources_digest(root)
    for edited in ("symbolic/kinematics.py", "emit/printers.py", "emit/lowering.py"):
        path = copy / edited
        text = path.read_text()
        path.write_text(text + "\n# changed\n")
        assert compile_mod.sources_digest(copy) != before, edited
        path.write_text(text)


def test_numpy_module_writers_do_not_race(tmp_path):
    """Eight threads load the same new generated module at once, 30 times: every load works, no
    temporary file is left behind (they all used one temp name and renamed it from under each other)."""
    robot = symkin.Robot.from_ets("Rz(q) tx(0.7) Rz(q) tx(0.2)", name="race_writer")
    ((fname, text),) = symkin.generate(robot, "numpy").items()
    errors: list[BaseException] = []
    for rnd in range(30):
        files = {fname: text + f"\n# {tmp_path.name} round {rnd}\n"}  # new content: a new module name
        barrier = threading.Barrier(8)

        def load(files=files, barrier=barrier) -> None:
            try:
                barrier.wait()
                module = load_numpy(files, tmp_path)
                assert np.allclose(module.fkine([0.3, 0.4]), robot.fkine([0.3, 0.4]))
            except BaseException as exc:  # noqa: BLE001 - reported below
                errors.append(exc)

        threads = [threading.Thread(target=load) for _ in range(8)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
    assert not errors, errors[:3]
    assert len(list(tmp_path.glob("*.py"))) == len(list(tmp_path.glob("*.code"))) == 30  # module, bytecode
    left = [p.name for p in tmp_path.iterdir() if p.suffix not in (".py", ".code")]
    assert left == []


def _run(code: str, env: dict[str, str], cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env={**os.environ, **env}, cwd=cwd,
        timeout=600,
    )  # fmt: skip


def test_warm_c_cache_works_without_a_compiler(tmp_path):
    code = (
        "import symkin; r = symkin.Robot.from_ets('Rz(q) tx(1) Rz(q) tx(0.5)', name='nocc');"
        "k = symkin.compile(r); print(k.fkine([0.2, 0.3])[0, 3], k.ik(r.fkine([0.2, 0.3]), seed=0).success)"
    )
    env = {"SYMKIN_CACHE": str(tmp_path / "cache")}
    warm = _run(code, env, tmp_path)
    assert warm.returncode == 0, warm.stderr
    cold = _run(code, {**env, "CC": str(tmp_path / "no-such-compiler")}, tmp_path)
    assert cold.returncode == 0, cold.stderr
    assert cold.stdout == warm.stdout
    # a robot that was never built still says clearly that a compiler is needed
    other = _run(code.replace("tx(0.5)", "tx(0.25)"), {**env, "CC": str(tmp_path / "nocc")}, tmp_path)
    assert other.returncode != 0 and "CompileError" in other.stderr and "C compiler" in other.stderr


def test_relative_cache_survives_chdir(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    code = (
        "import os, numpy as np, symkin\n"
        "r = symkin.Robot.from_ets('Rz(q) tx(1) Rz(q) tx(0.5)', name='relcache')\n"
        "k = symkin.compile(r)\n"
        "os.chdir('../b')\n"
        "assert k.ik(r.fkine([0.2, 0.3]), seed=0).success\n"  # loads the library by its path
        "assert symkin.MMC(k).backend == 'c'\n"
        "assert symkin.compile(r) is k\n"
        "print(k.path)\n"
    )
    res = _run(code, {"SYMKIN_CACHE": "rel-cache"}, tmp_path / "a")
    assert res.returncode == 0, res.stderr
    assert Path(res.stdout.strip()).is_absolute()
    assert (tmp_path / "a" / "rel-cache").is_dir() and not (tmp_path / "b" / "rel-cache").exists()


def test_unwritable_cache_only_costs_speed(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("not a folder")
    code = (
        "import symkin\n"
        "for b in ('numpy', 'casadi', 'c'):\n"
        "    k = symkin.compile('planar2', backend=b)\n"
        "    print(b, round(float(k.fkine([0.1, 0.2])[0, 3]), 12))\n"
    )
    res = _run(code, {"SYMKIN_CACHE": str(blocker / "cache")}, tmp_path)
    assert res.returncode == 0, res.stderr
    values = {line.split()[1] for line in res.stdout.splitlines()}
    assert len(res.stdout.splitlines()) == 3 and len(values) == 1
