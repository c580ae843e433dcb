"""``symkin bench WHAT``: the benchmarks (kin, tree, ik, mmc, qrmc, calls, sincos, compile, urdf, reach,
collide, meshes, diff)."""

from __future__ import annotations

import argparse
import json
from typing import Any

import numpy as np

from symkin.cli.checks import UserError, at_least_1, check_cflags_for, need_matplotlib, positive_float
from symkin.cli.common import (
    Deprecated,
    add_command,
    add_robot_argument,
    add_srdf_option,
    single_chain,
    transformed,
    with_srdf,
)

__all__ = ["add_parser", "run"]

#: the benchmarks ``symkin bench`` runs
BENCHMARKS = (
    *("kin", "tree", "ik", "mmc", "qrmc", "calls", "sincos"),
    *("compile", "urdf", "reach", "collide", "meshes", "diff"),
)


def add_parser(sub: Any) -> None:
    s = add_command(
        sub,
        "bench",
        "benchmarks: kin (per call, batched; with trees), tree (the tree rows alone), ik (Table 1), "
        "mmc (Table I), qrmc (QRMC vs RRMC at singularities), calls (one at a time), sincos (the C "
        "sin/cos against glibc's), compile (cold, by "
        "chain length), urdf (every chain of "
        "example-robot-data), reach (Dask maps), collide (collision checks, collision-aware IK), meshes "
        "(the covering sphere model against Pinocchio + coal on the real meshes), diff (the JAX and "
        "PyTorch backends against pytorch_kinematics)",
    )
    s.add_argument(
        "what",
        choices=BENCHMARKS,
        help="which benchmark",
    )
    add_robot_argument(
        s,
        "default: panda for kin, sincos, compile, collide, meshes and diff, ur5 for ik and reach, the "
        "paper's three for mmc, ur5 and panda for calls",
    )
    s.add_argument(
        "--robot", dest="robot_option", action=Deprecated, new="the ROBOT argument", help=argparse.SUPPRESS
    )
    s.add_argument("--joints", default="6,12,24,36", help="compile: joint counts of the random chains")
    s.add_argument(
        "--derivatives",
        type=int,
        choices=(0, *range(3, 9)),
        default=0,
        metavar="K",
        help="compile: also each robot with the derivatives of orders 3..K (K in 3..8), side by side",
    )
    s.add_argument(
        "--batch", type=at_least_1, default=None, help="kin: batch size (default 100000); collide: (20000)"
    )
    s.add_argument(
        "-n",
        "--problems",
        type=at_least_1,
        help="ik: problems (default 10000; 1000 with --analytic); mmc: tasks per robot (default 1000); "
        "qrmc: random tasks on the UR5 and the Panda besides the singular ones (default 0); urdf: at most "
        "N chains (default all); meshes: uniform configurations of each kind (default 100000); diff: IK "
        "targets (default 1024)",
    )
    s.add_argument("--seed", type=int, default=0, help="seed of the random problems")
    s.add_argument(
        "--plot",
        metavar="PNG",
        help="mmc: a Fig. 3 style plot of one task; qrmc: manipulability, joint speeds and error of two "
        "singular tasks; compile: time and ops against joints; urdf: compile time against joints",
    )
    s.add_argument("--analytic", action="store_true", help="ik: closed-form IK against EAIK and sampling")
    s.add_argument(
        "--starts", type=at_least_1, default=32, help="ik --analytic: LM searches per pose for sampling"
    )
    s.add_argument(
        "--resolution", type=positive_float, default=0.1, help="reach: voxel edge, m (default 0.1)"
    )
    s.add_argument(
        "--orientations", type=at_least_1, default=50, help="reach: orientations per voxel (default 50)"
    )
    s.add_argument("--fault", action="store_true", help="reach: also kill a worker mid-run and compare")
    s.add_argument(
        "--repeat", type=at_least_1, default=3, help="reach: runs of each measurement (best is kept)"
    )
    s.add_argument("--no-cold", action="store_true", help="kin, tree: skip the cold compile of each tree")
    s.add_argument(
        "--backends", default="c,numpy,casadi", help="urdf: backends to compile each chain on (default all)"
    )
    add_srdf_option(s, " (collide)")
    s.add_argument(
        "--build",
        action="store_true",
        help="collide: also the cold build of a 300-sphere model of ROBOT (its self pairs as tables)",
    )
    s.add_argument(
        "--unrolled",
        action="store_true",
        help="collide --build: also that model as straight-line code (minutes)",
    )
    s.add_argument(
        "--batches",
        default="1,1024,100000",
        help="diff: batch sizes, comma separated (default 1,1024,100000)",
    )
    s.add_argument(
        "--no-torch-compile", action="store_true", help="diff: skip torch.compile (slow to compile)"
    )
    s.add_argument("--json", action="store_true", help="print JSON")
    s.set_defaults(func=run, robot_option=None)


