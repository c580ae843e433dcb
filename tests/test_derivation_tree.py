"""The derivation of a tree: the walk once, each frame's pose and Jacobian, mimic rules, checked."""

from __future__ import annotations

from symkin import Tree
from symkin.derive.chain import derivation
from symkin.derive.program import tree_derivation
from tests.model.tree_urdfs import DUAL_ARM, GRIPPER


def test_mimic_rules_frames_and_check_in_markdown_and_latex():
    tree = Tree.from_urdf(GRIPPER)
    md = tree_derivation(tree)
    assert r"$\theta_{4} = 2\, q_{2} + 0.1$, $\theta_{5} = -q_{2} - 0.05$" in md  # a mimic of a mimic
    assert r"$\theta_{6} = -q_{3} + 0.01$" in md
    assert md.count("### link") == len(tree.segments)
    assert "### Frame `fa_tip2`" in md and "### Frame `fb`" in md
    assert "(tolerance 1e-12): ok" in md and "FAILED" not in md
    tex = tree_derivation(tree, "latex")
    assert tex.startswith("\\documentclass") and "###" not in tex and "\\section{" in tex
    assert derivation(tree) == md  # the chain's entry takes a tree too


def test_checks_catch_a_wrong_step(monkeypatch):
    """The 30-digit checks compare with the literal products along each path and with the numeric
    Tree: a walk with one wrong sign fails both."""
    import symkin.derive.program as dp

    real = dp.derive_tree_program

    def broken(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        tp = real(*args, **kwargs)
        s, e = tp.lines[10]
        return type(tp)(**{**tp.__dict__, "lines": (*tp.lines[:10], (s, -e), *tp.lines[11:])})

    monkeypatch.setattr(dp, "derive_tree_program", broken)
    md = tree_derivation(Tree.from_urdf(GRIPPER))
    assert "J0: FAILED" in md and "(tolerance 1e-12): FAILED" in md


def test_abbreviations_of_ten_joints_or_more_are_unambiguous():
    """With 13 joints cos q_12 and cos(q_1 + q_2) must not both read c_{12}."""
    import re

    md = tree_derivation(Tree.from_urdf(DUAL_ARM))
    legend = next(line for line in md.splitlines() if line.startswith("Notation:"))
    names = re.findall(r"\$([cs]_\{[^}]*\}) = ", legend)
    assert "c_{12}" in names and "c_{1,2}" in names and len(names) == len(set(names))
