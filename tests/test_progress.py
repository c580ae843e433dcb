"""Progress bars only when stderr is a terminal, for every long command alike."""

from __future__ import annotations

import io
import os
import subprocess
import sys
from pathlib import Path

import symkin.progress as progress

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


def test_long_commands_print_no_bar_into_a_pipe() -> None:
    """`symkin servo` (its loop reports progress) with stderr a pipe: no tqdm output at all; the other
    long commands share symkin.progress.bar."""
    env = {**os.environ, "SYMKIN_CACHE": os.environ["SYMKIN_CACHE"]}
    runs = [
        ["servo", "planar3", "--target-q", "0.5 0.5 0.5", "--controller", "rrmc", "--backend", "numpy"],
    ]
    for argv in runs:
        res = subprocess.run(
            [sys.executable, "-m", "symkin", *argv],
            capture_output=True,
            text=True,
            env=env,
            cwd=ROOT,
            timeout=600,
        )
        assert "it/s" not in res.stderr and "\r" not in res.stderr and "%|" not in res.stderr, res.stderr
