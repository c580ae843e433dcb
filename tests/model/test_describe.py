"""Notebook views of robots: a Markdown joint table with limits, safe with hostile names."""

from __future__ import annotations

import symkin


def test_robot_markdown_lists_every_joint_with_limits() -> None:
    md = symkin.load("stanford")._repr_markdown_()
    assert md.startswith("**stanford**: 6 joints (RRPRRR)")
    assert "| q2 | q2 | prismatic | tz | 0.3048 m | 1.27 m | - |" in md
    assert "| q0 | q0 | revolute | Rz | -2.967 rad (-170.0°) | 2.967 rad (170.0°) | - |" in md
    assert md.count("\n| q") == 6
    panda = symkin.load("panda")._repr_markdown_()
    assert "| q3 | panda\\_joint4 | revolute | -Ry |" in panda and "2.175 rad/s" in panda
    assert "Configurations: `qz`, `qr`." in panda


def test_hostile_names_are_escaped() -> None:
    r = symkin.Robot.from_ets("Rz(q) tx(1)", name="<script>x|y", joint_names=("a|b`<img>",))
    md = r._repr_markdown_()
    assert "<script>" not in md and "<img>" not in md and "a\\|b" in md
    assert md.count("|") - md.count("\\|") == 8 * 3  # header, rule, one row: 8 bars each
