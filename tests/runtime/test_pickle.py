"""Robots and compiled kinematics pickle (for Dask workers): kinematics as robot + backend,
rebuilt on unpickling from the compile cache of the process that loads them."""

from __future__ import annotations

import os
import pickle
import subprocess
import sys

import numpy as np
import pytest

import symkin

PLANAR = "Rz(q) tx(0.6) Rz(q) tx(0.25) Rz(q) tx(0.15)"

LOAD = """
import pickle, sys
kin, robot, Q = pickle.loads(sys.stdin.buffer.read())
print(type(kin).__name__, kin.backend, robot.name, type(kin.fkine).__name__)
sys.stdout.buffer.write(pickle.dumps((kin.fkine(Q), kin.jacob0(Q))))
"""
# what a backend's functions are: a C extension's functions, or a generated module's Python functions
FUNCTION_TYPE = {"c": "builtin_function_or_method", "numpy": "function"}


def _no_generated_code_in(data: bytes, kin) -> None:
    """No line of the generated sources, and not the path of the built code, is in the pickle."""
    lines = {ln.strip() for src in kin.files.values() for ln in src.splitlines() if len(ln.strip()) >= 20}
    assert lines  # there is generated code to look for
    assert not [ln for ln in lines if ln.encode() in data]
    assert str(kin.path).encode() not in data


def test_robot_pickles_to_an_equal_robot():
    robot = symkin.Robot.from_ets(PLANAR, name="planar3", qlim=[[-1, -2, -3], [1, 2, 3]])
    robot.fkine(np.zeros(3))  # fills its cached numeric kinematics, which are not pickled
    data = pickle.dumps(robot)
    assert b"NumericKinematics" not in data and len(data) < 2000
    copy = pickle.loads(data)
    assert copy.key == robot.key and copy.name == "planar3" and np.array_equal(copy.qlim, robot.qlim)
    q = np.array([0.3, -0.4, 1.1])
    assert np.array_equal(copy.fkine(q), robot.fkine(q))
    ur5 = symkin.load("ur5")
    assert np.array_equal(pickle.loads(pickle.dumps(ur5)).configs["qr"], ur5.configs["qr"])


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_kinematics_pickle_to_robot_and_backend_and_rebuild_in_another_process(backend):
    robot = symkin.Robot.from_ets(PLANAR, name="planar3")
    kin = symkin.compile(robot, backend=backend)
    Q = robot.random_q(6, seed=11)
    T_ref, J_ref = robot.fkine(Q), robot.jacob0(Q)  # the numeric reference, before any pickling
    data = pickle.dumps((kin, robot, Q))
    assert len(data) < 4000 and b"fkine_jacob0" not in data  # the generated code is not in the pickle
    _no_generated_code_in(data, kin)
    copy = pickle.loads(pickle.dumps(kin))  # in this process
    assert type(copy) is type(kin) and copy.backend == backend and copy.robot.fingerprint == robot.fingerprint
    assert type(copy.fkine).__name__ == FUNCTION_TYPE[backend]
    assert np.abs(copy.fkine(Q) - T_ref).max() < 1e-12 and np.abs(copy.jacob0(Q) - J_ref).max() < 1e-12
    out = subprocess.run([sys.executable, "-c", LOAD], input=data, capture_output=True, env=dict(os.environ),
                         timeout=300, check=True)  # fmt: skip
    head, _, payload = out.stdout.partition(b"\n")
    assert head.decode() == f"Kinematics {backend} planar3 {FUNCTION_TYPE[backend]}"
    T_kin, J_kin = pickle.loads(payload)
    assert T_kin.shape == T_ref.shape and J_kin.shape == J_ref.shape
    # the kinematics rebuilt in the other process against this process's numeric reference
    assert np.abs(T_kin - T_ref).max() < 1e-12 and np.abs(J_kin - J_ref).max() < 1e-12


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_tree_and_its_kinematics_pickle(backend):
    from tests.model.tree_urdfs import QUADRUPED

    tree = symkin.Tree.from_urdf(QUADRUPED)
    kin = symkin.compile(tree, backend=backend)
    kin.select(tree.frames[0]), tree.select(tree.frames[0])  # memoised views are not pickled
    data = pickle.dumps(kin)
    assert len(data) < 8000 and b"FrameView" not in data  # tree + backend
    _no_generated_code_in(data, kin)
    copy = pickle.loads(data)
    assert type(copy) is symkin.Kinematics and copy.backend == backend
    assert type(copy.fkine_all).__name__ == FUNCTION_TYPE[backend]
    assert copy.frames == tree.frames
    Q = tree.random_q(4, seed=3)
    ref = pickle.loads(pickle.dumps(tree))
    assert np.abs(copy.fkine_all(Q) - ref.fkine_all(Q)).max() < 1e-12
    frame = tree.frames[-1]
    assert np.abs(copy.jacob0(Q, frame) - ref.jacob0(Q, frame)).max() < 1e-12
