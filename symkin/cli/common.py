"""What several commands share: the parser classes, the ROBOT argument and its options (``--tool``,
``--base``, ``--base-link``, ``--end-link``, ``--frames``, ``path.urdf:FRAME``) and their
resolution into a Robot or a :class:`symkin.Tree`, the target pose of ``ik`` and ``servo``, the
options of the Dask commands, and the output helpers."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from symkin.cli.checks import UserError, at_least_1

__all__ = [
    "damaged",
    "ROBOT_HELP",
    "BACKENDS",
    "Formatter",
    "Parser",
    "Deprecated",
    "add_command",
    "add_robot_command",
    "add_robot_argument",
    "add_link_options",
    "add_target_options",
    "add_scale_options",
    "split_frame",
    "is_urdf",
    "urdf_of",
    "single_chain",
    "transformed",
    "chain_or_tree",
    "target",
    "scheduler",
    "floats",
    "configuration",
    "fmt",
    "add_obstacle_options",
    "add_collision_options",
    "collision_model",
    "environment_of",
    "add_srdf_option",
    "with_srdf",
]

ROBOT_HELP = (
    "a built-in robot name (see `symkin list`), a quoted ETS string, a DH table file, a URDF file or "
    "path.urdf:FRAME (the chain to link FRAME)"
)
TRANSFORM_HELP = (
    "constant ETS text like 'tz(0.1) Rx(pi/2)', or 'x y z roll pitch yaw' (m, rad; pi/2 and 90deg "
    "allowed), or 16 numbers of a row-major 4x4 matrix"
)
BACKENDS = ("c", "numpy", "casadi")
_URDF = (".urdf", ".xml", ".xacro")  # .xacro: refused by the URDF reader, with how to expand it


# -- the parser ----------------------------------------------------------------------------------
class Formatter(argparse.HelpFormatter):
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


class Parser(argparse.ArgumentParser):
    """argparse with symkin's one-line errors (``symkin: error: ...``, exit 2)."""

    def error(self, message: str) -> Any:  # type: ignore[override]
        self.exit(
            2, f"symkin: error: {self.prog.split(' ', 1)[-1] + ': ' if ' ' in self.prog else ''}{message}\n"
        )


class Deprecated(argparse.Action):
    """A renamed option kept working: stores into the new option's dest and says so on stderr."""

    def __init__(self, *args: Any, new: str = "", **kwargs: Any) -> None:
        self.new = new
        super().__init__(*args, **kwargs)

    def __call__(self, parser: Any, namespace: Any, values: Any, option_string: Any = None) -> None:
        print(f"symkin: {option_string} is deprecated; use {self.new}", file=sys.stderr)
        setattr(namespace, self.dest, values)


def add_command(sub: Any, name: str, text: str) -> argparse.ArgumentParser:
    """The parser of ``symkin NAME`` (``text`` is its line in ``symkin --help`` and its description)."""
    return sub.add_parser(name, help=text, description=text, formatter_class=Formatter)


def add_robot_command(sub: Any, name: str, text: str, default: str | None = None) -> argparse.ArgumentParser:
    """The parser of ``symkin NAME ROBOT`` (:func:`add_command` with :func:`add_robot_argument`)."""
    s = add_command(sub, name, text)
    add_robot_argument(s, default)
    return s


def add_robot_argument(s: argparse.ArgumentParser, default: str | None = None) -> None:
    """The ROBOT argument (optional when ``default`` describes what it defaults to) and --tool/--base."""
    if default is None:
        s.add_argument("robot", metavar="ROBOT", help=ROBOT_HELP)
    else:
        s.add_argument("robot", metavar="ROBOT", nargs="?", default=None, help=f"{ROBOT_HELP} ({default})")
    s.add_argument(
        "--tool", metavar="T", help="append this constant transform after the end effector: " + TRANSFORM_HELP
    )
    s.add_argument(
        "--base", metavar="T", help="place this constant transform before the first link: " + TRANSFORM_HELP
    )


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


