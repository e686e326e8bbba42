"""rmw_zenoh's formats as its design document (ros2/rmw_zenoh docs/design.md, "Topic and
Service name mapping to Zenoh key expressions" and "Graph Cache") gives them: the examples
there are the oracle. And the bridge's checks of what a client sends (JSON and CDR)."""

from __future__ import annotations

import json
import socket
import struct
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("rosbags")

from seamtrack.bridge import messages, rmw, wire
from seamtrack.bridge.lockstep import Answer, BridgeFailure

STRING_HASH = "RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"


def test_topic_keys_are_the_design_documents() -> None:
    assert rmw.type_hash("std_msgs/msg/String") == STRING_HASH
    assert (
        rmw.topic_key(0, "/chatter", "std_msgs/msg/String")
        == f"0/chatter/std_msgs::msg::dds_::String_/{STRING_HASH}"
    )
    assert (
        rmw.topic_key(0, "/robot1/chatter", "std_msgs/msg/String")
        == f"0/robot1/chatter/std_msgs::msg::dds_::String_/{STRING_HASH}"
    )


def test_liveliness_tokens_are_the_design_documents() -> None:
    assert (
        rmw.node_token(2, "aac3178e146ba6f1fc6e6a4085e77f21", 0, "listener", "")
        == "@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/0/NN/%/%/listener"
    )
    sub = rmw.entity_token(
        2, "aac3178e146ba6f1fc6e6a4085e77f21", 0, 10, "MS", "listener", "", "/chatter",
        "std_msgs/msg/String",
    )  # fmt: skip
    assert sub == (
        "@ros2_lv/2/aac3178e146ba6f1fc6e6a4085e77f21/0/10/MS/%/%/listener/%chatter/"
        f"std_msgs::msg::dds_::String_/{STRING_HASH}/::,10:,:,:,,"
    )
    fields = rmw.parse_token(sub)
    assert fields is not None
    assert (fields["kind"], fields["topic"], fields["hash"]) == ("MS", "/chatter", STRING_HASH)


def test_every_bridge_topic_has_a_rihs01_hash_of_its_type() -> None:
    from seamtrack.bridge.zenoh_transport import PUBLISHES, SUBSCRIBES

    for topic, msgtype in {**PUBLISHES, **SUBSCRIBES}.items():
        key = rmw.topic_key(0, topic, msgtype)
        domain, *_, dds, digest = key.split("/")
        assert domain == "0" and dds == rmw.dds_type_name(msgtype)
        assert digest.startswith("RIHS01_") and len(digest) == 7 + 64
        int(digest[7:], 16)  # hex


def test_attachment_layout() -> None:
    gid = bytes(range(16))
    raw = rmw.attachment(7, 123456789, gid)
    assert len(raw) == 33
    assert struct.unpack("<qqB", raw[:17]) == (7, 123456789, 16) and raw[17:] == gid


def test_loopback_by_default() -> None:
    from seamtrack.bridge import zenoh_transport, zmq_transport

    assert zmq_transport.DEFAULT_ENDPOINT.startswith("tcp://127.0.0.1:")
    assert zenoh_transport.DEFAULT_ENDPOINT.startswith("tcp/127.0.0.1:")


def test_an_ipc_path_a_server_listens_on_is_refused(tmp_path: Path) -> None:
    """ZeroMQ would take an ipc:// path over from the server on it (or remove a file there):
    the second server is refused instead, and so is a path that holds a file; a socket file
    left by a server that is gone is taken."""
    pytest.importorskip("zmq")
    from seamtrack.bridge.zmq_transport import ZmqTransport

    endpoint = f"ipc://{tmp_path / 'bridge'}"
    first = ZmqTransport(endpoint)
    try:
        with pytest.raises(BridgeFailure, match="another server listens there") as info:
            ZmqTransport(endpoint)
        assert info.value.field == "--endpoint"
    finally:
        first.close()
    kept = tmp_path / "notes.txt"
    kept.write_text("mine")
    with pytest.raises(BridgeFailure, match="not a socket"):
        ZmqTransport(f"ipc://{kept}")
    assert kept.read_text() == "mine"
    stale = tmp_path / "stale"
    with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
        s.bind(str(stale))  # a socket file nobody listens on
    ZmqTransport(f"ipc://{stale}").close()


