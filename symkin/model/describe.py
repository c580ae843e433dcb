"""Markdown descriptions of robots for notebooks (``Robot._repr_markdown_``) and for compiled
kinematics (``Kinematics._repr_markdown_``): the joint table with kinds, axes, limits and speeds.

Every name shown is escaped (Markdown and HTML characters), so a robot's or joint's name cannot
change the rendered page.
"""

from __future__ import annotations

import math
from typing import Any

__all__ = ["robot_markdown", "md_text"]

_ESCAPE = {
    "\\": "\\\\",
    "`": "\\`",
    "*": "\\*",
    "_": "\\_",
    "|": "\\|",
    "[": "\\[",
    "]": "\\]",
    "#": "\\#",
    "<": "&lt;",
    ">": "&gt;",
    "&": "&amp;",
    "$": "\\$",
    "\n": " ",
    "\r": " ",
}


def md_text(text: str, limit: int = 200) -> str:
    """``text`` escaped for Markdown and HTML, on one line, at most ``limit`` characters."""
    text = str(text)
    if len(text) > limit:
        text = text[: limit - 3] + "..."
    return "".join(_ESCAPE.get(ch, ch) for ch in text)


def _limit(value: float, revolute: bool) -> str:
    if not math.isfinite(value):
        return "none"
    if revolute:
        return f"{value:.4g} rad ({math.degrees(value):.1f}°)"
    return f"{value:.4g} m"


def robot_markdown(robot: Any, title: str | None = None) -> str:
    """A Markdown summary of ``robot``: name, structure, ETS, one row per joint, configurations."""
    kinds = {e.joint: e for e in robot.ets if e.is_joint}
    head = title or f"**{md_text(robot.name)}**"
    lines = [
        f"{head}: {robot.n} joints ({robot.ets.structure}), base to end effector: "
        f"`{str(robot.ets).replace('`', '')}`",
        "",
        "| joint | name | type | axis | lower limit | upper limit | max speed |",
        "|---|---|---|---|---|---|---|",
    ]
    for j in range(robot.n):
        e = kinds[j]
        rev = e.is_revolute
        lo, hi = (float(v) for v in robot.qlim[:, j])
        speed = "-"
        if robot.qd_max is not None:
            v = float(robot.qd_max[j])
            speed = f"{v:.4g} rad/s" if rev else f"{v:.4g} m/s"
        axis = ("-" if e.flip else "") + e.axis.value
        lines.append(
            f"| q{j} | {md_text(robot.joint_names[j], 80)} | {'revolute' if rev else 'prismatic'} | {axis} "
            f"| {_limit(lo, rev)} | {_limit(hi, rev)} | {speed} |"
        )
    lines.append("")
    lines.append("Configurations: " + ", ".join(f"`{k}`" for k in robot.configs) + ".")
    if robot.source:
        lines.append(f"Source: {md_text(robot.source, 600)}.")
    return "\n".join(lines) + "\n"
