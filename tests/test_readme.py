"""The README's and the documentation pages' Python examples run as written; the README keeps the
two commands that install and run symkin and its tests."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
DOCS = ROOT / "docs"
PAGES = [README, *sorted(DOCS.rglob("*.md"))]  # the README and every page of the site
BLOCKS = [
    (page, index, block)
    for page in PAGES
    for index, block in enumerate(re.findall(r"```python\n(.*?)```", page.read_text(), re.S))
]

# the landing page's two commands: install and run the main job, install and run the tests
RUN_COMMAND = (
    "python3 -m venv .venv && . .venv/bin/activate && pip install . && "
    "symkin compile panda --backend c -o build/panda"
)
TEST_COMMAND = (
    'python3 -m venv .venv && . .venv/bin/activate && pip install ".[test,scale]" && '
    "python -m pytest -q -n auto"
)

OPTIONAL = ("roboticstoolbox", "jax", "torch")  # blocks of optional extras run where installed


def _name(page: Path) -> str:
    return page.relative_to(ROOT).as_posix()


@pytest.mark.parametrize(
    "page, index, block", BLOCKS, ids=[f"{_name(page)}:{index}" for page, index, _ in BLOCKS]
)
def test_python_block_runs(page, index, block, capsys):
    for module in OPTIONAL:
        if f"import {module}" in block:
            pytest.importorskip(module)
    if "symkin.view" in block:  # the view extra's examples
        pytest.importorskip("viser")
    if "symkin.workspace" in block:  # the scale extra's examples
        pytest.importorskip("zarr")
        pytest.importorskip("distributed")
    exec(compile(block, f"{_name(page)} python block {index}", "exec"), {})  # noqa: S102


def test_the_pages_moved_out_of_the_readme_still_hold_python_examples():
    pages = {_name(page) for page, _, _ in BLOCKS}
    assert "README.md" in pages and "docs/getting-started.md" in pages
    moved = [b for b in BLOCKS if b[0] != README]
    assert len(moved) >= 14, f"only {len(moved)} python blocks in docs/ (the README had 14 before the move)"


def test_readme_keeps_its_two_commands():
    text = README.read_text()
    assert RUN_COMMAND in text, "the README lost its install-and-run command"
    assert TEST_COMMAND in text, "the README lost its install-and-test command"
    assert "mkdocs build --strict" in text and "mkdocs serve" in text  # how to build the docs


def test_readme_and_docs_are_free_of_internal_labels():
    text = "".join(page.read_text() for page in PAGES)
    assert not re.search(r"(?i)\bseed 0\d\d|\blab \d", text)
    assert "--from-q" not in text and "--target-q" in text


def test_readme_names_the_test_command_that_ci_runs():
    ci = (ROOT / ".ci" / "run").read_text()
    assert "python -m pytest -q -n auto" in README.read_text()
    assert "python -m pytest -q -p no:cacheprovider -n auto" in ci
