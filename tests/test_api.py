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
