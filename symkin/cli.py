"""The ``symkin`` command.

Every command that takes a ROBOT accepts a built-in name (``panda``), an ETS string in quotes
(``"Rz(q) tx(1) Rz(q) tx(1)"``), a DH table file, a URDF file or ``path.urdf:FRAME`` for the
chain to one link (also ``--base-link/--end-link``), and ``--tool``/``--base`` to add a constant
transform after the end effector / before the first link. ``compile``, ``check`` and ``derive``
take a whole tree with ``--frames a,b,c`` (a branching URDF without a frame is a tree of its
leaves). User mistakes print one line ``symkin: error: ...`` and exit with status 2, checked before
any long work starts where they can be; a failed check or an unsolved problem exits 1. When the
reader of the output goes away (``symkin list | head -1``), symkin stops quietly with status 141
(128 + SIGPIPE), as a program killed by SIGPIPE would; an output that cannot be written (a full
disk, ``> /dev/full``) is an error: ``symkin: error: cannot write the output: ...``, status 2.
Progress bars appear only when stderr is a terminal (:mod:`symkin.progress`).
"""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from symkin.cli_checks import UserError
from symkin.cli_checks import check_cflags_for as _check_cflags
from symkin.cli_checks import int_at_least as _int_at_least
from symkin.cli_checks import need_matplotlib as _need_matplotlib
from symkin.cli_checks import output_dir as _output_dir
from symkin.cli_checks import output_file as _output_file
from symkin.cli_checks import positive_float as _positive

__all__ = ["main"]

_at_least_1 = _int_at_least(1)

ROBOT_HELP = (
    "a built-in robot name (see `symkin list`), a quoted ETS string, a DH table file, a URDF file or "
    "path.urdf:FRAME (the chain to link FRAME)"
)
TRANSFORM_HELP = (
    "constant ETS text like 'tz(0.1) Rx(pi/2)', or 'x y z roll pitch yaw' (m, rad; pi/2 and 90deg "
    "allowed), or 16 numbers of a row-major 4x4 matrix"
)


class _Formatter(argparse.HelpFormatter):
    """Help that shows every option's default (unless its text already names it)."""

    def _get_help_string(self, action: argparse.Action) -> str:
        text = action.help or ""
        if (
            not action.option_strings
            or action.default is None
            or action.default is False
            or action.default == argparse.SUPPRESS
            or "default" in text.lower()
        ):
            return text
        return text + " (default: %(default)s)"


class _Deprecated(argparse.Action):
    """A renamed option kept working: stores into the new option's dest and says so on stderr."""

    def __init__(self, *args: Any, new: str = "", **kwargs: Any) -> None:
        self.new = new
        super().__init__(*args, **kwargs)

    def __call__(self, parser: Any, namespace: Any, values: Any, option_string: Any = None) -> None:
        print(f"symkin: {option_string} is deprecated; use {self.new}", file=sys.stderr)
        setattr(namespace, self.dest, values)


def _robot(args: argparse.Namespace, default: str | None = None) -> Any:
    """The serial ROBOT of a command (or ``default`` when it is optional and not given), with
    --tool/--base and, for a URDF, ``path.urdf:FRAME`` or --base-link/--end-link."""
    from symkin.cli_tree import single_chain

    return single_chain(args, default)


def _custom(args: argparse.Namespace) -> bool:
    """Whether --tool or --base changed the robot (benchmarks then take the Robot, not its name)."""
    return getattr(args, "tool", None) is not None or getattr(args, "base", None) is not None


def _floats(text: str, what: str, count: int | None = None) -> np.ndarray:
    try:
        values = np.array([float(x) for x in text.replace(",", " ").split()])
    except ValueError:
        raise UserError(f"{what} must be numbers separated by spaces or commas, got {text!r}") from None
    if count is not None and values.size != count:
        raise UserError(f"{what} needs {count} numbers, got {values.size}")
    if not np.isfinite(values).all():
        raise UserError(f"{what} must be finite numbers, got {text!r}")
    return values


def _fmt(a: np.ndarray) -> str:
    return np.array2string(np.asarray(a), precision=5, suppress_small=True, max_line_width=110)


# ----------------------------------------------------------------------------------------------
def cmd_list(args: argparse.Namespace) -> int:
    from symkin.model.robots import list_robots, load

    rows = []
    for name in list_robots():
        r = load(name)
        rows.append((name, r.n, r.ets.structure, r.source.split(";")[0][:70]))
    if args.json:
        print(json.dumps([{"name": a, "n": b, "joints": c, "source": d} for a, b, c, d in rows], indent=2))
        return 0
    print(f"{'robot':10} {'n':>2}  {'joints':8} source")
    for name, n, s, src in rows:
        print(f"{name:10} {n:>2}  {s:8} {src}")
    return 0


