"""The generated C as an engineer embeds it: C99 and C++ with strict warnings, two robots in one
program under their own prefixes, the header's macros and joint table; prefixes that could clash
with the extension module's names are refused, every other one compiles and loads."""

from __future__ import annotations

import shutil
import subprocess
import tempfile

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import symkin
from symkin.emit.c.backend import check_prefix
from symkin.errors import CompileError, SymkinError
from symkin.model.robots import load

CC = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
CXX = shutil.which("c++") or shutil.which("g++") or shutil.which("clang++")
STRICT = ["-Wall", "-Wextra", "-pedantic", "-Werror"]

MAIN = r"""
#include <cstdio>
#include "arm_a.h"
#include "arm_b.h"

int main()
{
    static const double qa_min[] = ARM_A_QMIN;
    static const double qb_max[] = ARM_B_QMAX;
    double qa[ARM_A_N], qb[ARM_B_N], T[ARM_A_T_SIZE], J[ARM_B_J_SIZE], Qb[2 * ARM_B_N], Jb[2 * ARM_B_J_SIZE];
    for (int i = 0; i < ARM_A_N; ++i)
        qa[i] = 0.5 * qa_min[i] + 0.1 * i;
    for (int i = 0; i < ARM_B_N; ++i)
        qb[i] = Qb[i] = Qb[ARM_B_N + i] = 0.3 * qb_max[i] - 0.05 * i;
    arm_a_fkine(qa, T);
    arm_b_jacob0(qb, J);
    arm_b_jacob0_batch(Qb, Jb, (ptrdiff_t)2);
    std::printf("%s %s %s\n", arm_a_robot_name, arm_b_robot_name, arm_a_joint_names[ARM_A_N - 1]);
    for (int i = 0; i < ARM_A_T_SIZE; ++i)
        std::printf("%.17g ", T[i]);
    std::printf("\n");
    for (int i = 0; i < ARM_B_J_SIZE; ++i)
        std::printf("%.17g ", J[i]);
    std::printf("\n%.17g %.17g\n", Jb[ARM_B_J_SIZE + 3], arm_a_manipulability(qa, ARM_A_AXES_TRANS));
    return 0;
}
"""


@pytest.fixture(scope="module")
def two_robots(tmp_path_factory):
    out = tmp_path_factory.mktemp("embedded")
    a, b = load("panda"), load("ur5")  # one of each strategy (program, expanded)
    symkin.write_generated(a, "c", out, prefix="arm_a")
    symkin.write_generated(b, "c", out, prefix="arm_b")
    return out, a, b


@pytest.mark.skipif(CC is None, reason="no C compiler")
@pytest.mark.parametrize("std", ["-std=c99", "-std=c11"])
def test_generated_c_is_strict_c(two_robots, std):
    out, _, _ = two_robots
    for name in ("arm_a.c", "arm_b.c"):
        proc = subprocess.run(
            [CC, std, *STRICT, "-c", name, "-o", "/dev/null"], cwd=out, capture_output=True, text=True
        )
        assert proc.returncode == 0, proc.stderr


