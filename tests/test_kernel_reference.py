"""The compiled kinematics and collision queries against outputs stored before the chain and tree
kernels were merged into one (``tests/data/kernel_reference.py`` made them): FK, J and distances
to 2e-15 and Hessians to 1e-14 relative to max(1, |x|), collision verdicts identical, on every
backend the stored file holds. The collision models are built from the stored shapes.

The example-robot-data sweep (``tests/data/sweep_reference.npz``, every distinct chain of the
collection) is checked with ``SYMKIN_SWEEP_REFERENCE=1`` (it compiles a few hundred chains)."""

from __future__ import annotations

import os

import numpy as np
import pytest

from tests.data import kernel_reference as ref

STORED = ref.load(ref.KERNEL)
MODELS = {**ref.models(), **ref.geometry_models()}


def test_the_stored_file_covers_every_model_and_backend():
    assert set(STORED) == set(MODELS)
    for name, entry in STORED.items():
        backends = {k.split("/", 1)[0] for k in entry if "/" in k}
        assert backends == set(ref.COLLISION_BACKENDS if "geometry" in entry else ref.BACKENDS), name


def test_a_difference_beyond_the_tolerance_is_reported():
    entry = STORED["planar2"]
    fresh = {k: v.copy() for k, v in entry.items() if "/" in k}
    assert ref.differences(MODELS["planar2"], entry, fresh) == []
    fresh["c/batch/jacob0"][0, 0, 0] += 3e-15 * max(1.0, abs(fresh["c/batch/jacob0"][0, 0, 0]))
    fresh["numpy/one/hessian0"][0, 0, 0, 0] += 5e-15  # within the Hessians' 1e-14
    assert ref.differences(MODELS["planar2"], entry, fresh) == [
        "c/batch/jacob0: relative difference 3e-15 > 2e-15"
    ]


@pytest.mark.parametrize("name", sorted(STORED))
def test_outputs_agree_with_the_stored_ones(name):
    assert ref.check(name, STORED[name], MODELS[name]) == []


@pytest.mark.skipif(os.environ.get("SYMKIN_SWEEP_REFERENCE") != "1", reason="set SYMKIN_SWEEP_REFERENCE=1")
def test_the_example_robot_data_sweep_agrees_with_the_stored_outputs():
    pytest.importorskip("example_robot_data")
    if not ref.SWEEP.exists():
        pytest.skip("no stored sweep (python -m tests.data.kernel_reference --sweep)")
    stored = ref.load(ref.SWEEP)
    bad = []
    for name, entry in stored.items():
        bad += ref.check(name, entry, ref.sweep_model(str(entry["where"])))
    assert bad == [], f"{len(bad)} differences, e.g. {bad[:5]}"
    assert np.all([len(e["Q"]) == 2 for e in stored.values()])