def test_a_protocol_1_client_is_refused_naming_protocol_2() -> None:
    """Protocol 1 sent the profiles as JSON: a client that says it speaks it is told which
    protocol to speak instead (an ``error`` message, ``status`` ``refused``), before anything
    else is sent to it."""
    zmq = pytest.importorskip("zmq")
    import socket

    from seamtrack.bridge.zmq_transport import ZmqTransport

    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    server = ZmqTransport(f"tcp://127.0.0.1:{port}", timeout_s=2.0, wait_s=10.0)
    ctx = zmq.Context()
    client = ctx.socket(zmq.REQ)
    client.setsockopt(zmq.LINGER, 0)
    try:
        client.connect(f"tcp://127.0.0.1:{port}")
        client.send_json({"op": "hello", "protocol": 1, "profile": True})
        with pytest.raises(BridgeFailure, match="protocol 1, not 2") as info:
            server.start(None, None, "frame")  # type: ignore[arg-type]
        assert "'protocol': 2" in info.value.fix
        server.close()  # lingers until the refusal is out
        assert client.poll(5000)  # the client is told, not left waiting
        refusal = client.recv_json()
        assert refusal["op"] == "error" and refusal["status"] == "refused"
        assert "protocol 1, not 2" in refusal["reason"] and "'protocol': 2" in refusal["reason"]
    finally:
        client.close(0)
        ctx.term()
        server.close()


# --------------------------------------------------------------------------- JSON commands
def _command(body: object, seq: int = 3) -> bytes:
    return json.dumps({"op": "command", "seq": seq, "command": body}).encode()


def test_a_json_command_is_read_exactly() -> None:
    body = {"target_mm": [1.5, -2.25, 0.1], "speed_mm_s": 5, "stop_at_target": True}
    cmd, within = wire.command_from_json(wire.parse(_command(body)), 3)
    assert cmd is not None and within == 0.0
    assert cmd.target_world.tolist() == [1.5, -2.25, 0.1] and cmd.speed_mm_s == 5.0
    assert cmd.stop_at_target and cmd.rotation_world is None
    assert wire.command_from_json(wire.parse(_command(None)), 3) == (None, 0.0)
    body["ask_within_mm"] = 1.0
    assert wire.command_from_json(wire.parse(_command(body)), 3)[1] == 1.0


@pytest.mark.parametrize(
    ("raw", "why"),
    [
        (b"\x80\x04\x95pickle", "not JSON"),
        (b"[1, 2]", "not an object"),
        (b'{"op": "command", "seq": 3, "command": {"target_mm": [NaN, 0, 0]}}', "not JSON"),
        (_command({"target_mm": [0, 0], "speed_mm_s": 1}), "'target_mm'"),
        (_command({"target_mm": [0, 0, 0], "speed_mm_s": 0}), "'speed_mm_s'"),
        (_command({"target_mm": [0, 0, 0], "speed_mm_s": 1, "exec": "x"}), "unknown"),
        (_command({"target_mm": [0, 0, 0], "speed_mm_s": 1, "ask_within_mm": -1}), "negative"),
        (_command({"target_mm": [0, 0, 0], "speed_mm_s": 1}, seq=2), "step 2 where step 3"),
        (_command({"target_mm": [0, 0, 0], "speed_mm_s": 1, "rotation": [[2, 0, 0]] * 3}), "rot"),
        (json.dumps({"op": "command", "seq": 3, "pad": "x" * 5000}).encode(), "4096-byte"),
        (_command({"target_mm": [0, 0, 0], "speed_mm_s": 1, "then": {}}), "'then'"),
        (_command({"target_mm": [0, 0, 0], "speed_mm_s": 1, "then": [{}] * 17}), "at most 16"),
        (_command({"target_mm": [0, 0, 0], "speed_mm_s": 1, "then": [[1]]}), "not a command"),
        (_command({"target_mm": [0, 0, 0], "speed_mm_s": 1, "then": [{"then": []}]}), "own"),
        (_command({"target_mm": [0, 0, 0], "speed_mm_s": 1, "then": [{"speed_mm_s": 1}]}), "'tar"),
    ],
)
def test_bad_json_commands_are_refused(raw: bytes, why: str) -> None:
    with pytest.raises(BridgeFailure, match=why):
        wire.command_from_json(wire.parse(raw), 3)


def test_a_step_carries_its_profiles_as_described_binary_parts() -> None:
    """The step's JSON header says where each profile is and how to read it; read so, the
    parts give the profile's own points (NaN kept) and reasons; a part of the wrong size is
    refused before it is read."""
    from seamtrack.bridge.lockstep import Frame, Step
    from seamtrack.sensing.profiles import Feature, Profile

    rng = np.random.default_rng(2)
    profiles = []
    for n in (5, 3):
        pts = rng.uniform(-30, 30, (n, 2))
        pts[1] = np.nan
        reason = rng.integers(0, 8, n).astype(np.uint8)
        profiles.append(Profile(pts, valid=reason == 0, reason=reason))
    lost = Feature.failed("no stripe")
    frames = [
        Frame(0.01 * i, 0.01 * i + 0.002, lost, np.eye(4), np.zeros(3), p, None)
        for i, p in enumerate(profiles)
    ]
    step = Step(4, 0.03, np.zeros(3), np.zeros(3), frames)
    parts = wire.step_parts(step, with_profile=True)
    header = json.loads(parts[0])
    assert len(parts) == 5 and header["seq"] == 4
    for i, profile in enumerate(profiles):
        got = wire.profile_arrays(header, parts, i)
        assert got is not None
        np.testing.assert_array_equal(got[0], profile.points_laser)
        np.testing.assert_array_equal(got[1], profile.reason)
    with pytest.raises(ValueError, match="bytes"):
        wire.profile_arrays(header, [*parts[:2], parts[2][:-1], *parts[3:]], 0)
    bare = wire.step_parts(step, with_profile=False)
    assert len(bare) == 1 and json.loads(bare[0])["frames"][0]["profile"] is None