def cmd_compile(args: argparse.Namespace) -> int:
    from symkin.cli_tree import chain_or_tree, compile_tree_report
    from symkin.compile import compile as compile_robot
    from symkin.compile import generate
    from symkin.model.tree import Tree

    robot = chain_or_tree(args)
    out = _output_dir(args.output) if args.output else None
    _check_cflags(args.backend)
    if isinstance(robot, Tree):
        if args.prefix or args.precision != "double" or args.libm:
            raise UserError(
                "--prefix, --precision and --libm shape the C of one chain; a tree compiles with the "
                "defaults (name one chain as ROBOT.urdf:FRAME)"
            )
        return compile_tree_report(robot, args.backend, args.output)
    t0 = time.perf_counter()
    command = f"symkin compile {robot.identifier} --backend {args.backend}"
    c_only = (("--prefix", args.prefix), ("--precision", args.precision != "double"), ("--libm", args.libm))
    for flag, given in c_only:
        if given and args.backend != "c":
            raise UserError(f"{flag} applies to the C backend only")
        if given and not args.output:
            raise UserError(f"{flag} shapes the files written with -o DIR; give -o too")
    if args.prefix:
        command += f" --prefix {args.prefix}"
    if args.precision != "double":
        command += f" --precision {args.precision}"
    if args.libm:
        command += " --libm"
    if args.strategy:
        command += f" --strategy {args.strategy}"
    files = generate(
        robot,
        args.backend,
        command,
        strategy=args.strategy,
        prefix=args.prefix,
        precision=args.precision,
        libm=args.libm,
    )
    t_gen = time.perf_counter() - t0
    if out is not None:
        out.mkdir(parents=True, exist_ok=True)
        for name, text in sorted(files.items()):
            (out / name).write_text(text)
        from symkin.compiled import write_manifest

        manifest = write_manifest(robot, args.backend, files, out, args.precision)
        print(
            f"wrote {len(files)} files to {out}/: {', '.join(sorted(files))} (and {manifest.name}, which "
            "symkin.load_compiled reads)"
        )
    if args.precision == "float":
        from symkin.emit.c.backend import float_error

        err = float_error(robot, files)
        print(f"single-precision code against double on 100 random q: max |fkine| error {err['fkine']:.1e}, "
              f"max |jacob0| error {err['jacob0']:.1e}")  # fmt: skip
    t1 = time.perf_counter()
    kin = compile_robot(robot, backend=args.backend, strategy=args.strategy)
    t_build = time.perf_counter() - t1
    first = next(iter(files.values())).splitlines()
    ops = next((ln.split(":", 1)[1].strip() for ln in first[:8] if "Operations" in ln), "")
    print(f"{robot.name}: {robot.n} joints ({robot.ets.structure}), ETS {robot.ets}")
    print(f"backend {args.backend}: derived + generated in {t_gen:.2f} s, built/loaded in {t_build:.2f} s")
    if ops:
        print(f"operations after CSE: {ops}")
    q = robot.configs.get("qr", robot.configs["qz"])
    qname = "qr" if "qr" in robot.configs else "qz"
    print(f"\nat {qname} = {_fmt(q)}:")
    print(f"fkine (4x4):\n{_fmt(kin.fkine(q))}")
    print(f"jacob0 (6x{robot.n}, rows v, omega):\n{_fmt(kin.jacob0(q))}")
    print(f"manipulability: {float(kin.manipulability(q)):.6g}")
    err = float(np.abs(kin.jacob0(q) - robot.jacob0(q)).max())
    print(f"max |jacob0 - numeric reference| = {err:.2e}")
    reps = 2000
    t = time.perf_counter()
    for _ in range(reps):
        kin.jacob0(q)
    print(f"jacob0: {(time.perf_counter() - t) / reps * 1e6:.2f} us per call from Python")
    return 0


def cmd_generate(args: argparse.Namespace) -> int:
    from symkin.emit.snapshot import compare_or_update

    _output_dir(args.output)
    differ = compare_or_update(args.output, update=not args.check, progress=True)
    if args.check:
        if differ:
            print(f"{len(differ)} generated files are out of date in {args.output}/ (run `symkin generate`):")
            for d in differ:
                print(f"  {d}")
            return 1
        print(f"{args.output}/ is up to date")
        return 0
    print(f"updated {len(differ)} files in {args.output}/" if differ else f"{args.output}/ was up to date")
    return 0


def cmd_check(args: argparse.Namespace) -> int:
    from symkin.check import check
    from symkin.cli_tree import chain_or_tree
    from symkin.model.tree import Tree

    robot = chain_or_tree(args)
    backends = args.backend or ("c", "numpy", "casadi")
    for b in args.backend or ("c",):
        _check_cflags(b)
    if isinstance(robot, Tree):
        from symkin.check_tree import check_tree

        report = check_tree(robot, backends=backends, samples=args.samples, seed=args.seed)
    else:
        report = check(robot, backends=backends, samples=args.samples, seed=args.seed)
    print(json.dumps(report.as_dict(), indent=2) if args.json else report.format())
    return 0 if report.ok else 1


def cmd_derive(args: argparse.Namespace) -> int:
    from symkin.cli_tree import chain_or_tree
    from symkin.derivation import derivation
    from symkin.model.tree import Tree

    robot = chain_or_tree(args)
    sections = _sections(args.sections)
    _output_file(args.output, "-o")
    if isinstance(robot, Tree):
        if args.ik:
            raise UserError("--ik derives the closed form of one chain: name it as ROBOT.urdf:FRAME")
        if sections is not None:
            raise UserError("--sections chooses parts of a chain's derivation, not of a tree's")
        from symkin.derivation_tree import tree_derivation

        text = tree_derivation(robot, fmt=args.format)
    elif args.ik:
        if sections is not None:
            raise UserError("--sections chooses parts of the kinematics derivation, not of --ik")
        from symkin.derivation_ik import ik_derivation

        text = ik_derivation(robot, fmt=args.format)
    else:
        text = derivation(
            robot,
            fmt=args.format,
            symbolic_constants=args.symbolic_constants,
            simplify=not args.no_simplify,
            form=args.form,
            sections=sections,
        )
    if args.output:
        Path(args.output).write_text(text)
        print(f"wrote the derivation of {robot.name} to {args.output}")
    else:
        print(text)
    return 0


def _sections(text: str | None) -> tuple[str, ...] | None:
    if text is None:
        return None
    from symkin.derivation import SECTIONS

    names = tuple(w for w in text.replace(",", " ").split())
    bad = [w for w in names if w not in SECTIONS]
    if bad or not names:
        raise UserError(
            f"--sections takes names from {', '.join(SECTIONS)} separated by commas, not {text!r}"
        )
    return names


