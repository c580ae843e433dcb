"""A MkDocs hook: the table of contents of a notebook page from the headings the page really has.

mkdocs-jupyter builds a notebook's table of contents from a Markdown export in which a heading's
inline code is lost: "## Via points: `mstraj`" is listed as "Via points:" and linked to
``#via-points``, while the rendered heading's id is ``via-points-mstraj``, so the link pointed at
nothing (and ``mkdocs build --strict`` does not check notebook pages). Here the table of contents
of every notebook page is rebuilt from the headings of its Markdown cells (those nbconvert gives an
anchor link) as rendered: their ids, levels and text.
"""

from __future__ import annotations

import re
from typing import Any

from mkdocs.structure.toc import get_toc

HEADING = re.compile(r'<h([1-6])\b[^>]*?\bid="([^"]+)"[^>]*>(.*?)</h\1>', re.S)
ANCHOR_LINK = re.compile(r'<a class="anchor-link"[^>]*>.*?</a>', re.S)
TAG = re.compile(r"<[^>]+>")


def headings(html: str) -> list[dict[str, Any]]:
    """The Markdown-cell headings of a notebook page as nested table-of-contents tokens."""
    tokens: list[dict[str, Any]] = []
    stack: list[dict[str, Any]] = []
    for level, anchor, inner in HEADING.findall(html):
        if not ANCHOR_LINK.search(inner):
            continue  # a heading inside a cell's output, not one of the notebook's sections
        text = TAG.sub("", ANCHOR_LINK.sub("", inner)).strip()
        token = {"level": int(level), "id": anchor, "name": text, "children": []}
        while stack and stack[-1]["level"] >= token["level"]:
            stack.pop()
        (stack[-1]["children"] if stack else tokens).append(token)
        stack.append(token)
    return tokens


def on_page_content(html: str, page: Any, **kwargs: Any) -> str:
    if page.file.src_uri.endswith(".ipynb"):
        tokens = headings(html)
        if tokens:
            page.toc = get_toc(tokens)
    return html
