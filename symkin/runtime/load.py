"""``symkin.compile`` and ``symkin.load_compiled``: a model, or a folder of generated code, ->
the runtime's kinematics object, through the compiler (:mod:`symkin.compiler.compile`)."""

from __future__ import annotations

from pathlib import Path

from symkin.compiler.compile import Artifact, check_backend, check_strategy, load_artifact
from symkin.compiler.manifest import import_module_file, read_manifest
from symkin.model.resolve import resolve_robot
from symkin.model.robot import Robot
from symkin.model.tree import Tree, as_tree
from symkin.runtime.kinematics import Kinematics, kinematics_of, load_kinematics

__all__ = ["compile", "load_compiled"]


def compile(  # noqa: A001
    robot: Robot | Tree | str, backend: str = "c", cache: bool = True, strategy: str | None = None
) -> Kinematics:
    """Compile ``robot`` (a Robot, a built-in name or ETS text) into a :class:`Kinematics`, or a
    :class:`symkin.Tree` into one kernel for all its frames (the same class, with ``frame=name``).

    ``backend`` is ``"c"`` (a generated C library behind a CPython extension, the fast path),
    ``"numpy"`` (a generated Python module, batched) or ``"casadi"`` (``casadi.Function`` objects,
    for optimisation problems). Every backend has the numeric reference's methods and shapes.
    ``strategy`` chooses how the code is derived (see :func:`symkin.generate`; default by size).
    With ``cache`` the generated code comes from the compile cache and the object from a bounded
    in-process memo when they are there.
    """
    check_backend(backend)
    if isinstance(robot, str):
        robot = resolve_robot(robot)
    as_tree(robot)  # TypeError for what is not a model
    check_strategy(strategy, robot)
    return load_kinematics(robot, backend, cache, strategy)


def load_compiled(folder: str | Path, name: str | None = None, verify: bool = True) -> Kinematics:
    """The :class:`symkin.Kinematics` of the generated code of a chain or a tree in ``folder``
    (``symkin compile -o DIR`` or :func:`symkin.write_generated`), as :func:`compile` gives it.

    C: the ``.c``/``.h`` files are compiled (cached by content, needs a C compiler) and their
    extension module imported; NumPy and CasADi: the module in the folder is imported. ``name``
    picks one robot when the folder holds several (the prefix, the robot or tree name, or the
    manifest's stem). With ``verify`` a file whose sha256 differs from the manifest's (edited since
    it was written) raises CompileError; ``verify=False`` loads edited files as they are.
    """
    m = read_manifest(folder, name, verify)
    if m.backend == "c":
        art = load_artifact(m.files, "c")
    else:
        (pyname,) = [f for f in m.files if f.endswith(".py")]
        if m.backend == "numpy":
            module = import_module_file(m.folder / pyname, m.files[pyname])
            art = Artifact(m.files, module, m.folder / pyname)
        else:
            art = load_artifact({pyname: m.files[pyname]}, "casadi")
    return kinematics_of(m.robot, art, m.backend)
