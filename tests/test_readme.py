"""The README's Python examples run as written."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_readme_python_block_runs(index, capsys):
    if "symkin.workspace" in BLOCKS[index]:  # the scale extra's examples
        pytest.importorskip("zarr")
        pytest.importorskip("distributed")
    exec(compile(BLOCKS[index], f"README.md python block {index}", "exec"), {})  # noqa: S102


def test_readme_names_the_test_command_that_ci_runs():
    ci = (README.parent / ".ci" / "run").read_text()
    assert "python -m pytest -q" in README.read_text() and "python -m pytest -q" in ci
