"""Arbitrary names in generated code (issue 23, item 7): a robot, joint, link or frame name, or a
command line, of any text is rendered into every template (chain and tree, C, NumPy, CasADi, JAX
and PyTorch, and the closed-form IK) as inert comment text or an escaped string literal. The C is
compiled and the Python imported from its bytes (so an encoding declaration in a comment would
count) for each example, and the loaded code must compute the reference's kinematics under those
names (JAX and PyTorch in float64, where installed).

Each example compiles C, so the example counts are small; hostile pieces (comment ends,
backslashes, trigraphs, quotes, newlines, control characters, non-ASCII) are drawn often.
"""

from __future__ import annotations

import importlib.util
import tempfile
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import symkin
from symkin import Robot, Tree
from symkin.compiler.compile import OPTIONAL_BACKENDS, generate
from symkin.errors import RobotError, SymkinError
from tests.conftest import assert_close

FEW = settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])

PIECES = [
    "*/", "/*", "*", "/", "\\", "??/", "??=", "?", "\n", "\r", "\r\n", "\x0c", "\x0b", "\t", "\x1b",
    '"""', '"', "'", "'''", "#", "# -*- coding: latin-1 -*-", "coding: 1", "coding=ascii", "é", "日本",
    "\u2028", "\x85", "\ufeff", "\U0001f916", "//", "%s", "{{ x }}", "{%", " ", "a", "1", "_",
]  # fmt: skip


def _text_ok(s: str) -> bool:
    """Names are text a C string carries whole: no NUL (hypothesis never draws lone surrogates)."""
    return bool(s) and "\0" not in s


NAME = st.one_of(
    st.lists(st.sampled_from(PIECES), min_size=1, max_size=5).map("".join),
    st.text(min_size=1, max_size=16),
).filter(_text_ok)


def _array_of(backend: str) -> Callable[[np.ndarray], Any] | None:
    """q as ``backend``'s generated functions take it in float64 (JAX with 64-bit floats on), or
    None when the backend's library (JAX, PyTorch) is not installed."""
    if backend not in OPTIONAL_BACKENDS:
        return np.asarray
    if importlib.util.find_spec(backend) is None:
        return None
    from tests.diff_libs import lib

    return lib(backend).array


def _check_files(files: dict[str, str]) -> None:
    """Every generated file is ASCII, and the Python ones compile from their bytes, as an import
    reads them (PEP 263: a ``coding:`` comment on line 1 or 2 would change the encoding)."""
    for fname, text in files.items():
        assert text.isascii(), fname
        if fname.endswith(".py"):
            compile(text.encode(), fname, "exec", dont_inherit=True)


@FEW
@given(name=NAME, joints=st.lists(NAME, min_size=2, max_size=2, unique=True), command=NAME)
@example(name="a*\\", joints=["x??/", '"""\n#'], command="compile a*\\")  # a*\ was a*/, ending the comment
def test_chain_names_and_commands_in_every_backend(name, joints, command):
    robot = Robot.from_ets("Rz(q0) tx(0.5) Ry(q1) tz(0.3)", name=name, joint_names=joints)
    q = np.array([0.3, -0.8])
    with tempfile.TemporaryDirectory() as tmp:
        for backend in symkin.BACKENDS:
            folder = Path(tmp) / backend
            symkin.write_generated(robot, backend, folder, command=command)
            _check_files({p.name: p.read_text() for p in folder.iterdir() if p.suffix in (".c", ".h", ".py")})
            x = _array_of(backend)
            if x is None:  # JAX or PyTorch not installed: the files were checked
                continue
            kin = symkin.load_compiled(folder)  # C compiled, Python imported from the folder
            assert kin.robot.name == name and kin.robot.joint_names == tuple(joints)
            assert_close(np.asarray(kin.fkine(x(q))), robot.fkine(q), 1e-12, backend)
            assert_close(np.asarray(kin.jacob0(x(q), frame=0)), robot.jacob0(q, frame=0), 1e-12, backend)


TREE_URDF = """<robot name="t"><link name="base"/><link name="l1"/><link name="fa"/><link name="fb"/>
<joint name="ja" type="revolute"><parent link="base"/><child link="l1"/><origin xyz="0 0 0.1"/>
<axis xyz="0 0 1"/><limit lower="-2" upper="2" velocity="1"/></joint>
<joint name="jb" type="revolute"><parent link="l1"/><child link="fa"/><origin xyz="0.2 0 0"/>
<axis xyz="0 1 0"/><limit lower="-2" upper="2" velocity="1"/></joint>
<joint name="jc" type="revolute"><parent link="l1"/><child link="fb"/><origin xyz="0 0.2 0"/>
<axis xyz="1 0 0"/><mimic joint="jb" multiplier="0.5"/><limit lower="-2" upper="2" velocity="1"/></joint>
</robot>"""


