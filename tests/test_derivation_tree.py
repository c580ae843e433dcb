"""The derivation of a tree: the walk once, each frame's pose and Jacobian, mimic rules, checked."""

from __future__ import annotations

from symkin import Tree
from symkin.derive.tree import tree_derivation
from tests.model.tree_urdfs import GRIPPER


def test_mimic_rules_frames_and_check_in_markdown_and_latex():
    tree = Tree.from_urdf(GRIPPER)
    md = tree_derivation(tree)
    assert r"$\theta_{4} = 2\, q_{2} + 0.1$, $\theta_{5} = -q_{2} - 0.05$" in md  # a mimic of a mimic
    assert r"$\theta_{6} = -q_{3} + 0.01$" in md
    assert md.count("### link") == len(tree.segments)
    assert "### Frame `fa_tip2`" in md and "### Frame `fb`" in md
    assert "(ok, tolerance 1e-12)" in md
    tex = tree_derivation(tree, "latex")
    assert tex.startswith("\\documentclass") and "###" not in tex and "\\section{" in tex
