"""symkin: a symbolic, code-generating kinematics compiler for robot manipulators."""

from symkin.errors import SymkinError
from symkin.model.ets import ET, ETS, Axis, Const
from symkin.model.robot import Robot

__version__ = "0.1.0"
