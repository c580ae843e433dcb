"""`symkin check` on the JAX and PyTorch backends: FK, J and H in float64 and float32 against the
numeric reference, a chain and a tree, and a clear skip (not a failure) where a library is missing."""

from __future__ import annotations

import pytest

import symkin.check.tensor as tensor
from symkin import Tree
from symkin.check.kinematics import check
from symkin.cli.main import main
from symkin.model.robots import load
from tests.diff_libs import BACKENDS, lib
from tests.model.tree_urdfs import GRIPPER

ROWS = {"fkine", "jacob0", "jacobe", "hessian0", "hessiane", "fkine_jacob0", "jacob0_hessian0", "fkine_all"}


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_chain_checks_fk_j_h_in_float64_and_float32(backend):
    lib(backend)
    report = check(load("stanford"), backends=[backend], samples=3)
    assert report.ok, report.format()
    rows = {r.function: r for r in report.rows if r.backend == backend}
    assert ROWS | {"fkine (float32)", "hessian0 (large q)", "link_poses"} <= set(rows)
    assert max(rows[k].ref_error for k in ROWS) <= 1e-12
    assert 0 < rows["fkine (float32)"].ref_error <= tensor.F32_TOL  # float32 really ran, within its bound
    assert rows["jacob0"].fd_error is not None and rows["jacob0"].fd_error < 1e-6
    assert not report.skipped


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_tree_checks_every_frame(backend):
    lib(backend)
    tree = Tree.from_urdf(GRIPPER)
    report = check(tree, backends=[backend], samples=3)
    assert report.ok, report.format()
    assert f"{len(tree.frames)} frames" in report.robot
    assert {"jacob0_all", "hessiane"} <= {r.function for r in report.rows if r.backend == backend}


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_wrong_backend_function_fails_the_check(backend, monkeypatch):
    L = lib(backend)
    import symkin

    kin = symkin.compile(load("planar3"), backend=backend)
    view = tensor.NumpyView(kin)
    real = kin.function

    def wrong(kind, frame=None):  # the generated hessian0, off by a relative 1e-6
        fn = real(kind, frame)
        return (lambda q: fn(q) * (1 + 1e-6)) if kind == "hessian0" else fn

    monkeypatch.setattr(kin, "function", wrong)
    report = check(kin.model, backends=[view], samples=3)
    assert not report.ok and "hessian0" in {r.function for r in report.rows if not r.ok}
    assert L.backend == backend


def test_a_missing_library_is_skipped_with_a_line_not_a_failure(monkeypatch, capsys):
    monkeypatch.setitem(tensor.TENSOR_BACKENDS, "jax", ("symkin_no_such_library", "jax"))
    report = check(load("planar2"), backends=["numpy", "jax"], samples=2)
    assert report.ok and {r.backend for r in report.rows} == {"ref", "numpy"}
    line = "jax: skipped: symkin_no_such_library not installed (pip install 'symkin[jax]')"
    assert report.skipped == (line,)
    assert report.skipped[0] in report.format() and report.as_dict()["skipped"] == list(report.skipped)
    assert main(["check", "planar2", "--backend", "jax", "--samples", "2"]) == 0
    assert "jax: skipped: symkin_no_such_library not installed" in capsys.readouterr().out


def test_the_cli_default_covers_the_installed_libraries(monkeypatch, capsys):
    import symkin.check.kinematics as check_module

    seen = {}

    def record(robot, backends, samples, seed):
        seen["backends"] = tuple(backends)
        return check_module.CheckReport(robot.name, 0, ())

    monkeypatch.setattr(check_module, "check", record)
    assert main(["check", "planar2"]) == 0
    assert seen["backends"] == ("c", "numpy", "casadi", "jax", "torch")
