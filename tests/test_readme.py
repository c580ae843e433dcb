"""The README's Python examples run as written."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

README = Path(__file__).resolve().parents[1] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)


OPTIONAL = ("roboticstoolbox",)  # blocks showing the compare extra run where it is installed


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_readme_python_block_runs(index, capsys):
    for module in OPTIONAL:
        if f"import {module}" in BLOCKS[index]:
            pytest.importorskip(module)
    if "symkin.workspace" in BLOCKS[index]:  # the scale extra's examples
        pytest.importorskip("zarr")
        pytest.importorskip("distributed")
    exec(compile(BLOCKS[index], f"README.md python block {index}", "exec"), {})  # noqa: S102


def test_readme_is_free_of_internal_labels():
    text = README.read_text()
    assert not re.search(r"(?i)\bseed 0\d\d|\blab \d", text)
    assert "--from-q" not in text and "--target-q" in text


def test_readme_names_the_test_command_that_ci_runs():
    ci = (README.parent / ".ci" / "run").read_text()
    assert "python -m pytest -q" in README.read_text() and "python -m pytest -q" in ci
