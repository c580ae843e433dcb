"""Teaching derivations: closed forms checked symbolically, the two Jacobians agree, the documents
are complete."""

from __future__ import annotations

import re
import shutil
import subprocess

import numpy as np
import pytest
import sympy as sp

import symkin
from symkin.derive.chain import DISPLAY_MAX_OPS, Derivation, derivation, derive_steps
from symkin.derive.common import ops_of
from symkin.errors import SymkinError
from symkin.model.latex import const_latex, ets_latex, robot_latex
from tests.conftest import assert_close

SECTIONS = (
    "The elementary transform sequence (eq 1)",
    "The elementary transforms (Fig. 2)",
    "Link frames (eq 5)",
    "Forward kinematics",
    "Partial derivatives of the pose (eq 26)",
    "Jacobian columns by eqs 27-28",
    "Jacobian columns by the fast form (eqs 31-34)",
    "The manipulator Jacobian (eqs 29-30)",
    "The manipulator Hessian (eq 20 of the manipulability paper)",
    "How the results were checked",
)


def same(a: sp.Expr, b: sp.Expr) -> bool:
    """a = b identically (the trig functions of sums expanded)."""
    return sp.expand(sp.expand_trig(sp.sympify(a) - b)) == 0


@pytest.fixture(scope="module")
def planar_sym() -> Derivation:
    return derive_steps("planar3", symbolic_constants=True)


@pytest.fixture(scope="module")
def panda() -> tuple[Derivation, None]:
    return derive_steps("panda", fmt="latex"), None


def numeric_fn(d: Derivation, M: sp.Matrix):  # noqa: ANN201
    return sp.lambdify(d.q, d.numeric(M), "numpy")


# -- the planar arm reads like the hand derivation of a textbook -------------------------------


def test_planar3_pose_is_l1c1_plus_l2c12_plus_l3c123(planar_sym: Derivation) -> None:
    q1, q2, q3 = planar_sym.q
    l1, l2, l3 = sp.symbols("l_1:4", positive=True)
    c, s = sp.cos, sp.sin
    assert planar_sym.constants == {l1: 1, l2: 1, l3: 1}
    T = planar_sym.T
    assert same(T[0, 3], l1 * c(q1) + l2 * c(q1 + q2) + l3 * c(q1 + q2 + q3))
    assert same(T[1, 3], l1 * s(q1) + l2 * s(q1 + q2) + l3 * s(q1 + q2 + q3))
    assert T[2, 3] == 0
    assert same(T[0, 0], c(q1 + q2 + q3)) and same(T[1, 0], s(q1 + q2 + q3))
    # the compact form itself, not only an equal one
    assert T[0, 3] == l1 * c(q1) + l2 * c(q1 + q2) + l3 * c(q1 + q2 + q3)


def test_planar3_jacobian_entries(planar_sym: Derivation) -> None:
    q1, q2, q3 = planar_sym.q
    l1, l2, l3 = sp.symbols("l_1:4", positive=True)
    c, s = sp.cos, sp.sin
    s1, s12, s123 = s(q1), s(q1 + q2), s(q1 + q2 + q3)
    c1, c12, c123 = c(q1), c(q1 + q2), c(q1 + q2 + q3)
    expected = sp.Matrix(
        [
            [-l1 * s1 - l2 * s12 - l3 * s123, -l2 * s12 - l3 * s123, -l3 * s123],
            [l1 * c1 + l2 * c12 + l3 * c123, l2 * c12 + l3 * c123, l3 * c123],
            [0, 0, 0],
            [0, 0, 0],
            [0, 0, 0],
            [1, 1, 1],
        ]
    )
    for J in (planar_sym.J0, planar_sym.J0_fast):
        assert expected == J  # structurally: the textbook form
    for j in range(3):  # eq 26: dT/dq_j's translation column is J_v
        assert planar_sym.dT[j][:3, 3] == expected[:3, j]


def test_planar3_with_numbers_is_c1_plus_c12_plus_c123() -> None:
    d = derive_steps("planar3")
    q1, q2, q3 = d.q
    assert d.constants == {}
    assert same(d.T[0, 3], sp.cos(q1) + sp.cos(q1 + q2) + sp.cos(q1 + q2 + q3))
    assert same(d.J0[0, 0], -sp.sin(q1) - sp.sin(q1 + q2) - sp.sin(q1 + q2 + q3))
    assert "c_{1} + c_{12} + c_{123}" in d.text
    assert "- s_{1} - s_{12} - s_{123}" in d.text


