"""The paper's algorithm II (convergence radius, Sec. 4.3) as an external tracker for
``seamtrack serve --transport zmq``: pyzmq and the standard library only, nothing of seamtrack.

Usage: python zmq_algorithm2.py ENDPOINT [--radius-mm 1.0] [--misbehave KIND]
       [--no-profile] [--dump-profiles FILE] [--then 2]

It says hello, then answers every step with its command. A step is a multipart message: a JSON
header, then each frame's profile as raw little-endian arrays (float64 points, uint8 reasons)
that the header describes; algorithm II needs only the seam points, ``--dump-profiles`` reads
the profiles too (standard library only) and writes them as JSON lines. Each command carries
the next ``--then`` points of the queue (``then``: the bridge goes on to them itself when the
torch comes within the radius, between frames; ``--then 0``: it asks at each switch instead).

``--misbehave`` is for the tests: ``garbage`` (bytes that are not JSON), ``oversized`` (a 10 kB
message), ``silent`` (no answer to step 5), ``vanish`` (exit at step 5), ``bad-command`` (a NaN
target), ``multipart`` (a command in two parts).
"""

from __future__ import annotations

import argparse
import json
import math
import struct
import sys
import time

import zmq


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

    def update(self, point: list[float]) -> None:
        if self.last_pushed is not None and _dist(point, self.last_pushed) < self.min_spacing:
            return
        self.points.append(point)
        self.last_pushed = point

    def step(self, tcp: list[float], taken: int = 0) -> dict | None:
        # The bridge went on to `taken` of the points sent with the last command (its `then`):
        # the torch came within the radius of those before them, between the frames.
        del self.points[:taken]
        while len(self.points) > 1 and _dist(tcp, self.points[0]) <= self.radius:
            self.points.pop(0)
            self.command = None
        if not self.points:
            return None
        last = len(self.points) == 1
        if self.command is None or taken or last != self.command["stop_at_target"]:
            self.command = self._go(0)
        if not last and self.then:  # the points that follow, taken over without a round trip
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


def _dist(a: list[float], b: list[float]) -> float:
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


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("endpoint")
    ap.add_argument("--radius-mm", type=float, default=1.0)
    ap.add_argument("--misbehave", default="")
    ap.add_argument("--no-profile", action="store_true")
    ap.add_argument("--then", type=int, default=2, help="points sent ahead with each command")
    ap.add_argument("--dump-profiles", default="")
    args = ap.parse_args()
    dump = open(args.dump_profiles, "w") if args.dump_profiles else None
    ctx = zmq.Context()
    sock = ctx.socket(zmq.REQ)
    sock.setsockopt(zmq.LINGER, 0)
    sock.connect(args.endpoint)
    sock.send_json({"op": "hello", "protocol": 2, "profile": not args.no_profile})
    reset = sock.recv_json()
    speed = reset["context"]["welding_speed_mm_s"]
    tracker = ConvergenceRadius(speed, args.radius_mm, then=args.then)
    sock.send_json({"op": "ready"})
    while True:
        parts = sock.recv_multipart()  # blocks until the step is there: no polling
        msg = json.loads(parts[0])
        if msg["op"] == "end":
            print(json.dumps(msg["summary"]))
            if dump:
                dump.close()
            return 0
        for frame in msg["frames"]:
            if frame["found"]:
                tracker.update(frame["point_mm"])
            if dump and frame["profile"] is not None:
                points, reason = read_profile(frame["profile"], parts)
                row = {"t_capture_s": frame["t_capture_s"], "points": points, "reason": reason}
                dump.write(json.dumps(row) + "\n")
        cmd = tracker.step(msg["tcp_mm"], msg["then_taken"])
        if msg["seq"] == 5 and args.misbehave:
            if args.misbehave == "garbage":
                sock.send(b"\x80\x04garbage")
            elif args.misbehave == "oversized":
                sock.send_json({"op": "command", "seq": 5, "command": None, "pad": "x" * 10000})
            elif args.misbehave == "bad-command":
                bad = {"target_mm": [0.0, "nan", 0.0], "speed_mm_s": 5.0}
                sock.send_json({"op": "command", "seq": 5, "command": bad})
            elif args.misbehave == "multipart":
                sock.send_multipart([b'{"op": "command", "seq": 5,', b' "command": null}'])
            elif args.misbehave == "vanish":
                sock.close(0)
                ctx.term()
                return 0
            elif args.misbehave == "silent":
                time.sleep(30)  # connected, but no answer (until the test ends us)
            sock.recv()
            return 0
        sock.send(json.dumps({"op": "command", "seq": msg["seq"], "command": cmd}).encode())


if __name__ == "__main__":
    sys.exit(main())
