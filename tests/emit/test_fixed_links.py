"""Fixed joints with rpy offsets and long chains of fixed links through the compiler.

A 6-joint arm with 4 fixed joints of rpy ``0.1 0.2 0.3`` after it once took minutes to compile
and one with 2000 fixed links never finished: the strategy choice built the exact expanded form
first, constant rotations stayed exact cos/sin of rationals, and ``floatify`` evaluated shared
numeric subtrees again at every use. Each compile runs in a child process whose timeout is a
guard against a hang only; what is asserted is the result against the numeric reference.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
GUARD_S = 300  # generous: the whole child takes a few tens of seconds on a busy machine

CHILD = textwrap.dedent(
    """
    import json, sys
    import numpy as np
    import symkin
    from symkin.bench.urdf_sweep import synthetic_urdfs

    urdfs = synthetic_urdfs()
    out = []
    for name, backends, tree in json.loads(sys.argv[1]):
        model = (symkin.Tree if tree else symkin.Robot).from_urdf(urdfs[name])
        Q = model.random_q(5, seed=3)
        for backend in backends:
            kin = symkin.compile(model, backend)
            if tree:
                f = model.frames[0]
                pairs = [(getattr(kin, m)(Q, frame=f), getattr(model, m)(Q, f))
                         for m in ("fkine", "jacob0", "jacobe")]
            else:
                pairs = [(getattr(kin, m)(Q), getattr(model, m)(Q))
                         for m in ("fkine", "link_poses", "jacob0", "jacobe", "hessian0", "hessiane")]
                pairs.append((kin.fkine(Q[0]), model.fkine(Q[0])))
            err = max(float(np.abs(a - b).max()) for a, b in pairs)
            out.append([name, backend, tree, err])
    print(json.dumps(out))
    """
)


def run_child(cases: list[tuple[str, list[str], bool]], tmp_path: Path) -> list:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "SYMKIN_CACHE": str(tmp_path / "cache")}
    res = subprocess.run(
        [sys.executable, "-c", CHILD, json.dumps(cases)],
        capture_output=True, text=True, env=env, cwd=ROOT, timeout=GUARD_S,
    )  # fmt: skip
    assert res.returncode == 0, res.stderr[-3000:]
    return json.loads(res.stdout.strip().splitlines()[-1])


def test_arm_with_fixed_rpy_tails_compiles_and_matches_the_reference(tmp_path):
    cases = [(f"arm6_fixed{k}.urdf", ["numpy"], False) for k in (2, 3, 4)]
    cases.append(("arm6_fixed2000.urdf", ["numpy", "c", "casadi"], False))
    results = run_child(cases, tmp_path)
    assert [(r[0], r[1]) for r in results] == [(name, b) for name, bs, _ in cases for b in bs]
    for name, backend, _, err in results:
        assert err < 1e-10, (name, backend, err)


@pytest.mark.parametrize("name", ["fixed2000_arm6.urdf", "arm6_fixed300_between.urdf"])
def test_fixed_links_before_and_between_the_joints(name, tmp_path):
    (result,) = run_child([(name, ["numpy"], False)], tmp_path)
    assert result[3] < 1e-10, result


def test_tree_with_2000_fixed_links_compiles_and_matches_the_reference(tmp_path):
    cases = [
        ("arm6_fixed2000.urdf", ["numpy", "c"], True),
        ("arm6_fixed2000_quarter_turns.urdf", ["numpy"], True),
    ]
    for name, backend, tree, err in run_child(cases, tmp_path):
        assert tree and err < 1e-10, (name, backend, err)


def test_floatify_evaluates_each_shared_numeric_subexpression_once(tmp_path):
    """x_{k+1} = sin(x_k^2 + x_k), 40 levels: about 2^40 nodes as a tree, 120 distinct."""
    code = textwrap.dedent(
        """
        import mpmath, sympy as sp
        from symkin.symbolic.cse import floatify
        e, x = sp.cos(sp.Rational(1, 3)), mpmath.cos(mpmath.mpf(1) / 3)
        for _ in range(40):
            e = sp.sin(sp.Add(sp.Mul(e, e, evaluate=False), e, evaluate=False), evaluate=False)
            x = mpmath.sin(x * x + x)
        print(repr(float(floatify(e))), repr(float(x)))
        """
    )
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    res = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=GUARD_S
    )
    assert res.returncode == 0, res.stderr[-2000:]
    got, expected = res.stdout.split()
    assert got == expected
