"""The jinja2 environment shared by the emitters, and the header every generated file carries."""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, Any

from symkin.core.names import comment_safe, identifier
from symkin.emit.kernel import link_text
from symkin.errors import CompileError

if TYPE_CHECKING:
    import jinja2

__all__ = ["render", "python_module", "template_dir", "Header", "strategy_text"]


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


def python_module(
    template: str, kernel: Any, printed: list, suffix: str = "", **context: Any
) -> dict[str, str]:
    """Render a generated Python module ``symkin_<code_name><suffix>.py`` (NumPy and CasADi
    backends) of ``kernel``: ``printed`` are its functions as the template takes them."""
    module = f"symkin_{kernel.code_name}{suffix}"
    text = render(
        template,
        module=module,
        n=kernel.n,
        F=kernel.F,
        links=kernel.links and link_text(kernel.links),
        functions=printed,
        header=Header.of(kernel, ascii(kernel.name)),
        name_literal=ascii(kernel.name),
        frame_literals=[ascii(f.name) for f in kernel.frames],
        hessian_frames=sorted({h.frame for f in printed for h in _get(f, "hessians")}),
        framed_docs={kind: kernel.framed_doc(kind) for kind in kernel.framed},
        **context,
    )
    return {f"{module}.py": text}


def _get(f: Any, key: str) -> Any:
    return f[key] if isinstance(f, dict) else getattr(f, key)


@dataclass(frozen=True)
class Header:
    """What every generated file says about itself."""

    robot: str  # comment-safe robot identifier
    name_literal: str  # the robot's name as an escaped string literal (backend-specific quoting)
    ets: str  # a serial chain's ETS, else ""
    frames: str  # the frames' names
    version: str
    command: str
    counts: str
    strategy: str
    references: str

    @classmethod
    def of(cls, kernel: Any, literal: str) -> Header:
        """The header of ``kernel``'s files; ``literal`` quotes its name."""
        from symkin.core.version import __version__
        from symkin.symbolic.cse import OpCounts
        from symkin.symbolic.functions import REFERENCES

        functions = kernel.functions
        total = sum((f.code.counts for f in functions), OpCounts())
        return cls(
            robot=identifier(kernel.name),
            name_literal=literal,
            ets=comment_safe(kernel.ets, limit=4000),
            frames=comment_safe(", ".join(f.name for f in kernel.frames), limit=2000),
            version=__version__,
            command=comment_safe(kernel.command),
            counts=f"{total} over {len(functions)} functions",
            strategy=strategy_text(functions, kernel.F),
            references=REFERENCES,
        )


def strategy_text(functions: list, frames: int = 1) -> str:
    """How the functions' code was derived, for the generated headers."""
    if functions[0].code.strategy == "expanded":
        return "expanded (one exact expression per output, then common-subexpression elimination)"
    loops = any(f.code.hessians for f in functions)
    hessians = "Hessians as loops over the Jacobian columns" if loops else "Hessians written out"
    tree = (
        f", walked depth first over {frames} frames: the parts they share are computed once"
        if frames > 1
        else ""
    )
    return f"straight-line program (named link frames and Jacobian columns; {hessians}){tree}"
