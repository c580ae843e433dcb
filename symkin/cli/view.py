"""``symkin view``: a live browser view of a robot (viser, the ``view`` extra): joint sliders, link
frames, velocity ellipsoid, manipulability, the live Jacobian, collision shapes and a target-pose
gizmo driving IK. Serves until Ctrl-C (or ``--seconds``)."""

from __future__ import annotations

import argparse
import sys
from typing import Any

from symkin.cli import common
from symkin.cli.checks import UserError, positive_float

__all__ = ["add_parser", "run"]


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
        "live browser view: joint sliders, frames, velocity ellipsoid, manipulability, J, IK gizmo",
    )
    common.add_robot_argument(s)
    s.add_argument(
        "--q",
        metavar="'Q...'",
        help="first joint values, or a configuration name like qr (default qr, else qz)",
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
    common.add_link_options(s)
    common.add_obstacle_options(s)
    common.add_srdf_option(s)
    s.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    try:
        import viser  # noqa: F401
    except ImportError:
        raise UserError("view needs viser: pip install 'symkin[view]'") from None
    import warnings

    from symkin.runtime.load import compile as compile_robot
    from symkin.view import view
    from symkin.view.address import serve_address

    address = serve_address(args.host)  # an empty or wildcard host is refused before any work
    robot = common.with_srdf(args, common.single_chain(args, geometry=True))
    q = None if args.q is None else common.configuration(args.q, robot, "--q")
    env = common.environment_of(args)
    kin = compile_robot(robot, backend=args.backend)
    with warnings.catch_warnings():  # said below as one line
        warnings.filterwarnings("ignore", message="serving on every interface")
        viewer = view(kin, port=args.port, host=args.host, open_browser=not args.no_browser, q=q, env=env)
    if address.public:
        print(f"symkin: warning: {address.warning(viewer.port)}", file=sys.stderr, flush=True)
    how = f"for {args.seconds:g} s" if args.seconds else "until Ctrl-C"
    print(f"viewing {robot.name} at {viewer.url} ({how})", flush=True)
    try:
        viewer.wait(args.seconds)
    except KeyboardInterrupt:
        print("stopped", flush=True)
    finally:
        viewer.stop()
    return 0
