"""The paper's algorithm II (convergence radius, Sec. 4.3) as a ROS 2 tracker node on Zenoh,
speaking what rmw_zenoh_cpp speaks: CDR payloads (rosbags) on ``<domain>/<topic>/<dds type>/
<RIHS01 hash>`` key expressions, with liveliness tokens for the node and its entities. Only
``zenoh`` and ``rosbags`` (and the standard library): nothing of seamtrack.

Per step it does what a node that keeps up does: the torch and the seam points (a header and
fixed doubles) are read with struct where their CDR layout puts them, and each command is
serialized with rosbags once, then stamped with the step's time while it holds.

Usage: python zenoh_algorithm2.py LOCATOR [--radius-mm 1.0] [--misbehave KIND] [--then 2]

Works in SI units as a ROS node does (m, m/s). With each command it publishes its next
``--then`` points on ``/seamtrack/cmd_then`` (the bridge goes on to them itself when the torch
comes within the radius, between frames, and says how many on ``/seamtrack/then_taken``);
``--then 0``: no cmd_then, the bridge asks at each switch.

``--misbehave`` is for the tests: ``garbage`` (bytes that are not CDR), ``oversized`` (a
10 kB payload), ``silent`` (no answer to step 5), ``vanish`` (exit at step 5).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import queue
import struct
import sys
import time

import zenoh
from rosbags.typesys import Stores, get_typestore

TS = get_typestore(Stores.ROS2_JAZZY)
T = TS.types
DOMAIN = 0
QOS = "::,10:,:,:,,"


def dds(msgtype: str) -> str:
    package, kind, name = msgtype.split("/")
    return f"{package}::{kind}::dds_::{name}_"


def key(topic: str, msgtype: str) -> str:
    return f"{DOMAIN}/{topic.strip('/')}/{dds(msgtype)}/{TS.hash_rihs01(msgtype)}"


def token(session: str, entity: int, kind: str, topic: str, msgtype: str) -> str:
    return (
        f"@ros2_lv/{DOMAIN}/{session}/0/{entity}/{kind}/%/%/tracker/{topic.replace('/', '%')}/"
        f"{dds(msgtype)}/{TS.hash_rihs01(msgtype)}/{QOS}"
    )


def warm_up() -> None:
    """rosbags writes (and compiles) a type's serializer on its first use, which takes a good
    part of a second: do it before the run starts, not on its first step."""
    time_ = T["builtin_interfaces/msg/Time"](sec=0, nanosec=0)
    header = T["std_msgs/msg/Header"](stamp=time_, frame_id="")
    point = T["geometry_msgs/msg/Point"](x=0.0, y=0.0, z=0.0)
    vector = T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
    q = T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)
    messages = [
        T["geometry_msgs/msg/PoseStamped"](
            header=header, pose=T["geometry_msgs/msg/Pose"](position=point, orientation=q)
        ),
        T["geometry_msgs/msg/TwistStamped"](
            header=header, twist=T["geometry_msgs/msg/Twist"](linear=vector, angular=vector)
        ),
        T["geometry_msgs/msg/PointStamped"](header=header, point=point),
        T["std_msgs/msg/String"](data=""),
        T["std_msgs/msg/UInt32"](data=0),
        T["geometry_msgs/msg/PoseArray"](
            header=header, poses=[T["geometry_msgs/msg/Pose"](position=point, orientation=q)]
        ),
    ]
    for msg in messages:
        TS.deserialize_cdr(TS.serialize_cdr(msg, msg.__msgtype__), msg.__msgtype__)


class ConvergenceRadius:
    """Go to the oldest unreached seam point at the welding speed; take the next one as soon as
    the torch is within the radius; arrive at rest on the last one known (all in m)."""

    def __init__(self, speed: float, radius: float, min_spacing: float = 0.05e-3):
        self.speed, self.radius, self.min_spacing = speed, radius, min_spacing
        self.points: list[tuple[float, float, float]] = []
        self.last_pushed: tuple[float, float, float] | None = None
        self.command: tuple[tuple[float, float, float], bool] | None = None

    def update(self, point: tuple[float, float, float]) -> None:
        if self.last_pushed is not None and dist(point, self.last_pushed) < self.min_spacing:
            return
        self.points.append(point)
        self.last_pushed = point

    def step(
        self, tcp: tuple[float, float, float], taken: int = 0
    ) -> tuple[tuple[float, float, float], bool] | None:
        # The bridge went on to `taken` of the points sent in the last cmd_then: the torch came
        # within the radius of those before them, between the frames.
        if taken:
            del self.points[:taken]
            self.command = None
        while len(self.points) > 1 and dist(tcp, self.points[0]) <= self.radius:
            self.points.pop(0)
            self.command = None
        if not self.points:
            return None
        last = len(self.points) == 1
        if self.command is None or last != self.command[1]:
            self.command = (self.points[0], last)
        return self.command

    def ahead(self, n: int) -> list[tuple[float, float, float]]:
        """The next points to pass through (cmd_then), the last one known left out (the
        torch arrives at rest there: a command of its own)."""
        return self.points[1 : min(1 + n, len(self.points) - 1)]


#: A header's stamp (sec, nanosec), the first field of each command message (little-endian CDR,
#: after the 4-byte encapsulation header).
STAMP = struct.Struct("<iI")
HEADER = struct.Struct("<iII")  # the stamp, then the frame id's length


def stamped_doubles(raw: bytes, msgtype: str, n: int) -> tuple[tuple[int, int], tuple]:
    """A message of a header and n doubles (PointStamped: 3, PoseStamped: 7) as (its stamp as
    (sec, nanosec), the doubles), read with struct where the CDR layout puts them (the doubles
    aligned to 8 after the header's frame id); a big-endian message through rosbags."""
    if raw[:4] != b"\x00\x01\x00\x00":
        msg = TS.deserialize_cdr(raw, msgtype)
        values = msg.point if n == 3 else msg.pose.position
        stamp = (msg.header.stamp.sec, msg.header.stamp.nanosec)
        extra = () if n == 3 else (0.0,) * 4
        return stamp, (values.x, values.y, values.z, *extra)
    sec, nanosec, length = HEADER.unpack_from(raw, 4)
    at = 12 + length
    at += -at % 8  # from the end of the encapsulation header
    return (sec, nanosec), struct.unpack_from(f"<{n}d", raw, 4 + at)


def command_messages(tracker, cmd, ahead, then: int) -> list[tuple[str, bytearray]]:
    """The answer to a step as (topic, CDR bytes) serialized by rosbags, stamped 0: cmd_pose
    and cmd_speed (and cmd_then: the points ``ahead``); the caller stamps them."""
    stamp = T["builtin_interfaces/msg/Time"](sec=0, nanosec=0)
    zero = T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)
    if cmd is None:  # an empty frame id: brake to rest and wait
        target, stop, frame = (0.0, 0.0, 0.0), 0.0, ""
    else:
        target, stop, frame = cmd[0], 1.0 if cmd[1] else 0.0, "world"
    header = T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame)
    # Ask again within the radius (frame lockstep): that is where the switch comes.
    within = 0.0 if cmd is None or cmd[1] else tracker.radius
    orientation = T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=0.0)
    pose = T["geometry_msgs/msg/Pose"](
        position=T["geometry_msgs/msg/Point"](x=target[0], y=target[1], z=target[2]),
        orientation=orientation,
    )
    twist = T["geometry_msgs/msg/Twist"](
        linear=T["geometry_msgs/msg/Vector3"](x=tracker.speed, y=stop, z=within), angular=zero
    )
    messages = [
        ("/seamtrack/cmd_pose", T["geometry_msgs/msg/PoseStamped"](header=header, pose=pose)),
        ("/seamtrack/cmd_speed", T["geometry_msgs/msg/TwistStamped"](header=header, twist=twist)),
    ]
    if then:
        poses = [
            T["geometry_msgs/msg/Pose"](
                position=T["geometry_msgs/msg/Point"](x=a[0], y=a[1], z=a[2]),
                orientation=orientation,
            )
            for a in ahead
        ]
        then_header = T["std_msgs/msg/Header"](stamp=stamp, frame_id="world")
        array = T["geometry_msgs/msg/PoseArray"](header=then_header, poses=poses)
        messages.append(("/seamtrack/cmd_then", array))
    return [
        (topic, bytearray(TS.serialize_cdr(m, m.__msgtype__, little_endian=True)))
        for topic, m in messages
    ]


