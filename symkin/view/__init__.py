"""The live browser view (``symkin view``; viser, the ``view`` extra): :func:`view` serves a robot, a
chain or a tree, with a frame selector, joint sliders, link frames, its URDF meshes, velocity
ellipsoid, manipulability, live Jacobian, collision shapes, the closest pair and its distance, and a
target-pose gizmo driving IK, and returns the running :class:`Viewer`. viser is imported on the
first call, so this package imports without the extra."""

from symkin.view.meshes import urdf_meshes
from symkin.view.scene import Closest, MeshPart, Scene, ViewState
from symkin.view.server import Viewer, view

__all__ = ["Closest", "MeshPart", "Scene", "ViewState", "Viewer", "urdf_meshes", "view"]
