"""``symkin compile``: generate, build and load the kinematics code of a chain or of a URDF tree,
write it with ``-o DIR``, and print a summary (the pose, the Jacobian and the time per call)."""

from __future__ import annotations

import argparse
import time
from typing import Any

import numpy as np

from symkin.cli.checks import UserError, check_cflags_for, output_dir
from symkin.cli.common import BACKENDS, add_link_options, add_robot_command, chain_or_tree, fmt
from symkin.compiler.compile import OPTIONAL_BACKENDS
from symkin.errors import SymkinError
from symkin.model.differential import manipulability_one
from symkin.model.tree import as_tree

__all__ = ["add_parser", "run"]


def add_parser(sub: Any) -> None:
    s = add_robot_command(sub, "compile", "generate (and build) the kinematics code of a robot")
    s.add_argument("--backend", choices=(*BACKENDS, *OPTIONAL_BACKENDS), default="c", help="code to generate")
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
    s.add_argument(
        "--derivatives",
        type=int,
        default=0,
        metavar="K",
        help="also the partial derivatives of orders 3..K of every frame's pose (kin.derivative(q, k); "
        "1 and 2 are jacob0 and hessian0, always there) (default 0: none)",
    )
    add_link_options(s, frames=True)
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from symkin.bench.common import timed
    from symkin.compiler.compile import generate, write_files
    from symkin.runtime.load import compile as compile_model

    model = chain_or_tree(args)
    out = output_dir(args.output) if args.output else None
    check_cflags_for(args.backend)
    command, options = _command(args, model)
    files, t_gen = timed(lambda: generate(model, args.backend, command, **options))
    if out is not None:
        paths = write_files(model, args.backend, files, out, command, options.get("prefix"), args.precision)
        manifest = paths.pop(len(files))  # the generated files, the manifest, the collision code
        print(
            f"wrote {len(paths)} files to {out}/: {', '.join(p.name for p in paths)} "
            f"(and {manifest.name}, which symkin.load_compiled reads)"
        )
    if args.precision == "float":
        from symkin.emit.c.backend import float_error

        err = float_error(model, files)
        print(f"single-precision code against double on 100 random q: max |fkine| error {err['fkine']:.1e}, "
              f"max |jacob0| error {err['jacob0']:.1e}")  # fmt: skip
    build = dict(strategy=args.strategy, derivatives=args.derivatives)
    kin, t_build = timed(lambda: compile_model(model, backend=args.backend, **build))
    first = next(iter(files.values())).splitlines()
    ops = next((ln.split(":", 1)[1].strip() for ln in first[:8] if "Operations" in ln), "")
    print(_heading(model, kin.frames))
    print(f"backend {args.backend}: derived + generated in {t_gen:.2f} s, built/loaded in {t_build:.2f} s")
    if ops:
        print(f"operations: {ops}")
    if args.backend in OPTIONAL_BACKENDS:  # the library's float64 arrays; timed by `symkin bench diff`
        _report(model, kin, _on_numpy(kin, kin.fkine_jacob0_all), f", {kin.backend} float64", timed=False)
    else:
        _report(model, kin, kin.fkine_jacob0_all)
    if args.derivatives >= 3:
        _derivative_report(model, kin, args.derivatives)
    return 0


def _command(args: argparse.Namespace, model: Any) -> tuple[str, dict[str, Any]]:
    """The command recorded in the generated files of a chain or tree, and the options of
    ``generate``; the C-only options are refused for another backend or without ``-o``."""
    names = as_tree(model).frames
    frames = f" --frames {','.join(names)}" if getattr(args, "frames", None) or len(names) > 1 else ""
    command = f"symkin compile {model.identifier}{frames} --backend {args.backend}"
    c_only = {  # flag: what it adds to the recorded command ("" when not given)
        "--prefix": f" --prefix {args.prefix}" if args.prefix else "",
        "--precision": f" --precision {args.precision}" if args.precision != "double" else "",
        "--libm": " --libm" if args.libm else "",
    }
    for flag, given in c_only.items():
        if given and args.backend != "c":
            raise UserError(f"{flag} applies to the C backend only")
        if given and not args.output:
            raise UserError(f"{flag} shapes the files written with -o DIR; give -o too")
        command += given
    if args.strategy:
        command += f" --strategy {args.strategy}"
    from symkin.compiler.compile import check_derivatives

    try:
        derivatives = check_derivatives(args.derivatives)
    except SymkinError as exc:
        raise UserError(f"--derivatives: {exc}") from None
    if derivatives:
        command += f" --derivatives {derivatives}"
    options = dict(
        strategy=args.strategy,
        prefix=args.prefix,
        precision=args.precision,
        libm=args.libm,
        derivatives=derivatives,
    )
    return command, options


