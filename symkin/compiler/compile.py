"""The compiler: a model (a :class:`Robot` chain or a :class:`Tree`) -> its tree
(:func:`symkin.model.tree.as_tree`: a chain is the one-frame tree of :meth:`Tree.from_robot`) -> its
symbolic functions -> a :class:`~symkin.emit.kernel.Kernel` -> emitted sources -> a built and
loaded :class:`Artifact` (the C extension module, or the NumPy or CasADi Python module).
:func:`symkin.compile` (:mod:`symkin.runtime.load`) wraps an artifact in the runtime's kinematics
object.

Generated sources are cached per user (``$SYMKIN_CACHE`` or ``~/.cache/symkin``) under a key made
of everything they depend on (:func:`cache_key`): the model's tree (:attr:`Tree.fingerprint`:
structure, names, limits, speed limits; the C header lists the limits) and its name in generated
code, the backend and strategy,
the symkin version, the templates, the compiler's own Python code (symbolic, emit, compiler and the
model classes it prints) and the sympy version. So a warm compile neither imports sympy nor
re-derives anything, and a changed derivation never serves stale code. The derivation itself
(which depends on the tree's structure only) is shared by the backends and by models that differ
only in their limits.
"""

from __future__ import annotations

import contextlib
import hashlib
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from types import ModuleType
from typing import Any

from symkin.compiler.manifest import BACKENDS
from symkin.core.cache import cache_dir, verified
from symkin.core.version import __version__
from symkin.errors import CompileError, SymkinError
from symkin.model.robot import Robot
from symkin.model.tree import Tree, as_tree

__all__ = [
    "Artifact",
    "BACKENDS",
    "OPTIONAL_BACKENDS",
    "STRATEGIES",
    "build",
    "COMPILER_SOURCES",
    "cache_key",
    "cached_files",
    "compiler_digest",
    "sources_digest",
    "templates_digest",
    "check_backend",
    "require",
    "check_strategy",
    "check_derivatives",
    "generate",
    "generate_collision",
    "load_artifact",
    "derived_functions",
    "write_generated",
    "write_files",
]

# the backends whose generated module imports an optional library: backend -> (import, pip extra)
OPTIONAL_BACKENDS = {"jax": ("jax", "jax"), "torch": ("torch", "torch")}
STRATEGIES = ("expanded", "program")
Model = Robot | Tree

_FUNCTIONS: dict[tuple[str, str], list] = {}  # derived functions, shared by the backends
_FUNCTIONS_MAX = 32

# the compiler's own code: what it derives and prints depends on these files
COMPILER_SOURCES = (
    "symbolic",
    "emit",
    "compiler",
    "model/ets.py",
    "model/derivatives.py",
    "model/robot.py",
    "model/tree.py",
    "model/slots.py",
)


@dataclass(frozen=True)
class Artifact:
    """Built, loaded generated code: ``files`` (file name -> text), ``module`` (the C extension
    module, or the NumPy / CasADi Python module) and ``path`` (the library or module file; None
    when imported from memory)."""

    files: dict[str, str]
    module: ModuleType
    path: Path | None


def check_backend(backend: str) -> None:
    """SymkinError unless ``backend`` is one of :data:`BACKENDS`."""
    if backend not in BACKENDS:
        raise SymkinError(f"unknown backend {backend!r}: choose one of {', '.join(BACKENDS)}")


def require(backend: str) -> None:
    """MissingExtraError naming the pip extra unless the library ``backend``'s generated module
    imports (:data:`OPTIONAL_BACKENDS`: jax, torch) is installed; nothing for the other backends."""
    if backend not in OPTIONAL_BACKENDS:
        return
    import importlib.util

    module, extra = OPTIONAL_BACKENDS[backend]
    if importlib.util.find_spec(module) is None:
        from symkin.errors import MissingExtraError

        raise MissingExtraError(
            f"the {backend} backend needs {module}: pip install 'symkin[{extra}]' "
            "(see the README for the CPU build)"
        )


