"""`symkin check` of a tree: every chain row for each frame, the *_all functions, the C controllers' ones."""

from __future__ import annotations

from symkin import Tree
from symkin.check.kinematics import check
from tests.model.tree_urdfs import DUAL_ARM


def test_check_tree_covers_hessians_manipulability_and_the_c_controller_functions():
    report = check(Tree.from_urdf(DUAL_ARM), backends=("c", "numpy"), samples=3)
    names = {(r.backend, r.function) for r in report.rows}
    for backend in ("c", "numpy"):
        for fn in (
            "hessian0",
            "hessiane",
            "jacobm:all",
            "jacob0_dot",
            "fkine_jacob0_all",
            "hessian0 (large q)",
        ):
            assert (backend, fn) in names, fn
        assert (
            next(r for r in report.rows if r.backend == backend and r.function == "hessian0").fd_error < 1e-6
        )
    assert {("c", "C jacob0_hessian0_<k>"), ("c", "C manipulability_<k>")} <= names
    assert report.ok, report.format()
