"""``symkin bench diff`` (symkin.bench.diff) and the URDF it writes for pytorch_kinematics
(symkin.bench.urdf_text): the URDF reads back to the same robot, and a small run measures every
path and solves its IK targets (timings are the benchmark's business, not the test's)."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin.bench.urdf_text import chain_urdf
from symkin.model.robots import list_robots, load


@pytest.mark.parametrize("name", list_robots())
def test_chain_urdf_reads_back_to_the_same_forward_kinematics(name):
    robot = load(name)
    back = symkin.Robot.from_urdf(chain_urdf(robot), end_link="ee")
    assert back.n == robot.n and tuple(back.joint_names) == tuple(robot.joint_names)
    Q = robot.random_q(10, seed=0)
    np.testing.assert_allclose(back.fkine(Q), robot.fkine(Q), rtol=0, atol=1e-12)
    finite = np.isfinite(robot.qlim)
    np.testing.assert_array_equal(np.asarray(back.qlim)[finite], np.asarray(robot.qlim)[finite])


def test_a_small_run_measures_every_path_and_solves_its_targets():
    pytest.importorskip("torch")
    from symkin.bench.diff import format_diff, run_diff

    report = run_diff("planar3", batches=(1, 16), dtypes=("float64",), rounds=1, libraries=("torch",),
                      problems=16, compile_torch=False)  # fmt: skip
    paths = {r.path for r in report.rows}
    assert "torch" in paths and "torch.compile" not in paths  # compile_torch=False: no such rows
    assert {(r.what, r.batch) for r in report.rows} == {(w, b) for w in ("fkine", "jacob0") for b in (1, 16)}
    assert all(r.seconds > 0 for r in report.rows)
    ours = [r for r in report.ik if r.path == "torch"]
    assert len(ours) == 1 and ours[0].solved >= 0.9 and ours[0].median_pos < 1e-6
    if "pk" in paths:
        assert report.agreement < 1e-6  # pytorch_kinematics reads the URDF's numbers as float32
    text = format_diff(report)
    assert "bench diff planar3" in text and "IK:" in text
