"""``symkin bench calls``: it runs every section on a small problem and reports every goal."""

from __future__ import annotations

import copy
import importlib.util
import json
import math
import re

import pytest

from symkin.bench.calls import GOALS, format_calls, run_calls

# the optional package a goal's comparison needs: without it the figure is None ("n/a")
OPTIONAL = {"ik_rtb_over_single": "roboticstoolbox"} | {
    f"numpy_over_pinocchio_{f}": "pinocchio" for f in ("fkine", "jacob0", "manipulability")
}


def _installed(package: str) -> bool:
    return importlib.util.find_spec(package) is not None


@pytest.fixture(scope="module")
def report() -> dict:
    return run_calls(
        "ur5", "ur5", n_targets=12, n_tasks=3, rounds=1, startup_runs=1, progress=False, budget=0.005
    )


def _times(r: dict) -> dict[str, float]:
    """Every time (us or s) and rate (steps per s) the report measured, by where it is."""
    ik, pinv, ctl, st = r["ik"], r["pinv"], r["control"], r["startup"]
    out = {"ik.batch_us": ik["batch_us"], "ik.single_us": ik["single_us"], "ik.scalar": ik["scalar_batch_us"]}
    parts = ik["parts_ns"]
    out |= {f"ik.parts_ns.{k}": v for k, v in parts.items() if k != "rest_per_iteration"}
    if ik["rtb"] and "us" in ik["rtb"]:
        out["ik.rtb.us"] = ik["rtb"]["us"]
    for label, row in pinv.items():
        out[f"pinv.{label}.batch"] = row["batch_us_per_iteration"]
        out[f"pinv.{label}.single"] = row["single_us_per_iteration"]
    out |= {f"control.step_us.{k}": v for k, v in ctl["step_us"].items()}
    for name, row in ctl["servo_steps_per_s"].items():
        out[f"control.servo.{name}.c"], out[f"control.servo.{name}.python"] = row["c"], row["python"]
    for section in ("numpy", "casadi"):
        out |= {f"{section}.{k}.{c}": v for k, row in r[section].items() for c, v in row.items()}
    out |= {f"startup.{k}.{m}": v for k, row in st.items() for m, v in row.items()}
    return out


def _expected_figures(r: dict) -> dict[str, float | None]:
    """Each goal's figure from the reported times: the quotient of the two times it compares, or
    the time itself."""
    ik, pinv, ctl, npy, cas, st = (r[k] for k in ("ik", "pinv", "control", "numpy", "casadi", "startup"))
    rtb, pin = ik["rtb"], npy.get("pinocchio")
    per_it = {label: row["single_us_per_iteration"] for label, row in pinv.items()}
    out = {
        "ik_single_over_scalar_batch": ik["single_us"] / ik["scalar_batch_us"],
        "ik_rtb_over_single": rtb["us"] / ik["single_us"] if rtb and "us" in rtb else None,
        "pinv_nr_over_lm_per_iteration": per_it["NR pinv"] / per_it["LM"],
        "pinv_gn_over_lm_per_iteration": per_it["GN pinv"] / per_it["LM"],
        "rrmc_step_us": ctl["step_us"]["rrmc (C)"],
        "servo_rrmc_steps_per_s": ctl["servo_steps_per_s"]["rrmc"]["c"],
        "servo_mmc_steps_per_s": ctl["servo_steps_per_s"]["mmc"]["c"],
        "import_s": st["import_s"]["min"],
        "first_jacob0_s": st["first_jacob0_s"]["min"],
    }
    for f in ("fkine", "jacob0", "manipulability"):
        out[f"numpy_over_pinocchio_{f}"] = npy["numpy"][f] / pin[f] if pin else None
        out[f"casadi_over_raw_{f}"] = cas[f]["backend"] / cas[f]["raw"]
    out["casadi_over_raw_hessian0"] = cas["hessian0"]["backend"] / cas["hessian0"]["raw"]
    return out


