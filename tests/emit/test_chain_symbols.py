"""The C symbols and header macros embedded users of a chain link against, as symkin 0.1 exported
them, are still there: every symbol is looked up in a built Panda library, every macro in its
header, and a C program that uses them all compiles and links against the generated code."""

from __future__ import annotations

import ctypes
import re
import shutil
import subprocess

import pytest

import symkin

FUNCTIONS = (
    "fkine",
    "link_poses",
    "jacob0",
    "jacobe",
    "hessian0",
    "hessiane",
    "fkine_jacob0",
    "jacob0_hessian0",
)
SYMBOLS = (
    *(f"{name}{batch}" for name in FUNCTIONS for batch in ("", "_batch")),
    "fkine_frame",
    "jacob0_frame",
    "jacobe_frame",
    "manipulability",
    "jacobm",
    "robot_name",
    "joint_names",
)
MACROS = ("H", "N", "T_SIZE", "LINKS_SIZE", "J_SIZE", "H_SIZE", "QMIN", "QMAX", "QD_MAX")
MACROS += ("AXES_ALL", "AXES_TRANS", "AXES_ROT")
CC = shutil.which("cc") or shutil.which("gcc")

PROGRAM = r"""
#include <stdio.h>
#include "symkin_panda.h"

int main(void)
{
    static const double qmin[] = SYMKIN_PANDA_QMIN, qmax[] = SYMKIN_PANDA_QMAX, qd[] = SYMKIN_PANDA_QD_MAX;
    double q[2 * SYMKIN_PANDA_N], T[2 * SYMKIN_PANDA_T_SIZE], L[2 * SYMKIN_PANDA_LINKS_SIZE];
    double J[2 * SYMKIN_PANDA_J_SIZE], H[2 * SYMKIN_PANDA_H_SIZE], Jm[SYMKIN_PANDA_N];
    for (int i = 0; i < 2 * SYMKIN_PANDA_N; ++i)
        q[i] = 0.5 * (qmin[i % SYMKIN_PANDA_N] + qmax[i % SYMKIN_PANDA_N]) + 0.01 * qd[i % SYMKIN_PANDA_N];
    symkin_panda_fkine(q, T), symkin_panda_fkine_batch(q, T, 2);
    symkin_panda_link_poses(q, L), symkin_panda_link_poses_batch(q, L, 2);
    symkin_panda_jacob0(q, J), symkin_panda_jacob0_batch(q, J, 2);
    symkin_panda_jacobe(q, J), symkin_panda_jacobe_batch(q, J, 2);
    symkin_panda_hessian0(q, H), symkin_panda_hessian0_batch(q, H, 2);
    symkin_panda_hessiane(q, H), symkin_panda_hessiane_batch(q, H, 2);
    symkin_panda_fkine_jacob0(q, T, J), symkin_panda_fkine_jacob0_batch(q, T, J, 2);
    symkin_panda_jacob0_hessian0(q, J, H), symkin_panda_jacob0_hessian0_batch(q, J, H, 2);
    symkin_panda_fkine_frame(q, 3, T), symkin_panda_jacob0_frame(q, 3, J), symkin_panda_jacobe_frame(q, 3, J);
    double m = symkin_panda_manipulability(q, SYMKIN_PANDA_AXES_ALL);
    m += symkin_panda_jacobm(q, SYMKIN_PANDA_AXES_TRANS, Jm);
    printf("%s %s %d %g\n", symkin_panda_robot_name, symkin_panda_joint_names[0], SYMKIN_PANDA_AXES_ROT, m);
    return 0;
}
"""


@pytest.fixture(scope="module")
def panda():
    return symkin.compile("panda", backend="c")


def test_every_chain_symbol_is_exported_by_the_built_library(panda):
    lib = ctypes.CDLL(str(panda.path))
    missing = [name for name in SYMBOLS if not hasattr(lib, f"symkin_panda_{name}")]
    assert missing == []


def test_every_chain_macro_is_defined_by_the_header(panda):
    header = panda.files["symkin_panda.h"]
    missing = [name for name in MACROS if not re.search(rf"^#define SYMKIN_PANDA_{name}\b", header, re.M)]
    assert missing == []
    assert "#define SYMKIN_PANDA_F " not in header  # nothing of several frames in a one-frame kernel


@pytest.mark.skipif(CC is None, reason="no C compiler")
def test_a_program_using_them_all_links_against_the_generated_code(panda, tmp_path):
    for name in ("symkin_panda.h", "symkin_panda.c"):
        (tmp_path / name).write_text(panda.files[name])
    (tmp_path / "main.c").write_text(PROGRAM)
    cmd = [CC, "-std=c99", "-Wall", "-Wextra", "-Werror", "symkin_panda.c", "main.c", "-o", "prog", "-lm"]
    build = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True)
    assert build.returncode == 0, build.stderr
    out = subprocess.run([str(tmp_path / "prog")], capture_output=True, text=True, check=True).stdout.split()
    assert out[:3] == ["panda", symkin.load("panda").joint_names[0], "2"]
