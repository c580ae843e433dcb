"""The documentation site (mkdocs.yml, docs/): every page is in the navigation, the tutorial
notebooks run as written, and, where the `docs` extra is installed, the site builds with
warnings as errors (the notebooks executed by mkdocs-jupyter); in the built site every internal
link and anchor resolves (notebook pages too), nothing is asked of the network, the equations are
math markup and, in headless Chromium where installed, typeset by the bundled KaTeX offline."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from html.parser import HTMLParser
from urllib.parse import unquote, urlsplit

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


PART2 = (
    "part2-hessian",
    "part2-higher-order",
    "part2-analytic-forms",
    "part2-null-space",
    "part2-qp-control",
    "part2-qp-ik",
    "part2-qrmc",
)


def test_the_part2_topics_have_tutorials_in_the_navigation_and_the_guide():
    """One page per topic of Haviland and Corke's Part 2, listed under "Part 2" in the navigation
    and linked from the Part 2 guide."""
    assert {p.stem for p in NOTEBOOKS} >= set(PART2)
    nav = MKDOCS.read_text()
    group = nav[nav.index("      - Part 2:") : nav.index("  - User guide:")]
    guide = (DOCS / "guide" / "part2.md").read_text()
    for name in PART2:
        assert f"tutorials/{name}.ipynb" in group, name
        assert f"../tutorials/{name}.ipynb" in guide, name


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


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The site built once by `mkdocs build --strict`: broken links, docstrings mkdocstrings cannot
    parse and failing notebook cells are errors. Only where the docs extra is installed (a minute)."""
    for module in ("mkdocs", "material", "mkdocstrings_handlers.python", "mkdocs_jupyter", "ipykernel"):
        pytest.importorskip(module)
    out_dir = tmp_path_factory.mktemp("docs") / "site"
    out = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out_dir)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=900,
    )
    assert out.returncode == 0, out.stderr[-5000:]
    return out_dir


def test_the_site_builds_strictly(site):
    for page in ("index.html", "api/symkin/index.html", "tutorials/trajectories/index.html"):
        assert (site / page).is_file(), page


def test_every_internal_link_and_anchor_resolves(site):
    """Every relative href/src of every page, notebook pages included (which `--strict` does not
    check), names a file of the site and, with a #fragment, an id on that page."""
    pages = {p: Page.of(p) for p in site.rglob("*.html")}
    broken = []
    for path, page in pages.items():
        for url in page.urls:
            target, fragment = _resolve(site, path, url)
            if target is None:
                continue  # remote, mailto:, data:, javascript:
            if not target.exists():
                broken.append(f"{path.relative_to(site)}: {url} (no file)")
            elif fragment and target.suffix == ".html":
                ids = pages[target].ids if target in pages else Page.of(target).ids
                if fragment not in ids:
                    broken.append(f"{path.relative_to(site)}: {url} (no id {fragment!r})")
    assert not broken, "\n".join(broken)


def test_notebook_tables_of_contents_link_their_headings(site):
    # headings with code ("## Via points: `mstraj`") were listed as "Via points:" at #via-points
    page = Page.of(site / "tutorials/trajectories/index.html")
    assert "via-points-mstraj" in page.ids and "cartesian-ctraj-and-servo_path" in page.ids
    toc = re.findall(
        r'<a href="#([^"]+)" class="md-nav__link">\s*<span class="md-ellipsis">\s*([^<]+?)\s*<', page.html
    )
    assert ("via-points-mstraj", "Via points: mstraj") in toc, toc


def test_no_page_asks_the_network_for_scripts_styles_or_fonts(site):
    """No script, stylesheet, font, preconnect or image from http(s)://, or //host, in any page or
    stylesheet (Google Fonts, a CDN's MathJax or KaTeX): the site works offline."""
    remote = re.compile(r"^(?:https?:)?//", re.I)
    css_remote = re.compile(r"(?:url\(\s*['\"]?|@import\s+['\"]?)(?:https?:)?//", re.I)
    found = []
    for path in site.rglob("*.html"):
        page = Page.of(path)
        found += [f"{path.relative_to(site)}: {u}" for u in page.resources if remote.match(u)]
        found += [f"{path.relative_to(site)}: inline style" for s in page.styles if css_remote.search(s)]
    for path in site.rglob("*.css"):
        if css_remote.search(path.read_text(errors="replace")):
            found.append(f"{path.relative_to(site)}: url() or @import of a remote file")
    assert not found, "\n".join(found)
    assert "fonts.googleapis.com" not in (site / "index.html").read_text()


def test_equations_are_math_markup_with_the_bundled_katex(site):
    """Formulas are math, not code: Markdown pages carry pymdownx.arithmatex's markup, notebook
    Markdown cells $...$, and every page loads the bundled KaTeX (whose fonts are in the site)."""
    arithmatex = {}
    for path in site.rglob("*.html"):
        page = Page.of(path)
        rel = path.relative_to(site).as_posix()
        for asset in ("assets/katex/katex.min.js", "assets/katex/katex.min.css", "javascripts/math.js"):
            assert any(u.endswith(asset) for u in page.resources), f"{rel}: no {asset}"
        arithmatex[rel] = page.html.count('class="arithmatex"')
    assert arithmatex["guide/performance/index.html"] >= 2 and arithmatex["guide/analytic-ik/index.html"] >= 2
    assert arithmatex["guide/teaching/index.html"] >= 5
    for name in ("ik-and-rrmc", "analytical-jacobian", "forward-kinematics", *PART2):
        cells = Page.of(site / f"tutorials/{name}/index.html").markdown_cells
        assert sum(c.count("$") for c in cells) >= 8, name
    # no formula left as code in the tutorials' prose
    for notebook in NOTEBOOKS:
        prose = "".join(
            "".join(c["source"])
            for c in json.loads(notebook.read_text())["cells"]
            if c["cell_type"] == "markdown"
        )
        code = re.findall(r"`([^`]*)`", prose)
        assert not [c for c in code if re.search(r"\^|\+=|J\^T|sqrt\(|\bomega\b|\bgamma\b", c)], notebook.name
    css = (site / "assets/katex/katex.min.css").read_text()
    for font in re.findall(r"url\((fonts/[^)]+\.woff2)\)", css):
        assert (site / "assets/katex" / font).is_file(), font
    assert (site / "assets/katex/LICENSE").read_text().startswith("The MIT License")


