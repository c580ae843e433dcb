"""The jinja2 environment shared by the emitters, and the header every generated file carries."""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

from symkin.errors import CompileError
from symkin.model.robot import identifier

if TYPE_CHECKING:
    import jinja2

__all__ = [
    "render",
    "render_python_module",
    "template_dir",
    "Header",
    "comment_safe",
    "c_string",
    "identifier",
    "chain_tables",
]


def template_dir() -> Path:
    """``symkin/templates`` in an installed wheel, else the repository's top-level ``templates/``."""
    here = Path(__file__).resolve().parent.parent
    for candidate in (here / "templates", here.parent / "templates"):
        if (candidate / "c").is_dir():
            return candidate
    raise CompileError(f"symkin's templates folder is missing (looked in {here / 'templates'})")


@lru_cache(maxsize=1)
def _env() -> jinja2.Environment:
    import jinja2  # here: a warm compile (template_dir for the cache key) does without it

    env = jinja2.Environment(
        loader=jinja2.FileSystemLoader(str(template_dir())),
        undefined=jinja2.StrictUndefined,
        trim_blocks=True,
        lstrip_blocks=True,
        keep_trailing_newline=True,
        autoescape=False,
    )
    env.filters["lit"] = jinja2.pass_context(_literal)
    return env


def _literal(context: Any, text: str) -> str:
    """A C floating-point literal in the precision of the code being rendered (``real`` in the
    context): ``1.0`` stays for double, becomes ``1.0f`` for float (``HUGE_VAL``: ``HUGE_VALF``)."""
    if context.get("real", "double") != "float":
        return text
    if "HUGE_VAL" in text:
        return text.replace("HUGE_VAL", "HUGE_VALF")
    return text + "f"


def render(name: str, **context: Any) -> str:
    """Render template ``name`` (e.g. ``c/kinematics.c.j2``); errors name the template."""
    try:
        return _env().get_template(name).render(**context)
    except Exception as exc:  # jinja2.TemplateError, or an error raised inside the template
        raise CompileError(f"template {name} failed: {type(exc).__name__}: {exc}") from exc


def render_python_module(
    template: str,
    robot: Any,
    functions: list,
    printed: list,
    command: str,
    suffix: str = "",
    **context: Any,
) -> dict[str, str]:
    """Render a generated Python module ``symkin_<robot><suffix>.py`` (NumPy and CasADi backends)."""
    module = f"symkin_{identifier(robot.name)}{suffix}"
    text = render(
        template,
        module=module,
        n=robot.n,
        functions=printed,
        header=Header.of(robot, functions, command, ascii(robot.name)),
        name_literal=ascii(robot.name),
        **context,
    )
    return {f"{module}.py": text}


def chain_tables(robot: Any) -> dict[str, list[str]]:
    """Per joint along the chain: joint index, axis index, sign literal, revolute flag (as text)."""
    joints = [e for e in robot.ets if e.is_joint]
    return {
        "order": [str(e.joint) for e in joints],
        "axis": [str(e.axis.index) for e in joints],
        "sign": ["-1.0" if e.flip else "1.0" for e in joints],
        "revolute": [str(int(e.is_revolute)) for e in joints],
    }


_UNSAFE = re.compile(r"[^\x20-\x7e]")
# between * and /, / and *, ? and ?: where a space keeps a comment from ending or a trigraph from forming
_APART = re.compile(r"(?<=\*)(?=/)|(?<=/)(?=\*)|(?<=\?)(?=\?)")


def comment_safe(text: str, limit: int = 300) -> str:
    """Any text made inert inside a C block or line comment, a Python comment and a Python
    docstring, cut to ``limit`` characters.

    Only printable ASCII is kept: control characters (newlines, ``\\r``, form feeds, NUL) and
    non-ASCII become ``?``, a backslash becomes ``/`` (no line continuation, no string escape) and
    a double quote becomes ``'`` (no ``\"\"\"``). Then ``*`` and ``/`` next to each other, and two ``?``,
    are set apart by a space, after every replacement, so no ``*/`` or ``/*`` and no trigraph
    (``??/`` is a backslash in ISO C modes) can form.
    """
    text = _UNSAFE.sub("?", text).replace("\\", "/").replace('"', "'")
    text = _APART.sub(" ", text)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def c_string(text: str) -> str:
    """A C string literal of the UTF-8 bytes of ``text``: ASCII letters, digits and a few safe
    punctuation marks as they are, every other byte (non-ASCII too) escaped as octal."""
    out = []
    for b in text.encode("utf-8", "surrogatepass"):
        ch = chr(b)
        safe = b < 128 and (ch.isalnum() or ch in " _-.,:;()[]=+")
        out.append(ch if safe else f"\\{b:03o}")
    return '"' + "".join(out) + '"'


@dataclass(frozen=True)
class Header:
    """What every generated file says about itself."""

    robot: str  # comment-safe robot identifier
    name_literal: str  # the robot's name as an escaped string literal (backend-specific quoting)
    ets: str
    version: str
    command: str
    counts: str
    strategy: str
    references: str

    @classmethod
    def of(cls, robot: Any, functions: list, command: str, literal: str) -> Header:
        """The header for ``functions`` (KinFunction list) of ``robot``; ``literal`` quotes its name."""
        from symkin import __version__
        from symkin.symbolic.cse import OpCounts
        from symkin.symbolic.functions import REFERENCES

        total = sum((f.code.counts for f in functions), OpCounts())
        counts = f"{total} over {len(functions)} functions"
        return cls(
            strategy=strategy_text(functions),
            references=REFERENCES,
            robot=identifier(robot.name),
            name_literal=literal,
            ets=comment_safe(str(robot.ets), limit=4000),
            version=__version__,
            command=comment_safe(command),
            counts=counts,
        )


def strategy_text(functions: list) -> str:
    """How the functions' code was derived, for the generated headers."""
    if functions[0].code.strategy == "expanded":
        return "expanded (one exact expression per output, then common-subexpression elimination)"
    loops = any(f.code.hessians for f in functions)
    hessians = "Hessians as loops over the Jacobian columns" if loops else "Hessians written out"
    return f"straight-line program (named link frames and Jacobian columns; {hessians})"