def dist(a, b) -> float:
    dx, dy, dz = a[0] - b[0], a[1] - b[1], a[2] - b[2]
    return math.sqrt(dx * dx + dy * dy + dz * dz)


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("locator")
    ap.add_argument("--radius-mm", type=float, default=1.0)
    ap.add_argument("--misbehave", default="")
    ap.add_argument("--check-frames", action="store_true")
    ap.add_argument("--then", type=int, default=2, help="points sent ahead (cmd_then)")
    ap.add_argument("--timing", action="store_true", help="print this process's CPU time")
    args = ap.parse_args()
    config = zenoh.Config()
    config.insert_json5("mode", '"client"')
    config.insert_json5("connect/endpoints", json.dumps([args.locator]))
    config.insert_json5("scouting/multicast/enabled", "false")
    deadline = time.monotonic() + 60.0
    while True:  # the server may still be loading its scene
        try:
            session = zenoh.open(config)
            break
        except zenoh.ZError:
            if time.monotonic() > deadline:
                raise
            time.sleep(0.2)
    sid = str(session.zid())
    warm_up()

    subs = {
        "/seamtrack/context": "std_msgs/msg/String",
        "/seamtrack/status": "std_msgs/msg/String",
        "/seamtrack/seam_point_world": "geometry_msgs/msg/PointStamped",
        "/seamtrack/tcp": "geometry_msgs/msg/PoseStamped",
    }
    if args.check_frames:  # what a frame brings besides the seam point, counted and stamped
        subs["/seamtrack/profile"] = "sensor_msgs/msg/PointCloud2"
        subs["/tf"] = "tf2_msgs/msg/TFMessage"
        subs["/clock"] = "rosgraph_msgs/msg/Clock"
    seen: dict[str, list] = {"/seamtrack/profile": [], "/tf": [], "/clock": []}
    pubs = {
        "/seamtrack/cmd_pose": "geometry_msgs/msg/PoseStamped",
        "/seamtrack/cmd_speed": "geometry_msgs/msg/TwistStamped",
    }
    if args.then:  # the points that follow, and how many of them the bridge went on to
        pubs["/seamtrack/cmd_then"] = "geometry_msgs/msg/PoseArray"
        subs["/seamtrack/then_taken"] = "std_msgs/msg/UInt32"
    live = session.liveliness()
    tokens = [live.declare_token(f"@ros2_lv/{DOMAIN}/{sid}/0/0/NN/%/%/tracker")]
    # One subscription per topic it takes, as a ROS node has (so the bridge, seeing no one
    # take the profiles, the TF chain or the clock, sends none of them); their callbacks put
    # the samples in one queue that this thread reads. The callbacks run on Zenoh's own
    # thread (indirect=False), which calls them in the order the samples came on the one link:
    # a step's seam points before its /seamtrack/tcp (the default, a Python thread per
    # subscription, may call back for /seamtrack/tcp first).
    inbox: queue.SimpleQueue = queue.SimpleQueue()

    def keep(topic):
        def put(sample):
            inbox.put((topic, sample.payload.to_bytes()))

        return zenoh.handlers.Callback(put, indirect=False)

    subscribers = [
        session.declare_subscriber(key(topic, msgtype), keep(topic))
        for topic, msgtype in subs.items()
    ]

    def receive():
        return inbox.get()  # blocks until a sample is there: no polling

    entity = 1
    for topic, msgtype in subs.items():
        tokens.append(live.declare_token(token(sid, entity, "MS", topic, msgtype)))
        entity += 1
    publishers = {}
    gids = {}
    for topic, msgtype in pubs.items():
        publishers[topic] = session.declare_publisher(
            key(topic, msgtype), congestion_control=zenoh.CongestionControl.BLOCK
        )
        gids[topic] = hashlib.sha256(f"{sid}{topic}".encode()).digest()[:16]
        tokens.append(live.declare_token(token(sid, entity, "MP", topic, msgtype)))
        entity += 1
    seq = [0]

    def publish(topic, raw):
        seq[0] += 1
        attachment = struct.pack("<qqB", seq[0], time.time_ns(), 16) + gids[topic]
        publishers[topic].put(bytes(raw), attachment=attachment)

    tracker = None
    held: tuple = (False, [])  # the command last serialized, and its messages
    serialized: list = []
    steps, started, started_thread = 0, 0.0, 0.0
    taken = 0
    while True:
        topic, raw = receive()
        if topic == "/seamtrack/context":
            context = json.loads(TS.deserialize_cdr(raw, subs[topic]).data)["context"]
            if args.check_frames:  # latched: asked for again, as a late subscriber would
                got = [
                    r.ok.payload.to_bytes() for r in session.get(key(topic, subs[topic])) if r.ok
                ]
                seen["late_context"] = got == [raw]
                msgtype = "tf2_msgs/msg/TFMessage"
                replies = session.get(key("/tf_static", msgtype))
                static = [TS.deserialize_cdr(r.ok.payload.to_bytes(), msgtype) for r in replies]
                seen["late_tf_static"] = [
                    [[t.header.frame_id, t.child_frame_id] for t in m.transforms] for m in static
                ]
            speed = context["welding_speed_mm_s"] / 1000.0
            tracker = ConvergenceRadius(speed, args.radius_mm / 1000.0)
        elif topic in seen:
            msg = TS.deserialize_cdr(raw, subs[topic])
            if topic == "/seamtrack/profile":
                seen[topic].append([msg.header.stamp.sec, msg.header.stamp.nanosec, msg.width])
            elif topic == "/tf":
                seen[topic].append([[t.header.frame_id, t.child_frame_id] for t in msg.transforms])
            else:
                seen[topic].append([msg.clock.sec, msg.clock.nanosec])
        elif topic == "/seamtrack/status":
            print(TS.deserialize_cdr(raw, subs[topic]).data)
            if args.check_frames:
                print(json.dumps(seen))
            if args.timing:  # CPU before the first step (start-up) and from it on
                now = time.process_time()
                timing = {"steps": steps, "start_cpu_s": started, "loop_cpu_s": now - started}
                timing["thread_cpu_s"] = time.thread_time() - started_thread
                print(json.dumps(timing))
            break
        elif topic == "/seamtrack/then_taken":
            taken = TS.deserialize_cdr(raw, subs[topic]).data
        elif topic == "/seamtrack/seam_point_world":
            tracker.update(stamped_doubles(raw, subs[topic], 3)[1])
        elif topic == "/seamtrack/tcp":
            if not steps:
                started, started_thread = time.process_time(), time.thread_time()
            stamp, (x, y, z, *_) = stamped_doubles(raw, subs[topic], 7)
            cmd = tracker.step((x, y, z), taken)
            taken = 0
            if steps == 5 and args.misbehave:
                if args.misbehave == "garbage":
                    publishers["/seamtrack/cmd_pose"].put(b"\x00\x01garbage")
                elif args.misbehave == "oversized":
                    publishers["/seamtrack/cmd_pose"].put(b"\x00" * 10000)
                elif args.misbehave == "vanish":
                    for t in tokens:
                        t.undeclare()
                    session.close()
                    return 0
                time.sleep(30)
                return 0
            steps += 1
            ahead = [] if cmd is None or cmd[1] or not args.then else tracker.ahead(args.then)
            if (cmd, ahead) != held:  # a new command: serialized once (rosbags), then held
                held = (cmd, ahead)
                serialized = command_messages(tracker, cmd, ahead, args.then)
            for topic, raw in serialized:  # each message of the answer stamped with the step's
                STAMP.pack_into(raw, 4, *stamp)  # the header's stamp, its first field
                publish(topic, raw)
    for subscriber in subscribers:
        subscriber.undeclare()
    for t in tokens:
        t.undeclare()
    session.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
