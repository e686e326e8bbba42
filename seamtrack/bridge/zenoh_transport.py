"""The Zenoh transport: ROS 2 messages (CDR) on rmw_zenoh's key expressions, so that a ROS 2
node under ``RMW_IMPLEMENTATION=rmw_zenoh_cpp`` can be the tracker (:mod:`seamtrack.bridge.rmw`
gives the formats; docs/ros.md the topics).

The bridge is a node ``/seamtrack`` in a Zenoh session in router mode, listening on loopback
(rmw_zenoh's router port 7447 by default, so a ROS node connects to it as to ``rmw_zenohd``).
Per step it publishes, for each frame that arrived: ``/tf`` (world -> base -> [flange ->] tcp
-> sensor at capture), ``/seamtrack/profile`` (PointCloud2 in ``sensor``), when a seam
point was found ``/seamtrack/seam_point`` (PointStamped), and in image mode
``/seamtrack/image`` (:func:`seamtrack.bridge.messages.frame_messages`); then ``/clock``,
``/seamtrack/tcp_velocity`` (TwistStamped) and, last, ``/seamtrack/tcp`` (PoseStamped, the
torch tip in ``world``): the step's trigger. The tracker answers with the pair
``/seamtrack/cmd_pose`` (PoseStamped) and ``/seamtrack/cmd_speed`` (TwistStamped), both
stamped with the step's time; a tracker that publishes ``/seamtrack/cmd_then`` (PoseArray:
the targets that follow, passed through at cmd_speed's speed and ask_within; the transport's
``then``) adds it to each answer, and is told before each ``/seamtrack/tcp`` how many of them
took over (``/seamtrack/then_taken``, UInt32). Only the topics a subscriber matches are
written and put (``/seamtrack/tcp`` always).

The run starts once a node has declared a subscription to ``/seamtrack/tcp`` and publishers
of both command topics (their liveliness tokens); ``/seamtrack/context`` (String, JSON) then
gives it the run's context, after ``/tf_static`` (the links that do not move: world -> base,
[flange -> tcp,] tcp -> sensor, stamped 0). When that node's tokens go, the run ends
(disconnected). ``/tf_static``, the context, and ``/seamtrack/status`` once the run is over
are latched (transient local): a subscriber that comes later gets the last one on request (a
Zenoh get on the topic's key expression, answered by a queryable there as a publication cache
answers it).
"""

from __future__ import annotations

import json
import math
import operator
import queue
import struct
import threading
import time
from typing import Any

import numpy as np

from seamtrack.bridge import cdr, messages, rmw
from seamtrack.bridge.lockstep import Answer, BridgeFailure, Interrupted, Reply, Step, TfChain
from seamtrack.bridge.wire import MAX_MESSAGE_BYTES, MAX_THEN, context_json, make_command
from seamtrack.control.tracking import TrackerContext
from seamtrack.errors import SeamtrackError
from seamtrack.simulation.stop import StopRequest

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"
NODE = "seamtrack"

#: Topic -> message type of what the bridge publishes, and of the command pair it takes.
PUBLISHES = {
    "/tf": rmw.TFMESSAGE,
    "/tf_static": rmw.TFMESSAGE,
    "/clock": rmw.CLOCK,
    "/seamtrack/profile": rmw.POINTCLOUD2,
    "/seamtrack/image": "sensor_msgs/msg/Image",
    "/seamtrack/seam_point": rmw.POINT_STAMPED,
    "/seamtrack/seam_point_world": rmw.POINT_STAMPED,
    "/seamtrack/tcp_velocity": rmw.TWIST_STAMPED,
    "/seamtrack/then_taken": rmw.UINT32,
    "/seamtrack/tcp": rmw.POSE_STAMPED,
    "/seamtrack/context": rmw.STRING,
    "/seamtrack/status": rmw.STRING,
}
SUBSCRIBES = {
    "/seamtrack/cmd_pose": rmw.POSE_STAMPED,
    "/seamtrack/cmd_speed": rmw.TWIST_STAMPED,
    "/seamtrack/cmd_then": rmw.POSE_ARRAY,
}

#: Topics sent once whose last message a late subscriber gets on request.
LATCHED = ("/tf_static", "/seamtrack/context", "/seamtrack/status")

