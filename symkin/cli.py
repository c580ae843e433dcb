"""The ``symkin`` command.

Every command that takes a ROBOT accepts a built-in name (``panda``), an ETS string in quotes
(``"Rz(q) tx(1) Rz(q) tx(1)"``), a DH table file or a URDF file, ``path.urdf:FRAME`` for the
chain to one link and ``--base-link/--end-link``; ``compile``, ``check`` and ``derive`` take a
whole tree with ``--frames a,b,c`` (a branching URDF without a frame is a tree of its leaves).
User mistakes print one line ``symkin: error: ...`` and exit with status 2; a failed check or an
unsolved problem exits 1.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["main"]

ROBOT_HELP = (
    "a built-in robot name (see `symkin list`), a quoted ETS string, a DH table file, a URDF file or "
    "path.urdf:FRAME (the chain to link FRAME)"
)


class UserError(Exception):
    """A mistake in the command line; printed as one line."""


def _robot(spec: str) -> Any:
    from symkin.model.resolve import resolve_robot

    return resolve_robot(spec)


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
    if isinstance(robot, Tree):
        return compile_tree_report(robot, args.backend, args.output)
    t0 = time.perf_counter()
    command = f"symkin compile {robot.identifier} --backend {args.backend}"
    files = generate(robot, args.backend, command)
    t_gen = time.perf_counter() - t0
    if args.output:
        out = Path(args.output)
        out.mkdir(parents=True, exist_ok=True)
        for name, text in sorted(files.items()):
            (out / name).write_text(text)
        print(f"wrote {len(files)} files to {out}/: {', '.join(sorted(files))}")
    t1 = time.perf_counter()
    kin = compile_robot(robot, backend=args.backend)
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

    differ = compare_or_update(args.output, update=not args.check, progress=sys.stderr.isatty())
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
    if isinstance(robot, Tree):
        if args.ik:
            raise UserError("--ik derives the closed form of one chain: name it as ROBOT.urdf:FRAME")
        from symkin.derivation_tree import tree_derivation

        text = tree_derivation(robot, fmt=args.format)
    elif args.ik:
        from symkin.derivation_ik import ik_derivation

        text = ik_derivation(robot, fmt=args.format)
    else:
        text = derivation(
            robot,
            fmt=args.format,
            symbolic_constants=args.symbolic_constants,
            simplify=not args.no_simplify,
            form=args.form,
        )
    if args.output:
        Path(args.output).write_text(text)
        print(f"wrote the derivation of {robot.name} to {args.output}")
    else:
        print(text)
    return 0


def _target(args: argparse.Namespace, robot: Any) -> np.ndarray:
    """A target pose from --pose (x y z roll pitch yaw, rad), --matrix (16 numbers) or --from-q."""
    given = [x is not None for x in (args.pose, args.matrix, args.from_q)]
    if sum(given) != 1:
        raise UserError(
            "give exactly one of --pose 'x y z roll pitch yaw', --matrix '16 numbers', --from-q 'q...'"
        )
    if args.from_q is not None:
        return robot.fkine(_floats(args.from_q, "--from-q", robot.n))
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
    from symkin.cli_tree import single_chain
    from symkin.compile import compile as compile_robot

    robot = single_chain(args)
    Tep = _target(args, robot)
    kin = compile_robot(robot, backend=args.backend)
    if args.all or args.method == "analytic":
        return _ik_analytic(args, kin, Tep)
    kwargs: dict[str, Any] = {"method": args.method, "seed": args.seed}
    if args.damping:
        kwargs["damping"] = args.damping
    if args.q0 is not None:
        kwargs["q0"] = _floats(args.q0, "--q0", robot.n)
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


def _ik_analytic(args: argparse.Namespace, kin: Any, Tep: np.ndarray) -> int:
    """``symkin ik --all`` (every closed-form solution) or ``--method analytic`` (the nearest)."""
    q0 = _floats(args.q0, "--q0", kin.n) if args.q0 is not None else None
    t = time.perf_counter()
    if not args.all:
        res = kin.ik(Tep, method="analytic", q0=q0)
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
    from symkin.cli_tree import single_chain
    from symkin.compile import compile as compile_robot
    from symkin.runtime.loop import servo

    robot = single_chain(args)
    Tep = _target(args, robot)
    kin = compile_robot(robot, backend=args.backend)
    q0 = _floats(args.q0, "--q0", robot.n) if args.q0 else robot.configs.get("qr", robot.configs["qz"])
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


def _need_matplotlib() -> None:
    """Fail before a long run when a plot was asked for and matplotlib is missing."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise UserError("--plot needs matplotlib: pip install 'symkin[plot]'") from None


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

    if args.what == "compile":
        from symkin.bench.compile import format_compile, plot_compile, run_compile

        joints = _joint_counts(args.joints)
        if args.plot:
            _need_matplotlib()
        rows = run_compile(joints, seed=args.seed, reference=args.robot or "panda", progress=not args.json)
        print(json.dumps(rows, indent=2) if args.json else format_compile(rows))
        if args.plot:
            plot_compile(rows, args.plot)
            if not args.json:
                print(f"plot written to {args.plot}")
        return 0
    if args.what == "kin":
        from symkin.bench.kin import format_kin, run_kin

        result = run_kin(args.robot or "panda", batch=args.batch, progress=not args.json)
        if not args.json:
            print(format_kin(result), flush=True)
        result["trees"] = bench_trees(args)
        print(json.dumps(result, indent=2, default=_jsonable) if args.json else "")
        return 0
    if args.what in ("tree", "urdf"):
        if args.plot:
            _need_matplotlib()
        code, result = (0, bench_trees(args)) if args.what == "tree" else bench_urdf(args)
        print(json.dumps(result, indent=2, default=_jsonable) if args.json else "")
        return code
    if args.what == "ik" and args.analytic:
        from symkin.bench.analytic_ik import format_analytic, run_analytic

        robots = (args.robot,) if args.robot else ("ur5", "ur10", "puma560", "stanford")
        result = run_analytic(robots, n=args.problems or 1000, starts=args.starts, seed=args.seed)
        print(json.dumps(result, indent=2, default=_jsonable) if args.json else format_analytic(result))
        return 0
    if args.what == "ik":
        from symkin.bench.ik import format_table1, run_table1

        result = run_table1(
            _robot(args.robot or "ur5"),
            n_problems=args.problems or 10_000,
            seed=args.seed,
            progress=not args.json,
        )
        print(json.dumps(result, indent=2, default=_jsonable) if args.json else format_table1(result))
        return 0
    from symkin.bench.mmc import format_table1 as format_mmc
    from symkin.bench.mmc import plot_task
    from symkin.bench.mmc import run_table1 as run_mmc

    robots = (args.robot,) if args.robot else ("panda", "lbr_iiwa7", "sawyer")
    result = run_mmc(robots=robots, n_tasks=args.problems or 1000, seed=args.seed, progress=not args.json)
    print(json.dumps(result, indent=2, default=_jsonable) if args.json else format_mmc(result))
    if args.plot:
        from symkin.bench.mmc import table1_tasks
        from symkin.compile import compile as compile_robot

        kin = compile_robot(_robot(robots[0]), backend="c")
        q0, Tep = table1_tasks(kin, 1, np.random.default_rng(args.seed))
        plot_task(kin, q0[0], Tep[0], args.plot, title=f"{kin.name}: RRMC vs MMC (one Table I task)")
        if not args.json:
            print(f"plot written to {args.plot}")
    return 0