def test_a_command_with_then_is_read_exactly() -> None:
    then = [
        {"target_mm": [2, 0, 0], "speed_mm_s": 4, "ask_within_mm": 0.5},
        {"target_mm": [3, 0, 0], "speed_mm_s": 4, "stop_at_target": True},
    ]
    body = {"target_mm": [1, 0, 0], "speed_mm_s": 4, "ask_within_mm": 0.5, "then": then}
    message = wire.parse(_command(body))
    (cmd, within), rest = wire.commands_from_json(message, 3)
    assert cmd is not None and cmd.target_world.tolist() == [1, 0, 0] and within == 0.5
    assert [(c.target_world.tolist(), c.stop_at_target, w) for c, w in rest] == [
        ([2, 0, 0], False, 0.5),
        ([3, 0, 0], True, 0.0),
    ]
    assert wire.command_from_json(message, 3)[0].target_world.tolist() == [1, 0, 0]


def test_then_takes_over_on_the_tick_the_torch_comes_within_reach() -> None:
    """Frame lockstep between frames: the answer's ``then`` takes over, one after the other,
    at the tick the torch is within ``ask_within_mm`` of the target (exactly: at a distance of
    1 from a radius of 1), with no round trip; once the ``then`` is used up the tracker is
    asked (at that tick), and the step says how many took over. Oracle: distances along x."""
    from seamtrack.bridge.lockstep import BridgeTracker
    from seamtrack.control.tracking import Measurement
    from seamtrack.sensing.profiles import Feature

    def go(x: float, within: float, stop: bool = False) -> tuple:
        return wire.make_command([x, 0.0, 0.0], 5.0, stop, None, None, None), within

    answers = [
        (go(10, 1.0), [go(20, 1.0), go(30, 0.0, stop=True)]),
        (go(40, 1.0), [go(50, 1.0)]),
        (go(60, 0.0), []),
    ]

    class Client:
        def __init__(self) -> None:
            self.steps: list = []

        def exchange(self, step: object) -> Answer:
            self.steps.append(step)
            (command, within), then = answers[len(self.steps) - 1]
            return Answer(command, within, tuple(then))

    client = Client()
    tracker = BridgeTracker(client, chain=None, lockstep="frame")  # type: ignore[arg-type]
    zero = np.zeros(3)

    def at(x: float) -> float:
        cmd = tracker.command(0.0, np.array([x, 0.0, 0.0]), zero)
        assert cmd is not None
        return float(cmd.target_world[0])

    def frame() -> None:
        tracker.update(Measurement(Feature.failed("none"), 0.0, 0.0, np.eye(4), zero))

    frame()
    assert at(0.0) == 10 and len(client.steps) == 1
    assert at(8.999) == 10  # 1.001 away: holds
    assert at(9.0) == 20  # 1 away: B takes over, on this tick
    assert at(19.5) == 30 and at(29.5) == 30  # C: at rest there, nothing to ask
    assert len(client.steps) == 1
    frame()
    assert at(29.6) == 40 and client.steps[-1].then_taken == 2
    assert at(39.5) == 50 and len(client.steps) == 2
    assert at(49.5) == 60  # the then used up and within reach: asked on this tick
    assert len(client.steps) == 3 and client.steps[-1].then_taken == 1