def check_strategy(strategy: str | None, model: Any = None) -> None:
    """SymkinError unless ``strategy`` is None or one of :data:`STRATEGIES` ("expanded" needs one
    serial chain, :attr:`Tree.single_path`)."""
    if strategy is not None and strategy not in STRATEGIES:
        raise SymkinError(
            f"unknown strategy {strategy!r}: choose one of {', '.join(STRATEGIES)} (or None: by size)"
        )
    if strategy == "expanded" and model is not None and not getattr(model, "single_path", True):
        raise SymkinError(
            f"{model.name} is not one serial chain: a tree compiles as one program (strategy 'program'), "
            "not 'expanded'"
        )


def check_derivatives(derivatives: Any) -> int:
    """``derivatives`` (the highest derivative order to compile, :func:`symkin.compile`) as an int
    in 0..:data:`~symkin.model.derivatives.MAX_ORDER` (0, 1 and 2 add nothing: jacob0 and hessian0
    are always there); SymkinError otherwise."""
    from symkin.model.derivatives import MAX_ORDER

    if isinstance(derivatives, bool) or not isinstance(derivatives, int) or not 0 <= derivatives <= MAX_ORDER:
        raise SymkinError(
            f"derivatives must be an integer 0..{MAX_ORDER} (the highest derivative order compiled), "
            f"not {derivatives!r}"
        )
    return derivatives if derivatives >= 3 else 0


def _check_model(model: Any, backend: str, strategy: str | None) -> None:
    """The checks before a compile: ``backend``, ``strategy`` and ``model`` (a chain or tree with joints)."""
    check_backend(backend)
    as_tree(model)  # TypeError for what is not a model
    check_strategy(strategy, model)
    if model.n == 0:
        raise SymkinError(f"{model.name!r} has no joints (on the paths to its frames): nothing to compile")


@lru_cache(maxsize=1)
def templates_digest() -> str:
    """sha256 of every template."""
    from symkin.emit.templates import template_dir

    h = hashlib.sha256()
    root = template_dir()
    for path in sorted(root.rglob("*.j2")):
        h.update(path.relative_to(root).as_posix().encode())
        h.update(path.read_bytes())
    return h.hexdigest()


@lru_cache(maxsize=1)
def compiler_digest() -> str:
    """sha256 of the compiler's Python sources (:data:`COMPILER_SOURCES`) and the sympy version."""
    from importlib import metadata

    h = hashlib.sha256(sources_digest(Path(__file__).resolve().parent.parent).encode())
    with contextlib.suppress(metadata.PackageNotFoundError):  # sympy is a declared dependency
        h.update(metadata.version("sympy").encode())
    return h.hexdigest()


def sources_digest(root: Path) -> str:
    """sha256 of the :data:`COMPILER_SOURCES` under the package folder ``root``."""
    h = hashlib.sha256()
    paths: list[Path] = []
    for part in COMPILER_SOURCES:
        p = root / part
        paths += sorted(p.rglob("*.py")) if p.is_dir() else [p]
    for path in paths:
        h.update(path.relative_to(root).as_posix().encode() + b"\0")
        h.update(path.read_bytes() + b"\0")
    return h.hexdigest()


def cache_key(
    model: Model, backend: str, strategy: str | None = None, what: str = "kinematics", derivatives: int = 0
) -> str:
    """The key of ``model``'s generated ``what`` (its kinematics, with the derivatives up to order
    ``derivatives``, or "analytic-ik" for the closed-form IK) on ``backend`` (see the module
    docstring)."""
    if what != "kinematics":  # e.g. "analytic-ik": depends on the ETS and name only
        parts = (__version__, what, backend, model.key)
    else:
        parts = (__version__, backend, model.code_name, as_tree(model).fingerprint, str(strategy))
        parts += (f"derivatives {derivatives}",) if derivatives else ()
    text = "\n".join((*parts, templates_digest(), compiler_digest()))
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def derived_functions(model: Model, strategy: str | None = None, derivatives: int = 0) -> list:
    """The derived functions of ``model`` (:func:`symkin.symbolic.functions.kin_functions`; imports
    sympy), then its derivatives of orders 3..``derivatives``
    (:func:`symkin.symbolic.functions.derivative_functions`), memoised by its tree's structure and
    the strategy (the derivatives by the orders): shared by the backends."""
    from symkin.symbolic.functions import derivative_functions, kin_functions

    tree = as_tree(model)
    functions = _memo((tree.key, str(strategy)), lambda: kin_functions(tree, strategy))
    if derivatives >= 3:
        orders = tuple(range(3, derivatives + 1))
        functions = functions + _memo((tree.key, orders), lambda: derivative_functions(tree, orders))
    return functions