def add_target_options(s: argparse.ArgumentParser, q0_help: str) -> None:
    """The target pose, backend, start and output options of ``ik`` and ``servo``."""
    s.add_argument("--pose", metavar="'X Y Z R P Y'", help="target position (m) and roll pitch yaw (rad)")
    s.add_argument("--matrix", metavar="'16 NUMBERS'", help="target pose as a row-major 4x4 matrix")
    s.add_argument(
        "--target-q", metavar="'Q...'", help="target = the pose of the robot at these joint values"
    )
    s.add_argument("--from-q", dest="target_q", action=Deprecated, new="--target-q", help=argparse.SUPPRESS)
    s.add_argument("--backend", choices=BACKENDS, default="c", help="kinematics backend")
    s.add_argument("--q0", metavar="'Q...'", help=q0_help)
    s.add_argument("--json", action="store_true", help="print JSON")
    add_link_options(s)


def add_scale_options(s: argparse.ArgumentParser) -> None:
    """The Dask and store options of ``reach`` and ``dataset`` (the ``scale`` extra)."""
    s.add_argument("--seed", type=int, default=0, help="seed of the random orientations and samples")
    s.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="a Dask scheduler such as tcp://host:8786, or 'synchronous' (default: a local cluster)",
    )
    s.add_argument("--workers", type=at_least_1, help="local cluster size (default: one worker per core)")
    s.add_argument("--backend", choices=BACKENDS, default="c", help="kinematics backend")
    s.add_argument("--overwrite", action="store_true", help="replace the store instead of resuming it")
    s.add_argument("--json", action="store_true", help="print JSON")


# -- ROBOT: a serial chain or a URDF tree --------------------------------------------------------
def split_frame(spec: str) -> tuple[str, str | None]:
    """``"robot.urdf:tool0"`` -> ``("robot.urdf", "tool0")``; anything else -> ``(spec, None)``."""
    text = spec.strip()
    if "(" in text:
        return spec, None
    head, sep, tail = text.rpartition(":")
    if sep and tail and "/" not in tail and Path(head).suffix.lower() in _URDF:
        return head, tail
    return spec, None


def is_urdf(path: str) -> bool:
    return "(" not in path and Path(path.strip()).suffix.lower() in _URDF


def urdf_of(args: argparse.Namespace) -> Path | None:
    """The URDF file ROBOT names (``path.urdf`` or ``path.urdf:FRAME``), or None."""
    path = split_frame(args.robot)[0] if isinstance(args.robot, str) else None
    return Path(path).expanduser() if path is not None and is_urdf(path) else None


def _end(args: argparse.Namespace, frame: str | None) -> str | None:
    end = getattr(args, "end_link", None)
    if frame and end and frame != end:
        raise UserError(f"ROBOT names frame {frame!r} and --end-link names {end!r}: give one")
    return frame or end


def single_chain(args: argparse.Namespace, default: str | None = None, geometry: bool = False) -> Any:
    """The serial Robot a command works on: ROBOT (or ``default`` when it is optional and not
    given), ``path.urdf:FRAME``, ``--base-link/--end-link``, then ``--tool``/``--base``; a branching
    URDF without a frame is a clear error. ``geometry``: a URDF's ``<collision>`` elements become
    the robot's collision geometry (:func:`symkin.geometry.geometry_from_urdf`; meshes skipped)."""
    from symkin.errors import URDFError
    from symkin.model.resolve import resolve_robot
    from symkin.model.robot import Robot

    spec = args.robot if args.robot is not None else default
    tool, base_transform = getattr(args, "tool", None), getattr(args, "base", None)
    path, frame = split_frame(spec) if isinstance(spec, str) else (spec, None)
    end, base = _end(args, frame), getattr(args, "base_link", None)
    if not isinstance(path, str) or not is_urdf(path):
        if frame or end or base:
            raise UserError("--base-link, --end-link and ROBOT:FRAME apply to URDF files only")
        return resolve_robot(spec, tool=tool, base=base_transform)
    try:
        robot = Robot.from_urdf(Path(path).expanduser(), base_link=base, end_link=end)
    except URDFError as exc:
        if "branches" in str(exc) and end is None:
            raise UserError(
                f"{path} branches: name the frame as {path}:FRAME or with --end-link FRAME "
                f"(`symkin list-frames {path}` shows the tree)"
            ) from None
        raise
    if geometry:
        robot = _with_urdf_geometry(robot, path)
    return resolve_robot(robot, tool=tool, base=base_transform)


def transformed(args: argparse.Namespace) -> bool:
    """Whether --tool or --base change the robot."""
    return getattr(args, "tool", None) is not None or getattr(args, "base", None) is not None


