"""What compiled chains and trees share: the generated code of one model on one backend, its
files, library or module, and the model's joints, names and limits (no sympy here)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

__all__ = ["CompiledModel"]


class CompiledModel:
    """Generated code of ``model`` (a :class:`symkin.Robot` chain or a :class:`symkin.Tree`) on one
    backend ("c", "numpy" or "casadi"); the generated functions named in ``METHODS`` are bound as
    attributes (on the C backend, the extension module's functions themselves).

    Attributes: ``model``, ``backend``, ``n``, ``name``, ``joint_names``, ``qlim``, ``qd_max``,
    ``files`` (the generated sources), ``path`` (the compiled library or module), ``module``.
    """

    METHODS: tuple[str, ...] = ()

    def __init__(
        self,
        model: Any,
        backend: str,
        functions: dict[str, Callable[..., Any]],
        files: dict[str, str],
        path: Path | None = None,
        module: ModuleType | None = None,
    ) -> None:
        self.model = model
        self._n = int(model.n)  # kept: a Robot counts the joints of its ETS on every call
        self.backend = backend
        self.files = files
        self.path = path
        self.module = module
        for name in self.METHODS:
            setattr(self, name, functions[name])
        self._setup(functions)

    def _setup(self, functions: dict[str, Callable[..., Any]]) -> None:
        """What a subclass adds to a new object (its own name for the model, caches, ...)."""

    @property
    def n(self) -> int:
        """Number of joints."""
        return self._n

    @property
    def name(self) -> str:
        return self.model.name

    @property
    def joint_names(self) -> tuple[str, ...]:
        return self.model.joint_names

    @property
    def qlim(self) -> np.ndarray:
        return self.model.qlim

    @property
    def qd_max(self) -> np.ndarray | None:
        return self.model.qd_max

    @property
    def c_prefix(self) -> str:
        """The prefix of the exported C symbols (``symkin_<name>`` unless generated with another)."""
        headers = sorted(f for f in self.files if f.endswith(".h"))
        if self.backend != "c" or not headers:
            raise AttributeError("c_prefix exists only on the C backend")
        return headers[0][:-2]

    def random_q(self, N: int | None = None, seed: Any = None) -> np.ndarray:
        """Uniform random configurations within qlim: (n,) or (N, n)."""
        return self.model.random_q(N, seed)
