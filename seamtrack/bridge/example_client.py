"""An external tracker for ``seamtrack serve`` (ZeroMQ transport): the paper's algorithm II,
written with pyzmq and the standard library only, nothing else of seamtrack, so that it reads
as a client in any language would be written from docs/ros.md.

Usage::

    seamtrack serve paper-verification                       # terminal 1
    python -m seamtrack.bridge.example_client                # terminal 2
    python -m seamtrack.bridge.example_client ipc:///tmp/b --radius-mm 0.5 --then 0

It says hello (protocol 3), then answers every step with its command, and prints the run's
summary (one JSON line) when the ``end`` comes; a refusal (``error``) or an ``end`` of a failed
run is printed to stderr with its reason, exit code 1. A step is a multipart message: its
packed record and its frames' (little-endian, the :data:`STEP` and :data:`FRAME` layouts of
docs/ros.md), then each frame's profile as raw little-endian arrays (float64 points, uint8
reasons); the command goes back as packed records too (:data:`COMMAND`, :data:`MOVE`).
Algorithm II needs only the seam points, ``--dump-profiles`` reads the profiles too and
writes them as JSON lines. Each command carries the next ``--then`` points of
the queue (``then``: the bridge goes on to them itself when the torch comes within the radius,
between frames; ``--then 0``: it asks at each switch instead). ``--token-file`` sends a
server's shared token (needed beyond loopback); ``--timing`` prints its CPU time after the
summary (a JSON line: before the first step, and from it on).

Per step it does little, as a client that keeps up should: it receives the step part by part
(part 0 says which parts follow: two for each frame that brings its profile), unpacks only the
fields it reads, and packs a command once, sending it again while it holds with only its seq
new (:meth:`ConvergenceRadius.step` returns the same object until its points change).

Algorithm II, exactly as seamtrack's in-process ``convergence-radius`` (so that the run is the
same, byte for byte, with ``--set tracker.params={}``): every found seam point is queued
unless it is closer than ``min_spacing_mm`` (0.05) to the last point queued (a torch that
waits keeps seeing the same spot); at each step, while more than one point is queued and the
torch is within ``radius_mm`` of the oldest (``sqrt(dx² + dy² + dz²) <= r``), that one is
dropped; the command goes to the oldest at the welding speed, passing through it
(``stop_at_target`` false), or arriving at rest on it when it is the only one left.
"""

from __future__ import annotations

import argparse
import json
import math
import struct
import sys
import time

DEFAULT_ENDPOINT = "tcp://127.0.0.1:5555"

# Protocol 3's records (docs/ros.md), little-endian whatever the machine.
STEP = struct.Struct("<4sIHHd3d3d")  # b"STP3", seq, then_taken, frames, t_s, tcp, velocity
FRAME = struct.Struct("<ddB3xI3d16d3d")  # t_capture, t_arrival, flags, n, point, T, tcp
FRAME_HEAD = struct.Struct("<ddB3xI3d")  # what of a FRAME this client reads: up to its point
COMMAND = struct.Struct("<4sIBB2x")  # b"CMD3", seq, flags (1: a command), then
MOVE = struct.Struct("<B7x3ddd3d9d3d")  # flags (1: stop), target, speed, ask_within, ...
_ZEROS = (0.0,) * 15  # a move's velocity_ff, rotation and angular velocity: not sent