def _no_transform(args: argparse.Namespace, hint: str) -> None:
    """--tool/--base change one chain: refused for a tree (``hint`` ends the message)."""
    if transformed(args):
        raise UserError(f"--tool/--base change one chain{hint}")


def chain_or_tree(args: argparse.Namespace, geometry: bool = False) -> Any:
    """The Robot or :class:`symkin.Tree` a command works on (``compile``, ``check``, ``derive``,
    ``view``): a Tree for ``--frames``, or for a branching URDF without ``ROBOT:FRAME``/``--end-link``.
    ``geometry``: a URDF's ``<collision>`` elements become the model's collision geometry, as in
    :func:`single_chain`."""
    from symkin.model.tree import Tree

    path, frame = split_frame(args.robot)
    frames = getattr(args, "frames", None)
    if frames is not None:
        if not is_urdf(path):
            raise UserError("--frames applies to URDF files only")
        if frame or getattr(args, "end_link", None):
            raise UserError("give either --frames (a tree) or one frame (ROBOT:FRAME, --end-link)")
        names = [f.strip() for f in frames.split(",") if f.strip()]
        if not names:
            raise UserError(f"--frames needs link names separated by commas, not {frames!r}")
        _no_transform(args, ", not a tree of --frames")
        tree = Tree.from_urdf(Path(path).expanduser(), frames=names, base_link=args.base_link)
        return _with_urdf_geometry(tree, path) if geometry else tree
    if is_urdf(path) and _end(args, frame) is None:
        tree = Tree.from_urdf(Path(path).expanduser(), base_link=getattr(args, "base_link", None))
        if len(tree.frames) > 1:
            _no_transform(args, f": name the frame as {path}:FRAME or with --end-link")
            return _with_urdf_geometry(tree, path) if geometry else tree
    return single_chain(args, geometry=geometry)


def _with_urdf_geometry(model: Any, path: str) -> Any:
    """``model`` with the ``<collision>`` elements of the URDF ``path`` as its geometry (meshes
    skipped), when there are any."""
    from symkin.geometry.urdf import geometry_from_urdf

    shapes = geometry_from_urdf(Path(path).expanduser(), model)
    return model.with_geometry(shapes) if shapes.shapes else model


# -- values ----------------------------------------------------------------------------------------
def target(args: argparse.Namespace, robot: Any) -> np.ndarray:
    """A target pose from --pose (x y z roll pitch yaw, rad), --matrix (16 numbers) or --target-q."""
    given = [x is not None for x in (args.pose, args.matrix, args.target_q)]
    if sum(given) != 1:
        raise UserError(
            "give exactly one of --pose 'x y z roll pitch yaw', --matrix '16 numbers', --target-q 'q...'"
        )
    if args.target_q is not None:
        return robot.fkine(floats(args.target_q, "--target-q", robot.n))
    if args.matrix is not None:
        from symkin.core.pose import as_pose

        return as_pose(floats(args.matrix, "--matrix", 16).reshape(4, 4), "--matrix")  # the one pose rule
    from symkin.model.transform import rpy_matrix

    pose = floats(args.pose, "--pose", 6)
    return rpy_matrix(pose[:3], pose[3:])


def scheduler(args: argparse.Namespace) -> Any:
    """--scheduler of ``reach`` and ``dataset`` (None: a local cluster)."""
    return args.scheduler if args.scheduler else None


def floats(text: str, what: str, count: int | None = None) -> np.ndarray:
    """The numbers of option ``what`` (separated by spaces or commas; ``count`` of them if given)."""
    try:
        values = np.array([float(x) for x in text.replace(",", " ").split()])
    except ValueError:
        raise UserError(f"{what} must be numbers separated by spaces or commas, got {text!r}") from None
    if count is not None and values.size != count:
        raise UserError(f"{what} needs {count} numbers, got {values.size}")
    if not np.isfinite(values).all():
        raise UserError(f"{what} must be finite numbers, got {text!r}")
    return values


def configuration(text: str, robot: Any, what: str) -> np.ndarray:
    """Joint values from option ``what``: a named configuration of ``robot`` (``qr``...) or n numbers."""
    name = text.strip()
    if name in robot.configs:
        return np.asarray(robot.configs[name])
    return floats(text, what, robot.n)


