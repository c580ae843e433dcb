"""symkin: a symbolic, code-generating kinematics compiler for robot manipulators.

Pipeline: model (ETS, Robot, DH/URDF/PoE importers, built-in robots) -> symbolic (sympy) ->
emit (C, NumPy, CasADi from jinja2 templates) -> runtime (compiled kinematics, IK, control).
"""

from symkin.compiler.compile import BACKENDS, generate, generate_collision, write_generated
from symkin.core.version import __version__  # noqa: E402
from symkin.errors import (
    CompileError,
    ConfigurationError,
    ETSParseError,
    FrameError,
    GeometryError,
    MissingExtraError,
    NoAnalyticIKError,
    ParameterError,
    PoseError,
    RobotError,
    SymkinError,
    UnknownRobotError,
    URDFError,
    WorkspaceError,
)
from symkin.model.dh import DHLink
from symkin.model.ets import ET, ETS, Axis, Const
from symkin.model.geometry import Box, Capsule, Environment, Geometry, Sphere
from symkin.model.poe import poe_of
from symkin.model.resolve import resolve_robot
from symkin.model.robot import Robot
from symkin.model.robots import list_robots, load, load_dh_file
from symkin.model.spatial import joint_torques, velocity_transform, wrench_transform
from symkin.model.tree import Tree
from symkin.runtime.cartesian import PathResult, ctraj, servo_path
from symkin.runtime.control import MMC, StepInfo, rrmc
from symkin.runtime.ik import IKResult, ik, pose_error
from symkin.runtime.kinematics import Kinematics
from symkin.runtime.load import compile, load_compiled
from symkin.runtime.loop import ServoResult, servo
from symkin.runtime.null_space import joint_limit_cost, null_space_rrmc
from symkin.runtime.qrmc import QRMC, qrmc
from symkin.runtime.servo import p_servo
from symkin.runtime.trajectory import Trajectory, jtraj, mstraj, quintic, trapezoidal

_LAZY = {  # sympy-based teaching derivations: loaded on first use so `import symkin` stays light
    "derive_steps": ("symkin.derive.chain", "derive_steps"),
    "Derivation": ("symkin.derive.chain", "Derivation"),
    "singularities": ("symkin.derive.singularities", "singularities"),
    "SingularityReport": ("symkin.derive.singularities", "SingularityReport"),
}


#: Subpackages loaded on first use: the callable ``symkin.symbolic(robot)`` (sympy expressions)
#: and ``symkin.derive(robot)`` (the written derivation), and ``symkin.geometry`` (collision
#: geometry sources and the NumPy reference).
_SUBPACKAGES = ("symbolic", "derive", "geometry")


def __getattr__(name: str):  # noqa: ANN202
    import importlib

    if name in _SUBPACKAGES:
        return importlib.import_module(f"symkin.{name}")
    if name in _LAZY:
        module, attr = _LAZY[name]
        return getattr(importlib.import_module(module), attr)
    raise AttributeError(f"module 'symkin' has no attribute {name!r}")


__all__ = [
    "BACKENDS",
    "ET",
    "ETS",
    "Axis",
    "Box",
    "Capsule",
    "CompileError",
    "ConfigurationError",
    "Const",
    "Derivation",
    "DHLink",
    "Environment",
    "ETSParseError",
    "FrameError",
    "Geometry",
    "GeometryError",
    "MissingExtraError",
    "IKResult",
    "Kinematics",
    "MMC",
    "NoAnalyticIKError",
    "ParameterError",
    "PathResult",
    "PoseError",
    "QRMC",
    "Robot",
    "RobotError",
    "ServoResult",
    "SingularityReport",
    "Sphere",
    "StepInfo",
    "SymkinError",
    "Trajectory",
    "Tree",
    "URDFError",
    "WorkspaceError",
    "UnknownRobotError",
    "__version__",
    "compile",
    "ctraj",
    "derive",
    "derive_steps",
    "generate",
    "generate_collision",
    "geometry",
    "ik",
    "joint_limit_cost",
    "joint_torques",
    "jtraj",
    "list_robots",
    "load",
    "load_compiled",
    "load_dh_file",
    "mstraj",
    "null_space_rrmc",
    "p_servo",
    "poe_of",
    "pose_error",
    "qrmc",
    "quintic",
    "resolve_robot",
    "rrmc",
    "servo",
    "servo_path",
    "singularities",
    "symbolic",
    "trapezoidal",
    "velocity_transform",
    "wrench_transform",
    "write_generated",
]
