"""The URDF sweep's chain enumeration (on small URDFs written here) and one chain's check."""

from __future__ import annotations

import numpy as np

from symkin.bench.urdf_sweep import _one, find_chains, format_sweep
from symkin.compile import compile as compile_model
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


def test_one_chain_is_compiled_and_checked(tmp_path):
    (tmp_path / "gripper.urdf").write_text(GRIPPER)
    chains, _, _ = find_chains(tmp_path)
    chain = next(c for c in chains if c.leaf == "fa_tip2")
    _one(chain, ("numpy",), compile_model, tmp_path, {}, seed=0)
    assert chain.failure == "" and chain.error["numpy"] < 1e-12 and chain.compile_s["numpy"] > 0
    row = {"urdf": chain.urdf, "base": chain.base, "leaf": chain.leaf, "n": chain.n, "mimic": True,
           "same_as": [], "compile_s": chain.compile_s, "error": chain.error, "pinocchio": None,
           "failure": ""}  # fmt: skip
    text = format_sweep({"ok": True, "files": 1, "unreadable": [], "found": 2, "distinct": 1, "find_s": 0.0,
                         "backends": ["numpy"], "rows": [row]})  # fmt: skip
    assert "failures: 0" in text and "joints per distinct chain: 3: 1" in text
    assert np.isfinite(chain.error["numpy"])


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
