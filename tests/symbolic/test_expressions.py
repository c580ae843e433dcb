"""symkin.symbolic(robot): the public sympy expressions, checked against the numeric reference."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest
import sympy as sp

import symkin
from symkin.errors import SymkinError
from tests.conftest import assert_close


def test_expanded_expressions_evaluate_to_the_reference() -> None:
    robot = symkin.load("ur5")
    k = symkin.symbolic(robot)
    assert len(k.q) == 6 and all(s.is_real for s in k.q)
    assert k.T.shape == (4, 4) and k.J0.shape == (6, 6) and k.Je.shape == (6, 6)
    assert len(k.H0) == 6 and len(k.He) == 6
    f = sp.lambdify(k.q, [k.T, k.J0, k.Je, *k.H0, *k.He], "numpy")
    for q in robot.random_q(3, seed=0):
        T, J0, Je, *H = f(*q)
        assert_close(T, robot.fkine(q), 1e-12, "T")
        assert_close(J0, robot.jacob0(q), 1e-12, "J0")
        assert_close(Je, robot.jacobe(q), 1e-12, "Je")
        assert_close(np.array(H[:6], dtype=float), robot.hessian0(q), 1e-12, "H0")
        assert_close(np.array(H[6:], dtype=float), robot.hessiane(q), 1e-12, "He")


def test_constants_stay_exact_and_sums_merge() -> None:
    k = symkin.symbolic("planar2")
    q0, q1 = k.q
    assert k.T[0, 3] == sp.cos(q0) + sp.cos(q0 + q1)
    panda = symkin.symbolic("panda")
    assert sp.Rational(333, 1000) in panda.T[2, 3].atoms(sp.Rational) or panda.T[2, 3].has(
        sp.Rational(333, 1000)
    )


def test_program_form_is_linear_and_expands_to_the_same() -> None:
    robot = symkin.Robot.from_ets("Rz(q) tx(0.4) Ry(q) tz(0.3) Rx(q) tx(0.2) Rz(q) tz(0.1)")
    e, p = symkin.symbolic(robot), symkin.symbolic(robot, form="program")
    assert p.lines and all(isinstance(s, sp.Symbol) for s, _ in p.lines)
    subs = {}
    for s, x in p.lines:
        subs[s] = x.xreplace(subs)
    for q in robot.random_q(2, seed=1):
        at = dict(zip(e.q, q))
        for A, B in ((e.T, p.T), (e.J0, p.J0), (e.H0[1], p.H0[1])):
            a = np.array(A.xreplace(at).evalf(), dtype=float)
            b = np.array(B.xreplace(subs).xreplace(at).evalf(), dtype=float)
            assert_close(a, b, 1e-12, "program vs expanded")


def test_bad_input() -> None:
    with pytest.raises(SymkinError, match="expanded, program"):
        symkin.symbolic("ur5", form="tree")
    with pytest.raises(SymkinError, match="no joints"):
        symkin.symbolic(symkin.Robot.from_ets("tx(1)"))


def test_import_symkin_stays_free_of_sympy() -> None:
    code = "import sys, symkin; f = symkin.symbolic; print('sympy' in sys.modules, callable(f))"
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.split() == ["False", "True"]
