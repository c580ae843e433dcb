"""One frame of a kinematic tree seen as a serial chain: what IK, servo and MMC take.

``ik(tree, Tep, frame="left_hand")`` solves for all n joints of the tree with the task on one
frame; the joints off that frame's path have zero Jacobian columns and stay where they start
(the damping of LM keeps its step defined). A :class:`FrameView` has the chain interface
(``n``, ``qlim``, ``qd_max``, ``revolute``, ``fkine``, ``jacob0``, ``jacobe``, ``hessian0``,
``manipulability``, ``jacobm``, ``ik``) over either the numeric reference :class:`symkin.Tree`
or compiled tree kinematics.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symkin.core.arrays import as_batch, axes_rows
from symkin.model.robot import jacobm_of, manipulability_of
from symkin.model.slots import hessian_of_columns

__all__ = ["FrameView", "frame_view"]


def frame_view(tree: Any, source: Any, frame: Any) -> FrameView:
    """The (memoised) view of ``frame`` of ``source`` (a Tree or compiled tree kinematics).

    The views live in ``source._frame_views``: a reference cycle (view -> source -> views) that
    the garbage collector frees with the source, where a module-level map would keep it alive."""
    name = tree.frames[tree.frame_position(frame)]
    views = getattr(source, "_frame_views", None)
    if views is None:
        views = {}
        try:
            object.__setattr__(source, "_frame_views", views)  # frozen dataclasses too
        except (AttributeError, TypeError):  # no instance dict: an unmemoised view
            return FrameView(tree, source, name)
    view = views.get(name)
    if view is None:
        view = views[name] = FrameView(tree, source, name)
    return view


class FrameView:
    """Frame ``frame`` of a tree as chain kinematics of all its ``n`` joints (module docstring)."""

    def __init__(self, tree: Any, source: Any, frame: str) -> None:
        self.tree, self.source, self.frame = tree, source, frame
        self.n = tree.n
        self.qlim = tree.qlim
        self.qd_max = tree.qd_max
        self.revolute = tree.revolute
        self.joint_names = tree.joint_names
        self.name = f"{tree.name}:{frame}"
        self.backend = getattr(source, "backend", "reference")
        slots = [tree.slots[k] for k in tree.path_slots(frame)]
        self._slots = slots
        self._joints = [s.joint for s in slots]
        self._plain = not any(s.is_mimic for s in slots)  # J's columns are the slots' columns
        fkjac = getattr(source, "c_fkjac_of", None)
        if fkjac is not None:
            self.c_fkjac = fkjac(frame)
        controller_fns = getattr(source, "c_controller_functions", None)
        fns = controller_fns(frame) if controller_fns is not None else None
        if fns is not None:  # the C controllers' functions (symkin.runtime.mmc_c.kinematics_functions)
            self.c_controller_fns = fns

    def __repr__(self) -> str:
        return f"FrameView({self.name!r}, n={self.n}, backend={self.backend!r})"

    def fkine(self, q: Any) -> np.ndarray:
        """Pose of the frame in the base-link frame, (4, 4) or (N, 4, 4)."""
        return self.source.fkine(q, frame=self.frame)

    def jacob0(self, q: Any) -> np.ndarray:
        """Base-frame Jacobian of the frame, (6, n) or (N, 6, n)."""
        return self.source.jacob0(q, frame=self.frame)

    def jacobe(self, q: Any) -> np.ndarray:
        """Jacobian of the frame in the frame itself, (6, n) or (N, 6, n)."""
        return self.source.jacobe(q, frame=self.frame)

    def fkine_jacob0(self, q: Any) -> tuple[np.ndarray, np.ndarray]:
        return self.source.fkine_jacob0(q, frame=self.frame)

    def hessian0(self, q: Any) -> np.ndarray:
        """Base-frame Hessian of the frame, (n, 6, n) or (N, n, 6, n) (see :meth:`symkin.Tree.hessian0`)."""
        return self.jacob0_hessian0(q)[1]

    def jacob0_hessian0(self, q: Any) -> tuple[np.ndarray, np.ndarray]:
        """J0 and H0 of the frame. Generated (the C kernel's ``jacob0_hessian0``, Haviland and Corke,
        Maximising Manipulability During Resolved-Rate Motion Control, 2020, eq 20) when the source
        is compiled C and no mimic joint is on the path; else from the compiled Jacobian's columns
        (mimic-free path) or the numeric reference."""
        generated = getattr(getattr(self.source, "module", None), "jacob0_hessian0", None)
        if generated is not None and self._plain:
            out = generated(q, self.frame)
            if out is not NotImplemented:
                return out
        if not self._plain or self.source is self.tree:
            return self.jacob0(q), self.tree.hessian0(q, frame=self.frame)
        Q, single = as_batch(q, self.n, self.name)
        J = np.asarray(self.jacob0(Q))
        Jv = np.swapaxes(J[:, :3, self._joints], 1, 2)
        Jw = np.swapaxes(J[:, 3:, self._joints], 1, 2)
        H = hessian_of_columns(Jv, Jw, self._slots, self.n)
        return (J[0], H[0]) if single else (J, H)

    def manipulability(self, q: Any, axes: str = "all") -> np.ndarray | float:
        """Yoshikawa manipulability of the chosen rows of the frame's J0 (eq 52)."""
        Q, single = as_batch(q, self.n, self.name)
        m = manipulability_of(np.asarray(self.jacob0(Q))[:, axes_rows(axes)])
        return float(m[0]) if single else m

    def jacobm(self, q: Any, axes: str = "all") -> np.ndarray:
        """Manipulability Jacobian of the frame (Haviland and Corke, 2020, eq 11), (n,) or (N, n)."""
        rows = axes_rows(axes)
        Q, single = as_batch(q, self.n, self.name)
        J, H = self.jacob0(Q), self.hessian0(Q)
        Jm = jacobm_of(np.asarray(J)[:, rows], np.asarray(H)[:, :, rows])
        return Jm[0] if single else Jm

    def random_q(self, N: int | None = None, seed: Any = None) -> np.ndarray:
        return self.tree.random_q(N, seed)

    def ik(self, Tep: Any, **kwargs: Any) -> Any:
        """Numerical IK of the frame (:func:`symkin.runtime.ik.ik`): the C loop when the compiled
        C kinematics give this frame's ``fkine_jacob0`` and n <= 12, else the NumPy solver."""
        from symkin.runtime.ik import ik

        c_loop = hasattr(self, "c_fkjac") and self.n <= 12
        kwargs.setdefault("backend", "c" if c_loop else "numpy")
        return ik(self, Tep, **kwargs)
