"""What compiled kinematics say about their model, on every backend: the properties that
:class:`symkin.runtime.kinematics.Kinematics` (C, NumPy, CasADi) and
:class:`symkin.runtime.diff.kinematics.DiffKinematics` (JAX, PyTorch) both pass through from
``self.model`` (a :class:`symkin.Robot` chain or a :class:`symkin.Tree`)."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["ModelAttributes"]


class ModelAttributes:
    """``robot`` and ``tree`` (both the model), ``n`` (kept as ``_n``: a Robot counts the joints of
    its ETS on every call), ``name``, ``joint_names`` and ``qlim`` ((2, n) float, read-only)."""

    model: Any
    _n: int

    @property
    def robot(self) -> Any:
        return self.model

    @property
    def tree(self) -> Any:
        return self.model

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