def _target(args: argparse.Namespace, robot: Any) -> np.ndarray:
    """A target pose from --pose (x y z roll pitch yaw, rad), --matrix (16 numbers) or --target-q."""
    given = [x is not None for x in (args.pose, args.matrix, args.target_q)]
    if sum(given) != 1:
        raise UserError(
            "give exactly one of --pose 'x y z roll pitch yaw', --matrix '16 numbers', --target-q 'q...'"
        )
    if args.target_q is not None:
        return robot.fkine(_floats(args.target_q, "--target-q", robot.n))
    if args.matrix is not None:
        return _floats(args.matrix, "--matrix", 16).reshape(4, 4)
    x, y, z, r, p, yaw = _floats(args.pose, "--pose", 6)
    cr, sr, cp, sp_, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(yaw), np.sin(yaw)
    T = np.eye(4)
    T[:3, :3] = [
        [cy * cp, cy * sp_ * sr - sy * cr, cy * sp_ * cr + sy * sr],
        [sy * cp, sy * sp_ * sr + cy * cr, sy * sp_ * cr - cy * sr],
        [-sp_, cp * sr, cp * cr],
    ]
    T[:3, 3] = [x, y, z]
    return T


def cmd_ik(args: argparse.Namespace) -> int:
    from symkin.compile import compile as compile_robot

    robot = _robot(args)
    Tep = _target(args, robot)
    numerical = {"--we": args.we, "--lam": args.lam, "--ilimit": args.ilimit, "--slimit": args.slimit}
    _check_cflags(args.backend)
    if args.all or args.method == "analytic":
        given = [k for k, v in numerical.items() if v is not None]
        if given:
            raise UserError(
                f"{', '.join(given)} set the numerical methods NR, GN and LM, not the closed form"
            )
        return _ik_analytic(args, compile_robot(robot, backend=args.backend), Tep)
    kin = compile_robot(robot, backend=args.backend)
    kwargs: dict[str, Any] = {"method": args.method, "seed": args.seed}
    if args.damping:
        kwargs["damping"] = args.damping
    if args.q0 is not None:
        kwargs["q0"] = _floats(args.q0, "--q0", robot.n)
    if args.we is not None:
        kwargs["we"] = _weights(args.we)
    if args.lam is not None:
        kwargs["lam"] = args.lam
    if args.tol is not None:
        kwargs["tol"] = args.tol
    if args.ilimit is not None:
        kwargs["ilimit"] = args.ilimit
    if args.slimit is not None:
        kwargs["slimit"] = args.slimit
    t = time.perf_counter()
    res = kin.ik(Tep, **kwargs)
    dt = time.perf_counter() - t
    if args.json:
        print(json.dumps({**_result_dict(res), "seconds": dt}, indent=2))
    else:
        print(f"target:\n{_fmt(Tep)}")
        status = "solved" if res.success else f"not solved: {res.reason}"
        print(f"{status} in {res.iterations} iterations, {res.searches} searches, {dt * 1e3:.2f} ms")
        print(f"q = {_fmt(res.q)}")
        print(f"residual = {res.residual:.3e}")
    return 0 if res.success else 1


def _weights(text: str) -> np.ndarray:
    """--we: 'position' (1 1 1 0 0 0), 'orientation' (0 0 0 1 1 1) or six weights >= 0."""
    named = {"position": [1, 1, 1, 0, 0, 0], "orientation": [0, 0, 0, 1, 1, 1]}
    if text.strip().lower() in named:
        return np.array(named[text.strip().lower()], dtype=float)
    we = _floats(text, "--we", 6)
    if (we < 0).any() or not we.any():
        raise UserError(f"--we needs six weights >= 0, not all 0 (or 'position'), got {text!r}")
    return we


def _ik_analytic(args: argparse.Namespace, kin: Any, Tep: np.ndarray) -> int:
    """``symkin ik --all`` (every closed-form solution) or ``--method analytic`` (the nearest)."""
    q0 = _floats(args.q0, "--q0", kin.n) if args.q0 is not None else None
    t = time.perf_counter()
    if not args.all:
        extra = {} if args.tol is None else {"tol": args.tol}
        res = kin.ik(Tep, method="analytic", q0=q0, **extra)
        dt = time.perf_counter() - t
        if args.json:
            print(json.dumps({**_result_dict(res), "seconds": dt}, indent=2))
        else:
            status = "solved" if res.success else f"not solved: {res.reason}"
            print(
                f"{status} (closed form) in {dt * 1e3:.3f} ms\n"
                f"q = {_fmt(res.q)}\nresidual = {res.residual:.3e}"
            )
        return 0 if res.success else 1
    sols = kin.ik_all(Tep, q0=q0, joint_limits=not args.no_limits)
    dt = time.perf_counter() - t
    errors = [float(np.abs(kin.robot.fkine(q) - Tep).max()) for q in sols]
    if args.json:
        print(json.dumps({"solutions": sols.tolist(), "fk_error": errors, "seconds": dt}, indent=2))
    else:
        print(f"target:\n{_fmt(Tep)}")
        where = "" if args.no_limits else " within the joint limits"
        print(f"{len(sols)} solution(s){where} (closed form, {kin.analytic.kind}) in {dt * 1e3:.3f} ms")
        for i, (q, e) in enumerate(zip(sols, errors)):
            print(f"  {i + 1}: q = {_fmt(q)}  |T(q) - T| = {e:.1e}")
    return 0 if len(sols) else 1


def _result_dict(res: Any) -> dict:
    import dataclasses

    out = {}
    for f in dataclasses.fields(res):
        v = getattr(res, f.name)
        out[f.name] = v.tolist() if isinstance(v, (np.ndarray, np.generic)) else v
    return out


