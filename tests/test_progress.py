"""Progress bars only when stderr is a terminal, for every long command alike."""

from __future__ import annotations

import io
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

import symkin.core.progress as progress

ROOT = Path(__file__).resolve().parents[1]


class _Tty(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_bars_need_a_terminal(monkeypatch) -> None:
    monkeypatch.setattr(sys, "stderr", io.StringIO())
    assert not progress.progress_shown(True)
    assert list(progress.bar(range(3), True, desc="x")) == [0, 1, 2]
    assert sys.stderr.getvalue() == ""
    tty = _Tty()
    monkeypatch.setattr(sys, "stderr", tty)
    assert progress.progress_shown(True) and not progress.progress_shown(False)
    assert list(progress.bar(range(3), True, desc="counting")) == [0, 1, 2]
    assert "counting" in tty.getvalue()


def _planar3_pose(q: list[float]) -> tuple[float, float, float]:
    """x, y and heading of planar3 (three revolute joints about z, unit links) by hand: the
    reference the servo's final configuration is checked against."""
    a = np.cumsum(q)
    return float(np.cos(a).sum()), float(np.sin(a).sum()), float(a[-1])


def test_long_commands_print_no_bar_into_a_pipe() -> None:
    """`symkin servo` (its loop reports progress) with stderr a pipe: no tqdm output at all, and the
    command still succeeds and prints its summary; the other long commands share
    symkin.core.progress.bar."""
    env = {**os.environ, "SYMKIN_CACHE": os.environ["SYMKIN_CACHE"]}
    argv = ["servo", "planar3", "--target-q", "0.5 0.5 0.5", "--controller", "rrmc", "--backend", "numpy"]
    res = subprocess.run(
        [sys.executable, "-m", "symkin", *argv],
        capture_output=True,
        text=True,
        env=env,
        cwd=ROOT,
        timeout=600,
    )
    assert res.returncode == 0, res.stdout + res.stderr
    assert "it/s" not in res.stderr and "\r" not in res.stderr and "%|" not in res.stderr, res.stderr
    summary = re.fullmatch(
        r"rrmc: arrived after (\d+) steps \(dt 0\.05 s\); mean manipulability \d+\.\d{4}\n"
        r"q final = \[([-\d. ]+)\]\n",
        res.stdout,
    )
    assert summary, res.stdout
    assert 0 < int(summary[1]) < 500  # it moved, and arrived before --max-steps (500)
    q_final = [float(x) for x in summary[2].split()]
    assert len(q_final) == 3
    # arrived: sum |e| < 0.1 (the servo's threshold) at the printed q, against the pose of --target-q
    err = np.subtract(_planar3_pose(q_final), _planar3_pose([0.5, 0.5, 0.5]))
    err[2] = (err[2] + np.pi) % (2 * np.pi) - np.pi
    err = np.abs(err)
    assert err.sum() < 0.1 + 1e-3, (q_final, err)
