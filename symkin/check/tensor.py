"""The JAX and PyTorch backends in ``symkin check``: which of them can run here, and their
generated kinematics seen from NumPy so :func:`symkin.check.kinematics.check` compares them with
the numeric reference as it does the other backends.

The libraries are optional (extras ``jax`` and ``torch``): :func:`available` says which are
installed, and a check skips the others with a line saying so rather than failing. The reference
is float64, so JAX runs with 64-bit floats enabled (``jax_enable_x64``, a process-wide switch the
check turns on). float32 is checked against the float64 reference at the same float32-rounded
configurations, within :data:`F32_TOL`.
"""

from __future__ import annotations

import importlib.util
from dataclasses import dataclass
from functools import partial
from typing import Any

import numpy as np

from symkin.check.measure import relative_error as _rel
from symkin.compiler.compile import OPTIONAL_BACKENDS

__all__ = [
    "TENSOR_BACKENDS",
    "F32_TOL",
    "available",
    "missing_reason",
    "NumpyView",
    "PrecisionErrors",
    "reference_errors",
]

#: the optional backends ``symkin check`` covers: backend -> (the library it imports, its pip extra)
TENSOR_BACKENDS = OPTIONAL_BACKENDS

# float32 against the float64 reference, relative to max(1, |ref|): 16 float32 ulps of 1 (eps =
# 1.19e-7), as tests/emit/test_tensor.py holds every built-in robot to
F32_TOL = 2e-6


def available(backend: str) -> bool:
    """Whether ``backend`` can run here: a built-in backend, or an optional one whose library is installed."""
    module = TENSOR_BACKENDS.get(backend, (None,))[0]
    return module is None or importlib.util.find_spec(module) is not None


def missing_reason(backend: str) -> str:
    """What a check says for an optional backend whose library is not installed."""
    module, extra = TENSOR_BACKENDS[backend]
    return f"{backend}: skipped: {module} not installed (pip install 'symkin[{extra}]')"


class NumpyView:
    """A :class:`symkin.runtime.diff.kinematics.DiffKinematics` taking and returning float64 NumPy
    arrays: ``view.fkine(Q)`` is ``kin.fkine(array(Q))`` copied back to the host (tuples element by
    element); ``dtype="float32"`` evaluates in float32 instead. The generated functions run as
    :meth:`~symkin.runtime.diff.kinematics.DiffKinematics.function` gives them (JAX: eagerly, as
    the check's many batch shapes would each compile anew under ``jax.jit``; the jitted functions
    trace the same code, which tests/emit/test_tensor.py checks). Attributes other than functions
    (``backend``, ``n``, ``frames``, ``model``) are the kinematics' own. ``device``: where the
    arrays go (a ``torch.device`` or name, a JAX device; None: the library's default)."""

    def __init__(self, kin: Any, device: Any = None) -> None:
        if kin.backend == "jax":
            import jax

            jax.config.update("jax_enable_x64", True)  # the reference's precision (module docstring)
        self.kin, self.device = kin, device
        self.backend: str = kin.backend
        self.model = kin.model
        self.n: int = kin.n
        self.frames: tuple[str, ...] = kin.frames

    def __getattr__(self, name: str) -> Any:
        if name == "kin":  # not set yet (unpickling, copying): no recursion through __getattr__
            raise AttributeError(name)
        if name in self.kin.kinds:  # a generated function: the plain one (JAX: eager, not jitted)
            return partial(self._generated, name)
        fn = getattr(self.kin, name)
        return partial(self._call, fn) if callable(fn) else fn

    def _generated(self, kind: str, Q: Any, *args: Any, frame: Any = None, **kw: Any) -> Any:
        return self._call(self.kin.function(kind, frame), Q, *args, **kw)

    def array(self, x: Any, dtype: str = "float64") -> Any:
        """x as an array of the backend in ``dtype`` ("float64" or "float32")."""
        xp = self.kin.ops.xp
        if self.backend == "jax":
            out = xp.asarray(np.asarray(x), dtype=getattr(xp, dtype))
            return out if self.device is None else self.kin.ops.jax.device_put(out, self.device)
        return xp.as_tensor(np.asarray(x), dtype=getattr(xp, dtype), device=self.device)

    def _call(self, fn: Any, Q: Any, *args: Any, dtype: str = "float64", **kw: Any) -> Any:
        Q = np.asarray(Q, dtype=float)
        N = len(Q) if Q.ndim == 2 else None
        out = fn(*(self.array(_padded(x, N), dtype) for x in (Q, *args)), **kw)
        if isinstance(out, tuple):
            return tuple(self._host(x)[:N] for x in out)
        return self._host(out)[:N]

    def _host(self, x: Any) -> np.ndarray:
        return np.asarray(self.kin.ops.numpy(x), dtype=float)


@dataclass(frozen=True)
class PrecisionErrors:
    """The largest errors of a backend against the numeric reference, relative to max(1, |ref|):
    ``float64`` over FK, J0, Je and H0 of every frame, ``float32`` over FK, J0 and H0 evaluated in
    float32 (against the float64 reference at the same float32-rounded configurations)."""

    float64: float
    float32: float


def reference_errors(model: Any, backend: str, Q: np.ndarray, device: Any = None) -> PrecisionErrors:
    """Compile ``model`` (a Robot or a Tree) on ``backend`` ("jax" or "torch") and compare it at the
    configurations ``Q`` (N, n) with the numeric reference ``model.fkine/jacob0/jacobe/hessian0``,
    on ``device`` (None: the library's default)."""
    from symkin.model.tree import as_tree
    from symkin.runtime.load import compile as compile_model

    view = NumpyView(compile_model(model, backend=backend), device)
    tree = as_tree(model)
    frames: tuple[Any, ...] = tree.frames if len(tree.frames) > 1 else (None,)
    Q = np.asarray(Q, dtype=float)
    Q32 = Q.astype(np.float32).astype(float)
    e64 = e32 = 0.0
    for frame in frames:
        kw = {} if frame is None else {"frame": frame}
        for kind in ("fkine", "jacob0", "jacobe", "hessian0"):
            e64 = max(e64, _rel(getattr(view, kind)(Q, **kw), getattr(model, kind)(Q, **kw)))
        for kind in ("fkine", "jacob0", "hessian0"):
            e32 = max(
                e32, _rel(getattr(view, kind)(Q32, dtype="float32", **kw), getattr(model, kind)(Q32, **kw))
            )
    return PrecisionErrors(e64, e32)


PAD = 32  # batches are padded to a multiple of this many rows: fewer distinct shapes to compile


def _padded(x: Any, N: int | None) -> np.ndarray:
    """A batch of N rows repeated from its last row up to a multiple of :data:`PAD` rows (JAX
    compiles each operation once per shape; the check's batches then share a few shapes)."""
    x = np.asarray(x, dtype=float)
    if N is None or N == 0:
        return x
    extra = -N % PAD
    return np.concatenate((x, np.repeat(x[-1:], extra, axis=0))) if extra else x