def cmd_servo(args: argparse.Namespace) -> int:
    from symkin.compile import compile as compile_robot
    from symkin.runtime.loop import servo

    robot = _robot(args)
    Tep = _target(args, robot)
    _need_matplotlib(args.plot)
    _check_cflags(args.backend)
    q0 = _floats(args.q0, "--q0", robot.n) if args.q0 else robot.configs.get("qr", robot.configs["qz"])
    kin = compile_robot(robot, backend=args.backend)
    res = servo(
        kin,
        q0,
        Tep,
        controller=args.controller,
        dt=args.dt,
        max_steps=args.max_steps,
        joint_limits=args.joint_limits,
        progress=not args.json,
    )
    steps = len(res.q) - 1
    summary = {
        "arrived": bool(res.arrived),
        "steps": steps,
        "final_error": float(np.abs(res.e[-1]).sum()) if len(res.e) else None,
        "mean_manipulability": float(np.mean(res.manipulability)),
        "q_final": res.q[-1].tolist(),
    }
    if args.plot:
        _plot_servo(res, args.dt, args.plot, f"{robot.name} {args.controller}")
        summary["plot"] = args.plot
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(
            f"{args.controller}: {'arrived' if res.arrived else 'did not arrive'} after {steps} steps "
            f"(dt {args.dt} s); mean manipulability {summary['mean_manipulability']:.4f}"
        )
        print(f"q final = {_fmt(res.q[-1])}")
        if args.plot:
            print(f"plot written to {args.plot}")
    return 0 if res.arrived else 1


