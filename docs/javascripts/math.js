// The equations of every page, rendered with the KaTeX bundled in assets/katex (no network):
// Markdown pages carry them as pymdownx.arithmatex's generic markup, \( .. \) and \[ .. \] in
// elements of class "arithmatex"; notebook pages as $ .. $ and $$ .. $$ in their Markdown cells
// and in the LaTeX outputs of their code cells (a sympy expression left as a cell's value).
// Run again on every page that Material's instant navigation loads (document$).
(function () {
  const arithmatex = [
    { left: "\\(", right: "\\)", display: false },
    { left: "\\[", right: "\\]", display: true },
  ];
  const notebook = [
    { left: "$$", right: "$$", display: true },
    { left: "$", right: "$", display: false },
    ...arithmatex,
  ];
  function render(body) {
    for (const el of body.querySelectorAll(".arithmatex")) {
      renderMathInElement(el, { delimiters: arithmatex, throwOnError: false });
    }
    for (const el of body.querySelectorAll(".jp-MarkdownCell .jp-RenderedMarkdown, .jp-RenderedLatex")) {
      renderMathInElement(el, { delimiters: notebook, throwOnError: false });
    }
    document.documentElement.dataset.mathRendered = "true"; // what the browser test waits for
  }
  if (typeof document$ !== "undefined") {
    document$.subscribe(({ body }) => render(body));
  } else {
    document.addEventListener("DOMContentLoaded", () => render(document.body));
  }
})();
