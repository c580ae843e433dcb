"""The generated C of a kinematic tree as an engineer embeds it, with the chain's options
(tests/emit/test_embedded_c.py): a prefix on every exported symbol and file, two trees in one
program, single precision and the C library's sin and cos."""

from __future__ import annotations

import ctypes
import shutil
import subprocess

import numpy as np
import pytest

import symkin
from symkin import Tree
from symkin.emit.c.backend import float_error
from symkin.emit.c.build import compile_library, load_library
from symkin.errors import CompileError, SymkinError
from tests.model.tree_urdfs import ARM_CAMERA, GRIPPER, QUADRUPED

CC = shutil.which("cc") or shutil.which("gcc") or shutil.which("clang")
STRICT = ["-Wall", "-Wextra", "-pedantic", "-Werror"]

MAIN = r"""
#include <stdio.h>
#include "legs.h"
#include "arm.h"

int main(void)
{
    double ql[LEGS_N], qa[ARM_N], T[LEGS_F * 16], J[ARM_F * 6 * ARM_N], Tf[16];
    for (int i = 0; i < LEGS_N; ++i)
        ql[i] = 0.3 - 0.1 * i;
    for (int i = 0; i < ARM_N; ++i)
        qa[i] = -0.2 + 0.15 * i;
    legs_fkine_all(ql, T);
    arm_jacob0_all(qa, J);
    arm_fkine_frame(qa, arm_frame_index("camera"), Tf);
    printf("%s %s %d\n", legs_robot_name, arm_robot_name, legs_frame_index("nowhere"));
    for (int i = 0; i < LEGS_F * 16; ++i)
        printf("%.17g ", T[i]);
    printf("\n");
    for (int i = 0; i < ARM_F * 6 * ARM_N; ++i)
        printf("%.17g ", J[i]);
    printf("\n");
    for (int i = 0; i < 16; ++i)
        printf("%.17g ", Tf[i]);
    printf("\n");
    return 0;
}
"""


def _sources(files: dict[str, str]) -> dict[str, str]:
    """The .c/.h pair (without the Python module), for a ctypes library."""
    return {k: v for k, v in files.items() if not k.endswith("_pymodule.c")}


def _call_all(lib, prefix: str, tree: Tree, Q: np.ndarray, dtype=np.float64) -> tuple[np.ndarray, np.ndarray]:
    """fkine_all and jacob0_all of every row of Q through the ``<prefix>_*_all_batch`` entry points."""
    N, F = len(Q), len(tree.frames)
    Q = np.ascontiguousarray(Q, dtype=dtype)
    out = []
    for name, shape in (("fkine_all", (F, 4, 4)), ("jacob0_all", (F, 6, tree.n))):
        buf = np.empty((N, *shape), dtype=dtype)
        fn = getattr(lib, f"{prefix}_{name}_batch")
        fn.restype = None
        fn(Q.ctypes.data_as(ctypes.c_void_p), buf.ctypes.data_as(ctypes.c_void_p), ctypes.c_ssize_t(N))
        out.append(buf.astype(float))
    return out[0], out[1]


def _strict_c(folder, name: str, *flags: str) -> None:
    proc = subprocess.run(
        [CC, "-std=c99", *STRICT, *flags, "-c", name, "-o", "/dev/null"],
        cwd=folder,
        capture_output=True,
        text=True,
    )
    assert proc.returncode == 0, proc.stderr


def test_a_prefixed_tree_exports_only_prefixed_symbols(tmp_path):
    tree = Tree.from_urdf(QUADRUPED)
    files = symkin.generate(tree, "c", prefix="legs")
    assert sorted(files) == ["legs.c", "legs.h", "legs_lanes.c", "legs_pymodule.c"]  # lanes: built apart
    assert "#define LEGS_N" in files["legs.h"] and "#ifndef LEGS_H" in files["legs.h"]
    assert not any("symkin_quad_tree" in text for text in files.values())
    # the Python module built from the prefixed files: the same kinematics
    kin = symkin.load_compiled(symkin.write_generated(tree, "c", tmp_path, prefix="legs")[0].parent)
    lib = ctypes.CDLL(str(kin.path))
    for k in range(len(tree.frames)):
        assert hasattr(lib, f"legs_fkine_jacob0_{k}") and hasattr(lib, f"legs_jacob0_hessian0_{k}")
    assert hasattr(lib, "legs_fkine_all_batch") and hasattr(lib, "legs_frame_index")
    assert not hasattr(lib, "symkin_quad_tree_fkine_all")
    Q = tree.random_q(3, seed=5)
    T, J = _call_all(lib, "legs", tree, Q)
    np.testing.assert_allclose(T, tree.fkine_all(Q), atol=1e-13)
    np.testing.assert_allclose(J, tree.jacob0_all(Q), atol=1e-13)
    np.testing.assert_allclose(kin.jacob0_all(Q), tree.jacob0_all(Q), atol=1e-13)


