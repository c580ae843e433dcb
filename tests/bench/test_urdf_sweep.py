"""The URDF sweep's chain enumeration (on small URDFs written here) and one chain's check."""

from __future__ import annotations

import re

import numpy as np
import pytest

from symkin.bench.urdf_sweep import TOL, _one, find_chains, format_sweep
from symkin.model.tree import Tree
from symkin.runtime.load import compile as compile_model
from tests.model.tree_urdfs import GRIPPER, QUADRUPED, joint, urdf


def test_chains_root_to_leaf_deduplicated_mimic_as_trees_and_refusals_reported(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "a" / "quad.urdf").write_text(QUADRUPED)
    (tmp_path / "quad_copy.urdf").write_text(QUADRUPED.replace('name="quad"', 'name="other"'))
    (tmp_path / "gripper.urdf").write_text(GRIPPER)
    floating = urdf(
        ["w", "b", "c"], [joint("free", "w", "b", kind="floating", axis=None, limit=""), joint("j", "b", "c")]
    )
    (tmp_path / "floating.urdf").write_text(floating)
    (tmp_path / "broken.urdf").write_text("<robot name='x'><link name='a'/>")
    chains, bad, found = find_chains(tmp_path)
    assert found == 3 + 3 + 2 + 1  # quad twice, gripper's two leaves, the floating robot's one
    keys = {(c.urdf, c.leaf): c for c in chains}
    assert len(chains) == 3 + 2 + 1  # the copy adds nothing
    assert keys[("a/quad.urdf", "r_foot")].also == ["quad_copy.urdf:r_foot"]
    assert keys[("floating.urdf", "c")].base == "b"  # starts below the floating joint
    assert keys[("gripper.urdf", "fb")].model.__class__.__name__ == "Tree"  # a mimic joint on the path
    assert [b[0] for b in bad] == ["broken.urdf"] and "malformed XML" in bad[0][1]


class _Shifted:
    """Compiled kinematics whose FK (translation x) or J (first entry) is off by a known amount."""

    def __init__(self, kin, dT: float, dJ: float) -> None:
        self.kin, self.dT, self.dJ = kin, dT, dJ

    def fkine(self, *args, **kwargs):
        T = np.array(self.kin.fkine(*args, **kwargs))
        T[..., 0, 3] += self.dT
        return T

    def jacob0(self, *args, **kwargs):
        J = np.array(self.kin.jacob0(*args, **kwargs))
        J[..., 0, 0] += self.dJ
        return J


def _gripper_tip(root):
    """The chain to fa_tip2 of GRIPPER (three joints, two mimic joints on the path)."""
    root.mkdir(exist_ok=True)
    (root / "gripper.urdf").write_text(GRIPPER)
    chains, _, _ = find_chains(root)
    return next(c for c in chains if c.leaf == "fa_tip2")


def _row(c) -> dict:
    """A chain's row of the sweep's report, as run_sweep writes it."""
    return {"urdf": c.urdf, "base": c.base, "leaf": c.leaf, "n": c.n,
            "mimic": c.model.__class__.__name__ == "Tree", "same_as": c.also, "compile_s": c.compile_s,
            "error": c.error, "pinocchio": c.pinocchio, "snap": c.snap, "failure": c.failure}  # fmt: skip


def test_one_chain_is_compiled_and_checked(tmp_path):
    root = tmp_path / "erd"
    good, bad = _gripper_tip(root), _gripper_tip(root)
    _one(good, ("numpy",), compile_model, root, {}, seed=0)
    assert good.failure == "" and good.error["numpy"] < 1e-12 and good.compile_s["numpy"] > 0
    # a deliberately wrong model (the wrist 1 cm further out) compiled for the same chain is flagged
    (tmp_path / "wrong.urdf").write_text(GRIPPER.replace('xyz="0.3 0 0"', 'xyz="0.31 0 0"'))
    wrong = Tree.from_urdf(tmp_path / "wrong.urdf", frames=["fa_tip2"], base_link=bad.base)
    _one(bad, ("numpy",), lambda model, backend: compile_model(wrong, backend), root, {}, seed=0)
    assert 5e-3 < bad.error["numpy"] < 2e-2, bad.error
    assert f"numpy: FK/J differ from the reference by {bad.error['numpy']:.2e}" in bad.failure.split("; ")
    text = format_sweep({"ok": False, "files": 1, "unreadable": [], "found": 2, "distinct": 2, "find_s": 0.0,
                         "backends": ["numpy"], "rows": [_row(good), _row(bad)]})  # fmt: skip
    assert "joints per distinct chain: 3: 2" in text
    assert re.search(r"^numpy +2 +1 ", text, re.M), text  # compiled 2, within 1e-10: 1
    assert f"largest FK/J difference from the numeric reference: {bad.error['numpy']:.1e}" in text
    assert "failures: 1\n" in text and f"\n  gripper.urdf:fa_tip2: {bad.failure}" in text


@pytest.mark.parametrize(("dT", "dJ"), [(1e-6, 0.0), (0.0, 1e-6), (5e-11, 0.0)])
def test_the_error_is_the_difference_from_the_numeric_reference(tmp_path, dT, dJ):
    """Kinematics off by a known amount in FK or in J: the chain's error is that amount, and it is a
    failure when above the sweep's tolerance (1e-10)."""
    chain = _gripper_tip(tmp_path)
    _one(chain, ("numpy",), lambda m, b: _Shifted(compile_model(m, b), dT, dJ), tmp_path, {}, seed=0)
    shift = max(dT, dJ)
    assert abs(chain.error["numpy"] - shift) < 1e-13, chain.error
    failures = chain.failure.split("; ")
    flagged = f"numpy: FK/J differ from the reference by {chain.error['numpy']:.2e}" in failures
    assert flagged == (shift > TOL), chain.failure


def test_sweep_adds_its_own_chains_of_fixed_joints(tmp_path, monkeypatch):
    """Fixed joints with rpy after a 6-joint arm (2, 3, 4 and 2000 of them), 2000 before it and
    300 between its joints, 2000 quarter turns: each a distinct chain, compiled and checked with
    the collection's."""
    from symkin.bench import urdf_sweep

    (tmp_path / "gripper.urdf").write_text(GRIPPER)
    monkeypatch.setattr(urdf_sweep, "erd_robots_dir", lambda: tmp_path)
    r = urdf_sweep.run_sweep(backends=("numpy",), progress=False, limit=1)
    own = [row for row in r["rows"] if row["synthetic"]]
    assert sorted(row["urdf"] for row in own) == sorted(urdf_sweep.synthetic_urdfs())
    assert r["distinct"] == 1 and len(r["rows"]) == 1 + len(own)  # the collection's counts are its own
    assert r["ok"] and all(row["n"] == 6 and row["error"]["numpy"] < 1e-10 for row in own)
    text = format_sweep(r)
    assert "the sweep's own chains" in text and "arm6_fixed2000.urdf (6 joints)" in text
    assert "failures: 0" in text
