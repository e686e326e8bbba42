"""The bridge's hand-written CDR (seamtrack.bridge.cdr) against an independent serializer:
rosbags' own, fed the rosbags message objects of seamtrack.bridge.messages. The bytes must be
the same, byte for byte, for every message the bridge sends per frame."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("rosbags")

from seamtrack.bridge import cdr, rmw
from seamtrack.bridge import messages as m
from seamtrack.geometry import frames
from seamtrack.sensing.profiles import Feature, Profile, Reason

#: Capture times with awkward nanoseconds, and frame ids of every length modulo 4 (padding).
TIMES = [0.0, 0.01, 1.2345678915, 12.999999999]
FRAME_IDS = ["", "w", "tcp", "base", "sensor", "world"]


def _profile(rng: np.random.Generator, n: int) -> Profile:
    pts = np.column_stack([rng.uniform(-30, 30, n), rng.uniform(80, 120, n)])
    reason = rng.integers(0, len(Reason), n).astype(np.uint8)
    pts[reason == Reason.MISS] = np.nan
    return Profile(pts, valid=reason == 0, reason=reason, t_s=1.25)


@pytest.mark.parametrize("n", [0, 1, 3, 1024])
@pytest.mark.parametrize("t_s", TIMES)
def test_point_cloud_bytes_equal_rosbags(n: int, t_s: float) -> None:
    profile = _profile(np.random.default_rng(n), n)
    for frame_id in FRAME_IDS:
        want = m.encode(m.profile_cloud(profile, t_s, frame_id=frame_id))
        assert cdr.profile_cloud(profile, t_s, frame_id) == want
    valid = Profile(np.ones((n, 2)), valid=np.ones(n, bool), reason=np.zeros(n, np.uint8))
    assert cdr.profile_cloud(valid, t_s) == m.encode(m.profile_cloud(valid, t_s))


@pytest.mark.parametrize("t_s", TIMES)
def test_tf_clock_and_points_equal_rosbags(t_s: float) -> None:
    rng = np.random.default_rng(3)
    chain = []
    for parent, child in [("world", "base"), ("base", "flange"), ("flange", "tcp")]:
        T = frames.from_xyz_rpy(rng.uniform(-900, 900, 3), rng.uniform(-3, 3, 3))
        chain.append((parent, child, T))
    assert cdr.tf_message(chain, t_s) == m.encode(m.tf_message(chain, t_s))
    assert cdr.tf_message([], t_s) == m.encode(m.tf_message([], t_s))
    assert cdr.clock(t_s) == m.encode(m.clock(t_s))
    feature = Feature.found(rng.uniform(-20, 20, 2))
    assert cdr.seam_point(feature, t_s) == m.encode(m.seam_point(feature, t_s))


def test_small_messages_equal_rosbags() -> None:
    ty = m.typestore().types
    for text in ["", "a", "abcd", '{"x": 1}']:
        assert cdr.string(text) == m.encode(ty["std_msgs/msg/String"](data=text))
    for frame_id in FRAME_IDS:
        header = m.header(2.5, frame_id)
        V = ty["geometry_msgs/msg/Vector3"]
        twist = ty["geometry_msgs/msg/Twist"](linear=V(x=1, y=-2, z=3), angular=V(x=4, y=5, z=6))
        want = m.encode(ty["geometry_msgs/msg/TwistStamped"](header=header, twist=twist))
        assert cdr.twist_stamped(2.5, frame_id, (1, -2, 3), (4, 5, 6)) == want
        pose = ty["geometry_msgs/msg/Pose"](
            position=ty["geometry_msgs/msg/Point"](x=0.5, y=-1.5, z=2.25),
            orientation=ty["geometry_msgs/msg/Quaternion"](x=0.0, y=0.6, z=0.0, w=0.8),
        )
        want = m.encode(ty["geometry_msgs/msg/PoseStamped"](header=header, pose=pose))
        assert cdr.pose_stamped(2.5, frame_id, (0.5, -1.5, 2.25), (0, 0.6, 0, 0.8)) == want
    # rmw's encoders are these writers; decoded by rosbags they give the values back.
    pose = m.decode(rmw.encode_pose(1.5, "world", [1000.0, -20.0, 3.0], None), rmw.POSE_STAMPED)
    assert (pose.pose.position.x, pose.pose.position.y, pose.pose.orientation.w) == (1, -0.02, 1)


@pytest.mark.parametrize("bits", [8, 12])
def test_image_bytes_equal_rosbags(bits: int) -> None:
    from types import SimpleNamespace

    pixels = np.random.default_rng(bits).uniform(0, 1, (5, 7))
    image = SimpleNamespace(pixels=pixels, camera=SimpleNamespace(bit_depth=bits), t_s=0.5)
    assert cdr.image(image, 0.5) == m.encode(m.stripe_image_message(image, 0.5))


@pytest.mark.parametrize(
    "msgtype", ["geometry_msgs/msg/PoseStamped", "geometry_msgs/msg/TwistStamped"]
)
@pytest.mark.parametrize("little_endian", [True, False])
def test_the_command_reader_reads_and_refuses_as_rosbags_does(
    msgtype: str, little_endian: bool
) -> None:
    """What the bridge reads from a tracker: the values rosbags decodes; and of every
    truncation, every few bytes appended and bytes flipped in the string's length, it refuses
    exactly what rosbags refuses."""
    ts = m.typestore()
    rng = np.random.default_rng(5)
    values = rng.uniform(-2, 2, 7 if "Pose" in msgtype else 6).tolist()
    for frame_id in FRAME_IDS + ["wörld"]:
        header = m.header(3.000000007, frame_id)
        if "Pose" in msgtype:
            msg = ts.types[msgtype](header=header, pose=m.default("geometry_msgs/msg/Pose"))
            msg.pose.position.x, msg.pose.position.y, msg.pose.position.z = values[:3]
            q = msg.pose.orientation
            q.x, q.y, q.z, q.w = values[3:]
        else:
            msg = ts.types[msgtype](header=header, twist=m.default("geometry_msgs/msg/Twist"))
            t = msg.twist
            t.linear.x, t.linear.y, t.linear.z = values[:3]
            t.angular.x, t.angular.y, t.angular.z = values[3:]
        raw = bytes(ts.serialize_cdr(msg, msgtype, little_endian=little_endian))
        assert cdr.read_stamped(raw, msgtype) == (3_000_000_007, frame_id, tuple(values))
        mutants = [raw[:k] for k in range(len(raw))] + [raw + b"\x00" * k for k in range(1, 9)]
        lengths = [raw[:12] + bytes([b]) + raw[13:] for b in (0, 1, 2, 9, 200)]  # its length
        for bad in mutants + lengths:
            try:
                ts.deserialize_cdr(bad, msgtype)
                accepted = True
            except Exception:
                accepted = False
            try:
                cdr.read_stamped(bad, msgtype)
                assert accepted, bad
            except ValueError as exc:
                assert not accepted, (bad, exc)
                assert str(exc).startswith(f"not a {msgtype}")


@pytest.mark.parametrize("n", [0, 1, 3])
@pytest.mark.parametrize("little_endian", [True, False])
def test_the_pose_array_reader_reads_and_refuses_as_rosbags_does(
    n: int, little_endian: bool
) -> None:
    """``cmd_then`` (geometry_msgs/PoseArray): the poses rosbags decodes; of every truncation
    and every few bytes appended, exactly what rosbags refuses is refused; more poses than
    asked for are refused."""
    ts = m.typestore()
    msgtype = "geometry_msgs/msg/PoseArray"
    rng = np.random.default_rng(n)
    values = [tuple(rng.uniform(-2, 2, 7).tolist()) for _ in range(n)]
    for frame_id in FRAME_IDS + ["wörld"]:
        poses = []
        for v in values:
            pose = m.default("geometry_msgs/msg/Pose")
            pose.position.x, pose.position.y, pose.position.z = v[:3]
            q = pose.orientation
            q.x, q.y, q.z, q.w = v[3:]
            poses.append(pose)
        msg = ts.types[msgtype](header=m.header(3.000000007, frame_id), poses=poses)
        raw = bytes(ts.serialize_cdr(msg, msgtype, little_endian=little_endian))
        assert cdr.read_pose_array(raw, 16) == (3_000_000_007, frame_id, values)
        if n:
            with pytest.raises(ValueError, match=f"{n} poses, more than {n - 1}"):
                cdr.read_pose_array(raw, n - 1)
        mutants = [raw[:k] for k in range(len(raw))] + [raw + b"\x00" * k for k in range(1, 9)]
        for bad in mutants:
            try:
                ts.deserialize_cdr(bad, msgtype)
                accepted = True
            except Exception:
                accepted = False
            try:
                cdr.read_pose_array(bad, 16)
                assert accepted, bad
            except ValueError as exc:
                assert not accepted, (bad, exc)
                assert str(exc).startswith(f"not a {msgtype}")
