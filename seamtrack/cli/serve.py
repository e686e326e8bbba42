"""``seamtrack serve SCENE``: run a scene with its tracker in another process (the lockstep
bridge, :mod:`seamtrack.bridge.lockstep`; docs/ros.md).

SIGINT (Ctrl-C) and SIGTERM (``kill``, a CI time-out, a container stop) only set a flag, the
loop's :class:`~seamtrack.simulation.stop.StopRequest`, read after each tick and while the
bridge waits for the client: the run ends there as ``interrupted``, the client is sent its
``end``, the run folder is written (staged, so nothing half-written is left), one line says so,
and the exit code is 130 (SIGINT) or 143 (SIGTERM), as a shell reports a command a signal
ended. A second signal while the folder is written changes nothing."""

from __future__ import annotations

import argparse
import contextlib
import signal
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from seamtrack.cli.parsing import QUIET_HELP, SCENE_HELP, add_command

HELP = "run a scene with the tracker in another process (ZeroMQ, or ROS 2 over Zenoh)"


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Register the command on the ``seamtrack`` subparsers."""
    p = add_command(sub, "serve", cmd_serve, HELP, set_example="sensor.frame_rate_hz=50")
    p.add_argument("scene", help=SCENE_HELP)
    p.add_argument(
        "--transport",
        choices=["zmq", "zenoh"],
        default="zmq",
        help="zmq: packed records (protocol 3) or JSON (2) and raw profile arrays over a ZeroMQ "
        "ROUTER socket (one client a run); "
        "zenoh: ROS 2 messages as rmw_zenoh puts them",
    )
    p.add_argument(
        "--endpoint",
        help="where to listen: zmq default tcp://127.0.0.1:5555 (loopback; "
        "ipc:///PATH: a Unix socket, faster; tcp://HOST:PORT for another machine); "
        "zenoh default tcp/127.0.0.1:7447 (rmw_zenoh's router "
        "port); this machine only unless you say otherwise (then zmq needs --token-file)",
    )
    p.add_argument(
        "--token-file",
        help="zmq: a file holding a shared secret (16+ characters) that the client's hello "
        'must carry as "token"; needed to listen beyond loopback',
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
    p.add_argument("-q", "--quiet", action="store_true", help=QUIET_HELP)
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
    if args.transport == "zenoh":
        if args.token_file is not None:
            raise SeamtrackError(
                "is for --transport zmq",
                field="--token-file",
                fix="leave it out (a Zenoh router beyond loopback: docs/ros.md)",
            )
        if args.endpoint is not None:
            from seamtrack.bridge.zenoh_transport import check_locator

            check_locator(args.endpoint)
        return
    from seamtrack.bridge.zmq_transport import DEFAULT_ENDPOINT, check_endpoint, read_token

    token = None if args.token_file is None else read_token(args.token_file)
    check_endpoint(args.endpoint or DEFAULT_ENDPOINT, token)
    args.token = token


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

    return ZmqTransport(args.endpoint or ZMQ_ENDPOINT, args.timeout_s, args.wait_s, args.token)


def start_hint(args: argparse.Namespace, endpoint: str) -> str:
    """How to start a tracker for this serve (the example client that ships with seamtrack)."""
    if args.transport == "zenoh":
        return (
            "a ROS 2 node under RMW_IMPLEMENTATION=rmw_zenoh_cpp, without rmw_zenohd: this is "
            "its router (docs/ros.md)"
        )
    token = f" --token-file {args.token_file}" if args.token_file else ""
    return f"python -m seamtrack.bridge.example_client {endpoint}{token}"


@contextlib.contextmanager
def stop_on_signals(stop: Any) -> Iterator[None]:
    """SIGINT and SIGTERM request ``stop`` (a :class:`~seamtrack.simulation.stop.StopRequest`:
    a flag, nothing is raised; the first signal names it, cause ``sigint`` or ``sigterm``)
    while the block runs; the handlers that were there come back after it."""
    signums = (signal.SIGINT, signal.SIGTERM)
    before = {signum: signal.getsignal(signum) for signum in signums}

    def handler(signum: int, frame: Any) -> None:
        name = signal.Signals(signum).name
        stop.request(name.lower(), f"bridge: interrupted by {name}")

    for signum in signums:
        signal.signal(signum, handler)
    try:
        yield
    finally:
        for signum, handler_before in before.items():
            signal.signal(signum, handler_before)


def cmd_serve(args: argparse.Namespace) -> int:
    from seamtrack.simulation.stop import StopRequest

    stop = StopRequest()
    with stop_on_signals(stop):
        return _serve(args, stop)


def _serve(args: argparse.Namespace, stop: Any) -> int:
    from seamtrack.bridge.lockstep import serve
    from seamtrack.cli.signals import exit_code
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
    if stop.requested:  # before the run began: nothing was simulated, nothing is written
        print(f"seamtrack serve: {stop.cause.upper()} before the run began; "
              "nothing written", file=sys.stderr)  # fmt: skip
        return exit_code(stop)
    transport = make_transport(args)
    if not args.quiet:
        print(
            f"seamtrack serve: {scene.name}: waiting up to {args.wait_s:g} s for a tracker on "
            f"{transport.endpoint}; start one, e.g. {start_hint(args, transport.endpoint)}",
            file=sys.stderr,
        )
    sys.stderr.flush()
    result, tracker = serve(
        parts, transport, args.lockstep, seed=scene.config.simulation.seed, stop=stop
    )
    plot = not args.no_plot
    write_run(
        result,
        out,
        scene.to_toml(),
        scene.config.simulation.trace_period_s,
        extra=lambda stage: plot_run(result, stage / "error.png") if plot else None,
    )
    files = ["summary.json", "trace.csv", "frames.csv", "scene.toml"] + ["error.png"] * plot
    wrote = f"{out}/" + ", ".join(files)
    if exit_code(stop):  # stopped by a signal
        t_s = result.summary.get("sim_time_s", 0.0)
        print(
            f"seamtrack serve: {stop.cause.upper()}: stopped at t = "
            f"{t_s:.3f} s (status interrupted); wrote {wrote}",
            file=sys.stderr,
        )
        return exit_code(stop)
    if tracker.failure is not None:
        print(f"seamtrack: error: {tracker.failure}", file=sys.stderr)
        return 2
    if not args.quiet:
        print_table(list(result.summary.items()), f"seamtrack serve {scene.name}")
        print(f"wrote {wrote}")
    return 0