def check_report(r: dict) -> None:
    """The report's figures are positive finite times, each goal's figure is the quotient of the
    times it compares (None only when its optional package is missing) and its verdict the
    figure against the goal; the text shows every goal with its figure and verdict."""
    json.dumps(r)  # JSON-able
    assert set(r["checks"]) == set(GOALS)
    for where, t in _times(r).items():
        assert isinstance(t, float) and math.isfinite(t) and t > 0, (where, t)
    for row in r["startup"].values():
        assert row["min"] <= row["median"]
    assert (r["ik"]["rtb"] is not None) == _installed("roboticstoolbox")
    assert ("pinocchio" in r["numpy"]) == _installed("pinocchio")
    expected = _expected_figures(r)
    for key, (op, bar) in GOALS.items():
        check, want = r["checks"][key], expected[key]
        assert check["goal"] == f"{op} {bar:g}", key
        if want is None:
            assert key in OPTIONAL and check["value"] is None and check["met"] is None, key
            continue
        assert check["value"] == pytest.approx(want, rel=1e-12), key
        assert check["met"] == (want <= bar if op == "<=" else want >= bar), key
    text = format_calls(r)
    goals = text[text.index("Goals (targets for one call at a time):") :]
    for key, check in r["checks"].items():
        line = re.search(rf"^  {key} +(\S+) +goal +(\S+ \S+) +(\S+)$", goals, re.M)
        assert line, key
        assert line[2] == check["goal"], key
        assert line[3] == {None: "n/a", True: "met", False: "MISSED"}[check["met"]], key
        v = check["value"]
        if v is None:
            assert line[1] == "n/a", key
        else:  # three significant digits, or a whole number from 1000 on
            assert abs(float(line[1]) - v) <= (0.5 if v >= 1000 else 5e-3 * v), (key, line[1], v)


def test_bench_calls_runs_small_and_reports_every_goal(report):
    check_report(report)
    ik = report["ik"]
    assert ik["single_success"] == ik["batch_success"] == ik["scalar_batch_success"] == 1.0
    parts = ik["parts_ns"]  # the solver's time is its iterations' (kinematics and the rest)
    assert parts["kinematics_per_iteration"] + parts["rest_per_iteration"] == pytest.approx(
        parts["solver"] / parts["iterations_per_call"], rel=1e-9
    )
    assert "one call (ns): arguments" in format_calls(report)
    assert set(report["pinv"]) == {"LM", "NR pinv", "GN pinv"}
    for loops in report["control"]["servo_steps_per_s"].values():
        assert loops["c_steps"] > 0 and loops["python_steps"] > 0
    assert "import symkin" in format_calls(report)


def _corrupt(r: dict, how: str) -> dict:
    r = copy.deepcopy(r)
    checks = r["checks"]
    if how == "ratio inverted":
        checks["ik_single_over_scalar_batch"]["value"] = r["ik"]["scalar_batch_us"] / r["ik"]["single_us"]
    elif how == "ratio of other times":
        checks["casadi_over_raw_jacob0"]["value"] = (
            r["casadi"]["fkine"]["backend"] / r["casadi"]["fkine"]["raw"]
        )
    elif how == "verdict flipped":
        checks["rrmc_step_us"]["met"] = not checks["rrmc_step_us"]["met"]
    elif how == "figure missing":
        checks["import_s"] |= {"value": None, "met": None}
    elif how == "negative time":
        r["control"]["step_us"]["MMC.step (C)"] = -1.0
    elif how == "nan time":
        r["pinv"]["GN pinv"]["batch_us_per_iteration"] = math.nan
    elif how == "zero rate":
        r["control"]["servo_steps_per_s"]["mmc"]["python"] = 0.0
    elif how == "section empty":
        r["casadi"] = {}
    return r


@pytest.mark.parametrize(
    "how",
    ["ratio inverted", "ratio of other times", "verdict flipped", "figure missing", "negative time",
     "nan time", "zero rate", "section empty"],
)  # fmt: skip
def test_a_wrong_report_is_caught(report, how):
    """check_report catches a report whose figures do not follow from its times."""
    with pytest.raises((AssertionError, KeyError)):
        check_report(_corrupt(report, how))
