"""`symkin ik --method QP` and the QP rows of `symkin bench ik`."""

from __future__ import annotations

import json

import numpy as np
import pytest

from symkin.cli.main import main
from symkin.model.robots import load
from tests.test_cli_errors import one_line_error, symkin_cli


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_ik_method_qp_solves_within_the_limits(capsys):
    robot = load("panda")
    q = robot.random_q(seed=5)
    target = " ".join(map(str, q))
    code, out, _ = run(capsys, "ik", "panda", "--target-q", target, "--method", "QP", "--json")
    assert code == 0
    res = json.loads(out)
    assert res["success"] and robot.within_limits(res["q"])
    np.testing.assert_allclose(robot.fkine(res["q"]), robot.fkine(q), atol=1e-6)
    code, out, _ = run(
        capsys, "ik", "panda", "--target-q", target, "--method", "QP", "--manipulability", "0.01",
        "--xi", "0.5", "--rho-i", "0.5", "--rho-s", "0.02", "--slack-gain", "2", "--lam", "0.02",
    )  # fmt: skip
    assert code == 0 and "solved" in out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (("--slack-gain", "2"), "set the QP method: add --method QP"),
        (("--method", "QP", "--we", "position"), "every weight of we > 0"),
        (("--method", "QP", "--rho-i", "0.01", "--rho-s", "0.02"), "must exceed rho_s"),
        (("--method", "QP", "--manipulability", "-1"), "must be a finite number >= 0"),
    ],
)
def test_ik_qp_mistakes_exit_2_with_one_line(argv, message):
    res = symkin_cli("ik", "ur5", "--target-q", "0.1 -1 1 0.5 0.3 0.2", *argv)
    assert message in one_line_error(res)


def test_bench_ik_has_qp_rows(capsys):
    code, out, _ = run(capsys, "bench", "ik", "-n", "20")
    assert code == 0
    assert "QP (lambda_q=0.01)" in out and "QP + Jm (w_m=0.01)" in out
    assert "IK_QP" in out  # compared, or why not
