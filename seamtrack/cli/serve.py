"""``seamtrack serve SCENE``: run a scene with its tracker in another process (the lockstep
bridge, :mod:`seamtrack.bridge.lockstep`; docs/bridge.md)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

HELP = "run a scene with the tracker in another process (ZeroMQ JSON, or ROS 2 over Zenoh)"


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Register the command on the ``seamtrack`` subparsers."""
    p = sub.add_parser("serve", help=HELP, description=HELP)
    p.set_defaults(fn=cmd_serve)
    p.add_argument(
        "--set",
        action="append",
        metavar="KEY=VALUE",
        help="override a scene key, e.g. --set sensor.frame_rate_hz=50 (repeatable)",
    )
    p.add_argument("scene", help="built-in scene name (seamtrack init --list) or a .toml file")
    p.add_argument(
        "--transport",
        choices=["zmq", "zenoh"],
        default="zmq",
        help="zmq: JSON and raw profile arrays over a ZeroMQ REP socket; zenoh: ROS 2 messages "
        "as rmw_zenoh puts them",
    )
    p.add_argument(
        "--endpoint",
        help="where to listen: zmq default tcp://127.0.0.1:5555 (loopback; "
        "ipc:///PATH: a Unix socket, faster; tcp://HOST:PORT for another machine); "
        "zenoh default tcp/127.0.0.1:7447 (rmw_zenoh's router "
        "port); this machine only unless you say otherwise",
    )
    p.add_argument(
        "--lockstep",
        choices=["tick", "frame"],
        default="frame",
        help="frame (default): a step per sensor frame, and when the torch comes within the "
        "tracker's ask_within of its target; tick: a step every control tick",
    )
    p.add_argument(
        "--timeout-s", type=float, default=5.0, help="deadline for each answer (default 5 s)"
    )
    p.add_argument(
        "--wait-s", type=float, default=60.0, help="how long to wait for the tracker (default 60 s)"
    )
    p.add_argument("--domain-id", type=int, default=0, help="zenoh: the ROS_DOMAIN_ID (default 0)")
    p.add_argument("--out", help="output folder (default: runs/<scene name>)")
    p.add_argument("--no-plot", action="store_true", help="skip error.png")
    p.add_argument("-q", "--quiet", action="store_true", help="print nothing but errors")
    return p


def check_flags(args: argparse.Namespace) -> None:
    """The command's own numbers, checked before anything is loaded."""
    from seamtrack.errors import SeamtrackError

    for name in ("timeout_s", "wait_s"):
        value = getattr(args, name)
        if not 0 < value < 1e6:
            flag = "--" + name.replace("_", "-")
            raise SeamtrackError(
                f"must be > 0 s, got {value:g}", field=flag, fix=f"give {flag} in seconds, e.g. 5"
            )
    if not 0 <= args.domain_id <= 232:  # ROS 2's domain ids
        raise SeamtrackError(
            f"must be 0 to 232, got {args.domain_id}",
            field="--domain-id",
            fix="give the ROS_DOMAIN_ID of your ROS 2 nodes (0 by default)",
        )


def make_transport(args: argparse.Namespace) -> Any:
    check_flags(args)
    if args.transport == "zenoh":
        from seamtrack.bridge.zenoh_transport import DEFAULT_ENDPOINT, ZenohTransport

        return ZenohTransport(
            args.endpoint or DEFAULT_ENDPOINT,
            timeout_s=args.timeout_s,
            wait_s=args.wait_s,
            domain_id=args.domain_id,
        )
    from seamtrack.bridge.zmq_transport import DEFAULT_ENDPOINT as ZMQ_ENDPOINT
    from seamtrack.bridge.zmq_transport import ZmqTransport

    return ZmqTransport(args.endpoint or ZMQ_ENDPOINT, args.timeout_s, args.wait_s)


def cmd_serve(args: argparse.Namespace) -> int:
    from seamtrack.bridge.lockstep import serve
    from seamtrack.cli.tables import print_table
    from seamtrack.io.output import check_writable, write_run
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.scene import load_scene
    from seamtrack.viz.plots import plot_run

    check_flags(args)
    scene = load_scene(args.scene, list(args.set or []))
    out = Path(args.out) if args.out else Path("runs") / scene.name
    check_writable(out)
    parts = build_parts(scene)
    transport = make_transport(args)
    if not args.quiet:
        print(f"seamtrack serve: {scene.name} on {transport.endpoint}", file=sys.stderr)
    sys.stderr.flush()
    result, tracker = serve(parts, transport, args.lockstep, seed=scene.config.simulation.seed)
    write_run(
        result,
        out,
        scene.to_toml(),
        scene.config.simulation.trace_period_s,
        extra=None if args.no_plot else lambda stage: plot_run(result, stage / "error.png"),
    )
    if tracker.failure is not None:
        print(f"seamtrack: error: {tracker.failure}", file=sys.stderr)
        return 2
    if not args.quiet:
        print_table(list(result.summary.items()), f"seamtrack serve {scene.name}")
        print(f"wrote {out}/summary.json, trace.csv, frames.csv, scene.toml")
    return 0