def run(args: argparse.Namespace) -> int:
    if args.robot is None:
        args.robot = args.robot_option
    custom = transformed(args)
    if custom and args.robot is None:
        raise UserError("--tool/--base change a ROBOT: name one (symkin bench WHAT ROBOT --tool ...)")
    check_cflags_for("c")
    if args.plot and args.what not in ("mmc", "qrmc", "compile", "urdf"):
        raise UserError(f"--plot is for `symkin bench mmc`, `qrmc`, `compile` and `urdf`, not `{args.what}`")
    for option in ("srdf", "build", "unrolled"):
        if getattr(args, option) and args.what != "collide":
            raise UserError(f"--{option} is for `symkin bench collide`, not `{args.what}`")
    if args.unrolled and not args.build:
        raise UserError("--unrolled goes with --build")
    if args.derivatives and args.what != "compile":
        raise UserError(f"--derivatives is for `symkin bench compile`, not `{args.what}`")
    if args.what in ("tree", "urdf") and args.robot is not None:
        raise UserError(f"bench {args.what} measures its own robots; it takes no ROBOT")
    need_matplotlib(args.plot)
    if args.what == "compile":
        from symkin.bench.compile import format_compile, format_derivatives, plot_compile, run_compile

        if custom:
            raise UserError(
                "bench compile measures ROBOT by name in a fresh process; --tool/--base do not apply"
            )
        joints = _counts(args.joints, "--joints", "joint counts between 1 and 200 like '6,12,24,36'", 200)
        rows = run_compile(
            joints,
            seed=args.seed,
            reference=args.robot or "panda",
            progress=not args.json,
            derivatives=args.derivatives,
        )
        table = format_derivatives(rows) if args.derivatives >= 3 else format_compile(rows)
        _show(args, rows, lambda _: table)
        if args.plot:
            plot_compile(rows, args.plot)
            if not args.json:
                print(f"plot written to {args.plot}")
        return 0
    if args.what == "qrmc":
        return _qrmc(args)
    spec: Any = single_chain(args) if custom else args.robot
    if args.what == "calls":
        from symkin.bench.calls import format_calls, run_calls

        result = run_calls(spec or "ur5", spec or "panda", seed=args.seed, progress=not args.json)
        _show(args, result, format_calls)
        return 0
    if args.what == "sincos":
        from symkin.bench.sincos import format_sincos, run_sincos

        result = run_sincos(spec or "panda", seed=args.seed, progress=not args.json)
        _show(args, result, format_sincos)
        return 0
    if args.what == "reach":
        from symkin.bench.reach import format_reach, run_reach
        from symkin.workspace.run import require_scale

        require_scale()
        result = run_reach(
            single_chain(args, "ur5"), resolution=args.resolution, orientations=args.orientations,
            seed=args.seed, fault=args.fault, progress=not args.json, repeat=args.repeat,
        )  # fmt: skip
        _show(args, result, format_reach)
        return 0
    if args.what == "collide":
        from symkin.bench.collide import format_collide, run_collide

        robot = with_srdf(args, single_chain(args, "panda", geometry=True))
        result = run_collide(robot, batch=args.batch or 20_000, seed=args.seed, progress=not args.json)
        if not args.json:
            print(format_collide(result), flush=True)
        if args.build:
            from symkin.bench.collide_build import format_build, run_build

            result["build"] = run_build(robot, seed=args.seed, unrolled=args.unrolled)
            if not args.json:
                print("\n" + format_build(result["build"]))
        if args.json:
            print(json.dumps(result, indent=2, default=_jsonable))
        return 0
    if args.what == "meshes":
        from symkin.bench.meshes import format_meshes, run_meshes

        if custom:
            raise UserError(
                "bench meshes compares a built-in robot's stored model; --tool/--base do not apply"
            )
        result = run_meshes(args.robot or "panda", n=args.problems or 100_000, seed=args.seed)
        _show(args, result, format_meshes)
        missed = sum(
            result[k]["counts"]["coal_only"] + result[k]["counts"]["near_coal_only"]
            for k in ("self", "obstacles")
        )
        return 1 if missed else 0
    if args.what == "diff":
        return _diff(args)
    if args.what == "kin":
        from symkin.bench.kin import format_kin, run_kin

        result = run_kin(spec or "panda", batch=args.batch or 100_000, progress=not args.json)
        if not args.json:
            print(format_kin(result), flush=True)
        result["trees"] = _trees(args)
        _show(args, result)
        return 0
    if args.what in ("tree", "urdf"):
        code, result = (0, _trees(args)) if args.what == "tree" else _urdf(args)
        _show(args, result)
        return code
    if args.what == "ik" and args.analytic:
        from symkin.bench.analytic_ik import format_analytic, run_analytic

        robots = (spec,) if spec is not None else ("ur5", "ur10", "puma560", "stanford")
        result = run_analytic(
            robots, n=args.problems or 1000, starts=args.starts, seed=args.seed, progress=not args.json
        )
        _show(args, result, format_analytic)
        return 0
    if args.what == "ik":
        from symkin.bench.ik import format_table1, run_table1

        result = run_table1(
            single_chain(args, "ur5"),
            n_problems=args.problems or 10_000,
            seed=args.seed,
            progress=not args.json,
        )
        _show(args, result, format_table1)
        return 0
    from symkin.bench import mmc
    from symkin.runtime.load import compile as compile_robot

    if spec is None:
        robots: tuple[Any, ...] = ("panda", "lbr_iiwa7", "sawyer")
    else:
        robots = (compile_robot(single_chain(args), backend="c"),) if custom else (spec,)
    result = mmc.run_table1(
        robots=robots, n_tasks=args.problems or 1000, seed=args.seed, progress=not args.json
    )
    _show(args, result, mmc.format_table1)
    if args.plot:
        first = robots[0]
        kin = compile_robot(single_chain(args, first), backend="c") if isinstance(first, str) else first
        q0, Tep = mmc.table1_tasks(kin, 1, np.random.default_rng(args.seed))
        mmc.plot_task(kin, q0[0], Tep[0], args.plot, title=f"{kin.name}: RRMC vs MMC (one Table I task)")
        if not args.json:
            print(f"plot written to {args.plot}")
    return 0


