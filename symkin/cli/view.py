"""``symkin view``: a live browser view of a robot, a serial chain or a tree (viser, the ``view``
extra): a frame selector, joint sliders, link frames, the URDF's meshes, velocity ellipsoid,
manipulability, the live Jacobian, collision shapes, the closest pair and its distance, and a
target-pose gizmo driving IK. Serves until Ctrl-C (or ``--seconds``)."""

from __future__ import annotations

import argparse
import sys
import warnings
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
    s = common.add_robot_command(
        sub,
        "view",
        "live browser view of a chain or a tree: frame selector, joint sliders, meshes, velocity "
        "ellipsoid, manipulability, J, collision shapes and the closest pair, IK gizmo",
    )
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
        "--host",
        default="127.0.0.1",
        help="address to serve on; every interface only as exactly 0.0.0.0 or :: (with a warning); an "
        "empty host, *, 0, [::] and other wildcards are refused",
    )
    s.add_argument("--port", type=_port, default=8080, help="port to serve on (0: any free port)")
    s.add_argument("--no-browser", action="store_true", help="do not open the page in a browser")
    s.add_argument(
        "--seconds", type=positive_float, help="stop after this many seconds (default: serve until Ctrl-C)"
    )
    s.add_argument("--backend", choices=common.BACKENDS, default="c", help="kinematics backend")
    common.add_link_options(s, frames=True)
    common.add_collision_options(s)
    s.set_defaults(func=run)


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
    from symkin.view.address import serve_address

    address = serve_address(args.host)  # an empty or wildcard host is refused before any work
    urdf = common.urdf_of(args)
    with warnings.catch_warnings(record=True) as caught:  # skipped collision meshes: notes
        warnings.simplefilter("always")
        model, env, _ = common.collision_model(args, tree=True)
    notes = _grouped([str(w.message) for w in caught])
    q = None if args.q is None else common.configuration(args.q, model, "--q")
    kin = compile_robot(model, backend=args.backend)
    with warnings.catch_warnings():  # said below as one line
        warnings.filterwarnings("ignore", message="serving on every interface")
        viewer = view(
            kin, port=args.port, host=args.host, open_browser=not args.no_browser, q=q, env=env,
            frame=args.follow, urdf=urdf, meshes=args.meshes if urdf is not None else "none", notes=notes,
        )  # fmt: skip
    if address.public:
        print(f"symkin: warning: {address.warning(viewer.port)}", file=sys.stderr, flush=True)
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
