"""One frame of a model seen as a serial chain: what IK, servo and MMC take.

``ik(tree, Tep, frame="left_hand")`` solves for all n joints of the tree with the task on one
frame; the joints off that frame's path have zero Jacobian columns and stay where they start
(the damping of LM keeps its step defined). The same holds for link frame k of a chain
(``frame=k``). A :class:`FrameView` has the chain interface (``n``, ``qlim``, ``qd_max``,
``revolute``, ``fkine``, ``jacob0``, ``jacobe``, ``fkine_jacob0``, ``hessian0``,
``jacob0_hessian0``, ``derivative``, ``manipulability``, ``jacobm``, ``ik``) over any kinematics
whose methods take ``frame=``: the numeric references :class:`symkin.Robot` and
:class:`symkin.Tree` or compiled :class:`symkin.Kinematics`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["FrameView", "frame_view"]


def frame_view(model: Any, source: Any, frame: Any) -> FrameView:
    """The (memoised) view of ``frame`` of ``source`` (``model`` or its compiled kinematics).

    The views live in ``source._frame_views``: a reference cycle (view -> source -> views) that
    the garbage collector frees with the source, where a module-level map would keep it alive."""
    key = model.frame_name(frame)
    views = getattr(source, "_frame_views", None)
    if views is None:
        views = {}
        try:
            object.__setattr__(source, "_frame_views", views)  # frozen dataclasses too
        except (AttributeError, TypeError):  # no instance dict: an unmemoised view
            return FrameView(model, source, key)
    view = views.get(key)
    if view is None:
        view = views[key] = FrameView(model, source, key)
    return view


class FrameView:
    """Frame ``frame`` (a tree's frame name or a chain's link index) of ``source`` as chain
    kinematics of all the model's ``n`` joints (module docstring)."""

    def __init__(self, model: Any, source: Any, frame: Any) -> None:
        self.tree, self.source, self.frame = model, source, frame
        self.n = model.n
        self.qlim = model.qlim
        self.qd_max = model.qd_max
        self.revolute = model.revolute
        self.joint_names = model.joint_names
        self.name = f"{model.name}:{frame}"
        self.backend = getattr(source, "backend", "reference")
        fkjac_of = getattr(source, "c_fkjac_of", None)
        fkjac = fkjac_of(frame) if fkjac_of is not None else None
        if fkjac is not None:  # the C IK loop's kinematics (symkin.runtime.ik_c)
            self.c_fkjac = fkjac
        controller_fns = getattr(source, "c_controller_functions", None)
        fns = controller_fns(frame) if controller_fns is not None else None
        if fns is not None:  # the C controllers' functions (symkin.runtime.mmc_c.kinematics_functions)
            self.c_controller_fns = fns

    def __repr__(self) -> str:
        return f"FrameView({self.name!r}, n={self.n}, backend={self.backend!r})"

    def fkine(self, q: Any) -> np.ndarray:
        """Pose of the frame in the base frame, (4, 4) or (N, 4, 4)."""
        return self.source.fkine(q, self.frame)

    def jacob0(self, q: Any) -> np.ndarray:
        """Base-frame Jacobian of the frame, (6, n) or (N, 6, n)."""
        return self.source.jacob0(q, self.frame)

    def jacobe(self, q: Any) -> np.ndarray:
        """Jacobian of the frame in the frame itself, (6, n) or (N, 6, n)."""
        return self.source.jacobe(q, self.frame)

    def fkine_jacob0(self, q: Any) -> tuple[np.ndarray, np.ndarray]:
        return self.source.fkine_jacob0(q, self.frame)

    def hessian0(self, q: Any) -> np.ndarray:
        """Base-frame Hessian of the frame, (n, 6, n) or (N, n, 6, n)."""
        return self.source.hessian0(q, self.frame)

    def jacob0_hessian0(self, q: Any) -> tuple[np.ndarray, np.ndarray]:
        return self.source.jacob0_hessian0(q, self.frame)

    def derivative(self, q: Any, order: int = 1) -> np.ndarray:
        """Order-``order`` derivative of the frame's pose, (n,) * (order - 1) + (6, n) or batched."""
        return self.source.derivative(q, order, self.frame)

    def manipulability(self, q: Any, axes: str = "all") -> np.ndarray | float:
        """Yoshikawa manipulability of the chosen rows of the frame's J0 (eq 52)."""
        return self.source.manipulability(q, self.frame, axes)

    def jacobm(self, q: Any, axes: str = "all") -> np.ndarray:
        """Manipulability Jacobian of the frame (Haviland and Corke, 2020, eq 11), (n,) or (N, n)."""
        return self.source.jacobm(q, self.frame, axes)

    def random_q(self, N: int | None = None, seed: Any = None) -> np.ndarray:
        return self.tree.random_q(N, seed)

    def ik(self, Tep: Any, **kwargs: Any) -> Any:
        """Numerical IK of the frame (:func:`symkin.runtime.ik.ik`): the C loop when the compiled
        C kinematics give this frame's ``fkine_jacob0`` and n <= 12, else the NumPy solver."""
        from symkin.runtime.ik import ik

        c_loop = hasattr(self, "c_fkjac") and self.n <= 12
        kwargs.setdefault("backend", "c" if c_loop else "numpy")
        return ik(self, Tep, **kwargs)