#: Their QoS (rmw_zenoh's compact form): reliable, transient local, keep last 1.
LATCHED_QOS = ":1:,1:,:,:,,"

#: The links of the robot's chain that do not move (``/tf_static``, as (parent, child)).
STATIC_LINKS = {("world", "base"), ("flange", "tcp"), ("tcp", "sensor")}

#: The wait between seeing the tracker's tokens and publishing to it.
SETTLE_S = 0.3

#: Samples the command inbox holds (two a step are due).
INBOX = 64

#: How often the watchdog looks at the deadline of the step the loop waits on (s).
WATCH_S = 0.05

#: Zenoh drops a received message over this (transport/link/rx/max_message_size).
HARD_LIMIT_BYTES = 65536


def check_locator(endpoint: str) -> None:
    """Refuse, before anything runs, a Zenoh locator ``PROTOCOL/HOST:PORT`` whose port is not
    1-65535 (Zenoh itself says what else is wrong with a locator when it opens)."""
    proto, slash, rest = endpoint.partition("/")
    host, colon, port = rest.rpartition(":")
    if slash and colon and host and proto in ("tcp", "udp", "tls", "quic", "ws"):
        if not (port.isdigit() and 1 <= int(port) <= 65535):
            raise SeamtrackError(
                f"port {port[:20]!r} of {endpoint[:80]!r} is not 1-65535",
                field="--endpoint",
                fix="give a Zenoh locator tcp/HOST:PORT with PORT 1-65535, e.g. tcp/127.0.0.1:7448",
            )