@pytest.mark.skipif(CXX is None, reason="no C++ compiler")
def test_two_robots_link_into_one_cpp_program(two_robots):
    out, a, b = two_robots
    (out / "main.cpp").write_text(MAIN)
    cmd = [
        CXX,
        "-std=c++11",
        *STRICT,
        "-x",
        "c++",
        "arm_a.c",
        "arm_b.c",
        "-x",
        "c++",
        "main.cpp",
        "-o",
        "prog",
        "-lm",
    ]
    proc = subprocess.run(cmd, cwd=out, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    run = subprocess.run([str(out / "prog")], capture_output=True, text=True, check=True)
    lines = run.stdout.splitlines()
    assert lines[0] == f"panda ur5 {a.joint_names[-1]}"
    qa = 0.5 * a.qlim[0] + 0.1 * np.arange(a.n)
    qb = 0.3 * b.qlim[1] - 0.05 * np.arange(b.n)
    np.testing.assert_allclose(np.array(lines[1].split(), float).reshape(4, 4), a.fkine(qa), atol=1e-12)
    Jb = b.jacob0(qb)
    np.testing.assert_allclose(np.array(lines[2].split(), float).reshape(6, b.n), Jb, atol=1e-12)
    last = np.array(lines[3].split(), float)
    assert abs(last[0] - Jb.flat[3]) < 1e-12
    assert abs(last[1] - a.manipulability(qa, axes="trans")) < 1e-12


def test_header_states_units_limits_and_sizes(two_robots):
    out, a, _ = two_robots
    h = (out / "arm_a.h").read_text()
    for text in (
        "#define ARM_A_N 7",
        "ARM_A_QMIN",
        "ARM_A_QD_MAX",
        "ARM_A_AXES_TRANS 1",
        "ptrdiff_t N",
        "rad",
        "Licence:",
    ):
        assert text in h, text
    for name in a.joint_names:
        assert name in h
    qmin = h.split("#define ARM_A_QMIN {")[1].split("}")[0]
    np.testing.assert_array_equal(np.array(qmin.split(","), float), a.qlim[0])
    c = (out / "arm_a.c").read_text()
    assert "SYMKIN_RESTRICT" in c and "Licence:" in c


@pytest.mark.parametrize("bad", ["1abc", "a-b", "x" * 64, "", "caf\u00e9"])
def test_bad_prefixes_are_refused(bad):
    with pytest.raises(CompileError, match="prefix"):
        check_prefix(bad)
    with pytest.raises(SymkinError):
        symkin.generate(load("planar2"), "c", prefix=bad)


def test_prefix_is_for_the_c_backend_only():
    with pytest.raises(SymkinError, match="C backend only"):
        symkin.generate(load("planar2"), "numpy", prefix="arm")


def test_single_precision_code_is_float_and_close_to_double(tmp_path):
    from symkin.bench.compile import random_chain
    from symkin.emit.c.backend import float_error

    for robot in (load("panda"), random_chain(14, seed=2)):  # Hessians written out, and as loops
        files = symkin.generate(robot, "c", precision="float", prefix="armf")
        assert sorted(files) == ["armf.c", "armf.h"]  # no Python module in single precision
        assert "double" not in files["armf.h"] and "sinf" in files["armf.c"]
        err = float_error(robot, files)
        assert max(err.values()) < 1e-5, err  # float epsilon 1.2e-7, a few dozen operations deep
        if CC is not None:
            for name, text in files.items():
                (tmp_path / name).write_text(text)
            flags = [*STRICT, "-Wdouble-promotion"]
            proc = subprocess.run([CC, "-std=c99", *flags, "-c", "armf.c", "-o", "/dev/null"], cwd=tmp_path,
                                  capture_output=True, text=True)  # fmt: skip
            assert proc.returncode == 0, proc.stderr
    with pytest.raises(CompileError, match="precision"):
        symkin.generate(load("planar2"), "c", precision="half")


def test_libm_switch_gives_the_same_kinematics(tmp_path):
    import ctypes

    from symkin.emit.c.build import compile_library, load_library

    robot = load("ur5")
    files = symkin.generate(robot, "c", libm=True, prefix="arml")
    assert "#define SYMKIN_USE_LIBM 1" in files["arml.c"]
    plain = symkin.generate(robot, "c", prefix="arml")["arml.c"]
    assert "SYMKIN_USE_LIBM" in plain and "Sun Microsystems" in plain  # the switch, and fdlibm's notice
    sources = {k: v for k, v in files.items() if not k.endswith("_pymodule.c")}
    lib = load_library(compile_library(sources, "arml_libm"))
    q = robot.random_q(seed=4)
    T = np.empty(16)
    lib.arml_fkine(q.ctypes.data_as(ctypes.c_void_p), T.ctypes.data_as(ctypes.c_void_p))
    np.testing.assert_allclose(T.reshape(4, 4), robot.fkine(q), atol=1e-14)


TREE_MAIN = r"""
#include <cstdio>
#include "symkin_ur5_tree.h"

int main()
{
    const double q[SYMKIN_UR5_TREE_N] = {0.1, -0.7, 1.2, -0.4, 0.9, 0.3};
    double T[SYMKIN_UR5_TREE_F * 16], J[SYMKIN_UR5_TREE_F * 6 * SYMKIN_UR5_TREE_N];
    symkin_ur5_tree_fkine_jacob0_all(q, T, J);
    for (int i = 0; i < SYMKIN_UR5_TREE_F * 16; ++i)
        std::printf("%.17g ", T[i]);
    std::printf("\n");
    for (int i = 0; i < SYMKIN_UR5_TREE_F * 6 * SYMKIN_UR5_TREE_N; ++i)
        std::printf("%.17g ", J[i]);
    std::printf("\n");
    return 0;
}
"""


@pytest.mark.skipif(CC is None or CXX is None, reason="no C or C++ compiler")
def test_a_tree_kernel_is_strict_c_and_links_into_a_cpp_program(tmp_path):
    from pathlib import Path

    tree = symkin.Tree.from_urdf(Path(__file__).resolve().parents[2] / "examples" / "ur5.urdf")
    for name, text in symkin.generate(tree, "c").items():
        (tmp_path / name).write_text(text)
    c = subprocess.run([CC, "-std=c99", *STRICT, "-c", "symkin_ur5_tree.c", "-o", "/dev/null"],
                       cwd=tmp_path, capture_output=True, text=True)  # fmt: skip
    assert c.returncode == 0, c.stderr
    (tmp_path / "main.cpp").write_text(TREE_MAIN)
    cmd = [CXX, "-std=c++11", *STRICT, "-x", "c++", "symkin_ur5_tree.c", "main.cpp", "-o", "prog", "-lm"]
    proc = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    lines = subprocess.run(
        [str(tmp_path / "prog")], capture_output=True, text=True, check=True
    ).stdout.splitlines()
    q = np.array([0.1, -0.7, 1.2, -0.4, 0.9, 0.3])
    F = len(tree.frames)
    np.testing.assert_allclose(
        np.array(lines[0].split(), float).reshape(F, 4, 4), tree.fkine_all(q), atol=1e-12
    )
    J = np.array(lines[1].split(), float).reshape(F, 6, tree.n)
    np.testing.assert_allclose(J, tree.jacob0_all(q), atol=1e-12)


# issue 23, item 8: a prefix is refused where the names it makes could clash with the extension
# module's (its own py_<function> wrappers, the include guards and macros of C, Python and NumPy);
# every prefix that is accepted compiles and loads through load_compiled.

CLASHES = [
    "py",  # py_fkine: the module's own wrapper (compiled, then failed to build)
    "py_fkine",  # py_fkine_jacob0
    "Py_x",
    "pyctype",  # PYCTYPE_H, an include guard of Python.h
    "have_alloca",  # HAVE_ALLOCA_H, from pyconfig.h
    "npy_have_endian",  # NPY_HAVE_ENDIAN_H, from NumPy
    "numpy_x",
    "_math",  # _MATH_H, math.h's include guard
    "_x",
]


@pytest.mark.parametrize("bad", CLASHES)
def test_prefixes_that_could_clash_with_the_module_are_refused(bad, tmp_path, capsys):
    from symkin.cli.main import main

    with pytest.raises(CompileError, match=f"prefix '{bad}' makes symbols.*Choose another prefix"):
        check_prefix(bad)
    with pytest.raises(CompileError, match="Choose another prefix"):
        symkin.write_generated(load("planar2"), "c", tmp_path, prefix=bad)
    assert main(["compile", "planar2", "--prefix", bad, "-o", str(tmp_path / "cli")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Choose another prefix" in err[0], err
    assert not list(tmp_path.iterdir())  # nothing written


PREFIX = st.one_of(
    st.from_regex(r"[A-Za-z_][A-Za-z0-9_]{0,24}", fullmatch=True),
    st.sampled_from(
        [*CLASHES, "math", "Python", "stddef", "string", "fkine", "jacob0", "link_poses", "sk", "N", "q",
         "order", "methods", "module", "new_out", "get_q", "as_batch", "frame_index", "hessian_base",
         "SYMKIN", "symkin_planar2", "have", "PYx"]
    ),
)  # fmt: skip


@settings(max_examples=12, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(prefix=PREFIX)
@example(prefix="math")  # the generated math.h must not shadow <math.h>
@example(prefix="py")  # accepted before, then the module failed to compile
def test_every_accepted_prefix_compiles_and_loads(prefix):
    robot = load("planar2")
    try:
        check_prefix(prefix)
    except CompileError:
        assert prefix.upper().startswith(("_", "PY", "NPY", "NUMPY", "HAVE_")), prefix
        return
    with tempfile.TemporaryDirectory() as tmp:
        symkin.write_generated(robot, "c", tmp, prefix=prefix)
        kin = symkin.load_compiled(tmp)  # compiles the C and imports its module
        assert kin.c_prefix == prefix
        q = np.array([0.3, -0.4])
        np.testing.assert_allclose(kin.fkine(q), robot.fkine(q), atol=1e-12)
        assert kin.manipulability(q) == pytest.approx(robot.manipulability(q), abs=1e-12)