def _derivative_report(model: Any, kin: Any, order: int) -> None:
    """The derivative of the highest order at the first frame's random q against the reference."""
    q = model.random_q(seed=0)
    frame = None if len(kin.frames) == 1 else kin.frames[0]
    D = kin.derivative(q, order, frame)
    err = float(np.abs(D - model.derivative(q, order, frame)).max())
    where = "" if frame is None else f" of frame {frame}"
    print(f"derivative{order}{where}, shape {D.shape}: max |D - numeric reference| = {err:.2e} at a random q")
    per_call = _us_per_call(lambda x: kin.derivative(x, order, frame), q, 200)
    print(f"derivative{order}: {per_call:.2f} us per call")


def _heading(model: Any, frames: tuple[str, ...]) -> str:
    """What was compiled: the joints and frames, and a serial chain's ETS."""
    names = f"{len(frames)} frame{'s' * (len(frames) > 1)}: {', '.join(frames)}"
    try:
        chain = model.chain()  # a Robot itself, or a tree's one serial chain
    except SymkinError:  # several frames, or a mimic joint on the path
        return f"{model.name}: {model.n} joints and {names}"
    return f"{model.name}: {model.n} joints and {names}; ETS ({chain.ets.structure}) {chain.ets}"


def _report(model: Any, kin: Any, fkjac: Any, note: str = "", timed: bool = True) -> None:
    """Every frame's pose and Jacobian at the ready configuration (``qr``, else ``qz``) by ``fkjac``
    (a NumPy ``fkine_jacob0_all`` of ``kin``: (F, 4, 4), (F, 6, n); ``note`` ends the heading),
    checked against the numeric reference; when ``timed``, the time of the generated call of every
    frame (``fkine_jacob0`` of one frame, ``fkine_jacob0_all`` of several). One frame (a serial
    chain) is shown whole with its manipulability (Haviland and Corke, Manipulator Differential
    Kinematics, Part 1, 2023, eq 52), several by their positions."""
    qname = "qr" if "qr" in model.configs else "qz"
    q = model.configs[qname]
    T, J = fkjac(q)
    one = len(kin.frames) == 1
    print(f"\nat {qname} = {fmt(q)}{note}:")
    if one:
        print(f"fkine (4x4):\n{fmt(T[0])}")
        print(f"jacob0 (6x{model.n}, rows v, omega):\n{fmt(J[0])}")
        print(f"manipulability: {manipulability_one(J[0]):.6g}")
    else:
        print("frame positions (m):")
        for f, Tf in zip(kin.frames, T):
            print(f"  {f:24} {fmt(Tf[:3, 3])}")
    Tr, Jr = as_tree(model).fkine_jacob0_all(q)
    err = max(float(np.abs(T - Tr).max()), float(np.abs(J - Jr).max()))
    print(f"max |fkine, jacob0 - numeric reference| = {err:.2e}")
    if timed:
        name = "fkine_jacob0" if one else "fkine_jacob0_all"
        print(f"{name}: {_us_per_call(getattr(kin, name), q):.2f} us per call from Python")


def _on_numpy(kin: Any, fn: Any) -> Any:
    """``fn`` of JAX/PyTorch kinematics on float64 NumPy arrays: NumPy in (a writable copy), NumPy out."""
    if kin.backend == "jax":
        kin.ops.jax.config.update("jax_enable_x64", True)  # float64 in JAX is opt-in
    xp = kin.ops.xp

    def call(q: np.ndarray) -> Any:
        out = fn(xp.asarray(np.array(q, dtype=float), dtype=xp.float64))
        return tuple(kin.ops.numpy(a) for a in out) if isinstance(out, tuple) else kin.ops.numpy(out)

    return call


def _us_per_call(function: Any, q: np.ndarray, reps: int = 2000) -> float:
    t = time.perf_counter()
    for _ in range(reps):
        function(q)
    return (time.perf_counter() - t) / reps * 1e6
