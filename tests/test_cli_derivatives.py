"""`symkin derive ROBOT --order K` and `symkin compile ROBOT --derivatives K`; their mistakes exit 2
with one line."""

from __future__ import annotations

import json
import math

import pytest

from symkin.cli.main import main
from tests.model.tree_urdfs import GRIPPER


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_derive_order_writes_the_derivation(capsys, tmp_path):
    code, out, _ = run(capsys, "derive", "planar2", "--order", "3")
    assert code == 0
    assert out.startswith("# Partial derivatives of order 3 of planar2, step by step")
    assert "## Order 3: 4 distinct columns" in out and r"\mathbf{V}_{112}" in out
    assert "the difference simplifies to 0" in out and "largest difference" in out
    path = tmp_path / "d.tex"
    code, out, _ = run(capsys, "derive", "planar2", "--order", "2", "--format", "latex", "-o", str(path))
    assert code == 0 and path.read_text().startswith(r"\documentclass")


def test_compile_derivatives_reports_the_highest_order(capsys):
    code, out, _ = run(capsys, "compile", "planar3", "--backend", "numpy", "--derivatives", "4")
    assert code == 0
    line = next(ln for ln in out.splitlines() if ln.startswith("derivative4, shape (3, 3, 3, 6, 3)"))
    err = float(line.split("= ")[-1].split()[0])
    assert err < 1e-13


@pytest.mark.parametrize(
    "argv, message",
    [
        (("derive", "planar2", "--order", "0"), "order must be 1..8"),
        (("derive", "planar2", "--order", "1"), "--order 1 is the Jacobian"),
        (("derive", "planar2", "--order", "3", "--ik"), "--order writes its own derivation"),
        (("derive", "GRIPPER", "--order", "3"), "analyse one chain"),
        (("compile", "planar2", "--derivatives", "9"), "--derivatives: derivatives must be an integer 0..8"),
        (("compile", "planar2", "--derivatives", "-1"), "--derivatives"),
    ],
)
def test_mistakes_exit_2_with_one_line(capsys, tmp_path, argv, message):
    if "GRIPPER" in argv:
        path = tmp_path / "gripper.urdf"
        path.write_text(GRIPPER)
        argv = tuple(str(path) if a == "GRIPPER" else a for a in argv)
    code, out, err = run(capsys, *argv)
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err


def test_bench_compile_reports_the_cost_of_the_derivatives(capsys):
    """`symkin bench compile --derivatives K`: each robot cold without and with the orders 3..K, the
    compiled derivative checked against the numeric reference and its code larger; the table."""
    from symkin.bench.compile import format_derivatives

    code, out, _ = run(capsys, "bench", "compile", "planar2", "--joints", "3", "--derivatives", "3", "--json")
    assert code == 0
    rows = json.loads(out)
    assert [(r["robot"], r["derivatives"]) for r in rows] == [
        ("planar2", 0),
        ("planar2", 3),
        ("chain3_0", 0),
        ("chain3_0", 3),
    ]
    for plain, more in (rows[:2], rows[2:]):
        assert "derivative_error" not in plain
        assert more["derivative_error"] < 1e-12 and more["derivative_us"] > 0 and more["derivative_ops"] > 0
        assert more["source_kb"] > plain["source_kb"] and more["numpy_kb"] > plain["numpy_kb"]
    assert 0 < rows[3]["derivative_distinct"] <= 6 * math.comb(3 + 3 - 1, 3)  # one value per multiset and row
    table = format_derivatives(rows)
    assert "| derivatives up to |" in table
    assert "| planar2 | 2 | 3 |" in table and "| chain3_0 | 3 | - |" in table


@pytest.mark.parametrize(
    "argv, message",
    [
        (("bench", "kin", "--derivatives", "3"), "--derivatives is for `symkin bench compile`"),
        (("bench", "compile", "--derivatives", "2"), "--derivatives"),
        (("bench", "compile", "--derivatives", "9"), "--derivatives"),
    ],
)
def test_bench_derivatives_mistakes_exit_2(capsys, argv, message):
    code, _, err = run(capsys, *argv)
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err
