"""The QP rows of Table 1 and the comparison with roboticstoolbox-python's IK_QP on the same targets."""

from __future__ import annotations

import math

import pytest

import symkin
from symkin.bench.ik import run_table1, table1_problems
from symkin.bench.ik_qp import compare_rtb_qp, format_rtb_qp
from symkin.model.robots import load


def test_table1_qp_rows_solve_within_the_limits():
    robot = load("ur5")
    methods = ["QP (lambda_q=0.01)", "QP + Jm (w_m=0.01)"]
    result = run_table1(robot, n_problems=40, seed=0, methods=methods, progress=False, rtb=False)
    assert [(r["method"], r["setting"]) for r in result["rows"]] == [(m, s) for s in "ab" for m in methods]
    for row in result["rows"]:
        assert row["paper"] is None  # Part 1's table has no QP rows
        assert row["max_error"] < math.sqrt(2e-6)  # what E < 1e-6 allows
        if row["setting"] == "b":
            assert row["infeasible"] == 0


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_rtb_ik_qp_comparison_runs_both_on_the_same_targets(name):
    pytest.importorskip("roboticstoolbox")
    pytest.importorskip("quadprog")
    robot = load(name)
    _, Tep, starts = table1_problems(robot, 8, 0)
    kin = symkin.compile(robot, backend="c")
    result = compare_rtb_qp(robot, kin, Tep, starts, {"method": "QP"}, 1e-6, problems=8)
    assert result is not None and result["problems"] == 8
    for side in ("symkin", "rtb"):
        assert result[side]["success_pct"] == 100.0 and result[side]["outside_limits"] == 0
    # every UR5 joint spans two turns: no dampers on either side; the Panda's are damped
    assert result["rtb_parameters"]["kq"] == (0.0 if name == "ur5" else 1.0)
    assert "RTB IK_QP" in format_rtb_qp(result)