def test_equations_render_offline_in_a_browser(site):
    """Every page in headless Chromium with name resolution off (file:// only): the math is typeset
    by KaTeX (no raw markup, no KaTeX error; notebook LaTeX outputs too), its fonts load, and no
    request leaves the machine."""
    from tests.view.browser import Browser, chromium

    if chromium() is None:
        pytest.skip("no Chromium: apt-get install chromium")
    pytest.importorskip("websockets", reason="the DevTools client (comes with the view extra)")
    offline = ("--host-resolver-rules=MAP * ~NOTFOUND", "--allow-file-access-from-files")
    browser = Browser(chromium(), flags=offline)
    typeset = 0
    try:
        for path in sorted(site.rglob("*.html")):
            rel = path.relative_to(site).as_posix()
            if rel == "404.html":
                continue
            browser.open(path.as_uri())
            loaded = LOADED.replace("URL", json.dumps(path.as_uri()))
            _until(lambda loaded=loaded: browser.js(loaded), rel)
            got = browser.js(RENDERED)
            assert got["requests"] == [], f"{rel}: {got['requests']}"
            assert got["errors"] == 0 and got["raw"] == 0 and got["dollars"] == 0, f"{rel}: {got}"
            if got["katex"]:
                assert "KaTeX_Main" in got["fonts"] and "KaTeX_Math" in got["fonts"], f"{rel}: {got}"
            typeset += got["katex"]
    finally:
        browser.close()
    assert typeset >= 50


LOADED = (
    'location.href === URL && document.readyState === "complete"'
    ' && document.documentElement.dataset.mathRendered === "true"'
)

RENDERED = """(async () => {
  await document.fonts.ready;
  const cells = [...document.querySelectorAll(".jp-MarkdownCell .jp-RenderedMarkdown, .jp-RenderedLatex")];
  const prose = (cell) => {  // the text outside code and typeset math
    const copy = cell.cloneNode(true);
    copy.querySelectorAll("code, pre, .katex").forEach((e) => e.remove());
    return copy.textContent;
  };
  return {
    katex: document.querySelectorAll(".katex").length,
    errors: document.querySelectorAll(".katex-error").length,
    raw: [...document.querySelectorAll(".arithmatex")].filter((e) => !e.querySelector(".katex")).length,
    dollars: cells.map(prose).join(" ").split("$").length - 1,
    fonts: [...document.fonts].filter((f) => f.status === "loaded").map((f) => f.family),
    requests: performance
      .getEntriesByType("resource")
      .map((e) => e.name)
      .filter((n) => !n.startsWith("file:")),
  };
})()"""


def _until(condition, what: str, timeout: float = 30.0) -> None:
    import time

    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, f"{what}: the page did not finish rendering its math"
        time.sleep(0.05)


class Page(HTMLParser):
    """One built page: its ids, the URLs it links (a href), the resources it loads (script src, link
    href, img/iframe/source src), its inline styles and the text of its notebook Markdown cells."""

    def __init__(self) -> None:
        super().__init__()
        self.ids: set[str] = set()
        self.urls: list[str] = []
        self.resources: list[str] = []
        self.styles: list[str] = []
        self.markdown_cells: list[str] = []
        self.html = ""
        self._style = False

    @classmethod
    def of(cls, path) -> Page:
        page = cls()
        page.html = path.read_text(errors="replace")
        page.feed(page.html)
        page.markdown_cells = re.findall(
            r'class="jp-RenderedHTMLCommon jp-RenderedMarkdown jp-MarkdownOutput"[^>]*>(.*?)</div>',
            page.html,
            re.S,
        )
        return page

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        a = {k: v or "" for k, v in attrs}
        for key in ("id", "name") if tag == "a" else ("id",):
            if a.get(key):
                self.ids.add(a[key])
        if tag == "a" and "href" in a:
            self.urls.append(a["href"])
        if tag in ("script", "img", "iframe", "source", "video", "audio", "embed") and a.get("src"):
            self.resources.append(a["src"])
            self.urls.append(a["src"])
        if tag == "link" and a.get("href"):
            self.resources.append(a["href"])
            if "canonical" not in a.get("rel", ""):
                self.urls.append(a["href"])
        if a.get("style"):
            self.styles.append(a["style"])
        self._style = tag == "style"

    def handle_data(self, data: str) -> None:
        if self._style:
            self.styles.append(data)

    def handle_endtag(self, tag: str) -> None:
        self._style = False


def _resolve(site, page, url: str):
    """(file, fragment) that a relative URL of ``page`` names; (None, "") for a remote one."""
    parts = urlsplit(url)
    if parts.scheme or parts.netloc:
        return None, ""
    if not parts.path:
        return page, unquote(parts.fragment)
    base = site if parts.path.startswith("/") else page.parent  # the 404 page's links are absolute
    target = (base / unquote(parts.path).lstrip("/")).resolve()
    if target.is_dir() or parts.path.endswith("/"):
        target = target / "index.html"
    return target, unquote(parts.fragment)
