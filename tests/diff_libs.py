"""The JAX and PyTorch libraries for the tests of the differentiable backends: each test module
parametrises over :data:`BACKENDS`, and :func:`lib` skips cleanly where the library is not installed
(``pytest.importorskip``). JAX runs with 64-bit floats enabled (float64 is the reference's
precision; float32 is tested by asking for it)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

BACKENDS = ("jax", "torch")


class Lib:
    """One library: arrays in (``array``) and out (``numpy``) and its float dtypes."""

    def __init__(self, backend: str) -> None:
        self.backend = backend
        if backend == "jax":
            jax = pytest.importorskip("jax")
            jax.config.update("jax_enable_x64", True)
            self.mod, self.xp = jax, jax.numpy
        else:
            torch = pytest.importorskip("torch")
            self.mod = self.xp = torch
        self.float32, self.float64 = self.xp.float32, self.xp.float64

    def array(self, x: Any, dtype: Any = None) -> Any:
        """x (NumPy or a number) as an array of this library (float64 unless ``dtype``)."""
        dtype = self.float64 if dtype is None else dtype
        if self.backend == "jax":
            return self.xp.asarray(np.asarray(x), dtype=dtype)
        return self.xp.as_tensor(np.asarray(x), dtype=dtype)

    def numpy(self, x: Any) -> np.ndarray:
        """x as a float64 NumPy array (detached, on the host)."""
        if self.backend == "torch":
            x = x.detach().cpu()
        return np.asarray(x, dtype=float)

    def jacfwd(self, f: Any) -> Any:
        """Forward-mode Jacobian of f (JAX: ``jax.jacfwd``; PyTorch: ``torch.func.jacrev``, reverse mode)."""
        if self.backend == "jax":
            return self.mod.jacfwd(f)
        import torch.func

        return torch.func.jacrev(f)

    def vmap(self, f: Any) -> Any:
        if self.backend == "jax":
            return self.mod.vmap(f)
        import torch.func

        return torch.func.vmap(f)


def lib(backend: str) -> Lib:
    """The :class:`Lib` of ``backend`` (the test is skipped when the library is missing)."""
    return Lib(backend)
