"""``symkin compile --backend jax|torch``: the generated module, its pose and Jacobian in float64 against
the numeric reference, for a chain and a tree (skipped where the library is not installed)."""

from __future__ import annotations

import re

import pytest

from symkin.cli import main
from tests.diff_libs import BACKENDS, Lib
from tests.model.tree_urdfs import QUADRUPED


def _error(out: str) -> float:
    return float(re.search(r"numeric reference\| = (\S+)", out).group(1))


@pytest.mark.parametrize("backend", BACKENDS)
def test_compile_a_chain_and_a_tree_to_a_tensor_backend(backend, tmp_path, capsys):
    Lib(backend)  # skips without the library
    assert main(["compile", "puma560", "--backend", backend, "-o", str(tmp_path / "chain")]) == 0
    out = capsys.readouterr().out
    assert f"{backend} float64" in out and _error(out) < 1e-12
    assert (tmp_path / "chain" / f"symkin_puma560_{backend}.py").is_file()
    urdf = tmp_path / "quadruped.urdf"
    urdf.write_text(QUADRUPED)
    assert main(["compile", str(urdf), "--backend", backend]) == 0
    out = capsys.readouterr().out
    assert "frame positions (m)" in out and _error(out) < 1e-12
