"""``symkin check`` of a tree: every backend's tree kernel against two independent references.

Per backend: ``fkine_all``, ``jacob0_all``, ``fkine_jacob0_all`` and the per-frame ``fkine``,
``jacob0``, ``jacobe``, ``hessian0``, ``manipulability`` (and on C the functions the C controllers
call) against the numeric reference :class:`symkin.Tree`, and the Jacobians
against central differences of the backend's own poses; for the reference itself, each frame
against the serial chain :class:`symkin.Robot` to that frame (frames without mimic joints on
their path). Random configurations within limits, zero and points 1e-5 from zero.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from symkin.check.chain import FD_STEP, CheckReport, CheckRow, _rel, _shifted, _vee_rate
from symkin.model.tree import Tree

__all__ = ["check_tree", "tree_configurations"]


def tree_configurations(tree: Tree, n: int, seed: int = 0) -> np.ndarray:
    rng = np.random.default_rng(seed)
    zero = np.zeros((1, tree.n))
    return np.vstack((tree.random_q(n, seed=rng), zero, zero + rng.normal(scale=1e-5, size=zero.shape)))


def _fd_jacobians(fkine_all, Q: np.ndarray, T: np.ndarray, h: float) -> np.ndarray:  # noqa: ANN001
    """(N, F, 6, n) base-frame Jacobians of every frame from central differences of the poses."""
    plus, minus = _shifted(fkine_all, Q, h)  # (N, n, F, 4, 4)
    rate = _vee_rate(plus, minus, T[:, None], h)  # (N, n, F, 6)
    return np.transpose(rate, (0, 2, 3, 1))


def _c_controller_rows(tree: Tree, kin: object, Q: np.ndarray) -> list[CheckRow]:
    """The C functions the C controllers call (per frame without mimic joints on its path:
    ``jacob0_hessian0_<k>``, ``manipulability_<k>``) against the reference, through ctypes."""
    import ctypes

    P = ctypes.POINTER(ctypes.c_double)
    n, e_H, e_m, seen = tree.n, 0.0, 0.0, False
    for f in tree.frames:
        fns = kin.c_controller_functions(f)  # type: ignore[attr-defined]
        if fns is None:
            continue
        seen = True
        jh, manip = fns["jacob0_hessian0"], fns["manipulability"]
        jh.argtypes, jh.restype = [P, P, P], None
        manip.argtypes, manip.restype = [P, ctypes.c_int], ctypes.c_double
        H_ref = tree.hessian0(Q, f)
        for axes, code in (("all", 0), ("trans", 1), ("rot", 2)):
            m_ref = tree.manipulability(Q, f, axes)
            m = [manip(np.ascontiguousarray(q).ctypes.data_as(P), code) for q in Q]
            e_m = max(e_m, _rel(np.array(m), m_ref))
        for i, q in enumerate(np.ascontiguousarray(Q)):
            J, H = np.zeros(6 * n), np.zeros(n * 6 * n)
            jh(q.ctypes.data_as(P), J.ctypes.data_as(P), H.ctypes.data_as(P))
            e_H = max(e_H, _rel(H.reshape(n, 6, n), H_ref[i]))
    if not seen:
        return []
    return [
        CheckRow("c", "C jacob0_hessian0_<k>", e_H, None),
        CheckRow("c", "C manipulability_<k>", e_m, None),
    ]


def check_tree(
    tree: Tree, backends: Sequence[str] = ("c", "numpy", "casadi"), samples: int = 20, seed: int = 0
) -> CheckReport:
    """Compare every function of every backend's tree kernel with the references (module docstring)."""
    from symkin.errors import URDFError
    from symkin.runtime.load import compile as compile_model

    Q = tree_configurations(tree, samples, seed)
    h = FD_STEP
    T_ref, J_ref = tree.fkine_jacob0_all(Q)
    rows: list[CheckRow] = []
    for f in tree.frames:  # the reference against the serial chain of each frame
        try:
            robot = tree.chain(f)
        except URDFError:
            continue  # a mimic joint on the path: no chain Robot
        cols = [tree.slots[k].joint for k in tree.path_slots(f)]
        k = tree.frame_position(f)
        err = max(
            _rel(T_ref[:, k], robot.fkine(Q[:, cols])), _rel(J_ref[:, k][..., cols], robot.jacob0(Q[:, cols]))
        )
        rows.append(CheckRow("ref", f"chain:{f}"[:40], err, None))
    fd_ref = _fd_jacobians(tree.fkine_all, Q, T_ref, h)
    rows.append(CheckRow("ref", "jacob0_all", 0.0, _rel(fd_ref, J_ref)))
    for backend in backends:
        kin = compile_model(tree, backend=backend)
        T, J = kin.fkine_all(Q), kin.jacob0_all(Q)
        rows.append(CheckRow(backend, "fkine_all", _rel(T, T_ref), None))
        rows.append(
            CheckRow(backend, "jacob0_all", _rel(J, J_ref), _rel(_fd_jacobians(kin.fkine_all, Q, T, h), J))
        )
        T2, J2 = kin.fkine_jacob0_all(Q)
        rows.append(CheckRow(backend, "fkine_jacob0_all", max(_rel(T2, T_ref), _rel(J2, J_ref)), None))
        e_T = e_J = e_Je = 0.0
        for f in tree.frames:
            e_T = max(e_T, _rel(kin.fkine(Q, frame=f), tree.fkine(Q, f)))
            e_J = max(e_J, _rel(kin.jacob0(Q, frame=f), tree.jacob0(Q, f)))
            e_Je = max(e_Je, _rel(kin.jacobe(Q, frame=f), tree.jacobe(Q, f)))
            Tf, Jf = kin.fkine_jacob0(Q, frame=f)
            e_J = max(e_J, _rel(Jf, tree.jacob0(Q, f)), _rel(Tf, tree.fkine(Q, f)))
        rows.append(CheckRow(backend, "fkine(frame)", e_T, None))
        rows.append(CheckRow(backend, "jacob0(frame)", e_J, None))
        rows.append(CheckRow(backend, "jacobe(frame)", e_Je, None))
        e_H = e_m = 0.0
        for f in tree.frames:
            e_H = max(e_H, _rel(kin.hessian0(Q, frame=f), tree.hessian0(Q, f)))
            e_m = max(e_m, _rel(kin.manipulability(Q, frame=f), tree.manipulability(Q, f)))
        rows.append(CheckRow(backend, "hessian0(frame)", e_H, None))
        rows.append(CheckRow(backend, "manipulability(frame)", e_m, None))
        if backend == "c":
            rows.extend(_c_controller_rows(tree, kin, Q))
    return CheckReport(f"{tree.name} ({len(tree.frames)} frames)", len(Q), tuple(rows))
