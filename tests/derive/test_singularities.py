"""symkin derive --singularities: every reported factor is singular in the numeric reference Jacobian,
and every rank drop found along random lines through joint space is a zero of a reported factor."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import sympy as sp

import symkin
from symkin.cli.main import main
from symkin.derive.singular_lines import MAX_LINES, line_check
from symkin.derive.singularities import SINGULAR_TOL, singularities
from symkin.errors import ParameterError
from symkin.symbolic.singularities import singular_factors

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def _sigma_min(robot: symkin.Robot, Q: np.ndarray, rows: tuple[int, ...]) -> np.ndarray:
    """sigma_min of the numeric reference J (the rows used) at each configuration of Q."""
    return np.linalg.svd(robot.jacob0(Q)[:, list(rows), :], compute_uv=False)[:, -1]


def _dh_arms() -> dict[str, symkin.Robot]:
    """Arms beyond the built-in ones: DH tables of a shoulder-offset 6R (as a Fanuc LR Mate), a 5R
    (J is 6 x 5: its row minors), a spatial 3R (the position rows), a 7R with offsets at every
    other joint (as a Kinova Gen3), an R-P-R-R arm with a prismatic joint, and the UR5 from its URDF."""
    from symkin.model.dh import DHLink as L

    dh = symkin.Robot.from_dh
    return {
        "offset6": dh(
            [
                L(d=0.33, a=0.05, alpha="-pi/2"),
                L(a=0.33),
                L(a=0.035, alpha="-pi/2"),
                L(d=0.335, alpha="pi/2"),
                L(alpha="-pi/2"),
                L(d=0.08),
            ],
            name="offset6",
        ),
        "arm5": dh([L(d=0.15, alpha="pi/2"), L(a=0.3), L(a=0.25), L(alpha="pi/2"), L(d=0.1)], name="arm5"),
        "elbow3": dh([L(d=0.4, alpha="pi/2"), L(a=0.3), L(a=0.25)], name="elbow3"),
        "offset7": dh(
            [L(d=d, alpha="pi/2") for d in (0.28, 0.01, 0.41, 0.01, 0.31)] + [L(alpha="pi/2"), L(d=0.17)],
            name="offset7",
        ),
        "rprr": dh(
            [
                L(d=0.3, alpha="pi/2"),
                L(prismatic=True, alpha="-pi/2", qlim=(0.1, 0.8)),
                L(a=0.2, alpha="pi/2"),
                L(a=0.1),
            ],
            name="rprr",
        ),
        "ur5.urdf": symkin.Robot.from_urdf(str(EXAMPLES / "ur5.urdf"), end_link="tool0"),
    }


ARMS = [*symkin.list_robots(), *_dh_arms()]


@pytest.mark.parametrize("name", ARMS)
def test_every_arm_lists_exactly_its_singular_families(name: str) -> None:
    # each listed factor vanishes where J loses rank (sigma_min of the numeric reference ~0 on its zero
    # set), and the rank drops found along random lines through joint space are all zeros of a factor
    robot = _dh_arms()[name] if name in _dh_arms() else symkin.load(name)
    report = singularities(robot, seed=3, lines=24)
    A = report.analysis
    assert report.ok, report.summary()
    values = sp.lambdify(A.q, [s.factor.expr for s in report.singularities], "numpy")
    for k, s in enumerate(report.singularities):
        assert len(s.solutions) == 3, s.factor.expr
        f = np.array([float(values(*q)[k]) for q in s.solutions])
        assert np.abs(f).max() < 1e-9, f"{name}: {s.factor.expr} is not 0 at its solutions"
        assert _sigma_min(robot, s.solutions, A.rows).max() < SINGULAR_TOL, f"{name}: {s.factor.expr}"
        # moving the solved joint away from the solution leaves the singular set
        away = s.solutions.copy()
        away[:, s.factor.joints[0]] += 0.3
        assert _sigma_min(robot, away, A.rows).min() > 1e-6, f"{name}: {s.factor.expr}"
    assert _sigma_min(robot, robot.random_q(30, seed=7), A.rows).min() > 1e-6
    assert report.lines.ok and report.lines.lines == 24
    if report.singularities:
        assert len(report.lines.drops)  # the lines do cross the listed families
        # and would flag them if the factors were missing: the check is not vacuous
        bare = line_check(robot, A.rows, A.q, [], lines=24, seed=3)
        assert len(bare.unexplained) == len(bare.drops) > 0


@pytest.mark.parametrize("name", ["lbr_iiwa7", "lbr_iiwa14"])
def test_stretched_and_folded_elbow_of_the_iiwa_are_listed(name: str) -> None:
    # q4 = 0 (1-based; the arm stretched out, inside the limits) and q4 = pi: sigma_min ~ 2e-16 there.
    # The minors carry sin q4 and (cos q4 - 1)(cos q4 + 1): a gcd, not the intersection of factor sets
    robot = symkin.load(name)
    A = singular_factors(name)
    values = sp.lambdify(A.q, [f.expr for f in A.factors], "numpy")
    Q = robot.random_q(4, seed=5)
    for angle in (0.0, np.pi):
        Q[:, 3] = angle
        assert np.linalg.svd(robot.jacob0(Q), compute_uv=False)[:, -1].max() < 1e-12
        for q in Q:  # some listed factor vanishes at each
            assert min(abs(float(v)) for v in values(*q)) < 1e-12, (name, angle, A.factors)
    assert any(f.kind == "sin" and f.joints == (3,) for f in A.factors)
    report = singularities(name)
    assert report.ok
    (elbow,) = [s for s in report.singularities if s.factor.kind == "sin"]
    assert elbow.kind == "elbow" and "axes of joints 3 and 5 coincide" in elbow.meaning[0]


def test_iiwa7_folded_elbow_is_a_double_root() -> None:
    # upper arm and forearm both 0.4 m: folded back (q4 = pi) the wrist centre is the shoulder centre,
    # J has rank 4; the minors' gcd is sin q4 cos(q4 / 2)
    report = singularities("lbr_iiwa7")
    kinds = {s.factor.kind: s for s in report.singularities}
    assert set(kinds) == {"sin", "half-cos"}
    half = kinds["half-cos"]
    assert half.factor.expr == sp.cos(report.analysis.q[3] / 2) and half.rank == 4 and half.also == (0,)
    assert "coincide" in half.meaning[-1] and "cos(q_{4}/2) = 0" in report.text


def test_lines_flag_a_missing_factor() -> None:
    # without its factor sin q4, the iiwa's stretched elbow is a rank drop no factor explains
    robot = symkin.load("lbr_iiwa14")
    A = singular_factors(robot)
    check = line_check(robot, A.rows, A.q, [], lines=12, seed=0)
    assert not check.ok and len(check.unexplained)
    assert np.allclose(np.abs(np.sin(check.unexplained[:, 3])), 0, atol=1e-6)


def test_lines_must_be_a_bounded_count() -> None:
    for bad in (-1, 1.5, True, MAX_LINES + 1):
        with pytest.raises(ParameterError, match="lines"):
            singularities("planar2", lines=bad)


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
    assert "Singularities of planar3" in out and "singular (rank 2 of 3): $\\sigma_{min}" in out
    assert "All " in out and "rank drops found are zeros of a condition above" in out
    assert main(["derive", "planar3", "--singularities", "--singular-axes", "trans"]) == 0
    assert "No factor is common to all 3 minors" in capsys.readouterr().out
    assert main(["derive", "planar3", "--singularities", "--ik"]) == 2
    assert "--singularities" in capsys.readouterr().err


def test_a_report_missing_a_factor_is_not_ok(monkeypatch) -> None:
    # what the iiwa14's report was: no factor, yet "ok"; the lines now find the stretched elbow
    import dataclasses

    import symkin.derive.singularities as module

    real = module.singular_factors
    monkeypatch.setattr(
        module, "singular_factors", lambda *a, **k: dataclasses.replace(real(*a, **k), factors=())
    )
    report = module.singularities("lbr_iiwa14")
    assert not report.ok and not report.singularities and len(report.lines.unexplained)
    assert "are zeros of no condition above" in report.text and "the list is incomplete" in report.text
    assert report.summary().endswith("NOT ok")


def test_check_singularities_cli(capsys) -> None:
    assert main(["check", "lbr_iiwa14", "--singularities", "--lines", "8"]) == 0
    out = capsys.readouterr().out
    assert "sin(q4) = 0: singular, rank 5 of 6" in out and out.rstrip().endswith("ok")
    assert "lines: 8 x 400 samples" in out
    assert main(["check", "planar2", "--singularities", "--lines", str(MAX_LINES + 1)]) == 2
    assert "--lines" in capsys.readouterr().err
    assert main(["check", "planar2", "--singularities", "--backend", "c"]) == 2
