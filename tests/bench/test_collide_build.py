"""``symkin bench collide --build``: the cold build of a many-sphere model, its tables against the
straight-line form (both compiled; the same verdicts)."""

from __future__ import annotations

import os

import symkin
from symkin.bench.collide_build import dense_spheres, format_build, run_build
from symkin.emit import collision_self
from symkin.geometry import layout_of


def test_dense_model_keeps_the_links_and_halves_the_radii():
    panda = symkin.load("panda")
    model = dense_spheres(panda, 90, seed=1)
    assert len(model.geometry.shapes) == 90
    assert set(model.geometry.links) == set(panda.geometry.links)
    assert max(s.radius for s in model.geometry.shapes) == 0.5 * max(s.radius for s in panda.geometry.shapes)


def test_build_in_a_fresh_cache_and_the_two_forms_agree(monkeypatch):
    monkeypatch.setattr(collision_self, "UNROLL_PAIRS", 300)  # a small model past the threshold
    cache = os.environ.get("SYMKIN_CACHE")
    r = run_build("panda", total=60, unrolled=True, batch=400)
    assert os.environ.get("SYMKIN_CACHE") == cache  # restored
    assert r["spheres"] == 60 and r["pairs"] == len(
        layout_of(dense_spheres(symkin.load("panda"), 60)).self_pairs
    )
    assert r["tables"] and r["same_verdicts"] and 0 < r["proved"] < r["pairs"]
    assert r["tables_build"]["compile_s"] > 0 and r["proof_s"] > 0
    text = format_build(r)
    assert "fresh cache" in text and "straight-line" in text
