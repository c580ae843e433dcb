"""The tree program: size linear in the number of legs and frames, shared parts named once, and
the emitted functions' outputs equal to the numeric reference."""

from __future__ import annotations

import numpy as np

from symkin import Tree
from symkin.compiler.compile import derived_functions
from symkin.symbolic.kinematics import const_to_sympy, joint_symbols
from symkin.symbolic.program import derive_tree_program
from tests.model.tree_urdfs import GRIPPER, joint, urdf


def legs(k: int) -> Tree:
    """A body with k three-joint legs (hip about x, hip and knee about y)."""
    links, joints = ["body"], []
    for i in range(k):
        names = [f"h{i}", f"t{i}", f"s{i}"]
        links += names
        joints += [
            joint(f"haa{i}", "body", names[0], xyz=f"0.{i + 1} 0.1 0", rpy=f"0 0 0.{i + 1}", axis="1 0 0"),
            joint(f"hfe{i}", names[0], names[1], xyz="0 0.05 0", axis="0 1 0"),
            joint(f"kfe{i}", names[1], names[2], xyz="0 0 -0.2", axis="0 1 0"),
        ]
    return Tree.from_urdf(urdf(links, joints))


def ops(tree: Tree) -> dict[str, int]:
    return {f.name: f.code.counts.total for f in derived_functions(tree)}


def test_size_grows_linearly_with_legs():
    small, big = ops(legs(4)), ops(legs(8))
    for name in ("fkine_all", "jacob0_all", "fkine_jacob0_all"):
        assert big[name] <= 2.1 * small[name], name
    # one frame's own function does not grow with the others
    assert big["fkine_jacob0_0"] == small["fkine_jacob0_0"]


def test_frames_on_one_branch_share_their_common_path():
    """Frames at depths 3, 6 and 9 of one chain: the all-frames program costs about the deepest
    frame's, not the sum of three (each Jacobian column is named once per frame)."""
    links = [f"l{i}" for i in range(10)]
    joints = [
        joint(f"j{i}", links[i], links[i + 1], xyz="0.1 0 0", axis="0 1 0" if i % 2 else "0 0 1")
        for i in range(9)
    ]
    tree = Tree.from_urdf(urdf(links, joints), frames=["l3", "l6", "l9"])
    counts = ops(tree)
    alone = [counts[f"fkine_jacob0_{k}"] for k in range(3)]
    assert counts["fkine_jacob0_all"] < sum(alone)
    assert counts["fkine_all"] <= 1.05 * counts["fkine_2"]  # the shallower poses come with the deepest


def test_program_outputs_equal_the_reference():
    tree = Tree.from_urdf(GRIPPER)
    tp = derive_tree_program(tree, joint_symbols(tree.n), const_to_sympy)
    q = tree.random_q(seed=3)
    values = dict(zip(tp.q, q))
    for s, e in tp.lines:
        values[s] = float(e.evalf(subs=values))
    T, J = tree.fkine_jacob0_all(q)
    for k in range(len(tree.frames)):
        Tk = np.array(tp.T[k].evalf(subs=values), dtype=float)
        Jk = np.array(tp.J0[k].evalf(subs=values), dtype=float)
        Jek = np.array(tp.Je[k].evalf(subs=values), dtype=float)
        assert np.abs(Tk - T[k]).max() < 1e-13
        assert np.abs(Jk - J[k]).max() < 1e-13
        assert np.abs(Jek - tree.jacobe(q, tree.frames[k])).max() < 1e-13
