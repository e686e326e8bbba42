"""The shipped example client (:mod:`seamtrack.bridge.example_client`: the paper's algorithm II
with pyzmq and the standard library only), plus the misbehaviours the tests need.

Usage: python zmq_algorithm2.py ENDPOINT [--radius-mm 1.0] [--misbehave KIND]
       [--no-profile] [--dump-profiles FILE] [--then 2]

``--misbehave`` is for the tests: ``garbage`` (bytes that are not JSON), ``oversized`` (a 10 kB
message), ``silent`` (no answer to step 5 until 0.3 s after the deadline, then one),
``vanish`` (exit at step 5), ``bad-command`` (a NaN target), ``multipart`` (a command in two
parts). After misbehaving it prints (one JSON line) what the server sent it then, or null.
"""

from __future__ import annotations

import json
import sys
import time

import zmq

from seamtrack.bridge.example_client import (
    ConvergenceRadius,
    hello,
    parser,
    read_profile,
    timing,
)


def main() -> int:
    ap = parser()
    ap.add_argument("--misbehave", default="")
    ap.add_argument("--deadline-s", type=float, default=2.0, help="serve's --timeout-s")
    args = ap.parse_args()
    dump = open(args.dump_profiles, "w") if args.dump_profiles else None
    ctx = zmq.Context()
    sock = ctx.socket(zmq.REQ)
    sock.setsockopt(zmq.LINGER, 0)
    sock.connect(args.endpoint)
    sock.send_json({**hello(args), "protocol": 2})  # JSON steps: its misbehaviours are JSON
    reset = sock.recv_json()
    speed = reset["context"]["welding_speed_mm_s"]
    tracker = ConvergenceRadius(speed, args.radius_mm, then=args.then)
    sock.send_json({"op": "ready"})
    steps, started, started_thread = 0, 0.0, 0.0
    while True:
        parts = sock.recv_multipart()  # blocks until the step is there: no polling
        if not steps:
            started, started_thread = time.process_time(), time.thread_time()
        msg = json.loads(parts[0])
        if msg["op"] == "end":
            print(json.dumps(msg["summary"]))
            if args.timing:
                print(json.dumps(timing(steps, started, started_thread)))
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
                time.sleep(args.deadline_s + 0.3)  # connected, but the answer comes late
                sock.send(json.dumps({"op": "command", "seq": 5, "command": cmd}).encode())
            told = None
            if sock.poll(10000):
                told = json.loads(sock.recv())
            print(json.dumps(told))
            return 0
        sock.send(json.dumps({"op": "command", "seq": msg["seq"], "command": cmd}).encode())
        steps += 1


if __name__ == "__main__":
    sys.exit(main())
