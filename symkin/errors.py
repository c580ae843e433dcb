"""The exception hierarchy: one root, a few specific kinds.

Exceptions are for bad input. Solver outcomes (an unreachable IK target, an infeasible QP) are
reported in result objects, not raised.
"""

from __future__ import annotations

from collections.abc import Sequence


class SymkinError(Exception):
    """Root of every error symkin raises on purpose."""


class ETSParseError(SymkinError, ValueError):
    """Malformed ETS text. ``position`` is the character offset of the offending token."""

    def __init__(self, message: str, text: str = "", position: int | None = None) -> None:
        self.text = text
        self.position = position
        if position is not None and text:
            pointer = " " * position + "^"
            message = f"{message} (column {position + 1})\n  {text}\n  {pointer}"
        super().__init__(message)


class RobotError(SymkinError, ValueError):
    """An invalid robot description (DH table, PoE screws, joint limits, names)."""


class URDFError(RobotError):
    """A URDF that cannot be turned into a serial ETS (malformed XML, unsupported joints...)."""


class UnknownRobotError(SymkinError, KeyError):
    """A built-in robot name that does not exist."""

    def __str__(self) -> str:  # KeyError quotes its message; keep it readable
        return str(self.args[0]) if self.args else ""


class ConfigurationError(SymkinError, ValueError):
    """A joint configuration q of the wrong shape, with NaN/inf, or outside the joint limits."""


class FrameError(SymkinError, ValueError):
    """A frame that does not exist: a link frame index out of range, an unknown frame name."""


class PoseError(SymkinError, ValueError):
    """A target pose that is not a valid SE(3) matrix."""


class ParameterError(SymkinError, ValueError):
    """An invalid solver or controller parameter (IK ``ilimit``/``tol``, MMC ``dt``/``xi``/``rho``...)."""


class CompileError(SymkinError, RuntimeError):
    """Generating or compiling code failed (missing C compiler, compiler error, template error)."""


class NoAnalyticIKError(SymkinError, ValueError):
    """The arm has no closed-form inverse kinematics that symkin derives (the message says why and
    points at the numerical IK)."""


class WorkspaceError(SymkinError, ValueError):
    """Bad settings for a workspace map or dataset, or a store that holds a different one."""


class MissingExtraError(SymkinError, ImportError):
    """An optional dependency is not installed; the message names the extra to install."""


class GeometryError(SymkinError, ValueError):
    """Invalid collision geometry or environment: a shape on an unknown link, a negative radius,
    NaN or infinite numbers, an unknown shape kind."""


def check_choice(value: object, choices: Sequence[str], what: str) -> None:
    """Raise SymkinError ``unknown <what> <value>: choose one of ...`` unless ``value`` is one of
    ``choices``."""
    if value not in choices:
        raise SymkinError(f"unknown {what} {value!r}: choose one of {', '.join(choices)}")
