"""`symkin check`: every backend against the reference and finite differences, and loud failures."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin.check.kinematics import check
from symkin.model.robots import list_robots, load
from symkin.runtime.kinematics import KIN_METHODS


@pytest.mark.parametrize("name", list_robots())
def test_every_builtin_robot_checks_below_1e10(name):
    report = check(load(name), samples=5)  # every backend: c, numpy, casadi
    assert report.ok, report.format()
    assert max(r.ref_error for r in report.rows) < 1e-10


def _broken(kin, method: str, delta: float):
    """A copy of a compiled Kinematics whose ``method`` is off by ``delta`` in one entry."""
    original = getattr(kin, method)

    def wrong(q):
        out = np.array(original(q), copy=True)
        out[..., 0, -1] += delta
        return out

    fake = symkin.Kinematics(kin.robot, kin.backend, {m: getattr(kin, m) for m in KIN_METHODS}, kin.files)
    setattr(fake, method, wrong)
    return fake


@pytest.mark.parametrize(("method", "delta"), [("jacob0", 1e-7), ("hessiane", 1e-5), ("fkine", 1e-9)])
def test_a_deliberately_broken_backend_fails_loudly(method, delta):
    robot = load("ur5")
    kin = symkin.compile(robot, backend="numpy")
    report = check(robot, backends=[_broken(kin, method, delta)], samples=4)
    assert not report.ok
    failed = {r.function for r in report.rows if not r.ok}
    assert method in failed
    assert "FAIL" in report.format() and report.format().rstrip().endswith("FAILED")


def test_check_command_exits_1_when_a_backend_is_broken(monkeypatch, capsys):
    import symkin.check.kinematics as check_module
    from symkin.cli.main import main

    real_check = check_module.check

    def broken_check(robot, backends, samples, seed):
        kin = symkin.compile(robot, backend="numpy")
        return real_check(robot, backends=[_broken(kin, "jacob0", 1e-6)], samples=samples, seed=seed)

    monkeypatch.setattr(check_module, "check", broken_check)
    code = main(["check", "planar3", "--samples", "3"])
    out = capsys.readouterr().out
    assert code == 1 and "FAILED" in out