def test_planar3_text_uses_textbook_abbreviations(planar_sym: Derivation) -> None:
    text = planar_sym.text
    assert "x &= l_{1} c_{1} + l_{2} c_{12} + l_{3} c_{123}" in text
    assert "y &= l_{1} s_{1} + l_{2} s_{12} + l_{3} s_{123}" in text
    assert "- l_{1} s_{1} - l_{2} s_{12} - l_{3} s_{123}" in text
    assert "$c_{12} = \\cos(q_{1} + q_{2})$" in text
    assert "R_z(q_{1}) t_x(l_{1}) R_z(q_{2}) t_x(l_{2}) R_z(q_{3}) t_x(l_{3})" in text
    assert "| $l_{1}$ | $E_{2}$ | $1$ |" in text  # the table of values
    assert "$q_{1}$ is `q0`" in text  # the 1-based display vs symkin's 0-based joints


def test_literal_products_of_eqs_27_28_and_31_34_agree_symbolically() -> None:
    raw = derive_steps("planar3", symbolic_constants=True, simplify=False)
    assert not raw.simplified
    assert sp.simplify(raw.J0 - raw.J0_fast) == sp.zeros(6, 3)
    compact = derive_steps("planar3", symbolic_constants=True)
    assert sp.simplify(raw.J0 - compact.J0) == sp.zeros(6, 3)
    assert sp.simplify(raw.T - compact.T) == sp.zeros(4, 4)
    assert raw.checks["J0 = J0_fast"] == "symbolic"


def test_hessian_is_the_derivative_of_the_jacobian(planar_sym: Derivation) -> None:
    for i, qi in enumerate(planar_sym.q):
        assert (planar_sym.H0[i] - planar_sym.J0.diff(qi)).applyfunc(
            lambda x: sp.expand(sp.expand_trig(x))
        ) == (sp.zeros(6, 3))


def test_every_equality_was_proved(planar_sym: Derivation) -> None:
    assert set(planar_sym.checks.values()) == {"symbolic"}
    assert "eq 26: dT/dq_j" in planar_sym.checks and "eqs 31-34" in planar_sym.checks


# -- numbers: agree with the numeric reference --------------------------------------------------


def test_panda_jacobians_match_the_numeric_reference(panda: tuple[Derivation, None]) -> None:
    d, _ = panda
    robot = symkin.load("panda")
    assert robot.n == 7 and len(d.q) == 7
    fk, J27, Jfast = numeric_fn(d, d.T), numeric_fn(d, d.J0), numeric_fn(d, d.J0_fast)
    H = [numeric_fn(d, h) for h in d.H0]
    for q in robot.random_q(4, seed=3):
        assert_close(fk(*q), robot.fkine(q), 1e-12, "T")
        assert_close(J27(*q), robot.jacob0(q), 1e-12, "J0 by eqs 27-28")
        assert_close(Jfast(*q), robot.jacob0(q), 1e-12, "J0 by eqs 31-34")
        assert_close(np.array([h(*q) for h in H]), robot.hessian0(q), 1e-12, "H0")
    assert "failed" not in d.checks.values()


def test_seven_dof_derivation_stays_small_and_says_what_it_skipped(panda: tuple[Derivation, None]) -> None:
    """A size bound instead of wall time (which flakes on a loaded machine): the text of the Panda
    (63 KB, longest display 9.8 KB when this was written) and what was expanded symbolically."""
    d, _ = panda
    assert d.form == "expanded"
    assert len(d.text) < 120_000
    assert max(len(block) for block in d.text.split("\\[")) < 20_000
    assert sum(ops_of(x) for x in d.T) <= 3 * DISPLAY_MAX_OPS
    assert "not printed for more than 4 joints" in d.text
    assert "random points" in d.text  # checks too large to expand are done numerically and said so


def test_prismatic_joint_and_symbolic_negative_constant() -> None:
    robot = symkin.Robot.from_ets("Rz(q) tx(-0.5) Ry(-q) tz(0.3) tz(q) Rx(pi/2) tx(0.25)", name="toy")
    d = derive_steps(robot, symbolic_constants=True)
    l1 = sp.Symbol("l_1", positive=True)
    assert d.constants[l1] == sp.Rational(1, 2)
    assert "t_x(-l_{1})" in d.text
    J = numeric_fn(d, d.J0)
    for q in robot.random_q(3, seed=1):
        assert_close(J(*q), robot.jacob0(q), 1e-12, "toy J0")
        assert_close(numeric_fn(d, d.T)(*q), robot.fkine(q), 1e-12, "toy T")


def test_stanford_numbers() -> None:
    robot = symkin.load("stanford")
    d = derive_steps(robot)
    J = numeric_fn(d, d.J0_fast)
    for q in robot.random_q(3, seed=2):
        assert_close(J(*q), robot.jacob0(q), 1e-12, "stanford J0")


# -- documents ---------------------------------------------------------------------------------