def _qrmc(args: argparse.Namespace) -> int:
    """``symkin bench qrmc``: the UR5's singular tasks (and -n random tasks on the UR5 and the Panda)."""
    from symkin.bench import qrmc
    from symkin.runtime.load import compile as compile_robot

    if args.robot is not None or transformed(args):
        raise UserError("bench qrmc runs its own UR5 tasks (and the Panda's with -n); it takes no ROBOT")
    ur5 = compile_robot("ur5", backend="c")
    res = qrmc.run_singular(ur5, progress=not args.json, keep=bool(args.plot))
    runs = res.pop("runs", None)
    random = [
        qrmc.run_random(compile_robot(name, backend="c"), args.problems, args.seed, progress=not args.json)
        for name in (("ur5", "panda") if args.problems else ())
    ]
    out = {"singular": res, "random": random}
    _show(args, out, lambda _: qrmc.format_singular(res, random))
    if args.plot:
        qrmc.plot_singular({k: runs[k] for k in qrmc.PLOTTED}, ur5.qd_max, args.plot)
        if not args.json:
            print(f"plot written to {args.plot}")
    return 0


def _counts(text: str, option: str, what: str, most: int | None = None) -> tuple[int, ...]:
    """The whole numbers from 1 (to ``most``) of ``option``, separated by commas or spaces
    (``what``: what they must be, with an example)."""
    try:
        counts = tuple(int(x) for x in text.replace(",", " ").split())
    except ValueError:
        counts = ()
    if not counts or min(counts) < 1 or (most is not None and max(counts) > most):
        raise UserError(f"{option} must be {what}, not {text!r}")
    return counts


def _trees(args: argparse.Namespace) -> dict:
    """The tree rows of ``bench kin`` / ``bench tree`` (printed unless --json)."""
    from symkin.bench.tree import format_tree_kin, run_tree_kin

    trees = run_tree_kin(batch=args.batch or 100_000, seed=args.seed, cold=not args.no_cold)
    if not args.json:
        print(format_tree_kin(trees))
    return trees


def _urdf(args: argparse.Namespace) -> tuple[int, dict]:
    """``symkin bench urdf``: (exit code, result); the table printed unless --json."""
    from symkin.bench.urdf_sweep import format_sweep, plot_sweep, run_sweep

    sweep = run_sweep(backends=tuple(args.backends.split(",")), progress=not args.json, limit=args.problems)
    if not args.json:
        print(format_sweep(sweep))
    if args.plot and "rows" in sweep:
        plot_sweep(sweep, args.plot)
        if not args.json:
            print(f"plot written to {args.plot}")
    return (0 if sweep["ok"] else 1), sweep


def _show(args: argparse.Namespace, result: Any, text: Any = None) -> None:
    """``result`` as JSON with --json, else ``text(result)`` (nothing when there is no ``text``:
    the tables were printed as they came)."""
    print(json.dumps(result, indent=2, default=_jsonable) if args.json else text(result) if text else "")


def _jsonable(x: Any) -> Any:
    if isinstance(x, (np.ndarray, np.generic)):
        return x.tolist()
    raise TypeError(f"not JSON serialisable: {type(x).__name__}")


def _diff(args: argparse.Namespace) -> int:
    """``symkin bench diff``: the JAX and PyTorch backends against pytorch_kinematics."""
    from symkin.bench.diff import format_diff, run_diff

    batches = _counts(args.batches, "--batches", "positive batch sizes like '1,1024,100000'")
    report = run_diff(
        single_chain(args, "panda"), batches=batches, problems=args.problems or 1024, seed=args.seed,
        compile_torch=not args.no_torch_compile, progress=not args.json,
    )  # fmt: skip
    _show(args, report.as_dict(), lambda _: format_diff(report))
    return 0
