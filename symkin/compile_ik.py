"""``compile_analytic``: robot -> closed-form IK derivation -> generated code -> :class:`AnalyticIK`.

Cached like the kinematics (``$SYMKIN_CACHE/gen/ik-<key>.json``): the key covers the robot's
structural hash, the backend, the symkin version, the analytic-IK templates and the source of the
derivation and emitter modules, so a warm call neither imports sympy nor re-derives. A robot
without a closed form is cached too (its refusal message), so ``kin.has_analytic_ik`` is cheap.
"""

from __future__ import annotations

import hashlib
import json
import os
from functools import lru_cache
from pathlib import Path
from typing import Any

from symkin.emit.c.build import cache_dir
from symkin.errors import NoAnalyticIKError, SymkinError
from symkin.model.robot import Robot

__all__ = ["compile_analytic", "generate_analytic", "analytic_refusal", "NoAnalyticIKError"]

_TEMPLATES = (
    "c/analytic_ik.c.j2",
    "c/analytic_ik.h.j2",
    "c/analytic_ik_module.c.j2",
    "numpy/analytic_ik.py.j2",
    "python/analytic_ik.py.j2",
)
_SOURCES = (
    "symbolic/ik_geometry.py",
    "symbolic/analytic_ik.py",
    "emit/analytic_ik.py",
    "emit/analytic_ik_c.py",
)
_LOADED: dict[str, Any] = {}


@lru_cache(maxsize=1)
def _digest() -> str:
    from symkin.emit.templates import template_dir

    h = hashlib.sha256()
    root = template_dir()
    for name in _TEMPLATES:
        h.update(name.encode())
        h.update((root / name).read_bytes())
    pkg = Path(__file__).resolve().parent
    for name in _SOURCES:
        h.update((pkg / name).read_bytes())
    return h.hexdigest()


def _key(robot: Robot, backend: str) -> str:
    from symkin import __version__

    text = "\n".join(("analytic-ik", __version__, backend, robot.key, _digest()))
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def generate_analytic(
    robot: Robot, backend: str = "c", command: str | None = None
) -> tuple[dict[str, str], dict]:
    """The generated files of ``robot``'s closed form for ``backend`` and facts about it
    (``kind``, ``S``). Imports sympy. Raises NoAnalyticIKError when the arm has none."""
    from symkin.emit.analytic_ik import render_analytic
    from symkin.symbolic.analytic_ik import derive_analytic

    if backend not in ("c", "numpy", "casadi"):
        raise SymkinError(f"unknown backend {backend!r}: choose one of c, numpy, casadi")
    try:
        plan = derive_analytic(robot)
    except NoAnalyticIKError as exc:
        raise NoAnalyticIKError(f"{robot.name}: {exc}") from None
    command = command or f"symkin compile {robot.identifier} --ik --backend {backend}"
    files = render_analytic(plan, robot, backend, command)
    kind = plan.structure.kind + (f" ({plan.structure.position})" if plan.structure.position else "")
    return files, {"kind": kind, "S": plan.max_solutions}


def _cached(robot: Robot, backend: str, use_cache: bool) -> dict:
    key = _key(robot, backend)
    path = cache_dir() / "gen" / f"ik-{key}.json"
    if use_cache and path.exists():
        try:
            data = json.loads(path.read_text())
            body = json.dumps({k: data[k] for k in ("files", "meta", "refused")}, sort_keys=True)
            if data.get("sha256") == hashlib.sha256(body.encode()).hexdigest():
                return data
        except (OSError, ValueError, KeyError, TypeError):
            pass
    try:
        files, meta = generate_analytic(robot, backend)
        data = {"files": files, "meta": meta, "refused": None}
    except NoAnalyticIKError as exc:
        data = {"files": {}, "meta": {}, "refused": str(exc)}
    if use_cache:
        body = json.dumps(data, sort_keys=True)
        data["sha256"] = hashlib.sha256(body.encode()).hexdigest()
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_text(json.dumps(data))
            os.replace(tmp, path)
        except OSError:
            pass
    return data


def analytic_refusal(robot: Robot, backend: str = "c", cache: bool = True) -> str | None:
    """None when ``robot`` has a closed form, else why not (cached; no compile)."""
    return _cached(robot, backend, cache)["refused"]


def compile_analytic(robot: Robot | str, backend: str = "c", cache: bool = True) -> Any:
    """The closed-form solver (:class:`symkin.runtime.analytic_ik.AnalyticIK`) of ``robot``.

    ``backend``: ``"c"`` (C behind a CPython extension), ``"numpy"`` (batched NumPy module) or
    ``"casadi"`` (plain Python with ``math``: the closed form needs no CasADi). Raises NoAnalyticIKError
    with the reason when the arm has no closed form.
    """
    from symkin.runtime.analytic_ik import AnalyticIK

    if isinstance(robot, str):
        from symkin.model.resolve import resolve_robot

        robot = resolve_robot(robot)
    key = _key(robot, backend)
    if cache and key in _LOADED:
        return _LOADED[key]
    data = _cached(robot, backend, cache)
    if data["refused"]:
        raise NoAnalyticIKError(data["refused"])
    files = data["files"]
    if backend == "c":
        import sysconfig

        import numpy as np

        from symkin.emit.c.backend import load_extension
        from symkin.emit.c.build import compile_library

        name = next(f[:-2] for f in files if f.endswith("_pymodule.c"))
        module_name = (
            "_"
            + name[: -len("_pymodule")]
            + "_"
            + hashlib.sha256(
                "".join(files[k] for k in sorted(files) if not k.endswith("_pymodule.c")).encode()
            ).hexdigest()[:12]
        )
        flags = (f"-I{sysconfig.get_paths()['include']}", f"-I{np.get_include()}")
        path = compile_library(files, module_name, extra_cflags=flags)
        module = load_extension(module_name, path)
    else:
        from symkin.emit.numpy.backend import load_numpy

        module = load_numpy(files, cache_dir() / "analytic_ik")
    solver = AnalyticIK(robot, backend, module, files, data["meta"]["kind"], data["meta"]["S"])
    if cache:
        _LOADED[key] = solver
    return solver