def test_markdown_has_every_section(planar_sym: Derivation) -> None:
    text = planar_sym.text
    assert text.startswith("# Kinematics of planar3")
    for title in SECTIONS:
        assert f"## {title}" in text
    assert text.count("$$") % 2 == 0
    assert "{{" not in text and "}}}}" not in text


def check_latex_structure(text: str) -> None:
    body = re.sub(r"\\[{}]", "", text)  # escaped braces
    depth = 0
    for ch in body:
        depth += {"{": 1, "}": -1}.get(ch, 0)
        assert depth >= 0, "a } closes nothing"
    assert depth == 0, "unbalanced braces"
    stack = []
    for kind, env in re.findall(r"\\(begin|end)\{(\w+\*?)\}", text):
        if kind == "begin":
            stack.append(env)
        else:
            assert stack and stack.pop() == env, f"\\end{{{env}}} does not match"
    assert not stack
    assert text.count("\\[") == text.count("\\]")
    assert len(re.findall(r"(?<!\\)\$", text)) % 2 == 0


def test_latex_is_a_complete_document(panda: tuple[Derivation, None], tmp_path) -> None:  # noqa: ANN001
    for text in (panda[0].text, derivation("planar3", fmt="latex", symbolic_constants=True)):
        assert text.startswith("\\documentclass")
        assert "\\begin{document}" in text and text.rstrip().endswith("\\end{document}")
        for title in SECTIONS:
            assert f"\\section{{{title}}}" in text
        check_latex_structure(text)
    if shutil.which("pdflatex"):
        (tmp_path / "d.tex").write_text(derivation("planar3", fmt="latex"))
        run = subprocess.run(
            ["pdflatex", "-interaction=nonstopmode", "-halt-on-error", "d.tex"],
            cwd=tmp_path,
            capture_output=True,
            timeout=120,
        )
        assert run.returncode == 0, run.stdout.decode(errors="replace")[-2000:]


def test_text_names_sources_not_internal_labels(planar_sym: Derivation) -> None:
    for text in (
        planar_sym.text,
        derivation("ur5", sections="fk,jacobian"),
        derivation("planar2", form="program"),
    ):
        assert not re.search(r"(?i)seed \d|lab \d", text)
        assert "Haviland and Corke" in text and "Manipulator Differential Kinematics, Part 1" in text


def test_constants_are_written_in_one_style() -> None:
    """Lengths read as in the ETS (0.5, not 1/2): the same decimals in the sequence and the results."""
    text = derivation("Rz(q) tx(0.5) Rz(q) tx(0.25) Rx(pi/2) tz(0.333)", sections="ets,fk")
    assert "t_x(0.5)" in text and "0.5 c_{1}" in text and "0.25 c_{12}" in text
    assert "\\frac{c_{1}}{2}" not in text and "\\frac{c_{12}}{4}" not in text
    assert "\\frac{\\pi}{2}" in text  # angles stay multiples of pi
    # a root keeps its form: atan2 constants of a tilted axis print sqrt, not a power 0.5
    tilted = derivation("Rz(atan2(1, sqrt(2))) Rx(q) tx(0.5)", sections="ets,fk")
    assert "^{0.5}" not in tilted


def test_sections_shorten_the_text_in_both_forms() -> None:
    full = derive_steps("planar3")
    short = derive_steps("planar3", sections=("fk", "jacobian"))
    assert short.shown == ("fk", "jacobian") and len(short.text) < len(full.text)
    assert "## Forward kinematics" in short.text and "## The manipulator Jacobian (eqs 29-30)" in short.text
    for title in ("Link frames (eq 5)", "The manipulator Hessian", "The elementary transforms (Fig. 2)"):
        assert title not in short.text
    assert short.text.startswith("# Kinematics of planar3") and "| joint |" in short.text
    # the program form brings the link frames the pose and the Jacobian are written in
    prog = derive_steps("planar3", form="program", sections="jacobian")
    assert prog.shown == ("links", "fk", "jacobian")
    assert (
        "## Link frames (eq 5), one from the previous" in prog.text
        and "## The manipulator Hessian" not in prog.text
    )
    assert "## The elementary transforms" not in prog.text
    with pytest.raises(SymkinError, match="fk, derivatives"):
        derive_steps("planar2", sections=("fk", "jacobians"))


def test_markdown_repr_is_the_whole_derivation(
    panda: tuple[Derivation, None], planar_sym: Derivation
) -> None:
    assert planar_sym._repr_markdown_() == planar_sym.text
    md = panda[0]._repr_markdown_()  # a LaTeX derivation still shows Markdown in a notebook
    assert md.startswith("# Kinematics of panda") and "\\documentclass" not in md
    for title in SECTIONS:
        assert f"## {title}" in md


