"""``symkin view``: a live browser view of a robot, a serial chain or a tree (viser, the ``view``
extra): a frame selector, joint sliders, link frames, the URDF's meshes, velocity ellipsoid,
manipulability, the live Jacobian, collision shapes, the closest pair and its distance, and a
target-pose gizmo driving IK. Serves until Ctrl-C (or ``--seconds``)."""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path
from typing import Any

from symkin.cli import common
from symkin.cli.checks import UserError, positive_float

__all__ = ["add_parser", "run"]

_NOTES_PRINTED = 5


def _port(text: str) -> int:
    try:
        port = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"a port is an integer in 0..65535, not {text!r}") from None
    if not 0 <= port <= 65535:
        raise argparse.ArgumentTypeError(f"a port is an integer in 0..65535 (0: any free port), not {port}")
    return port


def add_parser(sub: Any) -> None:
    s = common.add_command(
        sub,
        "view",
        "live browser view of a chain or a tree: frame selector, joint sliders, meshes, velocity "
        "ellipsoid, manipulability, J, collision shapes and the closest pair, IK gizmo",
    )
    common.add_robot_argument(s)
    s.add_argument(
        "--q",
        metavar="'Q...'",
        help="first joint values, or a configuration name like qr (default qr, else qz)",
    )
    s.add_argument(
        "--follow",
        metavar="FRAME",
        help="the frame the gizmo, ellipsoid and J0 follow first: a tree's frame, or ee / link<k> of a "
        "chain (default the first; the page's frame selector changes it)",
    )
    s.add_argument(
        "--meshes",
        choices=("visual", "collision", "none"),
        default="visual",
        help="URDF: which meshes to draw on the links (mesh files need trimesh)",
    )
    s.add_argument(
        "--srdf",
        metavar="FILE",
        help="skip the link pairs a MoveIt SRDF disables (<disable_collisions>) in the closest pair",
    )
    s.add_argument("--host", default="127.0.0.1", help="address to serve on (0.0.0.0: every interface)")
    s.add_argument("--port", type=_port, default=8080, help="port to serve on (0: any free port)")
    s.add_argument("--no-browser", action="store_true", help="do not open the page in a browser")
    s.add_argument(
        "--seconds", type=positive_float, help="stop after this many seconds (default: serve until Ctrl-C)"
    )
    s.add_argument("--backend", choices=common.BACKENDS, default="c", help="kinematics backend")
    common.add_link_options(s, frames=True)
    common.add_obstacle_options(s)
    s.set_defaults(func=run)


def _urdf(args: argparse.Namespace) -> Path | None:
    """The URDF file ROBOT names, or None."""
    path = common.split_frame(args.robot)[0]
    return Path(path).expanduser() if common.is_urdf(path) else None


def _with_srdf(args: argparse.Namespace, model: Any, urdf: Path | None) -> Any:
    """``model`` with the link pairs of --srdf disabled, conservatively: two model links are
    skipped only when the SRDF disables every pair of the URDF links with collision elements that
    ride on them (ROBOT a URDF: links joined by fixed joints become one model link); ROBOT not a
    URDF: the SRDF names the model's links."""
    if args.srdf is None:
        return model
    from symkin.geometry.srdf import read_srdf

    geometry = model.geometry
    if geometry is None or not geometry.shapes:
        raise UserError(f"--srdf: {model.name} has no collision geometry")
    disabled = set(read_srdf(Path(args.srdf).expanduser()))
    links = geometry.links
    carriers: dict[str, set[str]] = {x: set() for x in links}
    if urdf is None:
        carriers = {x: {x} for x in links}
    else:
        from symkin.geometry.urdf import urdf_link_names
        from symkin.model.urdf import load_xml

        names = urdf_link_names(urdf, model)
        for el in load_xml(urdf)[0].findall("link"):
            name = el.get("name") or ""
            if el.find("collision") is not None and names.get(name) in carriers:
                carriers[names[name]].add(name)
    pairs = [
        (a, b)
        for i, a in enumerate(links)
        for b in links[i + 1 :]
        if carriers[a] and carriers[b]
        and all(tuple(sorted((x, y))) in disabled for x in carriers[a] for y in carriers[b])
    ]  # fmt: skip
    if disabled and not pairs:
        print(
            f"symkin: note: --srdf {args.srdf}: none of its disable_collisions pairs covers two links of "
            f"{model.name} with collision shapes",
            file=sys.stderr,
        )
    return model.with_geometry(geometry.with_disabled(pairs))


def _grouped(notes: list[str]) -> list[str]:
    """The URDF reader's notes, the collision meshes it skipped (one each) said in one line."""
    meshes = [x for x in notes if " is a mesh (" in x]
    if not meshes:
        return notes
    head = (
        f"{len(meshes)} <collision> meshes are not in the collision model, so not checked "
        "(symkin.geometry.geometry_from_urdf(..., mesh_spheres=K) fits spheres to them)"
    )
    return [head, *(x for x in notes if x not in meshes)]


def _note(lines: list[str]) -> None:
    for line in lines[:_NOTES_PRINTED]:
        print(f"symkin: note: {line}", file=sys.stderr)
    if len(lines) > _NOTES_PRINTED:
        print(f"symkin: note: ... and {len(lines) - _NOTES_PRINTED} more (the page's Notes)", file=sys.stderr)


def run(args: argparse.Namespace) -> int:
    try:
        import viser  # noqa: F401
    except ImportError:
        raise UserError("view needs viser: pip install 'symkin[view]'") from None
    from symkin.runtime.load import compile as compile_robot
    from symkin.view import view

    urdf = _urdf(args)
    with warnings.catch_warnings(record=True) as caught:  # skipped collision meshes: notes
        warnings.simplefilter("always")
        model = common.chain_or_tree(args, geometry=True)
        model = _with_srdf(args, model, urdf)
    notes = _grouped([str(w.message) for w in caught])
    q = None if args.q is None else common.configuration(args.q, model, "--q")
    env = common.environment_of(args)
    kin = compile_robot(model, backend=args.backend)
    viewer = view(
        kin, port=args.port, host=args.host, open_browser=not args.no_browser, q=q, env=env,
        frame=args.follow, urdf=urdf, meshes=args.meshes if urdf is not None else "none", notes=notes,
    )  # fmt: skip
    _note(list(viewer.notes))
    how = f"for {args.seconds:g} s" if args.seconds else "until Ctrl-C"
    print(f"viewing {model.name} at {viewer.url} ({how}): {viewer.scene.summary()}", flush=True)
    try:
        viewer.wait(args.seconds)
    except KeyboardInterrupt:
        print("stopped", flush=True)
    finally:
        viewer.stop()
    return 0
