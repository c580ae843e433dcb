"""``symkin bench calls``: it runs every section on a small problem and reports every goal."""

from __future__ import annotations

import json
import math

from symkin.bench.calls import GOALS, format_calls, run_calls


def test_bench_calls_runs_small_and_reports_every_goal():
    r = run_calls(
        "ur5", "ur5", n_targets=12, n_tasks=3, rounds=1, startup_runs=1, progress=False, budget=0.005
    )
    json.dumps(r)  # JSON-able
    assert set(r["checks"]) == set(GOALS)
    for key, check in r["checks"].items():
        v = check["value"]
        assert v is None or (math.isfinite(v) and v > 0), key
        assert check["met"] in (True, False, None)
    assert r["ik"]["single_success"] == 1.0 and r["ik"]["batch_success"] == 1.0
    assert set(r["pinv"]) == {"LM", "NR pinv", "GN pinv"}
    loops = r["control"]["servo_steps_per_s"]
    assert loops["rrmc"]["c_steps"] > 0 and loops["mmc"]["python_steps"] > 0
    text = format_calls(r)
    assert "Goals (targets for one call at a time)" in text and "import symkin" in text