def _memo(key: tuple, make: Callable[[], list]) -> list:
    functions = _FUNCTIONS.get(key)
    if functions is None:
        functions = make()
        if len(_FUNCTIONS) >= _FUNCTIONS_MAX:
            _FUNCTIONS.clear()
        _FUNCTIONS[key] = functions
    return functions


def generate(
    robot: Model,
    backend: str,
    command: str | None = None,
    strategy: str | None = None,
    prefix: str | None = None,
    precision: str = "double",
    libm: bool = False,
    derivatives: int = 0,
) -> dict[str, str]:
    """The generated source files of ``robot`` (a chain or a tree) for ``backend`` (file name ->
    text). Imports sympy.

    ``strategy``: ``"expanded"`` (one exact expression per output, then CSE: the smallest, most
    readable code for arms of up to about 7 joints), ``"program"`` (named link frames, Hessians as
    loops: linear in the number of joints; a tree always compiles so), or None to choose by size
    (the generated header says which was used). C backend only, for chains and trees alike:
    ``prefix``, the prefix of every exported symbol and file name instead of ``symkin_<robot>``
    (a tree: ``symkin_<tree>_tree``), so several robots link into one program;
    ``precision="float"`` for single-precision code (no Python module; for microcontrollers);
    ``libm`` to call the C library's sin and cos instead of the inline kernels.
    ``derivatives``: also the partial derivatives of orders 3..``derivatives`` of every frame's
    pose (``derivative3``..., :meth:`symkin.Kinematics.derivative`; 0, 1, 2: none).
    """
    _check_model(robot, backend, strategy)
    derivatives = check_derivatives(derivatives)
    if (prefix is not None or precision != "double" or libm) and backend != "c":
        raise SymkinError(f"prefix, precision and libm apply to the C backend only, not {backend!r}")
    if prefix is not None:
        from symkin.emit.c.backend import check_prefix

        check_prefix(prefix)  # before the derivation, which can take long
    from symkin.compiler.kernel import kernel_of

    tree = as_tree(robot)
    frames = f" --frames {','.join(tree.frames)}" if len(tree.frames) > 1 else ""
    more = f" --derivatives {derivatives}" if derivatives else ""
    command = command or f"symkin compile {robot.identifier}{frames} --backend {backend}{more}"
    kernel = kernel_of(robot, tree, derived_functions(robot, strategy, derivatives), command)
    if backend == "c":
        from symkin.emit.c.backend import render_c

        return render_c(kernel, prefix, precision, libm)
    if backend == "numpy":
        from symkin.emit.numpy.backend import render_numpy

        return render_numpy(kernel)
    if backend in OPTIONAL_BACKENDS:
        from symkin.emit.tensor import render_tensor

        return render_tensor(kernel, backend)
    from symkin.emit.casadi.backend import render_casadi

    return render_casadi(kernel)


def generate_collision(model: Model, backend: str, command: str | None = None) -> dict[str, str]:
    """The generated collision code of ``model``'s geometry on ``backend`` (file name -> text); {}
    when the model has no geometry.

    C: ``symkin_<robot>_collision.c`` (the FKCC kernel, functions ``skcoll_*``) and the distance
    primitives it includes, ``symkin_collide.h``; NumPy: ``symkin_<robot>_collision.py``; CasADi:
    ``symkin_<robot>_collision_casadi.py`` (``function(env)``: the distances' ``casadi.Function``);
    JAX and PyTorch: ``symkin_<robot>_collision_<backend>.py`` (``points(q)``)."""
    check_backend(backend)
    geometry = getattr(model, "geometry", None)
    if geometry is None or not geometry.shapes:
        return {}
    from symkin.emit import collision as emit
    from symkin.geometry.pairs import layout_of

    layout = layout_of(model)
    command = command or f"symkin compile {model.identifier} --backend {backend}"
    if backend != "c":
        return emit.render_collision_python(layout, backend, command)
    files = emit.render_collision(layout)
    note = f"/* Generated by symkin {__version__}: a copy of symkin/runtime/csrc/symkin_collide.h. */\n"
    return {
        f"{emit.collision_module_name(layout.tree.name)}.c": files["skcoll.c"],
        "symkin_collide.h": note + files["symkin_collide.h"],
    }