def fmt(a: np.ndarray) -> str:
    """An array as printed by the commands."""
    return np.array2string(np.asarray(a), precision=5, suppress_small=True, max_line_width=110)


def damaged(summary: dict) -> str:
    """`` (2 of them damaged)``: written blocks computed again because a chunk could not be read."""
    return f" ({summary['damaged']} of them damaged)" if summary["damaged"] else ""


# -- obstacles (collide, plot, reach) --------------------------------------------------------------
_KINDS = {  # option: JSON key, its numbers, what it is
    "sphere": ("spheres", "x y z r", "an obstacle sphere"),
    "capsule": ("capsules", "ax ay az bx by bz r", "an obstacle capsule"),
    "box": ("boxes", "cx cy cz hx hy hz", "an axis-aligned obstacle box (centre, half side lengths)"),
}


def add_obstacle_options(s: argparse.ArgumentParser) -> None:
    """--sphere, --capsule, --box (repeatable) and --env FILE: obstacles in the base frame."""
    for what, (_, numbers, text) in _KINDS.items():
        s.add_argument(f"--{what}", action="append", default=[], metavar=f"'{numbers.upper()}'", help=text)
    rows = ", ".join(f'"{key}": [[{numbers.replace(" ", ",")}]...]' for key, numbers, _ in _KINDS.values())
    s.add_argument("--env", metavar="FILE", help=f"obstacles from JSON: {{{rows}}} (base frame, m)")


def add_collision_options(s: argparse.ArgumentParser, text: str | None = None) -> None:
    """The obstacles and --srdf, and (``text``: what it does in this command) the --collision
    they then go with."""
    if text is not None:
        s.add_argument("--collision", action="store_true", help=text)
    add_obstacle_options(s)
    add_srdf_option(s, "" if text is None else " (with --collision)")


def collision_model(args: argparse.Namespace, tree: bool = False) -> tuple[Any, Any, Any]:
    """(model, obstacles, collision) of a command with obstacles: the Robot of :func:`single_chain`
    (or, ``tree``, the Robot or Tree of :func:`chain_or_tree`) with a URDF's collision geometry and
    --srdf applied, the obstacles of :func:`environment_of`, and what the solvers take as
    ``collision`` (None without --collision, else the obstacles, or True for self-collisions
    alone). Obstacles and --srdf of a command with --collision are refused without it; a command
    without that option (plot, collide, view) always has the geometry."""
    on = getattr(args, "collision", True)
    model = (chain_or_tree if tree else single_chain)(args, geometry=on)
    env = environment_of(args)
    if (len(env) or getattr(args, "srdf", None)) and not on:
        raise UserError(
            "--sphere, --capsule, --box, --env and --srdf are options of --collision: add --collision"
        )
    return with_srdf(args, model), env, (env if len(env) else True) if on else None


def environment_of(args: argparse.Namespace) -> Any:
    """The obstacles of --sphere, --capsule, --box and --env; a UserError naming the option (or the
    file, its key and row) for anything that is not such a shape."""
    from symkin.model.geometry import Environment

    shapes: dict[str, list[Any]] = {what: [] for what in _KINDS}
    for what, (_, numbers, _) in _KINDS.items():
        size = len(numbers.split())
        for text in getattr(args, what):
            shapes[what].append(_shape(what, floats(text, f"--{what}", size), f"--{what} {text!r}"))
    if args.env:
        data = _env_file(Path(args.env).expanduser())
        for what, (key, numbers, _) in _KINDS.items():
            rows, size = data.get(key, []), len(numbers.split())
            if not isinstance(rows, list):
                raise UserError(
                    f"--env {args.env}: {key} must be a list of rows of {size} numbers, not {_json(rows)}"
                )
            for i, row in enumerate(rows):
                where = f"--env {args.env}: {key}[{i}]"
                if not (
                    isinstance(row, list)
                    and len(row) == size
                    and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in row)
                ):
                    raise UserError(f"{where} must be {size} numbers, not {_json(row)}")
                try:
                    v = np.array([float(x) for x in row])
                except OverflowError:  # an integer beyond any double
                    raise UserError(f"{where}: the numbers must be finite") from None
                shapes[what].append(_shape(what, v, where))
    return Environment(*(tuple(shapes[what]) for what in _KINDS))


