"""The JAX and PyTorch backends on a GPU: the float64/float32 checks against the numeric reference
and ``symkin bench diff``, where CUDA is there (``python scripts/gpu_check.py`` runs them).

:func:`gpu_devices` finds the GPU of each installed library (PyTorch: ``torch.cuda.is_available()``;
JAX: its GPU devices). Without one, :func:`run_gpu_check` prints so and succeeds: the test suite
and CI run on CPUs. With one, every built-in robot is compiled on each library that has a GPU and
compared on it with the numeric reference (:func:`symkin.check.tensor.reference_errors`: FK, J0,
Je and H0 within 1e-12 in float64, FK, J0 and H0 within 2e-6 in float32), then
:func:`symkin.bench.diff.run_diff` measures FK, J and IK against pytorch_kinematics on the GPU
(needs PyTorch with CUDA).
"""

from __future__ import annotations

import contextlib
from typing import Any

import numpy as np

from symkin.bench.common import optional

__all__ = ["gpu_devices", "run_gpu_check", "F64_TOL", "NO_GPU"]

F64_TOL = 1e-12  # float64 against the numeric reference (relative to max(1, |ref|)), as on the CPU
NO_GPU = "no GPU here: torch.cuda.is_available() is false and JAX sees no GPU device; nothing to check"


def gpu_devices() -> dict[str, Any]:
    """backend ("torch", "jax") -> its GPU device, for each installed library that sees one."""
    out: dict[str, Any] = {}
    torch = optional("torch")
    if torch is not None and torch.cuda.is_available():
        out["torch"] = "cuda"
    jax = optional("jax")
    if jax is not None:
        with contextlib.suppress(RuntimeError):  # "Unknown backend: 'gpu' requested, but no platforms"
            out["jax"] = jax.devices("gpu")[0]
    return out


def run_gpu_check(
    robots: tuple[str, ...] | None = None,
    bench_robot: str = "panda",
    batches: tuple[int, ...] = (1, 1024, 100_000),
    samples: int = 64,
    bench: bool = True,
) -> int:
    """Print the GPU checks and benchmark of the module docstring; the exit status: 0 when every
    check holds (or there is no GPU), 1 otherwise."""
    devices = gpu_devices()
    if not devices:
        print(NO_GPU)
        return 0
    from symkin.check.tensor import F32_TOL, reference_errors
    from symkin.model.robots import list_robots, load

    ok = True
    print(f"GPU devices: {', '.join(f'{b}: {d}' for b, d in devices.items())}")
    print(f"{'backend':8} {'robot':14} {'float64 error':>14} {'float32 error':>14}  result")
    for backend, device in devices.items():
        for i, name in enumerate(robots or list_robots()):
            robot = load(name)
            Q = np.vstack((robot.random_q(samples, seed=i), *robot.configs.values()))
            err = reference_errors(robot, backend, Q, device)
            good = err.float64 <= F64_TOL and err.float32 <= F32_TOL
            ok &= good
            print(
                f"{backend:8} {name:14} {err.float64:14.2e} {err.float32:14.2e}  {'ok' if good else 'FAIL'}"
            )
    print(f"tolerances: {F64_TOL:g} float64, {F32_TOL:g} float32 (relative to max(1, |reference|))")
    if bench and "torch" in devices:
        from symkin.bench.diff import format_diff, run_diff

        libraries = ("torch", "jax") if "jax" in devices else ("torch",)
        print(format_diff(run_diff(bench_robot, batches=batches, libraries=libraries, device="cuda")))
    elif bench:
        print("bench diff: skipped (it needs PyTorch with CUDA)")
    print("all ok" if ok else "FAILED")
    return 0 if ok else 1
