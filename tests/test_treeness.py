"""Whether a model is a tree is asked in the model only: outside ``symkin/model/`` no code tests a
model's class (``isinstance``/``issubclass`` against Robot or Tree, ``type(x).__name__`` or
``x.__class__.__name__`` compared with their names) or reads a tree marker (``is_tree``,
``_symkin_tree``); the rest of symkin asks the model a question (``as_tree``, ``single_path``,
``chain(frame)``) or the compiled kernel how many frames it has. At most three such places in all."""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent / "symkin"
CLASSES = {"Robot", "Tree"}
MARKERS = {"is_tree", "_symkin_tree"}
MAX_PLACES = 3


def _names(node: ast.AST) -> set[str]:
    """The class names an isinstance/issubclass second argument mentions (a name, an attribute, a tuple)."""
    if isinstance(node, ast.Tuple):
        return set().union(*(_names(e) for e in node.elts))
    if isinstance(node, ast.Name):
        return {node.id}
    if isinstance(node, ast.Attribute):
        return {node.attr}
    return set()


def _class_name_of(node: ast.AST) -> bool:
    """``type(x).__name__`` or ``x.__class__.__name__``."""
    if not (isinstance(node, ast.Attribute) and node.attr == "__name__"):
        return False
    inner = node.value
    if isinstance(inner, ast.Attribute) and inner.attr == "__class__":
        return True
    return isinstance(inner, ast.Call) and isinstance(inner.func, ast.Name) and inner.func.id == "type"


def treeness(source: str) -> list[int]:
    """The lines of ``source`` that ask whether a model is a Robot or a Tree (module docstring)."""
    lines = []
    for node in ast.walk(ast.parse(source)):
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in ("isinstance", "issubclass")
        ):
            if len(node.args) == 2 and _names(node.args[1]) & CLASSES:
                lines.append(node.lineno)
        elif getattr(node, "attr", None) in MARKERS or getattr(node, "value", None) in MARKERS:
            lines.append(node.lineno)
        elif isinstance(node, ast.Compare):
            sides = [node.left, *node.comparators]
            named = any(isinstance(s, ast.Constant) and s.value in CLASSES for s in sides)
            if named and any(_class_name_of(s) for s in sides):
                lines.append(node.lineno)
    return sorted(set(lines))


def _places() -> dict[str, list[int]]:
    out = {}
    for path in sorted(ROOT.rglob("*.py")):
        found = treeness(path.read_text())
        if found:
            out[path.relative_to(ROOT.parent).as_posix()] = found
    return out


def test_the_finder_sees_each_way_of_asking():
    source = (
        "isinstance(m, Tree)\nisinstance(m, (Robot, int))\nissubclass(C, symkin.Tree)\nkin.is_tree\n"
        "getattr(kin, '_symkin_tree', False)\nm.__class__.__name__ == 'Tree'\ntype(m).__name__ != 'Robot'\n"
        "isinstance(m, TreeProgram)\nm.single_path\nlen(kin.frames) > 1\n"
    )
    assert treeness(source) == [1, 2, 3, 4, 5, 6, 7]


def test_only_the_model_asks_whether_a_model_is_a_tree():
    places = _places()
    outside = {path: lines for path, lines in places.items() if not path.startswith("symkin/model/")}
    assert outside == {}, f"ask the model (as_tree, single_path, chain) instead: {outside}"
    assert sum(len(lines) for lines in places.values()) <= MAX_PLACES, places