def test_a_seam_hint_reaches_the_extractor_where_its_line_crosses_the_laser_plane() -> None:
    """A client's ``seam_hint`` (a point and a heading, world) becomes each frame's SeamHint:
    where that line crosses the laser plane, in the laser frame. Oracle, analytic: the sensor
    at (10, 0, 100) looking down the world -z (x_S = x_W, y_S = -y_W, z_S = -z_W); the line
    through (50, 3, 0) heading +x crosses x_S = 0 at world (10, 3, 0), i.e. y_L = -3, z_L = 100;
    the heading is x_S."""
    from seamtrack.bridge.lockstep import BridgeTracker

    message = {
        "op": "command",
        "seq": 3,
        "command": None,
        "seam_hint": {"point_mm": [50, 3, 0], "direction": [2, 0, 0]},
    }
    line = wire.seam_hint_from_json(message)
    assert line == ((50.0, 3.0, 0.0), (1.0, 0.0, 0.0), (1.5, 0.4))

    class Client:
        seam_hint = line

        def exchange(self, step: object) -> Answer:
            return Answer(None, 0.0, (), self.seam_hint)

    client = Client()
    tracker = BridgeTracker(client, chain=None)  # type: ignore[arg-type]
    T = np.diag([1.0, -1.0, -1.0, 1.0])
    T[:3, 3] = (10.0, 0.0, 100.0)
    assert tracker.hint(T) is None  # no answer yet
    tracker.command(0.0, np.zeros(3), np.zeros(3))
    hint = tracker.hint(T)
    assert hint is not None
    assert hint.point_laser == pytest.approx((-3.0, 100.0), abs=1e-12)
    assert hint.direction == pytest.approx((1.0, 0.0, 0.0), abs=1e-12)
    assert hint.tolerance_mm == (1.5, 0.4)
    client.seam_hint = None
    tracker.command(0.001, np.zeros(3), np.zeros(3))
    assert tracker.hint(T) is None
    assert wire.seam_hint_from_json({"op": "command", "seam_hint": None}) is None


@pytest.mark.parametrize(
    ("hint", "why"),
    [
        ({"point_mm": [0, 0, 0]}, "needs point_mm and direction"),
        ({"point_mm": [0, 0, "nan"], "direction": [1, 0, 0]}, "needs point_mm"),
        ({"point_mm": [0, 0, 0], "direction": [0, 0, 0]}, "zero direction"),
        ({"point_mm": [0, 0, 0], "direction": [1, 0, 0], "tolerance_mm": [1, 0]}, "> 0"),
        ({"point_mm": [0, 0, 0], "direction": [1, 0, 0], "exec": "x"}, "not an object"),
        ([0, 0, 0], "not an object"),
    ],
)
def test_bad_seam_hints_are_refused(hint: object, why: str) -> None:
    with pytest.raises(BridgeFailure, match=why):
        wire.seam_hint_from_json({"op": "command", "seq": 3, "command": None, "seam_hint": hint})


# --------------------------------------------------------------------------- CDR commands
def _pair(frame: str = "world", q=(0.0, 0.0, 0.0, 0.0), linear=(0.005, 1.0, 0.001)):
    from seamtrack.bridge.zenoh_transport import command_from_ros

    pose = messages.decode(rmw.encode_pose(1.0, frame, (10.0, 20.0, 30.0), None), rmw.POSE_STAMPED)
    pose.pose.orientation.x, pose.pose.orientation.y = q[0], q[1]
    pose.pose.orientation.z, pose.pose.orientation.w = q[2], q[3]
    speed = messages.decode(rmw.encode_twist(1.0, "world", linear, (0, 0, 0)), rmw.TWIST_STAMPED)
    command, within = command_from_ros(pose, speed)
    assert within == (0.0 if command is None else 1.0)
    return command


def test_a_ros_command_pair_is_read() -> None:
    cmd = _pair()
    assert cmd is not None
    assert np.allclose(cmd.target_world, (10.0, 20.0, 30.0), rtol=0, atol=1e-12)
    assert cmd.speed_mm_s == pytest.approx(5.0) and cmd.stop_at_target
    assert cmd.rotation_world is None
    assert _pair(frame="") is None  # no target: brake to rest and wait
    turned = _pair(q=(0.0, 0.0, np.sin(0.25), np.cos(0.25)))
    assert turned is not None and turned.rotation_world is not None
    assert np.allclose(
        turned.rotation_world[:2, :2], [[np.cos(0.5), -np.sin(0.5)], [np.sin(0.5), np.cos(0.5)]]
    )


@pytest.mark.parametrize(
    ("kwargs", "why"),
    [
        ({"frame": "map"}, "frame"),
        ({"q": (0.0, 0.0, 0.0, 2.0)}, "unit"),
        ({"linear": (0.0, 0.0, 0.0)}, "speed > 0"),
        ({"linear": (0.005, 0.5, 0.0)}, "stop 0 or 1"),
        ({"linear": (0.005, 1.0, -0.001)}, "ask within >= 0"),
        ({"linear": (float("nan"), 0.0, 0.0)}, "not finite"),
    ],
)
def test_bad_ros_commands_are_refused(kwargs: dict, why: str) -> None:
    with pytest.raises(BridgeFailure, match=why):
        _pair(**kwargs)


def test_cdr_garbage_is_refused() -> None:
    with pytest.raises(ValueError, match="not a geometry_msgs/msg/PoseStamped"):
        rmw.deserialize(b"\x00\x01garbage", rmw.POSE_STAMPED)
