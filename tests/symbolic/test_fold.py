"""Runs of constant transforms folded before the symbolic stage (symkin.symbolic.fold): a folded
transform is the product of its run, exact where that is exact; which runs fold; and what the
derivations of chains and trees with many fixed joints see."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest
import sympy as sp
from hypothesis import given, settings
from hypothesis import strategies as st

from symkin import ETS, Robot, Tree
from symkin.bench.urdf_sweep import synthetic_urdfs
from symkin.model.ets import ET, Axis, Const
from symkin.model.kinematics import const_matrix
from symkin.model.robots import list_robots, load
from symkin.symbolic import program
from symkin.symbolic.fold import MAX_RUN, Fixed, fold_constants
from symkin.symbolic.functions import EXPANDED_MAX_NODES, expanded_if_small
from symkin.symbolic.kinematics import ExpansionTooLargeError, const_to_sympy, derive, joint_symbols
from symkin.symbolic.program import derive_program, derive_tree_program
from tests.conftest import assert_close
from tests.symbolic.test_kinematics import assert_expanded_matches_reference
from tests.symbolic.test_program import assert_program_matches_reference, evaluator

URDFS = synthetic_urdfs()


def matrix(f: Fixed) -> np.ndarray:
    M = np.eye(4)
    M[:3, :3] = np.array([[float(x) for x in c] for c in f.cols]).T
    M[:3, 3] = [float(x) for x in f.t]
    return M


constants = st.one_of(
    st.integers(-4, 4).map(lambda k: Const.pi_times(Fraction(k, 2))),  # quarter turns
    st.integers(-3000, 3000).map(lambda k: Const(Fraction(k, 1000))),  # rationals
    st.sampled_from([Const(atan2=(Fraction(1), Fraction(3))), Const(Fraction(1, 3), Fraction(1, 4))]),
)
runs = st.lists(st.tuples(st.sampled_from(list(Axis)), constants), min_size=1, max_size=40).map(
    lambda items: [ET(a, const=c) for a, c in items if not c.is_zero]
)


@settings(max_examples=150, deadline=None)
@given(runs)
def test_fixed_is_the_product_of_its_run_and_inverts(run):
    expected = np.eye(4)
    for e in run:
        expected = expected @ const_matrix(e.axis, e.const)
    f = Fixed.of(run)
    assert f.count == len(run)
    np.testing.assert_allclose(matrix(f), expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(matrix(f.inverse()), np.linalg.inv(expected), rtol=0, atol=1e-12)


def test_quarter_turns_and_translations_stay_exact():
    quarter = ET(Axis.Rz, const=Const.pi_times(Fraction(1, 2)))
    f = Fixed.of([ET(Axis.tz, const=Const(Fraction(3, 100))), quarter] * 4000)
    assert f.cols == ((1, 0, 0), (0, 1, 0), (0, 0, 1)) and f.t == (0, 0, 120)
    assert all(isinstance(x, Fraction) for c in (*f.cols, f.t) for x in c)
    # rotations by arbitrary angles are doubles, rounded once; what stays exact stays exact
    f = Fixed.of(list(ETS.parse("tx(0.5) Rz(pi/2) tx(0.25) Rx(0.3) Ry(0.2)")))
    assert f.t == (Fraction(1, 2), Fraction(1, 4), 0) and all(isinstance(x, Fraction) for x in f.t)
    assert f.cols[1][1] == 0 and isinstance(f.cols[1][1], Fraction)  # Rz Rx Ry: R[1, 1] is exactly 0
    assert isinstance(f.cols[0][0], float)
    R, t = f.exprs
    assert t == (sp.Rational(1, 2), sp.Rational(1, 4), 0) and isinstance(R[0][0], sp.Float)


def _exact_product(run) -> sp.Matrix:
    M = sp.eye(4)
    for e in run:
        v, i = const_to_sympy(e.const), e.axis.index
        T = sp.eye(4)
        if e.axis.is_rotation:
            j, k = {0: (1, 2), 1: (2, 0), 2: (0, 1)}[i]
            T[j, j], T[j, k], T[k, j], T[k, k] = sp.cos(v), -sp.sin(v), sp.sin(v), sp.cos(v)
        else:
            T[i, 3] = v
        M = M * T
    return M


def test_digits_fold_to_that_precision_and_keep_what_is_exact():
    """The closed-form IK folds with digits=50: the product and its inverse to 50 digits (not 16),
    the exact entries still exact."""
    run = list(
        ETS.parse("tx(0.01) ty(0.02) tz(0.03) Rz(0.3) Ry(0.2) Rx(0.1) Rz(pi/2) tz(atan2(1,3)) Rx(pi/4+0.1)")
    )
    f = Fixed.of(run, digits=50)
    assert f.digits == 50
    M = sp.eye(4)
    cols, t = f.exprs
    for j in range(3):
        M[:3, j] = sp.Matrix(cols[j])
    M[:3, 3] = sp.Matrix(t)
    assert max(abs(sp.N(x, 60)) for x in M - _exact_product(run)) < 1e-48
    assert all(x._prec > 160 for x in M.atoms(sp.Float))  # 50 digits, not a double
    inv = f.inverse()
    Mi = sp.eye(4)
    cols, t = inv.exprs
    for j in range(3):
        Mi[:3, j] = sp.Matrix(cols[j])
    Mi[:3, 3] = sp.Matrix(t)
    assert max(abs(sp.N(x, 60)) for x in Mi * M - sp.eye(4)) < 1e-48
    double = Fixed.of(run)  # without digits: doubles, as the kinematics use
    assert double.digits is None and isinstance(double.cols[0][0], float)
    assert abs(float(double.cols[0][0]) - float(f.cols[0][0])) < 1e-15
    assert fold_constants(run, digits=50)[0].digits == 50 and fold_constants(run)[0].digits is None
    f = Fixed.of(list(ETS.parse("tx(0.5) Rz(pi/2) tx(0.25) Rx(0.3) Ry(0.2)")), digits=50)
    assert f.t == (Fraction(1, 2), Fraction(1, 4), 0) and all(isinstance(x, Fraction) for x in f.t)
    assert f.cols[1][1] == 0 and isinstance(f.cols[1][1], Fraction)


def test_which_runs_fold():
    tail = " ".join(["tx(0.01) Rz(pi/2)"] * 6)  # 12 exact transforms: more than one URDF joint holds
    ets = ETS.parse(f"tz(0.1) Rz(q0) tx(0.1) Rz(0.3) Ry(0.2) Rz(q1) tz(0.1) Rx(pi/2) Rz(-pi/4) Ry(q2) {tail}")
    shown = ["Fixed" if isinstance(e, Fixed) else str(e) for e in fold_constants(ets)]
    assert shown == ["tz(0.1)", "Rz(q0)", "Fixed", "Rz(q1)", "tz(0.1)", "Rx(pi/2)", "Rz(-pi/4)", "Ry(q2)",
                     "Fixed"]  # fmt: skip
    assert MAX_RUN < 2 * 6
    assert fold_constants(ETS.parse("Rz(q0) tx(1) Rz(q1)")) == tuple(ETS.parse("Rz(q0) tx(1) Rz(q1)"))


@pytest.mark.parametrize("name", list_robots())
def test_built_in_robots_have_no_run_that_folds(name):
    """So their derivations, and the code checked in under generated/, are what they were."""
    robot = load(name)
    assert fold_constants(robot.ets) == tuple(robot.ets)


def _trig_of_numbers(exprs) -> set:
    return {a for e in exprs for a in sp.sympify(e).atoms(sp.cos, sp.sin) if a.args[0].is_number}


@pytest.mark.parametrize(
    "name",
    ["arm6_fixed4.urdf", "arm6_fixed2000.urdf", "fixed2000_arm6.urdf", "arm6_fixed300_between.urdf",
     "arm6_fixed2000_quarter_turns.urdf"],
)  # fmt: skip
def test_program_sees_one_folded_constant_per_run_and_matches_the_reference(name):
    robot = Robot.from_urdf(URDFS[name])
    kp = derive_program(robot.ets, joint_symbols(robot.n), const_to_sympy, robot.name, fold=True)
    assert not _trig_of_numbers([e for _, e in kp.lines] + list(kp.T) + list(kp.J0))
    if name.startswith("arm6_fixed2000"):  # 2000 fixed links cost what 2 do (quarter turns: less)
        two = Robot.from_urdf(URDFS["arm6_fixed2.urdf"])
        size = len(derive_program(two.ets, kp.q, const_to_sympy, fold=True).lines)
        assert len(kp.lines) == size if name == "arm6_fixed2000.urdf" else len(kp.lines) < size
    f = evaluator(kp)
    for q in robot.random_q(3, seed=7):
        assert_program_matches_reference(f(q), robot, q)


def test_expanded_form_sees_folded_constants_and_matches_the_reference():
    robot = Robot.from_urdf(URDFS["arm6_fixed4.urdf"])
    sk = derive(robot, fold=True)
    assert not _trig_of_numbers([*sk.T, *sk.J0, *sk.Je])
    assert sk.T.atoms(sp.Float)  # the rpy rotations, rounded once
    assert _trig_of_numbers(derive(Robot.from_ets("Rz(q0) Rz(0.3) Ry(0.2)")).T)  # unfolded: exact
    for q in robot.random_q(2, seed=8):
        assert_expanded_matches_reference(sk, robot, q)


def test_tree_walks_a_chain_of_fixed_links_as_one_transform():
    tree = Tree.from_urdf(URDFS["arm6_fixed2000.urdf"])
    tp = derive_tree_program(tree, joint_symbols(tree.n), const_to_sympy, fold=True)
    two = Tree.from_urdf(URDFS["arm6_fixed2.urdf"])
    assert len(tp.lines) == len(derive_tree_program(two, tp.q, const_to_sympy, fold=True).lines)
    assert sum(link is None for link in tp.links) == 1999  # every fixed link but the frame's
    assert not _trig_of_numbers([e for _, e in tp.lines] + list(tp.T[0]))
    frame = tree.frames[0]
    for q in tree.random_q(2, seed=9):
        values = dict(zip(tp.q, map(sp.Float, q)))
        for s, e in tp.lines:
            values[s] = sp.Float(float(e.xreplace(values)))
        assert_close(np.array(tp.T[0].xreplace(values), dtype=float), tree.fkine(q, frame), 1e-10, "T")
        assert_close(np.array(tp.J0[0].xreplace(values), dtype=float), tree.jacob0(q, frame), 1e-10, "J0")


def test_choosing_the_expanded_form_stops_at_the_size_limit(monkeypatch):
    """The expanded derivation is abandoned as soon as T, J0 or H0 passes the limit: here T alone
    does, so neither the Jacobians nor the Hessians are derived."""
    robot = load("panda")

    def forbidden(*args, **kwargs):
        raise AssertionError("derived past the size limit")

    monkeypatch.setattr(program, "_jacobian_column", forbidden)  # J0, and the Je, H0 and He after it
    with pytest.raises(ExpansionTooLargeError):
        derive(robot, max_nodes=100)
    monkeypatch.undo()
    assert expanded_if_small(load("ur5")) is not None  # the same choice as before for the arms
    assert expanded_if_small(load("panda")) is not None and EXPANDED_MAX_NODES == 100_000