class ZenohTransport:
    """Serve one ROS 2 tracker node over Zenoh (see the module docstring)."""

    def __init__(
        self,
        endpoint: str = DEFAULT_ENDPOINT,
        timeout_s: float = 5.0,
        wait_s: float = 60.0,
        domain_id: int = 0,
    ) -> None:
        import zenoh

        self.endpoint = endpoint
        self.timeout_s = timeout_s
        self.wait_s = wait_s
        self.domain = domain_id
        self.stop = StopRequest()
        try:
            config = zenoh.Config()
            config.insert_json5("mode", '"router"')
            config.insert_json5("listen/endpoints", json.dumps([endpoint]))
            config.insert_json5("scouting/multicast/enabled", "false")  # listen, don't announce
            config.insert_json5("adminspace/enabled", "false")  # no router admin queries
            config.insert_json5("transport/link/rx/max_message_size", str(HARD_LIMIT_BYTES))
            self.session = zenoh.open(config)
        except Exception as exc:  # zenoh.ZError: the port is taken, the locator is wrong
            why = str(exc).split(" at /")[0][:200]  # zenoh's message, not its source path
            raise BridgeFailure(
                f"cannot listen on {endpoint!r}: {why}",
                field="--endpoint",
                fix="give a free zenoh locator, e.g. tcp/127.0.0.1:7448",
            ) from None
        self.events: queue.Queue[tuple[str, Any, Any]] = queue.Queue()
        sid = str(self.session.zid())
        self.session_id = sid
        live = self.session.liveliness()
        self._tokens = [live.declare_token(rmw.node_token(domain_id, sid, 0, NODE, ""))]
        self.pubs: dict[str, Any] = {}
        self.gids: dict[str, bytes] = {}
        entity = 1
        for topic, msgtype in PUBLISHES.items():
            key = rmw.topic_key(domain_id, topic, msgtype)
            # Reliable and blocking: in lockstep no message may be dropped, nor overtaken.
            self.pubs[topic] = self.session.declare_publisher(
                key, congestion_control=zenoh.CongestionControl.BLOCK
            )
            self.gids[topic] = rmw.gid(f"{sid}/{topic}")
            qos = LATCHED_QOS if topic in LATCHED else rmw.DEFAULT_QOS
            token = rmw.entity_token(domain_id, sid, 0, entity, "MP", NODE, "", topic, msgtype, qos)
            self._tokens.append(live.declare_token(token))
            entity += 1
        # Both command topics (and the wake-up key) in one FIFO channel that the loop's thread
        # reads: no Python callback per sample, and a step's pair wakes the loop once.
        self.topic_of = {}
        for topic, msgtype in SUBSCRIBES.items():
            self.topic_of[rmw.topic_key(domain_id, topic, msgtype)] = topic
            token = rmw.entity_token(domain_id, sid, 0, entity, "MS", NODE, "", topic, msgtype)
            self._tokens.append(live.declare_token(token))
            entity += 1
        self.wake_key = f"{domain_id}/seamtrack/cmd_/wake"
        self.inbox = self.session.declare_subscriber(
            f"{domain_id}/seamtrack/cmd_$*/**", zenoh.handlers.FifoChannel(INBOX)
        )
        self._local = zenoh.Locality.SESSION_LOCAL
        self._deadline: float | None = None
        self._stop = threading.Event()
        self._watchdog = threading.Thread(target=self._watch, daemon=True)
        self._watchdog.start()
        # Latched topics: a late subscriber gets the last message on request (a Zenoh get on
        # the topic's key, as a publication cache answers it).
        self.latched: dict[str, bytes] = {}
        self.queryables = [
            self.session.declare_queryable(
                rmw.topic_key(domain_id, topic, PUBLISHES[topic]), self._on_query(topic)
            )
            for topic in LATCHED
        ]
        self.watch = live.declare_subscriber(
            f"@ros2_lv/{domain_id}/**", self._on_token, history=True
        )
        # Who takes what (Zenoh's matching status, kept by a listener per publisher): a topic
        # no subscriber matches is neither written nor put (a tracker that takes the seam
        # points and the torch is not sent the profiles, the TF chain and the clock).
        self.matched = {topic: False for topic in PUBLISHES}
        self._listeners = [
            pub.declare_matching_listener(self._on_matching(topic))
            for topic, pub in self.pubs.items()
        ]
        self.seq = 0
        self.with_then = False  # the tracker node publishes cmd_then: three messages a step
        self.client: str | None = None
        self.with_profile = True
        #: Each command topic's last message and what it read as (a message the same to the
        #: byte but for its stamp is not read again), and the last answer, by those readings.
        self._read: dict[str, tuple[bytes, Any]] = {}
        self._answered: tuple[list[Any], Answer] | None = None

    # ------------------------------------------------------------------ callbacks
    def _on_query(self, topic: str) -> Any:
        def answer(query: Any) -> None:
            payload = self.latched.get(topic)
            if payload is not None:
                att = rmw.attachment(self.seq, time.time_ns(), self.gids[topic])
                query.reply(query.key_expr, payload, attachment=att)

        return answer

    def _on_matching(self, topic: str) -> Any:
        def update(status: Any) -> None:
            self.matched[topic] = bool(status.matching)

        return update

    def _on_token(self, sample: Any) -> None:
        self.events.put(("token", str(sample.kind), str(sample.key_expr)))
        if self._deadline is not None:  # the loop waits on the inbox: wake it to see this
            self._wake()

    def _wake(self) -> None:
        """Put an empty sample in the inbox, from this process to itself only."""
        self.session.put(self.wake_key, b"", allowed_destination=self._local)

    def _watch(self) -> None:
        """Wake the loop once its deadline has passed (the inbox's receive has no timeout)."""
        while not self._stop.wait(WATCH_S):
            deadline = self._deadline
            if deadline is not None and (time.monotonic() > deadline or self.stop.requested):
                self._wake()

    # ------------------------------------------------------------------ protocol
    def start(self, context: TrackerContext, chain: TfChain, lockstep: str) -> None:
        self._chain = chain
        need = {
            ("MS", "/seamtrack/tcp"),
            ("MP", "/seamtrack/cmd_pose"),
            ("MP", "/seamtrack/cmd_speed"),
        }
        seen: dict[str, set[tuple[str, str]]] = {}
        deadline = time.monotonic() + self.wait_s
        while self.client is None:
            kind, a, b = self._next(deadline, "--wait-s", "declare its tracker topics")
            if kind != "token":
                continue
            fields = rmw.parse_token(b)
            if fields is None or fields["session"] == self.session_id or "topic" not in fields:
                continue
            if a.endswith("PUT"):
                have = seen.setdefault(fields["session"], set())
                have.add((fields["kind"], fields["topic"]))
                if need <= have:
                    self.client = fields["session"]
        # Zenoh routes a new subscription to our publishers a little after its token shows:
        # wait until every topic the tracker subscribes to reaches it (matching status).
        client = self.client
        wanted = [t for kind, t in seen[client] if kind == "MS" and t in self.pubs]
        while not all(self.pubs[t].matching_status.matching for t in wanted):
            if time.monotonic() > deadline or self.stop.requested:
                self._next(deadline, "--wait-s", "receive from its subscriptions")
            time.sleep(0.01)
        time.sleep(SETTLE_S)
        for topic, pub in self.pubs.items():  # as of now; the listeners follow any change
            self.matched[topic] = bool(pub.matching_status.matching)
        while not self.events.empty():  # the node's tokens that came after the three needed
            _, what, token = self.events.get_nowait()
            fields = rmw.parse_token(token)
            if fields and fields["session"] == client and "topic" in fields:
                if what.endswith("DELETE"):
                    raise BridgeFailure("the tracker node disconnected", fix=_KEEP_RUNNING)
                seen[client].add((fields["kind"], fields["topic"]))
        self.with_then = ("MP", "/seamtrack/cmd_then") in seen[client]
        static = [link for link in chain(np.eye(4)) if link[:2] in STATIC_LINKS]
        self._put("/tf_static", cdr.tf_message(static, 0.0))
        message = {"lockstep": lockstep, "context": context_json(context)}
        self._put("/seamtrack/context", rmw.encode_string(json.dumps(message)))

    def exchange(self, step: Step) -> Answer:
        on = self.matched
        for f in step.frames:
            t = f.t_capture_s
            if f.profile is None:
                continue
            # messages.frame_messages' bytes, written directly for the topics someone takes;
            # the step's own /clock follows.
            if on["/tf"]:
                self._put("/tf", cdr.tf_message(self._chain(f.T_world_sensor), t))
            if on["/seamtrack/profile"]:
                self._put("/seamtrack/profile", cdr.profile_cloud(f.profile, t))
            if f.feature and on["/seamtrack/seam_point"]:
                self._put("/seamtrack/seam_point", cdr.seam_point(f.feature, t))
            if f.image is not None and on["/seamtrack/image"]:
                self._put("/seamtrack/image", cdr.image(f.image, t))
            if f.feature and on["/seamtrack/seam_point_world"]:
                world = rmw.encode_point(t, "world", f.feature.point_world)
                self._put("/seamtrack/seam_point_world", world)
        t = step.t_s
        if on["/clock"]:
            self._put("/clock", rmw.encode_clock(t))
        if on["/seamtrack/tcp_velocity"]:
            velocity = np.asarray(step.tcp_velocity_world, dtype=float) / messages.MM_PER_M
            self._put("/seamtrack/tcp_velocity", rmw.encode_twist(t, "world", velocity, (0, 0, 0)))
        if self.with_then:  # how many of the last cmd_then took over, before the trigger
            self._put("/seamtrack/then_taken", rmw.encode_uint32(step.then_taken))
        # The step's trigger, put whoever listens.
        self._put("/seamtrack/tcp", rmw.encode_pose(t, "world", step.tcp_world, None))
        return self._command(t, step.seq)

    _chain: TfChain

    def finish(self, summary: dict[str, Any]) -> None:
        from seamtrack.io.output import json_safe

        status, reason = summary.get("status"), summary.get("stop_reason")
        text = json.dumps({"status": status, "reason": reason, "summary": json_safe(summary)})
        self._put("/seamtrack/status", rmw.encode_string(text))
        time.sleep(SETTLE_S)  # let it leave before the session closes

    def close(self) -> None:
        self._stop.set()
        self._watchdog.join()
        for listener in self._listeners:
            listener.undeclare()
        for queryable in self.queryables:
            queryable.undeclare()
        for token in self._tokens:
            token.undeclare()
        self.session.close()

    # ------------------------------------------------------------------ internals
    def _put(self, topic: str, payload: bytes) -> None:
        if topic in LATCHED:
            self.latched[topic] = payload
        self.seq += 1
        stamp = time.time_ns()
        self.pubs[topic].put(payload, attachment=rmw.attachment(self.seq, stamp, self.gids[topic]))

    def _next(self, deadline: float, field: str, what: str) -> tuple[str, Any, Any]:
        try:
            while True:
                if self.stop.requested:
                    raise Interrupted(self.stop.reason)
                left = deadline - time.monotonic()
                if left <= 0:
                    raise queue.Empty
                try:
                    return self.events.get(timeout=min(left, WATCH_S))
                except queue.Empty:
                    continue
        except queue.Empty:
            timeout = self.wait_s if field == "--wait-s" else self.timeout_s
            raise BridgeFailure(
                f"the tracker node did not {what} within {timeout:g} s",
                field=field,
                fix="start the tracker node (RMW_IMPLEMENTATION=rmw_zenoh_cpp), or raise " + field,
            ) from None

    def _command(self, t_s: float, seq: int) -> Answer:
        want = int(round(t_s * 1e9))
        got: dict[str, Any] = {}
        self._deadline = time.monotonic() + self.timeout_s
        try:
            while not (_THEN if self.with_then else _PAIR) <= got.keys():
                kind, size, data = self._receive(seq)
                self._check(kind, size, data, want, got)
        finally:
            self._deadline = None
        readings = [got[k] for k in (_THEN_ORDER if self.with_then else _PAIR_ORDER)]
        last = self._answered
        if last is not None and all(map(operator.is_, readings, last[0])):
            return last[1]  # the same messages but for their stamps: the same answer
        answer = self._answer(got)
        self._answered = (readings, answer)
        return answer

    def _answer(self, got: dict[str, Any]) -> Answer:
        """The command pair (and cmd_then) read, as the tracker's :class:`Answer`."""
        (frame, pose), (_, speed) = got["/seamtrack/cmd_pose"], got["/seamtrack/cmd_speed"]
        command, within = command_from_values(frame, pose, speed)
        then: tuple[Reply, ...] = ()
        if self.with_then and command is not None:
            then_frame, poses = got["/seamtrack/cmd_then"]
            if poses and then_frame != "world":
                raise BridgeFailure(
                    f"cmd_then is in frame {then_frame[:40]!r}", fix="give its poses in 'world'"
                )
            passing = (speed[0], 0.0, *speed[2:])  # each passes through its target
            then = tuple(command_from_values("world", p, passing) for p in poses)
        return Answer(command, within, then)  # no seam_hint topic yet

    def _receive(self, seq: int) -> tuple[str, int, bytes | None]:
        """The next command sample (topic, size, bytes or None when oversized), blocking; a
        token event (the tracker gone) or the deadline ends the run."""
        while True:
            sample = self.inbox.recv()
            key = str(sample.key_expr)
            topic = self.topic_of.get(key)
            if topic is not None:
                payload = sample.payload
                size = len(payload)
                return topic, size, payload.to_bytes() if size <= MAX_MESSAGE_BYTES else None
            if key != self.wake_key:
                continue  # another type on a cmd_ topic: not the tracker's command
            if self.stop.requested:
                raise Interrupted(self.stop.reason)
            while not self.events.empty():
                _, what, token = self.events.get_nowait()
                fields = rmw.parse_token(token)
                if what.endswith("DELETE") and fields and fields["session"] == self.client:
                    raise BridgeFailure("the tracker node disconnected", fix=_KEEP_RUNNING)
            deadline = self._deadline
            if deadline is not None and time.monotonic() > deadline:
                raise BridgeFailure(
                    f"the tracker node did not answer step {seq} within {self.timeout_s:g} s",
                    field="--timeout-s",
                    fix="start the tracker node (RMW_IMPLEMENTATION=rmw_zenoh_cpp), or raise "
                    "--timeout-s",
                )

    def _check(
        self, kind: str, size: int, data: bytes | None, want: int, got: dict[str, Any]
    ) -> None:
        """One command message of the pair, checked and kept in ``got``."""
        if data is None:
            raise BridgeFailure(
                f"a message of {size} bytes on {kind} is over the {MAX_MESSAGE_BYTES}-byte limit",
                fix="publish one PoseStamped and one TwistStamped per step",
            )
        last = self._read.get(kind)
        if last is not None and data[12:] == last[0][12:] and data[:4] == last[0][:4]:
            # The last message again but for its stamp (a command held): only that is read.
            sec, nanosec = (_STAMP_LE if data[1] else _STAMP_BE).unpack_from(data, 4)
            stamp, read = sec * 1_000_000_000 + nanosec, last[1]
        else:
            try:  # the bytes rosbags would accept, read without building its objects
                values: Any
                if kind == "/seamtrack/cmd_then":
                    stamp, frame, values = cdr.read_pose_array(data, MAX_THEN)
                else:
                    stamp, frame, values = cdr.read_stamped(data, SUBSCRIBES[kind])
            except ValueError as exc:
                raise BridgeFailure(f"sent garbage on {kind}: {exc}", fix=_FIX_TYPES) from None
            read = (frame, values)
            self._read[kind] = (data, read)
        if stamp != want:
            raise BridgeFailure(
                f"answered on {kind} for t = {stamp * 1e-9:.9g} s where t = "
                f"{want * 1e-9:.9g} s was due",
                fix="stamp both command messages with the /seamtrack/tcp message's stamp",
            )
        if kind in got:
            raise BridgeFailure(f"sent two messages on {kind} in one step", fix=_FIX_TYPES)
        got[kind] = read


