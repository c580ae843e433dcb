"""The URDF sweep on the JAX and PyTorch backends: chains found as ``symkin bench urdf`` finds them
(:func:`symkin.bench.urdf_sweep.find_chains`), each compiled on both backends and compared with the
numeric reference (FK, J0, Je, H0 of the chain's frame) within 1e-12 in float64; float32 within
:data:`symkin.check.tensor.F32_TOL` on the small sample (on the whole collection it is reported).

By default a sample: five chains of the tests' own URDF texts. ``SYMKIN_SWEEP_TENSOR=1`` runs every
distinct chain of example-robot-data (a few hundred; needs the ``compare`` extra) and prints the
count, the worst float64 and float32 errors and the time (``pytest -s`` shows them)."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

from symkin.bench.urdf_sweep import find_chains
from symkin.check.tensor import F32_TOL, reference_errors
from tests.diff_libs import BACKENDS, lib
from tests.model.test_urdf import PANDA
from tests.model.tree_urdfs import ARM_CAMERA, DUAL_ARM, GRIPPER, QUADRUPED

F64_TOL = 1e-12
TEXTS = {
    "quadruped": QUADRUPED,
    "arm_camera": ARM_CAMERA,
    "gripper": GRIPPER,
    "dual": DUAL_ARM,
    "panda": PANDA,
}


def _configurations(model, i: int) -> np.ndarray:
    """Four random configurations within limits and the zero one."""
    return np.vstack((model.random_q(4, seed=i), np.zeros((1, model.n))))


def _sweep(chains, backend: str) -> list[tuple[str, float, float]]:
    """(where, float64 error, float32 error) of every chain on ``backend``."""
    out = []
    for i, ch in enumerate(chains):
        try:
            err = reference_errors(ch.model, backend, _configurations(ch.model, i))
        except Exception as exc:  # noqa: BLE001 - a chain that does not compile is a failure to list
            out.append(
                (f"{ch.urdf}:{ch.leaf}: {type(exc).__name__}: {str(exc)[:200]}", float("inf"), float("inf"))
            )
            continue
        out.append(
            (f"{ch.urdf}:{ch.leaf} ({ch.n} joints{', mimic' if ch.mimic else ''})", err.float64, err.float32)
        )
    return out


@pytest.fixture(scope="module")
def sample(tmp_path_factory):
    """Five chains of the tests' URDF texts: one per file, a mimic chain of the gripper among them."""
    root = tmp_path_factory.mktemp("urdfs")
    for name, text in TEXTS.items():
        (root / f"{name}.urdf").write_text(text)
    chains = find_chains(root)[0]
    picked = {}
    for ch in chains:  # the longest chain of each file
        if ch.n > getattr(picked.get(ch.urdf), "n", 0):
            picked[ch.urdf] = ch
    assert len(picked) == 5 and any(ch.mimic for ch in picked.values())
    return list(picked.values())


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_sample_of_urdf_chains_matches_the_reference(sample, backend):
    lib(backend)
    for where, e64, e32 in _sweep(sample, backend):
        assert e64 <= F64_TOL, f"{backend} {where}: float64 error {e64:.3g}"
        assert 0 < e32 <= F32_TOL, f"{backend} {where}: float32 error {e32:.3g}"


@pytest.mark.skipif(os.environ.get("SYMKIN_SWEEP_TENSOR") != "1", reason="set SYMKIN_SWEEP_TENSOR=1")
@pytest.mark.parametrize("backend", BACKENDS)
def test_every_example_robot_data_chain_matches_the_reference(backend):
    lib(backend)
    from symkin.bench.tree import erd_robots_dir

    root = erd_robots_dir()
    if root is None:
        pytest.skip("example-robot-data is not installed (the compare extra)")
    chains = find_chains(root)[0]
    t0 = time.perf_counter()
    rows = _sweep(chains, backend)
    seconds = time.perf_counter() - t0
    ran = [r for r in rows if np.isfinite(r[1])]
    worst64, worst32 = max(ran, key=lambda r: r[1]), max(ran, key=lambda r: r[2])
    print(
        f"\n{backend}: {len(rows)} chains ({len(rows) - len(ran)} failed to run) in {seconds:.0f} s;"
        f" worst float64 {worst64[1]:.3g} ({worst64[0]}),"
        f" worst float32 {worst32[2]:.3g} ({worst32[0]})"
    )
    bad = [r for r in rows if not r[1] <= F64_TOL]
    assert bad == [], f"{len(bad)} chains above {F64_TOL:g}, e.g. {bad[:5]}"
