"""Command-line mistakes end in one line and exit 2 before any long work starts; a closed output
pipe ends quietly (issue 12, item 12)."""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

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


# ---- issue 36, item 8: input files of the wrong structure; no error exits with an answer's status --
BAD_ENV = {
    "a number where a list goes": '{"spheres": 5}',
    "null where a list goes": '{"capsules": null}',
    "an object where a list goes": '{"boxes": {"a": 1}}',
    "text where a list goes": '{"spheres": "0 0 0 1"}',
    "a row nested once more": '{"spheres": [[[0, 0, 0, 0.1]]]}',
    "a row too short": '{"capsules": [[0, 0, 0, 1, 1, 1]]}',
    "text in a row": '{"spheres": [[0, 0, 0, "0.1"]]}',
    "true in a row": '{"spheres": [[0, 0, 0, true]]}',
    "null in a row": '{"boxes": [[0, 0, 0, 1, 1, null]]}',
    "NaN": '{"spheres": [[0, 0, 0, NaN]]}',
    "Infinity": '{"spheres": [[0, 0, Infinity, 0.1]]}',
    "a number beyond a double": '{"spheres": [[0, 0, 1e400, 0.1]]}',
    "an integer beyond a double": '{"spheres": [[0, 0, 0, 1' + "0" * 400 + "]]}",
    "a negative radius": '{"spheres": [[0, 0, 0, -1]]}',
    "a negative half extent": '{"boxes": [[0, 0, 0, 1, 1, -1]]}',
    "arrays nested too deeply": '{"spheres": ' + "[" * 100_000 + "]" * 100_000 + "}",
    "a top-level list": "[[[[1]]]]",
    "an unknown key": '{"cylinders": []}',
    "not JSON": "{spheres: []}",
    "not UTF-8": b'{"spheres": [[0, 0, 0, 0.1]]}\xff',
}


@pytest.mark.parametrize("what", list(BAD_ENV))
@pytest.mark.parametrize(
    "command",
    [
        ["collide", "ur5"],  # exit 1 means "in collision": a TypeError traceback exited 1
        ["plot", "ur5"],
        ["servo", "ur5", "--target-q", "0 0 0 0 0 0", "--collision"],
    ],
)
def test_an_env_file_of_the_wrong_structure_is_one_line(capsys, tmp_path, no_work, what, command):
    env = tmp_path / "env.json"
    text = BAD_ENV[what]
    env.write_bytes(text if isinstance(text, bytes) else text.encode())
    line = one_line_error(
        capsys,
        [*command, "--env", str(env), *(["-o", str(tmp_path / "p.png")] if command[0] == "plot" else [])],
    )
    assert str(env) in line


@pytest.mark.parametrize(
    "option, value", [("--sphere", "0 0 0 -1"), ("--box", "0 0 0 1 -1 1"), ("--capsule", "0 0 0 1 1 1 -2")]
)
def test_a_bad_obstacle_option_is_named(capsys, no_work, option, value):
    assert option in one_line_error(capsys, ["collide", "ur5", option, value])


@pytest.mark.parametrize(
    "error",
    [TypeError("'int' object is not iterable"), RecursionError("maximum recursion depth exceeded"),
     KeyError("x"), AttributeError("no"), MemoryError(), ZeroDivisionError("division by zero"),
     RuntimeError("")],
)  # fmt: skip
def test_an_unexpected_exception_is_one_line_and_status_2(capsys, monkeypatch, error):
    """A bug must not exit 1 (an answer: in collision, not solved) nor print a traceback."""
    from symkin.cli import collide

    def broken(args):
        raise error

    monkeypatch.setattr(collide, "run", broken)
    monkeypatch.delenv("SYMKIN_TRACEBACK", raising=False)
    line = one_line_error(capsys, ["collide", "ur5"])
    assert type(error).__name__ in line or "out of memory" in line


def test_symkin_traceback_shows_where_an_unexpected_exception_came_from(capsys, monkeypatch):
    from symkin.cli import collide

    def broken(args):
        raise TypeError("where")

    monkeypatch.setattr(collide, "run", broken)
    monkeypatch.setenv("SYMKIN_TRACEBACK", "1")
    assert main(["collide", "ur5"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("symkin: error: unexpected TypeError: where") and "Traceback" in err


def test_a_command_status_is_an_answer_or_2(monkeypatch, capsys):
    """Only 0 and 1 are answers; anything else a command returns is reported as an error status."""
    from symkin.cli import collide

    monkeypatch.setattr(collide, "run", lambda args: 7)
    assert main(["collide", "ur5"]) == 2
    monkeypatch.setattr(collide, "run", lambda args: None)
    assert main(["collide", "ur5"]) == 0


# ---- issue 36, item 9: sizes that overflow are refused up front in one line ------------------------
@pytest.mark.parametrize(
    "argv",
    [
        ["dataset", "planar2", "-n", str(10**20)],  # was a MemoryError traceback
        ["dataset", "planar2", "-n", str(10**12)],
        ["dataset", "planar2", "-n", "10", "--chunk", str(10**20)],
        ["reach", "planar2", "--orientations", str(10**12)],
        ["reach", "planar2", "--resolution", "1e-9"],
        ["reach", "planar2", "--slimit", str(10**12)],
    ],
)
def test_a_size_beyond_the_machine_is_one_line(capsys, tmp_path, no_work, argv):
    pytest.importorskip("zarr")
    line = one_line_error(capsys, [*argv, "-o", str(tmp_path / "store.zarr"), "--scheduler", "synchronous"])
    assert any(word in line for word in ("memory", "disk", "integer", "too many")), line
    assert not (tmp_path / "store.zarr").exists()  # refused before the store was made


@pytest.mark.parametrize(
    "argv",
    [
        ["check", "planar2", "--samples", str(10**12)],
        ["ik", "planar2", "--target-q", "0.1 0.2", "--ilimit", str(10**12)],
        ["ik", "planar2", "--target-q", "0.1 0.2", "--slimit", str(10**20)],
    ],
)
def test_a_count_beyond_the_machine_is_one_line(capsys, argv):
    line = one_line_error(capsys, argv)
    assert any(word in line for word in ("memory", "integer")), line


@pytest.mark.skipif(not Path("/dev/zero").exists(), reason="needs /dev/zero")
@pytest.mark.parametrize("kind", ["--env", "URDF", "DH"])
def test_an_endless_input_file_is_refused_before_it_fills_memory(capsys, tmp_path, no_work, kind):
    """/dev/zero as an obstacle file, a URDF or a DH table: read up to a bound, then one line."""
    if kind == "--env":
        argv = ["collide", "ur5", "--env", "/dev/zero"]
    else:
        link = tmp_path / ("arm.urdf" if kind == "URDF" else "arm.dh")
        link.symlink_to("/dev/zero")
        argv = ["list-frames", str(link)] if kind == "URDF" else ["compile", str(link)]
        if kind == "DH":
            from symkin.errors import RobotError
            from symkin.model.dh import dh_file_args

            with pytest.raises(RobotError, match="larger than"):
                dh_file_args(link)
            return
    assert "larger than" in one_line_error(capsys, argv)
