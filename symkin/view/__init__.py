"""The live browser view (``symkin view``; viser, the ``view`` extra): :func:`view` serves a robot's
joint sliders, link frames, velocity ellipsoid, manipulability, live Jacobian, collision shapes and a
target-pose gizmo driving IK, and returns the running :class:`Viewer`. viser is imported on the
first call, so this package imports without the extra."""

from symkin.view.scene import Scene, ViewState
from symkin.view.server import Viewer, view

__all__ = ["Scene", "ViewState", "Viewer", "view"]
