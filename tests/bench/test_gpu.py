"""scripts/gpu_check.py (symkin.bench.gpu) on a machine without a GPU: it says so and exits 0, fast.
With a GPU it runs the checks and the benchmark (minutes): not a test's business."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from symkin.bench.gpu import NO_GPU, gpu_devices, run_gpu_check

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="module")
def no_gpu():
    if gpu_devices():
        pytest.skip("a GPU is here: scripts/gpu_check.py would run the whole GPU check")


def test_without_a_gpu_the_script_says_so_and_exits_0(no_gpu):
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    run = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "gpu_check.py"), "--no-bench"],
        capture_output=True, text=True, timeout=120, env=env, cwd=ROOT,
    )  # fmt: skip
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == NO_GPU


def test_without_a_gpu_the_check_returns_0(no_gpu, capsys):
    assert run_gpu_check(robots=("planar2",)) == 0
    assert capsys.readouterr().out.strip() == NO_GPU