def _jsonable(x: Any) -> Any:
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, np.generic):
        return x.item()
    raise TypeError(f"not JSON serialisable: {type(x).__name__}")


# ----------------------------------------------------------------------------------------------
def build_parser() -> argparse.ArgumentParser:
    from symkin import __version__
    from symkin.cli_tree import add_link_options, cmd_list_frames

    p = argparse.ArgumentParser(
        prog="symkin",
        description="symkin: a symbolic, code-generating kinematics compiler for robot manipulators.",
        epilog="ROBOT is " + ROBOT_HELP + ". Run `symkin COMMAND --help` for the options of a command.",
    )
    p.add_argument("--version", action="version", version=f"symkin {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND", required=True)

    s = sub.add_parser("list", help="list the built-in robots")
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(func=cmd_list)

    s = sub.add_parser("compile", help="generate (and build) the kinematics code of a robot")
    s.add_argument("robot", metavar="ROBOT", help=ROBOT_HELP)
    s.add_argument(
        "--backend", choices=("c", "numpy", "casadi"), default="c", help="code to generate (default c)"
    )
    s.add_argument("-o", "--output", metavar="DIR", help="write the generated files into DIR")
    add_link_options(s, frames=True)
    s.set_defaults(func=cmd_compile)

    s = sub.add_parser("list-frames", help="print the link tree of a URDF (joints, links, leaves)")
    s.add_argument("urdf", metavar="URDF", help="a URDF file")
    s.add_argument("--base-link", metavar="LINK", help="start at this link (default the root)")
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(func=cmd_list_frames)

    s = sub.add_parser(
        "generate", help="regenerate the checked-in code of the built-in robots under generated/"
    )
    s.add_argument("-o", "--output", default="generated", metavar="DIR", help="folder (default generated)")
    s.add_argument("--check", action="store_true", help="only report out-of-date files (exit 1 if any)")
    s.set_defaults(func=cmd_generate)

    s = sub.add_parser(
        "check", help="compare every backend with the numeric reference and finite differences"
    )
    s.add_argument("robot", metavar="ROBOT", help=ROBOT_HELP)
    s.add_argument("--backend", action="append", choices=("c", "numpy", "casadi"), help="only this backend")
    s.add_argument("--samples", type=int, default=20, help="random configurations (default 20)")
    s.add_argument("--seed", type=int, default=0)
    s.add_argument("--json", action="store_true", help="print the table as JSON")
    add_link_options(s, frames=True)
    s.set_defaults(func=cmd_check)

    s = sub.add_parser("derive", help="write the derivation of FK, Jacobian and Hessian (Markdown or LaTeX)")
    s.add_argument("robot", metavar="ROBOT", help=ROBOT_HELP)
    s.add_argument("--format", choices=("markdown", "latex"), default="markdown")
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
        "intermediates; auto (default): program when the expanded form is too large to read",
    )
    s.add_argument("-o", "--output", metavar="FILE", help="write to FILE instead of printing")
    add_link_options(s, frames=True)
    s.set_defaults(func=cmd_derive)

    def target_options(s: argparse.ArgumentParser) -> None:
        s.add_argument("--pose", metavar="'X Y Z R P Y'", help="target position (m) and roll pitch yaw (rad)")
        s.add_argument("--matrix", metavar="'16 NUMBERS'", help="target pose as a row-major 4x4 matrix")
        s.add_argument("--from-q", metavar="'Q...'", help="target = forward kinematics of these joint values")
        s.add_argument("--backend", choices=("c", "numpy", "casadi"), default="c")
        s.add_argument("--q0", metavar="'Q...'", help="start configuration")
        s.add_argument("--json", action="store_true", help="print JSON")
        add_link_options(s)

    s = sub.add_parser("ik", help="solve inverse kinematics for one target pose")
    s.add_argument("robot", metavar="ROBOT", help=ROBOT_HELP)
    target_options(s)
    s.add_argument("--method", choices=("NR", "GN", "LM", "analytic"), default="LM")
    s.add_argument(
        "--all", action="store_true", help="print every closed-form solution (arms with a closed form)"
    )
    s.add_argument("--no-limits", action="store_true", help="--all: keep solutions outside the joint limits")
    s.add_argument("--damping", choices=("wampler", "chan", "sugihara"))
    s.add_argument("--seed", type=int, default=0)
    s.set_defaults(func=cmd_ik)

    s = sub.add_parser("servo", help="servo to a target pose with RRMC or MMC, optionally plotting")
    s.add_argument("robot", metavar="ROBOT", help=ROBOT_HELP)
    target_options(s)
    s.add_argument("--controller", choices=("mmc", "rrmc"), default="mmc")
    s.add_argument("--dt", type=float, default=0.05)
    s.add_argument("--max-steps", type=int, default=500)
    s.add_argument("--joint-limits", action="store_true", help="MMC: velocity dampers keep joints in limits")
    s.add_argument("--plot", metavar="PNG", help="write manipulability and error against time")
    s.set_defaults(func=cmd_servo)

    s = sub.add_parser(
        "bench",
        help="benchmarks: kin (per call, batched; with trees), tree (the tree rows alone), ik (Table 1), "
        "mmc (Table I), compile (cold, by length), urdf (every chain of example-robot-data)",
    )
    s.add_argument("what", choices=("kin", "tree", "ik", "mmc", "compile", "urdf"))
    s.add_argument(
        "--robot",
        help="robot (default: panda for kin and compile, ur5 for ik, the paper's three for mmc)",
    )
    s.add_argument(
        "--joints",
        default="6,12,24,36",
        help="compile: joint counts of the random chains (default 6,12,24,36)",
    )
    s.add_argument("--batch", type=int, default=100_000, help="kin: batch size (default 100000)")
    s.add_argument(
        "-n",
        "--problems",
        type=int,
        help="ik: problems (default 10000); mmc: tasks per robot; urdf: at most N chains",
    )
    s.add_argument("--seed", type=int, default=0)
    s.add_argument(
        "--plot",
        metavar="PNG",
        help="mmc: a Fig. 3 style plot of one task; compile: time and ops against joints; urdf: compile time "
        "against joints",
    )
    s.add_argument("--analytic", action="store_true", help="ik: closed-form IK against EAIK and sampling")
    s.add_argument("--starts", type=int, default=32, help="ik --analytic: LM searches per pose for sampling")
    s.add_argument("--no-cold", action="store_true", help="kin, tree: skip the cold compile of each tree")
    s.add_argument(
        "--backends", default="c,numpy,casadi", help="urdf: backends to compile each chain on (default all)"
    )
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(func=cmd_bench)
    return p


def main(argv: Sequence[str] | None = None) -> int:
    from symkin.errors import SymkinError

    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args) or 0)
    except (UserError, SymkinError, ValueError, FileNotFoundError) as exc:
        message = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        print(f"symkin: error: {message}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("symkin: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
