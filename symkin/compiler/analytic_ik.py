"""The closed-form IK through the compiler: robot -> closed-form derivation -> generated code ->
a built :class:`~symkin.compiler.compile.Artifact` (:func:`symkin.runtime.analytic_ik.compile_analytic`
wraps it in the runtime's solver).

Cached like the kinematics, in the same store and under the same key function
(:func:`symkin.compiler.compile.cache_key` with ``what="analytic-ik"``: the robot's structural hash,
the backend, the symkin version, the templates and the compiler's sources), so a warm call neither
imports sympy nor re-derives. A robot
without a closed form is cached too (its refusal message), so ``kin.has_analytic_ik`` is cheap.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

from symkin.compiler.compile import OPTIONAL_BACKENDS, Artifact, cache_key, check_backend
from symkin.core.cache import cache_dir, verified
from symkin.errors import NoAnalyticIKError, SymkinError
from symkin.model.robot import Robot

__all__ = ["analytic_key", "build_analytic", "generate_analytic", "analytic_refusal", "NoAnalyticIKError"]


def analytic_key(robot: Robot, backend: str) -> str:
    """The cache key of ``robot``'s closed form on ``backend`` (its ETS and name only)."""
    return cache_key(robot, backend, what="analytic-ik")


def generate_analytic(
    robot: Robot, backend: str = "c", command: str | None = None
) -> tuple[dict[str, str], dict]:
    """The generated files of ``robot``'s closed form for ``backend`` and facts about it
    (``kind``, ``S``). Imports sympy. Raises NoAnalyticIKError when the arm has none."""
    from symkin.emit.analytic_ik import render_analytic
    from symkin.symbolic.analytic_ik import derive_analytic

    check_backend(backend)
    if backend in OPTIONAL_BACKENDS:
        raise SymkinError(
            f"the closed-form IK has no {backend} backend: choose c, numpy or casadi "
            f"({backend}'s IK is the batched differentiable one, symkin.compile(robot, {backend!r}).ik)"
        )
    try:
        plan = derive_analytic(robot)
    except NoAnalyticIKError as exc:
        raise NoAnalyticIKError(f"{robot.name}: {exc}") from None
    command = command or f"symkin compile {robot.identifier} --ik --backend {backend}"
    files = render_analytic(plan, robot, backend, command)
    kind = plan.structure.kind + (f" ({plan.structure.position})" if plan.structure.position else "")
    return files, {"kind": kind, "S": plan.max_solutions}


def _cached(robot: Robot, backend: str, use_cache: bool) -> dict:
    def make() -> dict:
        try:
            files, meta = generate_analytic(robot, backend)
            return {"files": files, "meta": meta, "refused": None}
        except NoAnalyticIKError as exc:
            return {"files": {}, "meta": {}, "refused": str(exc)}

    return verified("gen", analytic_key(robot, backend), make, use_cache)  # the store of compile.cached_files


def analytic_refusal(robot: Robot, backend: str = "c", cache: bool = True) -> str | None:
    """None when ``robot`` has a closed form, else why not (cached; no compile)."""
    return _cached(robot, backend, cache)["refused"]


def build_analytic(robot: Robot, backend: str = "c", cache: bool = True) -> tuple[Artifact, dict]:
    """The built closed form of ``robot`` on ``backend`` and facts about it (``kind``, ``S``).

    ``backend``: ``"c"`` (C behind a CPython extension), ``"numpy"`` (batched NumPy module) or
    ``"casadi"`` (plain Python with ``math``: the closed form needs no CasADi). Raises NoAnalyticIKError
    with the reason when the arm has no closed form.
    """
    data = _cached(robot, backend, cache)
    if data["refused"]:
        raise NoAnalyticIKError(data["refused"])
    files = data["files"]
    if backend != "c":
        from symkin.emit.numpy.backend import load_numpy

        module = load_numpy(files, cache_dir() / "analytic_ik")
        file = getattr(module, "__file__", None)  # none when imported from memory (cache unwritable)
        return Artifact(files, module, Path(file) if file else None), data["meta"]
    import sysconfig

    import numpy as np

    from symkin.emit.c.build import compile_library, load_extension

    name = next(f[:-2] for f in files if f.endswith("_pymodule.c"))
    body = "".join(files[k] for k in sorted(files) if not k.endswith("_pymodule.c"))
    module_name = f"_{name[: -len('_pymodule')]}_{hashlib.sha256(body.encode()).hexdigest()[:12]}"
    flags = (f"-I{sysconfig.get_paths()['include']}", f"-I{np.get_include()}")
    path = compile_library(files, module_name, extra_cflags=flags)
    return Artifact(files, load_extension(module_name, path), path), data["meta"]
