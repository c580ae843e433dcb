"""The array operations the JAX and PyTorch runtimes share, one class per library.

The pose error, the IK step and the collision distances are written once against :class:`Ops`
(``ops.xp`` is ``jax.numpy`` or ``torch``; the names the two spell alike are called on it
directly, and :class:`Ops` itself wraps those its callers take as methods: ``arctan2``, ``clip``,
``linalg.pinv``, the float dtypes), and one subclass per library spells the rest: constants of an
array's dtype and device, casts, the linear solve, gathering along an axis, stopping gradients,
random numbers and the IK's iteration loop (``lax.while_loop`` under JAX, a Python loop that stops
when every problem has converged under PyTorch). Neither library is imported until an
:class:`Ops` is made.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = ["Ops", "JaxOps", "TorchOps", "ops_of"]


class Ops:
    """The operations of one array library (see the module docstring)."""

    name = ""
    xp: Any = None

    def const(self, values: Any, like: Any) -> Any:
        """``values`` (numbers, nested lists, a NumPy array) as an array of ``like``'s dtype and device."""
        raise NotImplementedError

    def is_array(self, x: Any) -> bool:
        raise NotImplementedError

    def cast(self, x: Any, like: Any) -> Any:
        """x in ``like``'s dtype (None: 32-bit integers), on its device."""
        raise NotImplementedError

    def atan2(self, y: Any, x: Any) -> Any:
        return self.xp.arctan2(y, x)  # torch.arctan2: torch.atan2's alias

    def clip(self, x: Any, lo: float, hi: float) -> Any:
        return self.xp.clip(x, lo, hi)  # torch.clip: torch.clamp's alias

    def take(self, x: Any, index: Any, axis: int) -> Any:
        """Entries of x at ``index`` along ``axis`` (index broadcast as ``take_along_axis``)."""
        raise NotImplementedError

    def solve(self, A: Any, b: Any) -> Any:
        """x of A x = b for A (..., n, n), b (..., n)."""
        raise NotImplementedError

    def pinv(self, A: Any) -> Any:
        return self.xp.linalg.pinv(A)

    def detach(self, x: Any) -> Any:
        """x without its gradient (the value passes, no derivative flows back)."""
        raise NotImplementedError

    def numpy(self, x: Any) -> Any:
        """x as a NumPy array (copied to the host)."""
        raise NotImplementedError

    def uniform(self, seed: int, shape: tuple[int, ...], lo: Any, hi: Any) -> Any:
        """Uniform random numbers in [lo, hi) (arrays broadcast to ``shape``, their dtype and device)."""
        raise NotImplementedError

    def loop(self, count: int, done: Callable[[Any], Any], body: Callable[[Any], Any], state: Any) -> Any:
        """``state = body(state)`` at most ``count`` times, stopping early once ``done(state)`` (a
        boolean array) is all true."""
        raise NotImplementedError

    def floating(self, x: Any) -> bool:
        """Whether x is an array of float32 or float64."""
        return getattr(x, "dtype", None) in (self.xp.float32, self.xp.float64)


class JaxOps(Ops):
    name = "jax"

    def __init__(self) -> None:
        import jax
        import jax.numpy as jnp

        self.jax, self.xp = jax, jnp

    def const(self, values: Any, like: Any) -> Any:
        return self.xp.asarray(values, dtype=like.dtype)

    def is_array(self, x: Any) -> bool:
        return isinstance(x, self.jax.Array)

    def cast(self, x: Any, like: Any) -> Any:
        return x.astype(self.xp.int32 if like is None else like.dtype)

    def take(self, x: Any, index: Any, axis: int) -> Any:
        return self.xp.take_along_axis(x, index, axis=axis)

    def solve(self, A: Any, b: Any) -> Any:
        return self.xp.linalg.solve(A, b[..., None])[..., 0]

    def detach(self, x: Any) -> Any:
        return self.jax.lax.stop_gradient(x)

    def numpy(self, x: Any) -> Any:
        import numpy as np

        return np.asarray(x)

    def uniform(self, seed: int, shape: tuple[int, ...], lo: Any, hi: Any) -> Any:
        key = self.jax.random.PRNGKey(seed % 2**32)
        return self.jax.random.uniform(key, shape, dtype=lo.dtype, minval=lo, maxval=hi)

    def loop(self, count: int, done: Callable[[Any], Any], body: Callable[[Any], Any], state: Any) -> Any:
        lax = self.jax.lax
        i, state = lax.while_loop(
            lambda c: (c[0] < count) & ~self.xp.all(done(c[1])),
            lambda c: (c[0] + 1, body(c[1])),
            (0, state),
        )
        return state


class TorchOps(Ops):
    name = "torch"

    def __init__(self) -> None:
        import torch

        self.xp = torch

    def const(self, values: Any, like: Any) -> Any:
        import numpy as np

        values = np.array(values) if isinstance(values, np.ndarray) else values  # writable: no warning
        return self.xp.as_tensor(values, dtype=like.dtype, device=like.device)

    def is_array(self, x: Any) -> bool:
        return isinstance(x, self.xp.Tensor)

    def cast(self, x: Any, like: Any) -> Any:
        return x.to(self.xp.int32) if like is None else x.to(dtype=like.dtype, device=like.device)

    def take(self, x: Any, index: Any, axis: int) -> Any:
        return self.xp.take_along_dim(x, index, dim=axis)

    def solve(self, A: Any, b: Any) -> Any:
        """x of A x = b; NaN rows where A is singular (as JAX's solve gives, not an exception: the
        IK marks those searches dead and the others go on)."""
        x, info = self.xp.linalg.solve_ex(A, b[..., None])
        return self.xp.where((info != 0)[..., None], float("nan"), x[..., 0])

    def detach(self, x: Any) -> Any:
        return x.detach()

    def numpy(self, x: Any) -> Any:
        return x.detach().cpu().numpy()

    def uniform(self, seed: int, shape: tuple[int, ...], lo: Any, hi: Any) -> Any:
        g = self.xp.Generator(device=lo.device).manual_seed(seed % 2**63)
        u = self.xp.rand(shape, generator=g, dtype=lo.dtype, device=lo.device)
        return lo + (hi - lo) * u

    def loop(self, count: int, done: Callable[[Any], Any], body: Callable[[Any], Any], state: Any) -> Any:
        for _ in range(count):
            if bool(done(state).all()):
                break
            state = body(state)
        return state


_OPS: dict[str, Ops] = {}


def ops_of(backend: str) -> Ops:
    """The :class:`Ops` of ``backend`` ("jax" or "torch"), made once."""
    ops = _OPS.get(backend)
    if ops is None:
        ops = _OPS[backend] = JaxOps() if backend == "jax" else TorchOps()
    return ops
