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
import numpy as np
kin, robot, q = pickle.loads(sys.stdin.buffer.read())
print(type(kin).__name__, kin.backend, robot.name)
np.save(sys.stdout.buffer, np.stack([kin.fkine(q), robot.fkine(q)]))
"""


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
    data = pickle.dumps((kin, robot, np.array([0.3, -0.4, 1.1])))
    assert len(data) < 4000 and b"fkine_jacob0" not in data  # the generated code is not in the pickle
    assert pickle.loads(pickle.dumps(kin)).fkine is not None
    out = subprocess.run([sys.executable, "-c", LOAD], input=data, capture_output=True, env=dict(os.environ),
                         timeout=300, check=True)  # fmt: skip
    head, _, payload = out.stdout.partition(b"\n")
    assert head.decode() == f"Kinematics {backend} planar3"
    import io

    T_kin, T_ref = np.load(io.BytesIO(payload))
    assert np.abs(T_kin - T_ref).max() < 1e-12  # the rebuilt kinematics against the numeric reference


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_tree_and_its_kinematics_pickle(backend):
    from tests.model.tree_urdfs import QUADRUPED

    tree = symkin.Tree.from_urdf(QUADRUPED)
    kin = symkin.compile(tree, backend=backend)
    kin.select(tree.frames[0]), tree.select(tree.frames[0])  # memoised views are not pickled
    data = pickle.dumps(kin)
    assert len(data) < 8000 and b"sk_sin" not in data and b"FrameView" not in data  # tree + backend
    copy = pickle.loads(data)
    assert type(copy).__name__ == "TreeKinematics" and copy.backend == backend
    assert copy.frames == tree.frames
    q = tree.random_q(seed=3)
    assert np.abs(copy.fkine_all(q) - pickle.loads(pickle.dumps(tree)).fkine_all(q)).max() < 1e-12