def test_unknown_format_is_rejected() -> None:
    with pytest.raises(SymkinError, match="markdown, latex"):
        derivation("planar2", fmt="html")  # type: ignore[arg-type]


def test_jupyter_latex_reprs(planar_sym: Derivation) -> None:
    summary = planar_sym._repr_latex_()
    assert summary.startswith("$$") and summary.endswith("$$")
    assert "l_{1} c_{1} + l_{2} c_{12} + l_{3} c_{123}" in summary
    check_latex_structure(summary)
    ets = symkin.load("panda").ets
    assert ets._repr_latex_() == "$" + ets_latex(ets) + "$"


# -- hand-written LaTeX of models ----------------------------------------------------------------


def test_ets_latex() -> None:
    ets = symkin.ETS.parse("tz(0.333) Rz(q0) Ry(-q1) Rx(-pi/2) tx(1/3) Rz(3*pi/4)")
    assert ets_latex(ets) == (
        "{}^{0}T_{e} = t_z(0.333) R_z(q_{1}) R_y(-q_{2}) R_x(-\\frac{\\pi}{2}) t_x(\\frac{1}{3}) "
        "R_z(\\frac{3\\pi}{4})"
    )
    assert ets_latex(ets, lhs=None, names={0: "d_{1}"}).startswith("t_z(d_{1}) R_z(q_{1})")
    assert const_latex(symkin.Const.of("atan2(sqrt(2), -1) - pi/2")) == (
        "\\operatorname{atan2}\\left(\\sqrt{2}, -1\\right) - \\frac{\\pi}{2}"
    )
    assert robot_latex(symkin.load("lbr_iiwa7")).startswith(
        "$\\text{lbr\\_iiwa7}:\\; {}^{0}T_{e} = R_z(q_{1})"
    )


# -- long chains: named intermediates, link frame by link frame --------------------------------


@pytest.fixture(scope="module")
def chain12() -> Derivation:
    from symkin.bench.compile import random_chain

    return derive_steps(random_chain(12, seed=1))


def test_long_chain_derivation_uses_named_intermediates(chain12: Derivation) -> None:
    d = chain12
    assert d.form == "program" and len(d.intermediates) > 100
    assert set(d.checks.values()) == {"numeric"}
    assert "\\zeta_{" in d.text and "one from the previous" in d.text
    assert "an expression of" not in d.text  # nothing had to be elided
    # every displayed formula is short: one named step
    assert max(ops_of(e) for _, e in d.intermediates) <= 12
    assert len(d.text) < 60_000


def test_long_chain_results_expand_to_the_reference(chain12: Derivation) -> None:
    from symkin.bench.compile import random_chain

    robot = random_chain(12, seed=1)
    q_syms = chain12.q
    f = sp.lambdify(q_syms, chain12.expand(chain12.J0), "numpy")
    g = sp.lambdify(q_syms, chain12.expand(chain12.T), "numpy")
    for q in robot.random_q(3, seed=2):
        assert_close(f(*q), robot.jacob0(q), 1e-12, "J0")
        assert_close(g(*q), robot.fkine(q), 1e-12, "T")
    links = sp.lambdify(q_syms, chain12.expand(chain12.links[5]), "numpy")
    q = robot.random_q(seed=3)
    assert_close(links(*q), robot.link_poses(q)[5], 1e-12, "link 5")


def test_long_chain_checks_catch_a_wrong_step(monkeypatch) -> None:
    """The 30-digit checks compare with the literal products: a program with one wrong sign fails."""
    import symkin.derive.program as dp
    from symkin.bench.compile import random_chain

    real = dp.derive_tree_program

    def broken(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        kp = real(*args, **kwargs)
        s, e = kp.lines[40]
        lines = (*kp.lines[:40], (s, -e), *kp.lines[41:])
        return type(kp)(**{**kp.__dict__, "lines": lines})

    monkeypatch.setattr(dp, "derive_tree_program", broken)
    d = dp.program_derivation(random_chain(9, seed=4), False)[0]
    assert "failed" in d.checks.values()


def test_form_can_be_chosen() -> None:
    d = derive_steps("planar3", form="program")
    assert d.form == "program" and set(d.checks.values()) == {"numeric"}
    with pytest.raises(symkin.SymkinError, match="unknown form"):
        derive_steps("planar3", form="short")


def test_names_cannot_open_math_or_code_in_the_derivation() -> None:
    robot = symkin.Robot.from_ets("Rz(q0) tx(1)", name="a$\\frac{1}{0}$`x`", joint_names=("j$1`",))
    for fmt in ("markdown", "latex"):
        text = derivation(robot, fmt=fmt)
        assert "$\\frac{1}{0}$" not in text and "j$1" not in text and "`x`" not in text
    assert "Kinematics of a??frac" in derivation(robot)
