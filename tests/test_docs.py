"""The documentation site (mkdocs.yml, docs/): every page is in the navigation, the tutorial
notebooks run as written, and, where the `docs` extra is installed, the site builds with
warnings as errors (the notebooks executed by mkdocs-jupyter)."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import pytest

from tests.test_readme import DOCS, ROOT

MKDOCS = ROOT / "mkdocs.yml"
NAV = re.findall(r"^\s*- (?:[^:\n]+: )?(\S+\.(?:md|ipynb))\s*$", MKDOCS.read_text(), re.M)
NOTEBOOKS = sorted((DOCS / "tutorials").glob("*.ipynb"))


def test_every_page_is_in_the_navigation_and_every_entry_exists():
    pages = {p.relative_to(DOCS).as_posix() for p in (*DOCS.rglob("*.md"), *DOCS.rglob("*.ipynb"))}
    assert set(NAV) == pages, f"not in nav: {pages - set(NAV)}; missing files: {set(NAV) - pages}"


def test_the_course_topics_have_tutorials():
    names = {p.stem for p in NOTEBOOKS}
    assert {"forward-kinematics", "ik-and-rrmc", "trajectories", "analytical-jacobian", "collision"} <= names


@pytest.mark.parametrize("notebook", NOTEBOOKS, ids=[p.stem for p in NOTEBOOKS])
def test_tutorial_notebook_runs(notebook, monkeypatch):
    """The code cells in order, in one namespace, as a kernel would run them (no outputs are
    checked in: mkdocs executes the notebooks when it builds the site)."""
    pytest.importorskip("matplotlib")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    nb = json.loads(notebook.read_text())
    assert not any(c.get("outputs") for c in nb["cells"]), "commit notebooks without outputs"
    monkeypatch.chdir(notebook.parent)
    namespace: dict = {"__name__": "__main__"}
    try:
        for i, cell in enumerate(nb["cells"]):
            if cell["cell_type"] == "code":
                source = "".join(cell["source"])
                exec(compile(source, f"{notebook.name} cell {i}", "exec"), namespace)  # noqa: S102
    finally:
        plt.close("all")


def test_the_site_builds_strictly(tmp_path):
    """`mkdocs build --strict`: broken links, docstrings mkdocstrings cannot parse and failing
    notebook cells are errors. Runs only where the docs extra is installed (about a minute)."""
    for module in ("mkdocs", "material", "mkdocstrings_handlers.python", "mkdocs_jupyter", "ipykernel"):
        pytest.importorskip(module)
    out = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(tmp_path / "site")],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert out.returncode == 0, out.stderr[-5000:]
    for page in ("index.html", "api/symkin/index.html", "tutorials/trajectories/index.html"):
        assert (tmp_path / "site" / page).is_file(), page
