"""Compiled tree kinematics: what :func:`symkin.compile` returns for a :class:`symkin.Tree` (no sympy).

It has the numeric reference's methods and shapes: ``fkine``, ``jacob0``, ``jacobe`` and
``fkine_jacob0`` of one frame (``frame=name``), ``fkine_all`` (F, 4, 4), ``jacob0_all`` (F, 6, n)
and ``fkine_jacob0_all`` for every frame in ``tree.frames`` order, each with a leading (N,) axis
for a batch. On the C backend the methods are the extension module's functions themselves.
:meth:`TreeKinematics.select` gives one frame as chain kinematics for IK, servo and MMC.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from symkin.compiler.compile import Artifact, build, cache_key
from symkin.runtime.casadi_calls import tree_functions
from symkin.runtime.compiled import CompiledModel
from symkin.runtime.memo import memoised

__all__ = ["TreeKinematics", "TREE_METHODS", "load_tree", "tree_kinematics_of"]

TREE_METHODS = ("fkine", "jacob0", "jacobe", "fkine_jacob0", "fkine_all", "jacob0_all", "fkine_jacob0_all")


def _rebuild(tree: Any, backend: str) -> TreeKinematics:
    """The compiled kinematics of ``tree`` on ``backend`` (the unpickler of :class:`TreeKinematics`)."""
    return load_tree(tree, backend)


def load_tree(tree: Any, backend: str = "c", cache: bool = True) -> TreeKinematics:
    """Every frame of ``tree`` in one kernel on ``backend``. The generated code depends on the
    structure only (the cache key); the object also carries the limits, speeds and source a
    controller reads, so trees that differ there get their own object."""
    key = cache_key(tree, backend)
    memo_key = (key, tree.qlim.tobytes(), np.asarray(tree.velocity).tobytes(), tree.source)
    return memoised(
        memo_key, lambda: tree_kinematics_of(tree, build(tree, backend, cache, key=key), backend), cache
    )


def tree_kinematics_of(tree: Any, art: Artifact, backend: str) -> TreeKinematics:
    """The :class:`TreeKinematics` of ``tree`` around its built code ``art``."""
    if backend == "casadi":
        fns = art.module.functions()
        functions = tree_functions(tree, fns, TREE_METHODS)
        kin = TreeKinematics(tree, backend, functions, art.files, art.path, art.module)
        kin.functions = fns  # type: ignore[attr-defined]
        return kin
    functions = {name: getattr(art.module, name) for name in TREE_METHODS}
    return TreeKinematics(tree, backend, functions, art.files, art.path, art.module)


class TreeKinematics(CompiledModel):
    """Generated kinematics of a tree on one backend ("c", "numpy" or "casadi").

    Attributes: ``tree``, ``backend``, ``n``, ``frames``, ``joint_names``, ``qlim``, ``qd_max``,
    ``name``, ``files`` (the generated sources), ``path`` (library or module), ``module``.
    """

    _symkin_tree = True  # marks trees for symkin.ik, servo and MMC

    fkine: Callable[..., np.ndarray]
    jacob0: Callable[..., np.ndarray]
    jacobe: Callable[..., np.ndarray]
    fkine_jacob0: Callable[..., tuple[np.ndarray, np.ndarray]]
    fkine_all: Callable[[Any], np.ndarray]
    jacob0_all: Callable[[Any], np.ndarray]
    fkine_jacob0_all: Callable[[Any], tuple[np.ndarray, np.ndarray]]

    METHODS = TREE_METHODS

    def _setup(self, functions: dict[str, Callable[..., Any]]) -> None:
        self.tree = self.model
        if self.backend == "c":
            self.c_fkjac_of = self._c_fkjac_of

    @property
    def frames(self) -> tuple[str, ...]:
        return self.tree.frames

    def __repr__(self) -> str:
        frames = list(self.frames)
        return f"TreeKinematics(tree={self.name!r}, n={self.n}, frames={frames}, backend={self.backend!r})"

    def __reduce__(self) -> tuple[Any, tuple[Any, str]]:
        """Pickle as (tree, backend): unpickling compiles again, which loads the generated code from
        the compile cache of the process that unpickles (a Dask worker, say) when it is there."""
        return (_rebuild, (self.tree, self.backend))

    def select(self, frame: Any = None) -> Any:
        """Frame ``frame`` as chain kinematics of all n joints (:class:`symkin.model.frame_view.FrameView`),
        for :func:`symkin.ik`, :func:`symkin.servo` and :class:`symkin.MMC`."""
        from symkin.model.frame_view import frame_view

        return frame_view(self.tree, self, frame)

    def hessian0(self, q: Any, frame: Any = None) -> np.ndarray:
        """Base-frame Hessian of ``frame``, (n, 6, n) or (N, n, 6, n) (see :meth:`symkin.Tree.hessian0`)."""
        return self.select(frame).hessian0(q)

    def jacob0_hessian0(self, q: Any, frame: Any = None) -> tuple[np.ndarray, np.ndarray]:
        """Base-frame Jacobian and Hessian of ``frame`` (generated on the C backend for a frame
        without mimic joints on its path)."""
        return self.select(frame).jacob0_hessian0(q)

    def manipulability(self, q: Any, frame: Any = None, axes: str = "all") -> np.ndarray | float:
        """Yoshikawa manipulability of ``frame`` (the chosen rows of its J0, Part 1 eq 52):
        float, or (N,) for a batch."""
        return self.select(frame).manipulability(q, axes)

    def jacobm(self, q: Any, frame: Any = None, axes: str = "all") -> np.ndarray:
        """Manipulability Jacobian of ``frame`` (Haviland and Corke, 2020, eq 11): (n,) or (N, n)."""
        return self.select(frame).jacobm(q, axes)

    def ik(self, Tep: Any, frame: Any = None, **kwargs: Any) -> Any:
        """Numerical IK of one frame (the other joints are free): see :func:`symkin.runtime.ik.ik`."""
        return self.select(frame).ik(Tep, **kwargs)

    def c_controller_functions(self, frame: str) -> dict[str, Any] | None:
        """The C functions the C controllers (MMC, RRMC, the servo loop) call for ``frame``, as
        ctypes functions (``jacob0_hessian0``, ``jacob0``, ``fkine``, ``manipulability``), or None
        when the backend is not C or a mimic joint is on the frame's path (its H is then not
        generated; the controllers run in Python)."""
        if self.backend != "c":
            return None
        from symkin.emit.c.build import load_library

        k = self.tree.frame_position(frame)
        lib, prefix = load_library(self.path), self.c_prefix
        try:
            return {
                name: getattr(lib, f"{prefix}_{name}_{k}")
                for name in ("jacob0_hessian0", "jacob0", "fkine", "manipulability")
            }
        except AttributeError:  # a mimic joint on the path
            return None

    def _c_fkjac_of(self, frame: str) -> Any:
        """The C entry point ``fkine_jacob0`` of ``frame`` as a ctypes function (C backend)."""
        from symkin.emit.c.build import load_library

        k = self.tree.frame_position(frame)
        self._lib = load_library(self.path)
        return getattr(self._lib, f"{self.c_prefix}_fkine_jacob0_{k}")
