"""The command line's URDF trees: ``path.urdf:FRAME``, ``--base-link/--end-link``, ``--frames``,
``symkin list-frames`` and the tree variants of ``compile``, ``check`` and ``derive``."""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

__all__ = [
    "split_frame",
    "chain_or_tree",
    "single_chain",
    "add_link_options",
    "cmd_list_frames",
    "compile_tree_report",
]

_URDF = (".urdf", ".xml", ".xacro")  # .xacro: refused by the URDF reader, with how to expand it


class TreeUserError(ValueError):
    """A command-line mistake about URDF frames (the CLI prints it as one line, exit 2)."""


def split_frame(spec: str) -> tuple[str, str | None]:
    """``"robot.urdf:tool0"`` -> ``("robot.urdf", "tool0")``; anything else -> ``(spec, None)``."""
    text = spec.strip()
    if "(" in text:
        return spec, None
    head, sep, tail = text.rpartition(":")
    if sep and tail and "/" not in tail and Path(head).suffix.lower() in _URDF:
        return head, tail
    return spec, None


def _is_urdf(path: str) -> bool:
    return "(" not in path and Path(path.strip()).suffix.lower() in _URDF


def add_link_options(s: argparse.ArgumentParser, frames: bool = False) -> None:
    """``--base-link``, ``--end-link`` (and ``--frames``) for a command taking ROBOT."""
    s.add_argument(
        "--base-link", metavar="LINK", help="URDF: the link poses are expressed in (default the root)"
    )
    s.add_argument("--end-link", metavar="LINK", help="URDF: the chain's last link (same as ROBOT.urdf:LINK)")
    if frames:
        s.add_argument(
            "--frames",
            metavar="A,B,...",
            help="URDF: the links of a tree to compile into one kernel (default: every leaf when the URDF "
            "branches)",
        )


def _end(args: argparse.Namespace, frame: str | None) -> str | None:
    end = getattr(args, "end_link", None)
    if frame and end and frame != end:
        raise TreeUserError(f"ROBOT names frame {frame!r} and --end-link names {end!r}: give one")
    return frame or end


def single_chain(args: argparse.Namespace, default: str | None = None) -> Any:
    """The serial Robot a command works on: ROBOT (or ``default``), ``path.urdf:FRAME``,
    ``--base-link/--end-link``, then ``--tool``/``--base``; a branching URDF without a frame is a
    clear error."""
    from symkin.errors import URDFError
    from symkin.model.resolve import resolve_robot
    from symkin.model.robot import Robot

    spec = args.robot if args.robot is not None else default
    tool, base_transform = getattr(args, "tool", None), getattr(args, "base", None)
    path, frame = split_frame(spec) if isinstance(spec, str) else (spec, None)
    end, base = _end(args, frame), getattr(args, "base_link", None)
    if not isinstance(path, str) or not _is_urdf(path):
        if frame or end or base:
            raise TreeUserError("--base-link, --end-link and ROBOT:FRAME apply to URDF files only")
        return resolve_robot(spec, tool=tool, base=base_transform)
    try:
        robot = Robot.from_urdf(Path(path).expanduser(), base_link=base, end_link=end)
    except URDFError as exc:
        if "branches" in str(exc) and end is None:
            raise TreeUserError(
                f"{path} branches: name the frame as {path}:FRAME or with --end-link FRAME "
                f"(`symkin list-frames {path}` shows the tree)"
            ) from None
        raise
    return resolve_robot(robot, tool=tool, base=base_transform)


def _no_transform(args: argparse.Namespace, hint: str) -> None:
    """--tool/--base change one chain: refused for a tree (``hint`` ends the message)."""
    if getattr(args, "tool", None) is not None or getattr(args, "base", None) is not None:
        raise TreeUserError(f"--tool/--base change one chain{hint}")


