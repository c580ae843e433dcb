"""`symkin check` of a tree covers every generated function, the C controllers' ones included."""

from __future__ import annotations

from symkin import Tree
from symkin.check.tree import check_tree
from tests.model.tree_urdfs import DUAL_ARM


def test_check_tree_covers_hessians_manipulability_and_the_c_controller_functions():
    report = check_tree(Tree.from_urdf(DUAL_ARM), backends=("c", "numpy"), samples=3)
    names = {(r.backend, r.function) for r in report.rows}
    for backend in ("c", "numpy"):
        assert {(backend, "hessian0(frame)"), (backend, "manipulability(frame)")} <= names
    assert {("c", "C jacob0_hessian0_<k>"), ("c", "C manipulability_<k>")} <= names
    assert report.ok, report.format()
