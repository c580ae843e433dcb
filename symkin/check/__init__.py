"""``symkin check``: every backend of a chain or tree against the numeric reference and finite
differences."""

from symkin.check.kinematics import CheckReport, CheckRow, check

__all__ = ["CheckReport", "CheckRow", "check"]