_PAIR = {"/seamtrack/cmd_pose", "/seamtrack/cmd_speed"}
_THEN = _PAIR | {"/seamtrack/cmd_then"}
_PAIR_ORDER, _THEN_ORDER = sorted(_PAIR), sorted(_THEN)
_STAMP_LE, _STAMP_BE = struct.Struct("<iI"), struct.Struct(">iI")  # a header's stamp
_KEEP_RUNNING = "keep the tracker node running until /seamtrack/status says the run is over"
_FIX_TYPES = "publish geometry_msgs/msg/PoseStamped and TwistStamped as docs/ros.md gives them"


def command_from_ros(pose_msg: Any, speed_msg: Any) -> Reply:
    """The command pair as a :class:`Command` and its ``ask_within_mm`` (docs/ros.md):
    ``cmd_pose`` in ``world`` (m; an all-zero quaternion keeps the tool's orientation; an
    empty ``frame_id`` brakes to rest and waits), ``cmd_speed``: ``linear.x`` the path speed
    (m/s, > 0), ``linear.y`` 1 to arrive at rest on the target (else 0), ``linear.z`` the
    distance from the target within which to ask again (m, frame lockstep; 0: at the next
    frame), ``angular`` the turn rate of the orientation goal (rad/s, world axes)."""
    p = pose_msg.pose.position
    q = pose_msg.pose.orientation
    v = speed_msg.twist.linear
    w = speed_msg.twist.angular
    return command_from_values(
        pose_msg.header.frame_id,
        (p.x, p.y, p.z, q.x, q.y, q.z, q.w),
        (v.x, v.y, v.z, w.x, w.y, w.z),
    )


