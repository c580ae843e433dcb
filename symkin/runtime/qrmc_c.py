"""The quadratic-rate step in C (``csrc/qrmc.h``, ``csrc/qrmc_impl.h``), a controller of the MMC
library (:mod:`symkin.runtime.mmc_c`): :class:`CQRMC` holds one :class:`~symkin.runtime.qrmc.QRMC`'s
options and warm start in a ``symkin_qrmc_ctrl``, whose first member is the library's
``symkin_mmc_ctrl`` (kinematics, speed limits, damping), so the library's step and servo loop run
it like the RRMC and MMC steps."""

from __future__ import annotations

import ctypes
import functools
from functools import lru_cache
from typing import Any

import numpy as np

from symkin.runtime.cext import layout
from symkin.runtime.mmc_c import _D, _I32, _KIND_QRMC, _CController, _ctrl_type

__all__ = ["CQRMC"]


@lru_cache(maxsize=16)
def _qrmc_type(n: int) -> type[ctypes.Structure]:
    """ctypes mirror of ``symkin_qrmc_ctrl`` for n joints (qrmc.h)."""
    return type(
        f"QRMCCtrl{n}",
        (ctypes.Structure,),
        {
            "_fields_": [
                ("base", _ctrl_type(n, 0)),
                ("horizon", _D),
                ("tol", _D),
                ("iterations", _I32),
                ("warm", _I32),
                ("seed", _D * n),
                ("prev", _D * n),
            ]
        },
    )


class CQRMC(_CController):
    """The C step of one :class:`~symkin.runtime.qrmc.QRMC` (its options, C kinematics).

    ``step(q, nu)`` returns what ``QRMC.step`` returns, in one C call, with the last answer as
    ``qd0``; :meth:`start` sets it (None: none). :meth:`servo` runs the library's servo loop from a
    cold start.
    """

    kind = _KIND_QRMC

    def __init__(self, ctrl: Any) -> None:
        from symkin.runtime.step import OSQP_SETTINGS

        super().__init__(ctrl.kin, ctrl.n, OSQP_SETTINGS, ctrl.axes, ctrl.qd_max)
        n = self.n
        Q = _qrmc_type(n)()
        layout(self.lib, "symkin_qrmc_layout", (n, ctypes.sizeof(Q)))
        ctypes.memmove(ctypes.addressof(Q.base), ctypes.addressof(self._ctrl), ctypes.sizeof(self._ctrl))
        self._q = Q
        self._ctrl = Q.base  # shares Q's memory
        self._addr = ctypes.addressof(Q)
        self._ctrl.damping, self._ctrl.singular_tol = float(ctrl.damping), float(ctrl.singular_tol)
        Q.horizon, Q.tol, Q.iterations = float(ctrl.horizon), float(ctrl.tol), int(ctrl.iterations)
        Q.seed[:] = np.asarray(ctrl.seed, dtype=float).tolist()
        Q.warm = 0
        self.fast = functools.partial(self._ext.step, self._addr, self.kind)

    def start(self, qd0: np.ndarray | None) -> None:
        """The next step's ``qd0`` (n,), or None."""
        if qd0 is None:
            self._q.warm = 0
        else:
            self._q.prev[:] = np.asarray(qd0, dtype=float).tolist()
            self._q.warm = 1

    @property
    def last(self) -> np.ndarray:
        """The last answer before the speed scaling (the next step's ``qd0``), (n,)."""
        return np.array(self._q.prev[:]) if self._q.warm else np.zeros(self.n)

    def servo(self, *args: Any) -> tuple:
        """:meth:`symkin.runtime.mmc_c._CController.servo`, started cold."""
        self._q.warm = 0
        return super().servo(*args)
