"""The package's import graph: every ``import`` of a symkin module, at module level, inside a
function or in an ``if TYPE_CHECKING:`` block (a circle of type annotations is a circle of the
design too), forms no cycle, and no private name (``_x``) is imported from another package of
symkin (``if TYPE_CHECKING:`` blocks excluded there: they never run)."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent / "symkin"


def _modules() -> dict[str, Path]:
    out = {}
    for path in ROOT.rglob("*.py"):
        parts = list(path.relative_to(ROOT.parent).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts.pop()
        out[".".join(parts)] = path
    return out


def _type_checking_nodes(tree: ast.AST) -> set[int]:
    skip: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If):
            name = getattr(node.test, "id", getattr(node.test, "attr", None))
            if name == "TYPE_CHECKING":
                skip.update(id(x) for stmt in node.body for x in ast.walk(stmt))
    return skip


def _imports(mods: dict[str, Path], typing: bool = False) -> dict[str, set[tuple[str, str | None]]]:
    """module -> {(imported module, imported name or None)}; ``typing``: with the imports of
    ``if TYPE_CHECKING:`` blocks."""
    graph: dict[str, set[tuple[str, str | None]]] = {}
    for mod, path in mods.items():
        tree = ast.parse(path.read_text())
        skip = set() if typing else _type_checking_nodes(tree)
        found: set[tuple[str, str | None]] = set()
        for node in ast.walk(tree):
            if id(node) in skip:
                continue
            if isinstance(node, ast.Import):
                found |= {(a.name, None) for a in node.names if a.name.split(".")[0] == "symkin"}
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    base = mod.split(".")
                    if path.name != "__init__.py":
                        base = base[:-1]
                    base = base[: len(base) - node.level + 1]
                    target = ".".join(base + ([node.module] if node.module else []))
                else:
                    target = node.module or ""
                if target.split(".")[0] != "symkin":
                    continue
                for a in node.names:
                    sub = f"{target}.{a.name}"
                    found.add((sub, None) if sub in mods else (target, a.name))
        graph[mod] = {(m, n) for m, n in found if m in mods and m != mod}
    return graph


def _cycles(graph: dict[str, set[tuple[str, str | None]]]) -> list[list[str]]:
    """Strongly connected components of more than one module (Tarjan, iterative)."""
    edges = {m: sorted({t for t, _ in out}) for m, out in graph.items()}
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    result = []
    counter = 0
    for root in sorted(edges):
        if root in index:
            continue
        work = [(root, 0)]
        while work:
            v, i = work.pop()
            if i == 0:
                index[v] = low[v] = counter
                counter += 1
                stack.append(v)
                on_stack.add(v)
            if i < len(edges[v]):
                work.append((v, i + 1))
                w = edges[v][i]
                if w not in index:
                    work.append((w, 0))
                elif w in on_stack:
                    low[v] = min(low[v], index[w])
                continue
            for w in edges[v]:
                if w in on_stack:
                    low[v] = min(low[v], low[w])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on_stack.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    result.append(sorted(comp))
    return sorted(result)


GRAPH = _imports(_modules())
GRAPH_WITH_TYPES = _imports(_modules(), typing=True)


def test_the_cycle_finder_finds_a_cycle():
    graph = {"a": {("b", None)}, "b": {("c", None)}, "c": {("a", None)}, "d": {("a", None)}}
    assert _cycles(graph) == [["a", "b", "c"]]


def test_no_import_cycles():
    assert _cycles(GRAPH_WITH_TYPES) == []


def test_no_private_name_is_imported_from_another_package():
    def package(mod: str) -> str:
        parts = mod.split(".")
        return ".".join(parts[:2]) if len(parts) > 2 else mod

    bad = sorted(
        f"{mod} imports {name} from {target}"
        for mod, out in GRAPH.items()
        for target, name in out
        if name and name.startswith("_") and not name.startswith("__") and package(target) != package(mod)
    )
    assert bad == []
