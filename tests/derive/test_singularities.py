"""symkin derive --singularities: every reported factor is singular in the compiled Jacobian."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin.cli.main import main
from symkin.derive.singularities import SINGULAR_TOL, singularities


def _sigma_min(kin, Q: np.ndarray, rows: tuple[int, ...]) -> np.ndarray:
    return np.linalg.svd(kin.jacob0(Q)[:, list(rows), :], compute_uv=False)[:, -1]


@pytest.mark.parametrize("name", ["ur5", "puma560", "stanford", "planar2", "planar3", "cobra600"])
def test_every_condition_is_singular_and_random_configurations_are_not(name: str) -> None:
    report = singularities(name, seed=2)
    kin = symkin.compile(symkin.load(name), backend="numpy")
    rows = report.analysis.rows
    assert report.ok and report.singularities
    for s in report.singularities:
        assert len(s.solutions) == 3, s.factor.expr
        f = np.array([float(s.factor.expr.subs(dict(zip(report.analysis.q, q)))) for q in s.solutions])
        assert np.abs(f).max() < 1e-9, f"{name}: {s.factor.expr} is not 0 at its solutions"
        assert _sigma_min(kin, s.solutions, rows).max() < SINGULAR_TOL, f"{name}: {s.factor.expr}"
        # moving the solved joint away from the solution leaves the singular set
        away = s.solutions.copy()
        away[:, s.factor.joints[0]] += 0.3
        assert _sigma_min(kin, away, rows).min() > 1e-6
    Q = symkin.load(name).random_q(30, seed=7)
    assert _sigma_min(kin, Q, rows).min() > 1e-6


def test_ur5_meanings_are_elbow_wrist_and_shoulder() -> None:
    report = singularities("ur5")
    kinds = {s.factor.joints: s.kind for s in report.singularities}
    assert kinds == {(2,): "elbow", (4,): "wrist", (1, 2, 3): "shoulder"}
    kin = symkin.compile(symkin.load("ur5"), backend="numpy")
    (wrist,) = [s for s in report.singularities if s.kind == "wrist"]
    assert "joints 4 and 6" in wrist.meaning[0]
    J = kin.jacob0(wrist.solutions)  # the omega rows of J0 are the joint axes (all revolute)
    assert np.linalg.norm(np.cross(J[:, 3:, 3], J[:, 3:, 5]), axis=-1).max() < 1e-9
    (elbow,) = [s for s in report.singularities if s.kind == "elbow"]
    assert "2, 3 and 4" in elbow.meaning[0]


def test_puma_wrist_centre_is_named() -> None:
    report = singularities("puma560")
    assert {s.kind for s in report.singularities} == {"wrist", "shoulder", "elbow"}
    (shoulder,) = [s for s in report.singularities if s.kind == "shoulder"]
    assert "axes 4, 5 and 6 meet" in shoulder.meaning[0]


def test_markdown_and_latex() -> None:
    md = singularities("planar2").text
    assert md.startswith("# Singularities of planar2") and "| 1 | $s_{2} = 0" in md
    tex = singularities("planar2", fmt="latex").text
    assert tex.startswith("\\documentclass") and "\\det J" in tex and tex.rstrip().endswith("\\end{document}")


def test_cli_option(capsys) -> None:
    assert main(["derive", "planar3", "--singularities"]) == 0
    out = capsys.readouterr().out
    assert "Singularities of planar3" in out and "singular: $\\sigma_{min}" in out
    assert main(["derive", "planar3", "--singularities", "--singular-axes", "trans"]) == 0
    assert "No factor is common to all 3 minors" in capsys.readouterr().out
    assert main(["derive", "planar3", "--singularities", "--ik"]) == 2
    assert "--singularities" in capsys.readouterr().err
