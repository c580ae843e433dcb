"""The public API: every exported name exists, and importing symkin does not import sympy."""

from __future__ import annotations

import subprocess
import sys

import symkin


def test_every_name_in_all_is_importable():
    for name in symkin.__all__:
        assert getattr(symkin, name) is not None, name


def test_runtime_import_does_not_import_sympy():
    code = "import sys, symkin; symkin.load('panda'); print('sympy' in sys.modules)"
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "False"


def test_derive_and_symbolic_stay_callable_after_their_submodules_are_imported():
    # importing a submodule binds the package as symkin.<name>; the package itself must be the
    # function, or symkin.derive(robot) breaks once anything imported symkin.derive.chain
    code = (
        "import symkin; a = symkin.derive('planar2'); import symkin.derive.chain, symkin.symbolic.program; "
        "b = symkin.derive('planar2'); from symkin import derive; c = derive('planar2'); "
        "s = symkin.symbolic('planar2'); print(a == b == c, s.T.shape)"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    assert res.stdout.strip() == "True (4, 4)"