def chain_or_tree(args: argparse.Namespace) -> Any:
    """The Robot or :class:`symkin.Tree` a command works on (``compile``, ``check``, ``derive``):
    a Tree for ``--frames``, or for a branching URDF without ``ROBOT:FRAME``/``--end-link``."""
    from symkin.model.tree import Tree

    path, frame = split_frame(args.robot)
    frames = getattr(args, "frames", None)
    if frames is not None:
        if not _is_urdf(path):
            raise TreeUserError("--frames applies to URDF files only")
        if frame or getattr(args, "end_link", None):
            raise TreeUserError("give either --frames (a tree) or one frame (ROBOT:FRAME, --end-link)")
        names = [f.strip() for f in frames.split(",") if f.strip()]
        if not names:
            raise TreeUserError(f"--frames needs link names separated by commas, not {frames!r}")
        _no_transform(args, ", not a tree of --frames")
        return Tree.from_urdf(Path(path).expanduser(), frames=names, base_link=args.base_link)
    if _is_urdf(path) and _end(args, frame) is None:
        tree = Tree.from_urdf(Path(path).expanduser(), base_link=getattr(args, "base_link", None))
        if len(tree.frames) > 1:
            _no_transform(args, f": name the frame as {path}:FRAME or with --end-link")
            return tree
    return single_chain(args)


def cmd_list_frames(args: argparse.Namespace) -> int:
    """``symkin list-frames path.urdf``: the tree with joint and link names, leaves marked."""
    from symkin.model.urdf_tree import describe_urdf

    rows = describe_urdf(Path(args.urdf).expanduser(), base_link=args.base_link)
    if args.json:
        print(json.dumps([{"depth": d, "link": ln, "joint": j, "kind": k} for d, ln, j, k in rows], indent=2))
        return 0
    leaves = [ln for _, ln, _, k in rows if k.endswith("leaf")]
    movable = sum(1 for *_, k in rows if ", q" in k)
    print(f"{args.urdf}: {len(rows)} links, {movable} independent joints, {len(leaves)} leaf links")
    for depth, link, joint, kind in rows:
        via = f"  <- {joint} ({kind})" if joint else "  (base)"
        print(f"{'  ' * depth}{link}{via}")
    print(f"\nleaf links (the default frames): {','.join(leaves)}")
    return 0


def bench_trees(args: argparse.Namespace) -> dict:
    """The tree rows of ``bench kin`` / ``bench tree`` (printed unless --json)."""
    from symkin.bench.tree import format_tree_kin, run_tree_kin

    trees = run_tree_kin(batch=args.batch, seed=args.seed, cold=not args.no_cold)
    if not args.json:
        print(format_tree_kin(trees))
    return trees


def bench_urdf(args: argparse.Namespace) -> tuple[int, dict]:
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


def compile_tree_report(tree: Any, backend: str, output: str | None) -> int:
    """``symkin compile path.urdf --frames ...``: generate, build, print the summary."""
    from symkin.compile import compile as compile_model
    from symkin.compile_tree import generate_tree

    t0 = time.perf_counter()
    command = f"symkin compile {tree.identifier} --frames {','.join(tree.frames)} --backend {backend}"
    files = generate_tree(tree, backend, command)
    t_gen = time.perf_counter() - t0
    if output:
        out = Path(output)
        out.mkdir(parents=True, exist_ok=True)
        for name, text in sorted(files.items()):
            (out / name).write_text(text)
        print(f"wrote {len(files)} files to {out}/: {', '.join(sorted(files))}")
    t1 = time.perf_counter()
    kin = compile_model(tree, backend=backend)
    t_build = time.perf_counter() - t1
    first = next(iter(files.values())).splitlines()
    ops = next((ln.split(":", 1)[1].strip() for ln in first[:8] if "Operations" in ln), "")
    print(f"{tree.name}: tree of {tree.n} joints and {len(tree.frames)} frames: {', '.join(tree.frames)}")
    print(f"backend {backend}: derived + generated in {t_gen:.2f} s, built/loaded in {t_build:.2f} s")
    if ops:
        print(f"operations: {ops}")
    q = np.zeros(tree.n)
    T, J = kin.fkine_jacob0_all(q)
    Tr, Jr = tree.fkine_jacob0_all(q)
    print("\nframe positions at q = 0 (m):")
    for f, Tf in zip(tree.frames, T):
        print(f"  {f:24} {np.array2string(Tf[:3, 3], precision=5, suppress_small=True)}")
    err = max(float(np.abs(T - Tr).max()), float(np.abs(J - Jr).max()))
    print(f"max |fkine_all, jacob0_all - numeric reference| = {err:.2e}")
    reps = 2000
    t = time.perf_counter()
    for _ in range(reps):
        kin.fkine_jacob0_all(q)
    per_call = (time.perf_counter() - t) / reps * 1e6
    print(f"fkine_jacob0_all (every frame): {per_call:.2f} us per call from Python")
    return 0
