"""Command-line mistakes end in one line and exit 2 before any long work starts; a closed output
pipe ends quietly (issue 12, item 12)."""

from __future__ import annotations

import importlib
import sys

import pytest

from symkin.cli.main import main


def one_line_error(capsys, argv: list[str]) -> str:
    try:
        code = main(argv)
    except SystemExit as exc:  # argparse
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("symkin: error:"), err
    return lines[0]


@pytest.fixture
def no_work(monkeypatch):
    """Fail the test if code generation, compilation, a servo run or a benchmark starts."""

    def forbidden(*args, **kwargs):
        raise AssertionError("long work started before the command line was checked")

    # modules that bind these functions when first imported must not bind the stand-in for good
    for module in ("symkin.compiler.snapshot", "symkin.bench.kin", "symkin.bench.ik", "symkin.bench.mmc"):
        importlib.import_module(module)

    for module, name in (
        ("symkin.compiler.compile", "generate"),
        ("symkin.runtime.load", "compile"),
        ("symkin.runtime.loop", "servo"),
        ("symkin.bench.kin", "run_kin"),
        ("symkin.bench.mmc", "run_table1"),
    ):
        monkeypatch.setattr(importlib.import_module(module), name, forbidden)


def test_output_that_is_a_file(capsys, tmp_path, no_work):
    target = tmp_path / "file.txt"
    target.write_text("x")
    assert "not a folder" in one_line_error(capsys, ["compile", "planar2", "-o", str(target)])
    assert "not a folder" in one_line_error(capsys, ["generate", "-o", str(target)])
    line = one_line_error(capsys, ["derive", "planar2", "-o", str(tmp_path / "missing" / "d.md")])
    assert "does not exist" in line


def test_a_folder_or_missing_file_as_robot(capsys, tmp_path, no_work):
    assert "is a folder" in one_line_error(capsys, ["compile", str(tmp_path)])  # was "unknown robot"
    assert "no such file" in one_line_error(capsys, ["check", str(tmp_path / "arm.dh")])


@pytest.mark.parametrize(
    "argv",
    [
        ["check", "planar2", "--samples", "-3"],  # was "negative dimensions are not allowed"
        ["check", "planar2", "--samples", "0"],
        ["bench", "kin", "--batch", "-1"],
        ["bench", "ik", "-n", "0"],
        ["servo", "planar2", "--target-q", "0.1 0.2", "--max-steps", "-5"],
        ["servo", "planar2", "--target-q", "0.1 0.2", "--dt", "inf"],  # failed mid-run
        ["servo", "planar2", "--target-q", "0.1 0.2", "--dt", "nan"],
        ["servo", "planar2", "--target-q", "0.1 0.2", "--dt", "0"],
        ["servo", "planar2", "--target-q", "0.1 0.2", "--dt", "fast"],
    ],
)
def test_bad_numbers(capsys, argv, no_work):
    line = one_line_error(capsys, argv)
    assert "argument" in line


def test_bad_symkin_cflags_is_named(capsys, monkeypatch, no_work):
    monkeypatch.setenv("SYMKIN_CFLAGS", "-O2 -fno-such-flag-at-all")
    assert "SYMKIN_CFLAGS" in one_line_error(capsys, ["compile", "planar2"])
    monkeypatch.setenv("SYMKIN_CFLAGS", "-O2 '-march=native")
    assert "SYMKIN_CFLAGS" in one_line_error(capsys, ["compile", "planar2"])


def test_bad_symkin_cflags_is_named_by_the_build_too(monkeypatch):
    from symkin.emit.c.build import compile_library
    from symkin.errors import CompileError

    monkeypatch.setenv("SYMKIN_CFLAGS", "-O2 -fno-such-flag-at-all")
    with pytest.raises(CompileError) as info:
        compile_library({"x.c": "int x(void) { return 1; }\n"}, "cflags_probe")
    assert "SYMKIN_CFLAGS" in str(info.value).splitlines()[0]


def test_plot_without_matplotlib_is_found_first(capsys, monkeypatch, tmp_path, no_work):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # import matplotlib raises ImportError
    argv = ["servo", "planar2", "--target-q", "0.1 0.2", "--plot", str(tmp_path / "p.png")]
    assert "matplotlib" in one_line_error(capsys, argv)
    assert "matplotlib" in one_line_error(
        capsys, ["bench", "mmc", "-n", "1", "--plot", str(tmp_path / "p.png")]
    )


def test_plot_into_a_missing_folder_is_found_first(capsys, tmp_path, no_work):
    argv = ["servo", "planar2", "--target-q", "0.1 0.2", "--plot", str(tmp_path / "no" / "p.png")]
    assert "does not exist" in one_line_error(capsys, argv)


class _ClosedPipe:
    """stdout whose reader has gone away (``symkin ... | head -1``)."""

    def write(self, text: str) -> int:
        raise BrokenPipeError(32, "Broken pipe")

    def flush(self) -> None:
        raise BrokenPipeError(32, "Broken pipe")

    def fileno(self) -> int:
        raise OSError("no file descriptor")


@pytest.mark.parametrize("argv", [["list"], ["derive", "planar2"], ["list", "--json"]])
def test_closed_pipe_ends_quietly(capsys, monkeypatch, argv):
    monkeypatch.setattr(sys, "stdout", _ClosedPipe())
    assert main(argv) == 141  # 128 + SIGPIPE, as a shell reports a command ended by a closed pipe
    assert capsys.readouterr().err == ""  # no traceback, no message