@pytest.mark.skipif(CC is None, reason="no C compiler")
def test_two_prefixed_trees_link_into_one_c_program(tmp_path):
    legs, arm = Tree.from_urdf(QUADRUPED), Tree.from_urdf(ARM_CAMERA)
    symkin.write_generated(legs, "c", tmp_path, prefix="legs")
    symkin.write_generated(arm, "c", tmp_path, prefix="arm")
    for name in ("legs.c", "arm.c"):
        _strict_c(tmp_path, name)
    (tmp_path / "main.c").write_text(MAIN)
    cmd = [CC, "-std=c99", *STRICT, "legs.c", "arm.c", "main.c", "-o", "prog", "-lm"]
    proc = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    lines = subprocess.run(
        [str(tmp_path / "prog")], capture_output=True, text=True, check=True
    ).stdout.splitlines()
    assert lines[0] == "quad arm_cam -1"
    ql = 0.3 - 0.1 * np.arange(legs.n)
    qa = -0.2 + 0.15 * np.arange(arm.n)
    F = len(legs.frames)
    np.testing.assert_allclose(
        np.array(lines[1].split(), float).reshape(F, 4, 4), legs.fkine_all(ql), atol=1e-12
    )
    J = np.array(lines[2].split(), float).reshape(len(arm.frames), 6, arm.n)
    np.testing.assert_allclose(J, arm.jacob0_all(qa), atol=1e-12)
    np.testing.assert_allclose(
        np.array(lines[3].split(), float).reshape(4, 4), arm.fkine(qa, "camera"), atol=1e-12
    )


@pytest.mark.parametrize("xml", [QUADRUPED, GRIPPER], ids=["quadruped", "gripper"])
def test_single_precision_tree_code_is_float_and_close_to_double(tmp_path, xml):
    tree = Tree.from_urdf(xml)
    files = symkin.generate(tree, "c", precision="float", prefix="treef")
    assert sorted(files) == ["treef.c", "treef.h"]  # no Python module in single precision
    assert (
        "double" not in files["treef.h"] and "double" not in files["treef.c"] and "sinf" in files["treef.c"]
    )
    err = float_error(tree, files)
    assert max(err.values()) < 1e-5, err  # float epsilon 1.2e-7, a few dozen operations deep
    if CC is not None:
        for name, text in files.items():
            (tmp_path / name).write_text(text)
        _strict_c(tmp_path, "treef.c", "-Wdouble-promotion")
    lib = load_library(compile_library(files, "treef_probe"))
    Q = tree.random_q(20, seed=6)
    T, J = _call_all(lib, "treef", tree, Q, dtype=np.float32)
    assert np.abs(T - tree.fkine_all(Q.astype(np.float32).astype(float))).max() < 1e-5
    assert np.abs(J - tree.jacob0_all(Q.astype(np.float32).astype(float))).max() < 1e-5


def test_the_libm_switch_gives_the_same_tree_kinematics(tmp_path):
    tree = Tree.from_urdf(QUADRUPED)
    files = symkin.generate(tree, "c", libm=True, prefix="treel")
    assert "#define SYMKIN_USE_LIBM 1" in files["treel.c"]
    plain = symkin.generate(tree, "c", prefix="treel")["treel.c"]
    assert "SYMKIN_USE_LIBM 1" not in plain and "Sun Microsystems" in plain  # the inline kernels
    if CC is not None:
        for name, text in _sources(files).items():
            (tmp_path / name).write_text(text)
        _strict_c(tmp_path, "treel.c")
    lib = load_library(compile_library(_sources(files), "treel_libm"))
    Q = tree.random_q(10, seed=4)
    T, J = _call_all(lib, "treel", tree, Q)
    np.testing.assert_allclose(T, tree.fkine_all(Q), atol=1e-12)
    np.testing.assert_allclose(J, tree.jacob0_all(Q), atol=1e-12)


def test_tree_options_are_checked_as_for_chains():
    tree = Tree.from_urdf(GRIPPER)
    with pytest.raises(CompileError, match="prefix"):
        symkin.generate(tree, "c", prefix="1legs")
    with pytest.raises(CompileError, match="precision"):
        symkin.generate(tree, "c", precision="half")
    for backend in ("numpy", "casadi"):
        with pytest.raises(SymkinError, match="C backend only"):
            symkin.generate(tree, backend, libm=True)