def _renamed(tree: Tree, name: str, joints: dict[str, str], links: dict[str, str]) -> Tree:
    """``tree`` with every name replaced (names a URDF cannot hold too: control characters)."""
    return replace(
        tree,
        name=name,
        base_link=links[tree.base_link],
        segments=tuple(replace(s, name=joints[s.name], link=links[s.link]) for s in tree.segments),
        slots=tuple(replace(s, name=joints[s.name], mimics=joints[s.mimics]) for s in tree.slots),
        frames=tuple(links[f] for f in tree.frames),
        joint_names=tuple(joints[j] for j in tree.joint_names),
    )


@FEW
@given(
    name=NAME,
    joints=st.lists(NAME, min_size=3, max_size=3, unique=True),
    links=st.lists(NAME, min_size=4, max_size=4, unique=True),
)
@example(name="coding", joints=["a*\\", "??/", "\r"], links=["b*\\", "/*", "a*\\", "caf\u00e9\n"])
def test_tree_link_frame_and_joint_names_in_every_backend(name, joints, links):
    plain = Tree.from_urdf(TREE_URDF)
    tree = _renamed(
        plain, name, dict(zip(("ja", "jb", "jc"), joints)), dict(zip(("base", "l1", "fa", "fb"), links))
    )
    q = np.array([0.4, -0.6])
    for backend in symkin.BACKENDS:
        _check_files(generate(tree, backend))  # the command names the frames too
        x = _array_of(backend)
        if x is None:
            continue
        kin = symkin.compile(tree, backend=backend)
        assert kin.frames == tree.frames
        for frame in tree.frames:  # by name: the C module decodes its frame names from C strings
            T = np.asarray(kin.fkine(x(q), frame))
            assert_close(T, plain.fkine(q, "fa" if frame == links[2] else "fb"), 1e-12, backend)


@settings(max_examples=5, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(name=NAME, command=NAME)
@example(name='a*\\"""', command="x*\\")
def test_analytic_ik_names_in_every_backend(name, command):
    from symkin.compiler.analytic_ik import generate_analytic
    from symkin.runtime.analytic_ik import compile_analytic

    robot = Robot.from_ets("Rz(q0) tx(0.7) Rz(q1) tx(0.4)", name=name)
    q = np.array([0.5, 0.9])
    for backend in symkin.BACKENDS:
        if backend in OPTIONAL_BACKENDS:  # no closed form there: a clear error, not a KeyError
            with pytest.raises(SymkinError, match=f"no {backend} backend"):
                generate_analytic(robot, backend, command=command)
            continue
        _check_files(generate_analytic(robot, backend, command=command)[0])
        res = compile_analytic(robot, backend).ik(robot.fkine(q), q0=q)
        assert res.success, (backend, res)
        assert_close(res.q, q, 1e-9, backend)


def test_a_link_named_with_a_trailing_star_backslash_compiles():
    """The issue's case: ``a*\\`` became ``a*/`` in a comment and ended it; the tree's C failed."""
    from xml.sax.saxutils import quoteattr

    link = quoteattr("a*\\")
    text = TREE_URDF.replace('"fa"', link)
    tree = Tree.from_urdf(text)
    kin = symkin.compile(tree, backend="c")
    assert_close(kin.fkine([0.1, 0.2], "a*\\"), tree.fkine([0.1, 0.2], "a*\\"), 1e-12)


def test_a_tree_named_coding_gives_an_importable_python_module(tmp_path):
    """Line 1 of the NumPy tree module read ``...the tree coding: 2 frames``: a PEP 263 encoding
    declaration (``unknown encoding: 2`` on import)."""
    tree = Tree.from_urdf(TREE_URDF, name="coding")
    for backend in ("numpy", "casadi"):
        _check_files(generate(tree, backend))


@pytest.mark.parametrize("bad", ["a\0b", "\ud800"])
def test_names_a_c_string_cannot_carry_are_refused(bad):
    with pytest.raises(RobotError, match="NUL or lone surrogates"):
        Robot.from_ets("Rz(q)", joint_names=[bad])
    plain = Tree.from_urdf(TREE_URDF)
    for kwargs in ({"name": bad}, {"frames": (bad, plain.frames[1])}, {"joint_names": (bad, "x")}):
        with pytest.raises(RobotError, match="NUL or lone surrogates"):
            replace(plain, **kwargs)