def _plot_servo(res: Any, dt: float, path: str, title: str) -> None:
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        raise UserError("--plot needs matplotlib: pip install 'symkin[plot]'") from None
    t = np.arange(len(res.manipulability)) * dt
    fig, (a1, a2) = plt.subplots(2, 1, figsize=(7, 5), sharex=True)
    a1.plot(t, res.manipulability)
    a1.set_ylabel("manipulability")
    a1.set_title(title)
    a2.plot(np.arange(len(res.e)) * dt, np.abs(np.asarray(res.e)).sum(axis=1))
    a2.set_ylabel("sum |e|")
    a2.set_xlabel("time (s)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def _joint_counts(text: str) -> tuple[int, ...]:
    try:
        counts = tuple(int(x) for x in text.replace(",", " ").split())
    except ValueError:
        counts = ()
    if not counts or any(c < 1 or c > 200 for c in counts):
        raise UserError(f"--joints must be joint counts between 1 and 200 like '6,12,24,36', not {text!r}")
    return counts


def cmd_bench(args: argparse.Namespace) -> int:
    from symkin.cli_tree import bench_trees, bench_urdf

    if args.robot is None:
        args.robot = args.robot_option
    custom = _custom(args)
    if custom and args.robot is None:
        raise UserError("--tool/--base change a ROBOT: name one (symkin bench WHAT ROBOT --tool ...)")
    _check_cflags("c")
    if args.plot and args.what not in ("mmc", "compile", "urdf"):
        raise UserError(f"--plot is for `symkin bench mmc`, `compile` and `urdf`, not `{args.what}`")
    if args.what in ("tree", "urdf") and args.robot is not None:
        raise UserError(f"bench {args.what} measures its own robots; it takes no ROBOT")
    _need_matplotlib(args.plot)
    if args.what == "compile":
        from symkin.bench.compile import format_compile, plot_compile, run_compile

        if custom:
            raise UserError(
                "bench compile measures ROBOT by name in a fresh process; --tool/--base do not apply"
            )
        joints = _joint_counts(args.joints)
        rows = run_compile(joints, seed=args.seed, reference=args.robot or "panda", progress=not args.json)
        print(json.dumps(rows, indent=2) if args.json else format_compile(rows))
        if args.plot:
            plot_compile(rows, args.plot)
            if not args.json:
                print(f"plot written to {args.plot}")
        return 0
    spec: Any = _robot(args) if custom else args.robot
    if args.what == "calls":
        from symkin.bench.calls import format_calls, run_calls

        result = run_calls(spec or "ur5", spec or "panda", seed=args.seed, progress=not args.json)
        print(json.dumps(result, indent=2, default=_jsonable) if args.json else format_calls(result))
        return 0
    if args.what == "reach":
        from symkin.bench.reach import format_reach, run_reach
        from symkin.workspace.run import require_scale

        require_scale()
        result = run_reach(
            _robot(args, "ur5"), resolution=args.resolution, orientations=args.orientations,
            seed=args.seed, fault=args.fault, progress=not args.json, repeat=args.repeat,
        )  # fmt: skip
        print(json.dumps(result, indent=2, default=_jsonable) if args.json else format_reach(result))
        return 0
    if args.what == "kin":
        from symkin.bench.kin import format_kin, run_kin

        result = run_kin(spec or "panda", batch=args.batch, progress=not args.json)
        if not args.json:
            print(format_kin(result), flush=True)
        result["trees"] = bench_trees(args)
        print(json.dumps(result, indent=2, default=_jsonable) if args.json else "")
        return 0
    if args.what in ("tree", "urdf"):
        code, result = (0, bench_trees(args)) if args.what == "tree" else bench_urdf(args)
        print(json.dumps(result, indent=2, default=_jsonable) if args.json else "")
        return code
    if args.what == "ik" and args.analytic:
        from symkin.bench.analytic_ik import format_analytic, run_analytic

        robots = (spec,) if spec is not None else ("ur5", "ur10", "puma560", "stanford")
        result = run_analytic(
            robots, n=args.problems or 1000, starts=args.starts, seed=args.seed, progress=not args.json
        )
        print(json.dumps(result, indent=2, default=_jsonable) if args.json else format_analytic(result))
        return 0
    if args.what == "ik":
        from symkin.bench.ik import format_table1, run_table1

        result = run_table1(
            _robot(args, "ur5"),
            n_problems=args.problems or 10_000,
            seed=args.seed,
            progress=not args.json,
        )
        print(json.dumps(result, indent=2, default=_jsonable) if args.json else format_table1(result))
        return 0
    from symkin.bench.mmc import format_table1 as format_mmc
    from symkin.bench.mmc import plot_task
    from symkin.bench.mmc import run_table1 as run_mmc
    from symkin.compile import compile as compile_robot

    if spec is None:
        robots: tuple[Any, ...] = ("panda", "lbr_iiwa7", "sawyer")
    else:
        robots = (compile_robot(_robot(args), backend="c"),) if custom else (spec,)
    result = run_mmc(robots=robots, n_tasks=args.problems or 1000, seed=args.seed, progress=not args.json)
    print(json.dumps(result, indent=2, default=_jsonable) if args.json else format_mmc(result))
    if args.plot:
        from symkin.bench.mmc import table1_tasks

        first = robots[0]
        kin = compile_robot(_robot(args, first), backend="c") if isinstance(first, str) else first
        q0, Tep = table1_tasks(kin, 1, np.random.default_rng(args.seed))
        plot_task(kin, q0[0], Tep[0], args.plot, title=f"{kin.name}: RRMC vs MMC (one Table I task)")
        if not args.json:
            print(f"plot written to {args.plot}")
    return 0


def cmd_plot(args: argparse.Namespace) -> int:
    robot = _robot(args)
    if args.q is None:
        q = robot.configs.get("qr", robot.configs["qz"])
    elif args.q.strip() in robot.configs:
        q = robot.configs[args.q.strip()]
    else:
        q = _floats(args.q, "--q", robot.n)
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise UserError("plot needs matplotlib: pip install 'symkin[plot]'") from None
    out = args.output or f"{robot.identifier}.png"
    robot.plot(q, frames=not args.no_frames, ellipsoid=args.ellipsoid, path=out)
    print(f"wrote {out}: {robot.name} at q = {_fmt(q)}")


def _scheduler(args: argparse.Namespace) -> Any:
    return args.scheduler if args.scheduler else None


def _rows(text: str) -> list[int]:
    try:
        return [int(x) for x in text.replace(",", " ").split()]
    except ValueError:
        raise UserError(
            f"--axes must be all, trans, rot or row indices 0-5 such as '0 1 5', not {text!r}"
        ) from None


def cmd_reach(args: argparse.Namespace) -> int:
    from symkin.workspace import reachability
    from symkin.workspace.run import require_scale

    require_scale(_scheduler(args))  # before compiling: say which extra is missing at once
    robot = _robot(args)
    bounds = None if args.bounds is None else _floats(args.bounds, "--bounds", 6).reshape(3, 2)
    axes: Any = args.axes if args.axes in ("all", "trans", "rot") else _rows(args.axes)
    ik_options = {"slimit": args.slimit, "ilimit": args.ilimit}
    rmap = reachability(
        robot, args.resolution, args.orientations, output=args.output, seed=args.seed,
        solutions=args.solutions, axes=axes, bounds=bounds, radius=args.radius, chunk=args.chunk,
        backend=args.backend, ik_options=ik_options, scheduler=_scheduler(args), workers=args.workers,
        overwrite=args.overwrite,
    )  # fmt: skip
    inside = rmap.reach > 0
    st = rmap.stats or {}
    summary = {
        "output": args.output,
        "shape": list(rmap.reach.shape),
        "orientations": len(rmap.rotations),
        "reachable_voxels": int(inside.sum()),
        "mean_reach_of_reachable": float(rmap.reach[inside].mean()) if inside.any() else 0.0,
        "max_manipulability": float(np.nanmax(rmap.manipulability)) if inside.any() else None,
        "blocks": int(st.get("blocks", 0)), "computed": int(st.get("computed", 0)),
        "skipped": int(st.get("skipped", 0)), "damaged": int(st.get("damaged", 0)),
        "seconds": float(st.get("seconds", 0.0)), "problems": int(st.get("problems", 0)),
    }  # fmt: skip
    if args.plot:
        rmap.plot(args.plot, axis=args.slice_axis, at=args.slice_at)
        summary["plot"] = args.plot
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    x, y, z = rmap.reach.shape
    K = len(rmap.rotations)
    print(f"{robot.name}: {x}x{y}x{z} voxels of {rmap.resolution:g} m, {K} orientations -> {args.output}")
    done, skipped = summary["computed"], summary["skipped"]
    print(f"blocks: {done} computed{_damaged(summary)}, {skipped} already written, of {summary['blocks']}")
    if summary["computed"]:
        rate = summary["problems"] / max(summary["seconds"], 1e-9)
        print(f"{summary['problems']} IK problems in {summary['seconds']:.1f} s ({rate:,.0f} per second)")
    best = summary["max_manipulability"] or 0.0
    print(
        f"reachable voxels: {summary['reachable_voxels']} (mean reachability index "
        f"{summary['mean_reach_of_reachable']:.3f}); best manipulability {best:.4g}"
    )
    if args.plot:
        print(f"plot written to {args.plot}")
    return 0


def cmd_dataset(args: argparse.Namespace) -> int:
    from symkin.workspace import samples
    from symkin.workspace.run import require_scale

    require_scale(_scheduler(args))
    robot = _robot(args)
    ds = samples(
        robot, args.n, output=args.output, seed=args.seed, chunk=args.chunk, backend=args.backend,
        scheduler=_scheduler(args), workers=args.workers, overwrite=args.overwrite,
    )  # fmt: skip
    st = ds.stats or {}
    summary = {"output": args.output, "samples": len(ds), "blocks": int(st.get("blocks", 0)),
               "computed": int(st.get("computed", 0)), "skipped": int(st.get("skipped", 0)),
               "damaged": int(st.get("damaged", 0)), "seconds": float(st.get("seconds", 0.0))}  # fmt: skip
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(f"{robot.name}: {len(ds)} (q, pose) samples -> {args.output} (arrays q {tuple(ds.q.shape)}, "
              f"pose {tuple(ds.pose.shape)})")  # fmt: skip
        print(f"blocks: {summary['computed']} computed{_damaged(summary)}, {summary['skipped']} already "
              f"written, in {summary['seconds']:.1f} s")  # fmt: skip
    return 0


def _damaged(summary: dict) -> str:
    """`` (2 of them damaged)``: written blocks computed again because a chunk could not be read."""
    return f" ({summary['damaged']} of them damaged)" if summary["damaged"] else ""


def _jsonable(x: Any) -> Any:
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(f"not JSON serialisable: {type(x).__name__}")


# ----------------------------------------------------------------------------------------------
def _robot_argument(s: argparse.ArgumentParser, default: str | None = None) -> None:
    """The ROBOT argument (optional when ``default`` describes what it defaults to) and --tool/--base."""
    if default is None:
        s.add_argument("robot", metavar="ROBOT", help=ROBOT_HELP)
    else:
        s.add_argument("robot", metavar="ROBOT", nargs="?", default=None, help=f"{ROBOT_HELP} ({default})")
    s.add_argument(
        "--tool",
        metavar="T",
        help="append this constant transform after the end effector: " + TRANSFORM_HELP,
    )
    s.add_argument(
        "--base",
        metavar="T",
        help="place this constant transform before the first link: " + TRANSFORM_HELP,
    )


class _Parser(argparse.ArgumentParser):
    """argparse with symkin's one-line errors (``symkin: error: ...``, exit 2)."""

    def error(self, message: str) -> Any:  # type: ignore[override]
        self.exit(
            2, f"symkin: error: {self.prog.split(' ', 1)[-1] + ': ' if ' ' in self.prog else ''}{message}\n"
        )


def build_parser() -> argparse.ArgumentParser:
    from symkin import __version__
    from symkin.cli_tree import add_link_options, cmd_list_frames

    p = _Parser(
        prog="symkin",
        description="symkin: a symbolic, code-generating kinematics compiler for robot manipulators.",
        epilog="ROBOT is " + ROBOT_HELP + ". Run `symkin COMMAND --help` for the options of a command.",
        formatter_class=_Formatter,
    )
    p.add_argument("--version", action="version", version=f"symkin {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)

    def command(name: str, text: str) -> argparse.ArgumentParser:
        return sub.add_parser(name, help=text, description=text, formatter_class=_Formatter)

    robot_argument = _robot_argument
    backends = ("c", "numpy", "casadi")
    s = command("list", "list the built-in robots")
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(func=cmd_list)

    s = command("compile", "generate (and build) the kinematics code of a robot")
    robot_argument(s)
    s.add_argument("--backend", choices=backends, default="c", help="code to generate")
    s.add_argument(
        "-o",
        "--output",
        metavar="DIR",
        help="write the generated files into DIR (symkin.load_compiled reads them)",
    )
    s.add_argument(
        "--prefix",
        "--name",
        metavar="PREFIX",
        help="C: start every exported symbol and file name with PREFIX (default symkin_<robot>), so the "
        "code of several robots links into one program",
    )
    s.add_argument(
        "--precision",
        choices=("double", "float"),
        default="double",
        help="C: float writes single-precision code for microcontrollers (checked against double; "
        "no Python module) (default double)",
    )
    s.add_argument(
        "--libm",
        action="store_true",
        help="C: call the C library's sin and cos instead of the inline kernels (the same as compiling "
        "with -DSYMKIN_USE_LIBM)",
    )
    s.add_argument(
        "--strategy",
        choices=("expanded", "program"),
        help="how the code is derived: expanded (one expression per output, then CSE) or program "
        "(named link frames, linear in the chain); default: chosen by size",
    )
    add_link_options(s, frames=True)
    s.set_defaults(func=cmd_compile)

    s = command("list-frames", "print the link tree of a URDF (joints, links, leaves)")
    s.add_argument("urdf", metavar="URDF", help="a URDF file")
    s.add_argument("--base-link", metavar="LINK", help="start at this link (default the root)")
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(func=cmd_list_frames)

    s = command("generate", "regenerate the checked-in code of the built-in robots under generated/")
    s.add_argument("-o", "--output", default="generated", metavar="DIR", help="folder to write")
    s.add_argument("--check", action="store_true", help="only report out-of-date files (exit 1 if any)")
    s.set_defaults(func=cmd_generate)

    s = command("check", "compare every backend with the numeric reference and finite differences")
    robot_argument(s)
    s.add_argument(
        "--backend",
        action="append",
        choices=backends,
        help="only this backend (repeat for several; default all)",
    )
    s.add_argument("--samples", type=_at_least_1, default=20, help="random configurations")
    s.add_argument("--seed", type=int, default=0, help="seed of the random configurations")
    s.add_argument("--json", action="store_true", help="print the table as JSON")
    add_link_options(s, frames=True)
    s.set_defaults(func=cmd_check)

    s = command("derive", "write the derivation of FK, Jacobian and Hessian (Markdown or LaTeX)")
    robot_argument(s)
    s.add_argument("--format", choices=("markdown", "latex"), default="markdown", help="output format")
    s.add_argument("--symbolic-constants", action="store_true", help="keep link lengths as named symbols")
    s.add_argument("--no-simplify", action="store_true", help="show the literal products of eqs 1, 5, 26-28")
    s.add_argument(
        "--ik", action="store_true", help="write the closed-form inverse kinematics derivation instead"
    )
    s.add_argument(
        "--form",
        choices=("auto", "expanded", "program"),
        default="auto",
        help="expanded: every result multiplied out; program: link frame by link frame with named "
        "intermediates; auto: program when the expanded form is too large to read",
    )
    s.add_argument(
        "--sections",
        metavar="LIST",
        help="only these parts, comma-separated, e.g. fk,jacobian (names: ets, transforms, links, fk, "
        "derivatives, jacobian, hessian, checks; default all)",
    )
    s.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of printing")
    add_link_options(s, frames=True)
    s.set_defaults(func=cmd_derive)

    def target_options(s: argparse.ArgumentParser, q0_help: str) -> None:
        s.add_argument("--pose", metavar="'X Y Z R P Y'", help="target position (m) and roll pitch yaw (rad)")
        s.add_argument("--matrix", metavar="'16 NUMBERS'", help="target pose as a row-major 4x4 matrix")
        s.add_argument(
            "--target-q", metavar="'Q...'", help="target = the pose of the robot at these joint values"
        )
        s.add_argument(
            "--from-q", dest="target_q", action=_Deprecated, new="--target-q", help=argparse.SUPPRESS
        )
        s.add_argument("--backend", choices=backends, default="c", help="kinematics backend")
        s.add_argument("--q0", metavar="'Q...'", help=q0_help)
        s.add_argument("--json", action="store_true", help="print JSON")
        add_link_options(s)

    s = command("ik", "solve inverse kinematics for one target pose")
    robot_argument(s)
    target_options(s, "first start of the search (default: random within the joint limits)")
    s.add_argument("--method", choices=("NR", "GN", "LM", "analytic"), default="LM", help="solver")
    s.add_argument(
        "--all", action="store_true", help="print every closed-form solution (arms with a closed form)"
    )
    s.add_argument("--no-limits", action="store_true", help="--all: keep solutions outside the joint limits")
    s.add_argument(
        "--damping",
        choices=("wampler", "chan", "sugihara"),
        help="LM damping (default chan: lambda E_k, eq 50 of Manipulator Differential Kinematics, Part 1)",
    )
    s.add_argument(
        "--we",
        metavar="W",
        help="task weights: 'position' (position only), 'orientation', or six weights >= 0 for "
        "vx vy vz wx wy wz (default all 1)",
    )
    s.add_argument("--lam", type=_positive, help="damping lambda of LM (default 0.1)")
    s.add_argument("--tol", type=_positive, help="converged when |e| < TOL (default 1e-6: 1 um, 1 urad)")
    s.add_argument("--ilimit", type=_at_least_1, help="iterations per search (default 30)")
    s.add_argument("--slimit", type=_at_least_1, help="searches from random starts (default 100)")
    s.add_argument("--seed", type=int, default=0, help="seed of the random restarts")
    s.set_defaults(func=cmd_ik)

    s = command("servo", "servo to a target pose with RRMC or MMC, optionally plotting")
    robot_argument(s)
    target_options(s, "start configuration (default: the ready pose qr, else qz)")
    s.add_argument(
        "--controller",
        choices=("mmc", "rrmc"),
        default="mmc",
        help="manipulability-maximising or plain resolved rate",
    )
    s.add_argument("--dt", type=_positive, default=0.05, help="control period (s)")
    s.add_argument("--max-steps", type=_int_at_least(0), default=500, help="give up after this many steps")
    s.add_argument("--joint-limits", action="store_true", help="MMC: velocity dampers keep joints in limits")
    s.add_argument("--plot", metavar="PNG", help="write manipulability and error against time")
    s.set_defaults(func=cmd_servo)

    s = command("plot", "draw a robot (links, joint frames, optionally the velocity ellipsoid) to a PNG")
    robot_argument(s)
    s.add_argument(
        "--q", metavar="'Q...'", help="joint values, or a configuration name like qr (default qr, else qz)"
    )
    s.add_argument("-o", "--output", metavar="PNG", help="file to write (default <robot>.png)")
    s.add_argument(
        "--ellipsoid", action="store_true", help="draw the manipulability ellipsoid of linear velocity"
    )
    s.add_argument("--no-frames", action="store_true", help="draw only the base and end-effector frames")
    s.set_defaults(func=cmd_plot)

    s = command(
        "bench",
        "benchmarks: kin (per call, batched; with trees), tree (the tree rows alone), ik (Table 1), "
        "mmc (Table I), calls (one at a time), compile (cold, by chain length), urdf (every chain of "
        "example-robot-data), reach (Dask maps)",
    )
    s.add_argument(
        "what",
        choices=("kin", "tree", "ik", "mmc", "calls", "compile", "urdf", "reach"),
        help="which benchmark",
    )
    robot_argument(
        s,
        "default: panda for kin and compile, ur5 for ik and reach, the paper's three for mmc, ur5 and "
        "panda for calls",
    )
    s.add_argument(
        "--robot", dest="robot_option", action=_Deprecated, new="the ROBOT argument", help=argparse.SUPPRESS
    )
    s.add_argument("--joints", default="6,12,24,36", help="compile: joint counts of the random chains")
    s.add_argument("--batch", type=_at_least_1, default=100_000, help="kin: batch size")
    s.add_argument(
        "-n",
        "--problems",
        type=_at_least_1,
        help="ik: problems (default 10000; 1000 with --analytic); mmc: tasks per robot (default 1000); "
        "urdf: at most N chains (default all)",
    )
    s.add_argument("--seed", type=int, default=0, help="seed of the random problems")
    s.add_argument(
        "--plot",
        metavar="PNG",
        help="mmc: a Fig. 3 style plot of one task; compile: time and ops against joints; urdf: compile time "
        "against joints",
    )
    s.add_argument("--analytic", action="store_true", help="ik: closed-form IK against EAIK and sampling")
    s.add_argument(
        "--starts", type=_at_least_1, default=32, help="ik --analytic: LM searches per pose for sampling"
    )
    s.add_argument("--resolution", type=_positive, default=0.1, help="reach: voxel edge, m (default 0.1)")
    s.add_argument(
        "--orientations", type=_at_least_1, default=50, help="reach: orientations per voxel (default 50)"
    )
    s.add_argument("--fault", action="store_true", help="reach: also kill a worker mid-run and compare")
    s.add_argument(
        "--repeat", type=_at_least_1, default=3, help="reach: runs of each measurement (best is kept)"
    )
    s.add_argument("--no-cold", action="store_true", help="kin, tree: skip the cold compile of each tree")
    s.add_argument(
        "--backends", default="c,numpy,casadi", help="urdf: backends to compile each chain on (default all)"
    )
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(func=cmd_bench, robot_option=None)

    add_workspace_commands(sub)
    return p


def add_workspace_commands(sub: Any) -> None:
    """``symkin reach`` and ``symkin dataset`` (the ``scale`` extra)."""

    def scale_options(s: argparse.ArgumentParser) -> None:
        s.add_argument("--seed", type=int, default=0, help="seed of the random orientations and samples")
        s.add_argument(
            "--scheduler",
            metavar="ADDRESS",
            help="a Dask scheduler such as tcp://host:8786, or 'synchronous' (default: a local cluster)",
        )
        s.add_argument(
            "--workers", type=_at_least_1, help="local cluster size (default: one worker per core)"
        )
        s.add_argument("--backend", choices=("c", "numpy", "casadi"), default="c", help="kinematics backend")
        s.add_argument("--overwrite", action="store_true", help="replace the store instead of resuming it")
        s.add_argument("--json", action="store_true", help="print JSON")

    text = "reachability and manipulability map of the workspace (Zarr, on Dask)"
    s = sub.add_parser("reach", help=text, description=text, formatter_class=_Formatter)
    _robot_argument(s)
    s.add_argument("--resolution", type=_positive, default=0.05, help="voxel edge in metres (default 0.05)")
    s.add_argument("--orientations", type=_at_least_1, default=50, help="orientations per voxel (default 50)")
    s.add_argument("-o", "--output", required=True, metavar="STORE", help="the Zarr store, e.g. map.zarr")
    s.add_argument("--chunk", type=_at_least_1, help="voxels per block edge (default: 16..4, >= 64 blocks)")
    s.add_argument("--solutions", action="store_true", help="also store one solution per orientation")
    s.add_argument("--axes", default="all", help="manipulability rows: all, trans, rot or indices '0 1 5'")
    s.add_argument("--bounds", metavar="'XMIN XMAX YMIN YMAX ZMIN ZMAX'", help="only voxels in this box (m)")
    s.add_argument(
        "--radius", type=_positive, help="radius of the mapped ball (default: sum of link lengths)"
    )
    s.add_argument("--slimit", type=_at_least_1, default=10, help="IK searches per target (default 10)")
    s.add_argument("--ilimit", type=_at_least_1, default=30, help="IK iterations per search (default 30)")
    s.add_argument("--plot", metavar="PNG", help="write a slice of the map (reachability, manipulability)")
    s.add_argument("--slice-axis", choices=("x", "y", "z"), default="z", help="plot: axis of the slice")
    s.add_argument("--slice-at", type=float, help="plot: coordinate of the slice (default: the centre)")
    scale_options(s)
    s.set_defaults(func=cmd_reach)

    text = "a (q, pose) dataset for learning (Zarr, on Dask)"
    s = sub.add_parser("dataset", help=text, description=text, formatter_class=_Formatter)
    _robot_argument(s)
    s.add_argument("-n", type=_at_least_1, required=True, help="number of samples (more than stored appends)")
    s.add_argument("-o", "--output", required=True, metavar="STORE", help="the Zarr store, e.g. data.zarr")
    s.add_argument("--chunk", type=_at_least_1, default=65536, help="samples per block (default 65536)")
    scale_options(s)
    s.set_defaults(func=cmd_dataset)


def main(argv: Sequence[str] | None = None) -> int:
    """Run one symkin command; returns the exit status (see the module docstring).

    The output is flushed here, inside the guard, not by the interpreter at exit: an output that
    cannot be written (a full disk, ``> /dev/full``) is an error of one line and status 2 like any
    other, not a success with nothing written or "Exception ignored" and status 120.
    """
    stdout = sys.stdout
    if stdout is not None:
        sys.stdout = _Output(stdout)
    try:
        code = _run(argv)
        if sys.stdout is not None:
            sys.stdout.flush()
        return code
    except BrokenPipeError:  # `symkin ... | head`: the reader left; stop quietly like other tools
        _silence_stdout()
        return 141  # 128 + SIGPIPE, what a shell reports for a command ended by a closed pipe
    except _OutputError as exc:
        _silence_stdout()
        _say(f"symkin: error: cannot write the output: {exc.cause.strerror or exc.cause}")
        return 2
    finally:
        if isinstance(sys.stdout, _Output):
            sys.stdout = stdout


def _run(argv: Sequence[str] | None) -> int:
    from symkin.errors import SymkinError

    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # --help, --version, or a one-line usage error (exit 2)
        return exc.code if isinstance(exc.code, int) else 2
    try:
        return int(args.func(args) or 0)
    except (BrokenPipeError, _OutputError):
        raise
    except (UserError, SymkinError, ValueError, OSError) as exc:
        message = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        _say(f"symkin: error: {message}")
        return 2
    except KeyboardInterrupt:
        _say("symkin: interrupted")
        return 130


class _OutputError(Exception):
    """The output (stdout) could not be written; ``cause`` is the OSError."""

    def __init__(self, cause: OSError) -> None:
        super().__init__(str(cause))
        self.cause = cause


class _Output:
    """``sys.stdout`` while a command runs: a failed write raises _OutputError, told apart from the
    command's own OSErrors (a file it cannot write); a closed pipe stays a BrokenPipeError."""

    def __init__(self, stream: Any) -> None:
        self._stream = stream

    def write(self, text: str) -> int:
        return self._guard(self._stream.write, text)

    def writelines(self, lines: Any) -> None:
        self._guard(self._stream.writelines, lines)

    def flush(self) -> None:
        self._guard(self._stream.flush)

    def __getattr__(self, name: str) -> Any:
        return getattr(self._stream, name)

    @staticmethod
    def _guard(fn: Any, *args: Any) -> Any:
        try:
            return fn(*args)
        except BrokenPipeError:
            raise
        except OSError as exc:
            raise _OutputError(exc) from exc


def _say(line: str) -> None:
    """One line on stderr; a stderr that cannot be written either is ignored (nowhere to report)."""
    with contextlib.suppress(OSError, ValueError, AttributeError):
        sys.stderr.write(line + "\n")
        sys.stderr.flush()


def _silence_stdout() -> None:
    """Point stdout at /dev/null so the interpreter's final flush does not fail again."""
    import os

    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError, AttributeError):  # stdout without a file descriptor (captured, None)
        pass


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