class ConvergenceRadius:
    """Go to the oldest unreached seam point at the welding speed; take the next one as soon as
    the torch is within the radius; arrive at rest on the last one known."""

    def __init__(
        self,
        speed_mm_s: float,
        radius_mm: float = 1.0,
        min_spacing_mm: float = 0.05,
        then: int = 2,
    ):
        self.speed = speed_mm_s
        self.radius = radius_mm
        self.min_spacing = min_spacing_mm
        self.then = then  # how many of the next points go with each command
        self.points: list[list[float]] = []
        self.last_pushed: list[float] | None = None
        self.command: dict | None = None
        self.made_of: list[list[float]] = []

    def update(self, point: list[float]) -> None:
        if self.last_pushed is not None and dist(point, self.last_pushed) < self.min_spacing:
            return
        self.points.append(point)
        self.last_pushed = point

    def step(self, tcp: list[float], taken: int = 0) -> dict | None:
        """The command for this step; the same object as the last one while it holds (the
        caller packs it once, not every step)."""
        # The bridge went on to `taken` of the points sent with the last command (its `then`):
        # the torch came within the radius of those before them, between the frames.
        del self.points[:taken]
        while len(self.points) > 1 and dist(tcp, self.points[0]) <= self.radius:
            self.points.pop(0)
        if not self.points:
            self.command = None
            return None
        # What the command is made of: the points it goes to, and whether one follows them
        # (the last point known is arrived at, at rest).
        made_of = self.points[: 2 + self.then]
        if self.command is None or made_of != self.made_of:
            self.made_of = made_of
            self.command = self._go(0)
            if len(self.points) > 1 and self.then:  # the next points, taken over in the bridge
                ahead = range(1, min(1 + self.then, len(self.points)))
                self.command["then"] = [self._go(i) for i in ahead]
        return self.command

    def _go(self, i: int) -> dict:
        """The command to the queue's point i."""
        last = i == len(self.points) - 1
        command = {"target_mm": self.points[i], "speed_mm_s": self.speed, "stop_at_target": last}
        if not last:  # the switch comes within the radius: be asked then (frame lockstep)
            command["ask_within_mm"] = self.radius
        return command


def dist(a: list[float], b: list[float]) -> float:
    dx, dy, dz = a[0] - b[0], a[1] - b[1], a[2] - b[2]
    return math.sqrt(dx * dx + dy * dy + dz * dz)


def read_profile(profile: dict, parts: list[bytes]) -> tuple[list, list]:
    """A frame's profile: [(y_mm, z_mm), ...] (None for NaN) and the reason codes; every part's
    size checked against its shape before it is read."""
    out = []
    for name, dtype, size in (("points", "<f8", 8), ("reason", "|u1", 1)):
        d = profile[name]
        if d["dtype"] != dtype:
            raise ValueError(f"{name}: dtype {d['dtype']}, not {dtype}")
        count = math.prod(d["shape"])
        raw = parts[d["part"]]
        if len(raw) != count * size:
            raise ValueError(f"{name}: {len(raw)} bytes for shape {d['shape']}")
        out.append(raw)
    n = profile["reason"]["shape"][0]
    values = struct.unpack(f"<{2 * n}d", out[0])  # little-endian on any machine
    points = [[None if v != v else v for v in values[2 * i : 2 * i + 2]] for i in range(n)]
    return points, list(out[1])


def read_step(head: bytes) -> tuple[int, int, list[float], list[tuple]]:
    """A protocol-3 step's part 0: seq, then_taken, the torch tip, and its frames as (found,
    point_mm, t_capture_s, n): n the points of its profile, whose two parts follow part 0
    (-1: none sent); its size checked before it is read."""
    _, seq, taken, count, _, x, y, z, *_ = STEP.unpack_from(head)
    if len(head) != STEP.size + count * FRAME.size:
        raise ValueError(f"a step of {count} frames in {len(head)} bytes")
    frames = []
    for k in range(count):
        t_capture, _, flags, n, px, py, pz = FRAME_HEAD.unpack_from(
            head, STEP.size + k * FRAME.size
        )
        frames.append((bool(flags & 1), [px, py, pz], t_capture, n if flags & 2 else -1))
    return seq, taken, [x, y, z], frames


def command_bytes(seq: int, command: dict | None) -> bytes:
    """A protocol-3 command answering step ``seq`` (None: brake to rest and wait)."""
    return command_head(seq, command) + moves_bytes(command)


def command_head(seq: int, command: dict | None) -> bytes:
    """The COMMAND record: the step answered, whether moves follow, and how many."""
    if command is None:
        return COMMAND.pack(b"CMD3", seq, 0, 0)
    return COMMAND.pack(b"CMD3", seq, 1, len(command.get("then", ())))


def moves_bytes(command: dict | None) -> bytes:
    """The command's MOVE records, then's too (none for None)."""
    if command is None:
        return b""
    records = []
    for m in (command, *command.get("then", ())):
        flags = 1 if m["stop_at_target"] else 0
        within = m.get("ask_within_mm", 0.0)
        records.append(MOVE.pack(flags, *m["target_mm"], m["speed_mm_s"], within, *_ZEROS))
    return b"".join(records)


def profile_row(t_capture_s: float, points: bytes, reason: bytes) -> dict:
    """A protocol-3 frame's profile as a JSON line: the points (None for NaN), the reasons."""
    n = len(reason)
    values = struct.unpack(f"<{2 * n}d", points)  # little-endian on any machine
    rows = [[None if v != v else v for v in values[2 * i : 2 * i + 2]] for i in range(n)]
    return {"t_capture_s": t_capture_s, "points": rows, "reason": list(reason)}


def parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="python -m seamtrack.bridge.example_client",
        description="algorithm II as a tracker process for seamtrack serve (ZeroMQ)",
    )
    ap.add_argument("endpoint", nargs="?", default=DEFAULT_ENDPOINT, help="serve's --endpoint")
    ap.add_argument("--radius-mm", type=float, default=1.0, help="the radius of convergence")
    ap.add_argument("--then", type=int, default=2, help="points sent ahead with each command")
    ap.add_argument("--no-profile", action="store_true", help="ask for no profiles")
    ap.add_argument("--dump-profiles", default="", help="write each frame's profile (JSON lines)")
    ap.add_argument("--token-file", default="", help="a file holding serve's shared token")
    ap.add_argument(
        "--timing", action="store_true", help="print this process's CPU time (a JSON line)"
    )
    return ap


def hello(args: argparse.Namespace, protocol: int = 3) -> dict:
    message = {"op": "hello", "protocol": protocol, "profile": not args.no_profile}
    if args.token_file:
        with open(args.token_file, encoding="utf-8") as f:
            message["token"] = f.read().strip()
    return message


def _fault(end: dict) -> bool:
    """Did the run end by the bridge (this client's fault, a signal) rather than by the
    simulation itself (completed, lost_seam, a time limit, ...)?"""
    return end["status"] == "interrupted" or str(end["reason"]).startswith("bridge:")


def timing(steps: int, started: float, started_thread: float) -> dict:
    """This process's CPU time (all its threads: ZeroMQ's I/O thread too) before the first
    step (start-up) and from it to the end, this thread's from it to the end, and the steps
    answered."""
    now, thread = time.process_time(), time.thread_time()
    return {"steps": steps, "start_cpu_s": started, "loop_cpu_s": now - started,
            "thread_cpu_s": thread - started_thread}  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    import zmq

    args = parser().parse_args(argv)
    dump = open(args.dump_profiles, "w") if args.dump_profiles else None
    ctx = zmq.Context()
    sock = ctx.socket(zmq.REQ)
    sock.setsockopt(zmq.LINGER, 0)
    sock.connect(args.endpoint)
    try:
        sock.send_json(hello(args))
        reset: dict = json.loads(sock.recv())
        if reset["op"] != "reset":  # a refusal: {"op": "error", "status", "reason"}
            print(f"refused: {reset.get('reason')}", file=sys.stderr)
            return 1
        tracker = ConvergenceRadius(
            reset["context"]["welding_speed_mm_s"], args.radius_mm, then=args.then
        )
        sock.send_json({"op": "ready"})
        steps, started, started_thread = 0, 0.0, 0.0
        sent, moves = None, b""  # the last command packed, and its records
        while True:
            head = sock.recv()  # blocks until the step is there: no polling
            if not steps:  # start-up: imports, connecting, hello
                started, started_thread = time.process_time(), time.thread_time()
            if head[:4] != b"STP3":  # the end of the run, a fault too: status and reason
                msg = json.loads(head)
                print(json.dumps(msg.get("summary", msg)))
                if args.timing:
                    print(json.dumps(timing(steps, started, started_thread)))
                if msg["op"] == "end" and not _fault(msg):
                    return 0
                print(f"{msg['status']}: {msg['reason']}", file=sys.stderr)
                return 1
            seq, taken, tcp, frames = read_step(head)
            for found, point, t_capture, n in frames:
                if n >= 0:  # its profile follows in two parts: n points, n reason codes
                    points, reason = sock.recv(), sock.recv()
                    if len(points) != 16 * n or len(reason) != n:
                        raise ValueError(f"step {seq}: profile parts not of {n} points")
                    if dump:
                        dump.write(json.dumps(profile_row(t_capture, points, reason)) + "\n")
                if found:
                    tracker.update(point)
            command = tracker.step(tcp, taken)
            if command is not sent:  # a new command: packed once, sent until it changes
                sent, moves = command, moves_bytes(command)
            sock.send(command_head(seq, command) + moves)
            steps += 1
    finally:
        if dump:
            dump.close()
        sock.close(0)
        ctx.term()


if __name__ == "__main__":
    sys.exit(main())