_ENV_BYTES = 64 * 2**20  # an obstacle file larger than this is refused before it is read


def _shape(what: str, v: np.ndarray, where: str) -> Any:
    """The obstacle ``what`` of the numbers ``v``; UserError naming ``where`` when they are not one."""
    from symkin.errors import SymkinError
    from symkin.model.geometry import Box, Capsule, Sphere

    if not np.isfinite(v).all():
        raise UserError(f"{where}: the numbers must be finite")
    try:
        if what == "sphere":
            return Sphere(v[:3], v[3])
        return Capsule(v[:3], v[3:6], v[6]) if what == "capsule" else Box(v[:3], v[3:])
    except SymkinError as exc:
        raise UserError(f"{where}: {exc}") from None


def _env_file(path: Path) -> dict:
    """The JSON object of an --env file (keys spheres, capsules, boxes)."""
    from symkin.core.sizes import read_bounded

    try:
        data = json.loads(read_bounded(path, _ENV_BYTES, f"--env {path}", UserError).decode("utf-8"))
    except (OSError, ValueError) as exc:
        raise UserError(f"--env {path}: {exc}") from None
    except RecursionError:
        raise UserError(f"--env {path}: arrays nested too deeply to be obstacles") from None
    if not isinstance(data, dict) or set(data) - {"spheres", "capsules", "boxes"}:
        raise UserError(f"--env {path}: a JSON object with keys spheres, capsules, boxes")
    return data


def _json(value: Any) -> str:
    """``value`` as JSON text, at most 60 characters."""
    try:
        text = json.dumps(value)
    except (ValueError, RecursionError):
        text = repr(type(value).__name__)
    return text if len(text) <= 60 else text[:57] + "..."


# -- SRDF (every command that checks collisions) ---------------------------------------------------
def add_srdf_option(s: argparse.ArgumentParser, when: str = "") -> None:
    """--srdf FILE: link pairs a MoveIt SRDF disables are not checked (``when``: what it needs)."""
    s.add_argument(
        "--srdf",
        metavar="FILE",
        help="skip the link pairs a MoveIt SRDF disables (<disable_collisions>); a pair of links stays "
        "checked unless the SRDF disables every pair of the URDF links merged into them; "
        "`symkin srdf ROBOT` writes one" + when,
    )


def srdf_carriers(args: argparse.Namespace, model: Any) -> dict[str, tuple[str, ...]]:
    """Per link of ``model``'s geometry, the link names an SRDF of ROBOT uses for it: the URDF
    links with collision elements attached to it (a URDF ROBOT), else its own name."""
    links = model.geometry.links
    path = urdf_of(args)
    if path is not None:
        from symkin.geometry.urdf import urdf_carriers

        carriers = urdf_carriers(path, model)
        return {x: carriers.get(x, (x,)) for x in links}
    return {x: (x,) for x in links}


def with_srdf(args: argparse.Namespace, model: Any) -> Any:
    """``model`` with the link pairs of --srdf disabled (conservatively, see
    :func:`symkin.geometry.srdf.srdf_disabled`); ``model`` itself without --srdf. A file none of
    whose pairs names two of the model's links is an error (another robot's SRDF); pairs the SRDF
    disables only in part are said on stderr."""
    path = getattr(args, "srdf", None)
    if path is None:
        return model
    from symkin.core.names import listed
    from symkin.geometry.srdf import pairs_text, srdf_disabled

    geometry = model.geometry
    if geometry is None or not geometry.shapes:
        raise UserError(f"--srdf: {model.name} has no collision geometry")
    carriers = srdf_carriers(args, model)
    pairs, partial, used = srdf_disabled(Path(path).expanduser(), carriers)
    if not used:
        names = sorted({x for c in carriers.values() for x in c})
        raise UserError(
            f"--srdf {path}: none of its disable_collisions pairs names two links of {model.name} with "
            f"collision geometry ({listed(names, 6)}): an SRDF of another robot?"
        )
    if partial:
        print(
            f"symkin: --srdf: {len(partial)} link pairs stay checked, the SRDF disabling only some of the "
            f"links merged into them: {pairs_text(partial, 4)}",
            file=sys.stderr,
        )
    return model.with_geometry(geometry.with_disabled(pairs))
