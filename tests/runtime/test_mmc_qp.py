"""The active-set solve of the MMC QP with obstacle rows against OSQP at tight tolerances on random
QPs (a different algorithm on the same problem)."""

from __future__ import annotations

import numpy as np
import pytest

from symkin.runtime.mmc_qp import (
    active_of,
    active_of_osqp,
    active_rows_of,
    active_set_rows_solve,
    mmc_closed_form,
    mmc_qp,
)

osqp = pytest.importorskip("osqp")
sp = pytest.importorskip("scipy.sparse")


def _random_qp(rng: np.random.Generator, n: int = 7, rows: int = 8):
    J = rng.normal(size=(6, n))
    Jm = rng.normal(size=n) * 0.01
    nu = rng.normal(size=6) * 0.2
    lower, upper = -rng.uniform(0.05, 1.0, n), rng.uniform(0.05, 1.0, n)
    Jd = rng.normal(size=(rows, n))
    dl = rng.normal(size=rows) * 0.3
    dl[rng.random(rows) < 0.3] = -np.inf  # free rows
    return J, Jm, nu, lower, upper, Jd, dl


def _osqp_tight(qp):
    P, A = sp.csc_matrix(qp.P), sp.csc_matrix(qp.A)
    l, u = np.maximum(qp.l, -1e30), np.minimum(qp.u, 1e30)
    solver = osqp.OSQP()
    solver.setup(P, qp.c, A, l, u, eps_abs=1e-11, eps_rel=1e-11, max_iter=200_000, verbose=False)
    return solver.solve(raise_error=False)


def test_active_set_with_rows_matches_tight_osqp_on_random_qps():
    rng = np.random.default_rng(0)
    lam, w = 0.005, 1e4
    settled = from_osqp = 0
    for _ in range(120):
        J, Jm, nu, lower, upper, Jd, dl = _random_qp(rng)
        qp = mmc_qp(J, Jm, nu, lower, upper, lam, w, 0.0, Jd, dl)
        ref = _osqp_tight(qp)
        qd0 = mmc_closed_form(J, Jm, nu, lam, w)
        found = active_set_rows_solve(
            J, Jm, nu, lower, upper, lam, w, Jd, dl, active_of(qd0, lower, upper), np.zeros(len(dl), bool)
        )
        if ref.info.status != "solved":  # infeasible rows and bounds: never a settled answer
            assert found is None
            continue
        if found is None:  # from OSQP's active set, as the polish does
            y = ref.y
            act = active_of_osqp(ref.x[:7], y[6:13], lower, upper)
            found = active_set_rows_solve(
                J, Jm, nu, lower, upper, lam, w, Jd, dl, act, active_rows_of(ref.x[:7], Jd, dl, y[13:])
            )
            from_osqp += found is not None
            if found is None:
                continue
        settled += 1
        x = found[0]
        assert np.abs(x[:7] - ref.x[:7]).max() < 1e-6
        assert (x[:7] >= lower).all() and (x[:7] <= upper).all()
        finite = np.isfinite(dl)
        assert (Jd[finite] @ x[:7] >= dl[finite] - 1e-8).all()
        assert np.allclose(x[7:], nu - J @ x[:7], atol=1e-15)
    assert settled >= 90 and from_osqp >= 1