def command_from_values(frame: str, pose: tuple[float, ...], speed: tuple[float, ...]) -> Reply:
    """:func:`command_from_ros` of the pair's fields: ``cmd_pose``'s frame id, its position and
    orientation (x, y, z, qx, qy, qz, qw), ``cmd_speed``'s linear and angular parts."""
    if frame == "":
        return None, 0.0
    if frame != "world":
        raise BridgeFailure(
            f"cmd_pose is in frame {frame[:40]!r}", fix="give the target in 'world' (or '' to stop)"
        )
    values = (*pose, *speed)
    if not rmw.is_finite(*values):
        raise BridgeFailure("sent a command that is not finite", fix=_FIX_TYPES)
    px, py, pz, qx, qy, qz, qw = pose
    vx, vy, vz, wx, wy, wz = speed
    if not vx > 0 or vy not in (0.0, 1.0) or vz < 0.0:
        raise BridgeFailure(
            "cmd_speed is not (speed > 0, stop 0 or 1, ask within >= 0)",
            fix="linear.x: the path speed in m/s; linear.y: 1 to arrive at rest; linear.z: "
            "the distance to ask again within, m (0: at the next frame)",
        )
    rotation = None
    norm = math.sqrt(qx * qx + qy * qy + qz * qz + qw * qw)
    if norm != 0.0:
        if abs(norm - 1.0) > 1e-6:
            raise BridgeFailure("cmd_pose's quaternion is not a unit one", fix=_FIX_TYPES)
        rotation = messages.rotation((qx, qy, qz, qw)).ravel().tolist()
    omega = None if (wx, wy, wz) == (0.0, 0.0, 0.0) else [wx, wy, wz]
    target = [px * 1000.0, py * 1000.0, pz * 1000.0]
    command = make_command(target, vx * 1000.0, vy == 1.0, None, rotation, omega)
    return command, vz * 1000.0