def write_generated(
    robot: Model, backend: str, folder: str | Path, command: str | None = None, **options: Any
) -> list[Path]:
    """Generate and write the files of ``robot`` (a chain or a tree) for ``backend`` into
    ``folder`` (:func:`write_files`); returns the paths (``options``: ``strategy``, ``prefix``,
    ``precision``, ``libm`` and ``derivatives`` of :func:`generate`)."""
    files = generate(robot, backend, command, **options)
    prefix, precision = options.get("prefix"), options.get("precision", "double")
    return write_files(robot, backend, files, folder, command, prefix, precision)


def write_files(
    robot: Model,
    backend: str,
    files: dict[str, str],
    folder: str | Path,
    command: str | None = None,
    prefix: str | None = None,
    precision: str = "double",
) -> list[Path]:
    """Write ``files`` (generated for ``robot`` on ``backend``) into ``folder``, then the manifest
    :func:`symkin.load_compiled` reads back (``<stem>.symkin.json``), then the collision code of
    the robot's geometry (:func:`generate_collision`; not with ``prefix`` or ``precision="float"``:
    the collision kernel's symbols are ``skcoll_*``); returns the paths in that order."""
    from symkin.compiler.manifest import write_manifest

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    extra = generate_collision(robot, backend, command) if prefix is None and precision == "double" else {}
    out = []
    for name, text in sorted(files.items()):
        (folder / name).write_text(text)
        out.append(folder / name)
    out.append(write_manifest(robot, backend, files, folder, precision))
    for name, text in sorted(extra.items()):
        (folder / name).write_text(text)
        out.append(folder / name)
    return out


def cached_files(
    model: Model,
    backend: str,
    key: str,
    use_cache: bool = True,
    strategy: str | None = None,
    derivatives: int = 0,
) -> dict[str, str]:
    """Generated files from the cache (``<cache>/gen/<key>.json``, verified by the sha256 of its key
    and content: :func:`symkin.core.cache.verified`), else generated and stored atomically."""
    make = lambda: {"files": generate(model, backend, strategy=strategy, derivatives=derivatives)}  # noqa: E731
    return verified("gen", key, make, use_cache)["files"]


def load_artifact(files: dict[str, str], backend: str) -> Artifact:
    """Build (C, cached by content) and import generated ``files`` of ``backend``."""
    if backend == "c":
        from symkin.emit.c.backend import build_c

        module, lib = build_c(files)
        return Artifact(files, module, lib)
    from symkin.emit.numpy.backend import load_numpy

    if backend in OPTIONAL_BACKENDS:
        require(backend)
    try:
        module = load_numpy(files, cache_dir() / backend)
    except ImportError as exc:  # pragma: no cover - casadi is a declared dependency
        raise CompileError(f"the {backend} backend cannot import its module: {exc}") from exc
    file = getattr(module, "__file__", None)
    return Artifact(files, module, Path(file) if file else None)


def build(
    model: Model,
    backend: str = "c",
    cache: bool = True,
    strategy: str | None = None,
    key: str | None = None,
    derivatives: int = 0,
) -> Artifact:
    """Generate (or take from the cache), build and load ``model``'s code on ``backend`` (with the
    derivatives of orders 3..``derivatives``)."""
    _check_model(model, backend, strategy)
    derivatives = check_derivatives(derivatives)
    key = key or cache_key(model, backend, strategy, derivatives=derivatives)
    return load_artifact(cached_files(model, backend, key, cache, strategy, derivatives), backend)
