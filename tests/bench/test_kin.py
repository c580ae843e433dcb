"""``symkin bench kin``: every path and batch row on a small robot, the kernels' rows included."""

from __future__ import annotations

import math

from symkin.bench.kin import BLOCK, format_kin, run_kin


def test_bench_kin_reports_every_row():
    r = run_kin("planar2", batch=2 * BLOCK + 3, progress=False)
    rows = r["batched_M_per_s"]
    assert set(rows) == {
        "c",
        "numpy",
        "c kernels, 4 lanes",
        f"4 lanes, {BLOCK} per call",
        "c kernels, scalar",
    }
    for row in rows.values():
        assert set(row) == {"fkine", "jacob0", "fkine_jacob0", "hessian0"}
        assert all(math.isfinite(v) and v > 0 for v in row.values())
    for path, row in r["per_call_us"].items():
        assert all(math.isfinite(v) and v > 0 for v in row.values()), path
    text = format_kin(r)
    assert f"4 lanes, {BLOCK} per call" in text and "4 lanes vs scalar" in text
