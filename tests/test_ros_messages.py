"""ROS 2 messages (seamtrack.bridge.messages): built with rosbags, read back by an independent
CDR decoder (mcap-ros2-support's, from the .msg text), and back to seamtrack's objects."""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("rosbags")
pytest.importorskip("mcap_ros2")

from mcap_ros2._dynamic import generate_dynamic
from scipy.spatial.transform import Rotation

import seamtrack as st
from seamtrack.bridge import frames as fr
from seamtrack.bridge import messages as m
from seamtrack.geometry import frames
from seamtrack.sensing.profiles import Feature, Profile, Reason


def _independent(typename: str, data: bytes):
    """Decode CDR bytes with mcap-ros2-support's own decoder, built from the .msg text."""
    decoders = generate_dynamic(typename.replace("/msg/", "/"), m.msg_definition(typename))
    return decoders[typename.replace("/msg/", "/")](data)


def _profile(rng: np.random.Generator, n: int = 64) -> Profile:
    pts = np.column_stack([rng.uniform(-30, 30, n), rng.uniform(80, 120, n)])
    reason = rng.integers(0, len(Reason), n).astype(np.uint8)
    pts[reason == Reason.MISS] = np.nan
    return Profile(pts, valid=reason == 0, reason=reason, t_s=1.25)


def test_profile_cloud_round_trips_through_cdr() -> None:
    rng = np.random.default_rng(7)
    profile = _profile(rng)
    data = m.encode(m.profile_cloud(profile))
    # mcap-ros2-support decodes the same bytes: the fields and the values (mm / 1000, bit for bit)
    other = _independent("sensor_msgs/msg/PointCloud2", data)
    assert [f.name for f in other.fields] == ["x", "y", "z", "reason"]
    assert (other.width, other.height, other.point_step) == (len(profile), 1, 32)
    raw = np.frombuffer(bytes(other.data), dtype=m.POINT_DTYPE)
    np.testing.assert_array_equal(raw["y"], profile.points_laser[:, 0] / 1000.0)
    np.testing.assert_array_equal(raw["z"], profile.points_laser[:, 1] / 1000.0)
    np.testing.assert_array_equal(raw["x"], 0.0)
    np.testing.assert_array_equal(raw["reason"], profile.reason)
    assert other.header.frame_id == "sensor"
    assert (other.header.stamp.sec, other.header.stamp.nanosec) == (1, 250_000_000)
    # back to a profile: the same points (m -> mm within an ulp), validity and reasons
    back = m.cloud_profile(m.decode(data, "sensor_msgs/msg/PointCloud2"))
    np.testing.assert_allclose(back.points_laser, profile.points_laser, rtol=3e-16, atol=0)
    np.testing.assert_array_equal(back.valid, profile.valid)
    np.testing.assert_array_equal(back.reason, profile.reason)
    assert back.t_s == 1.25
    points, valid = m.cloud_arrays(m.decode(data, "sensor_msgs/msg/PointCloud2"))
    assert points.shape == (len(profile), 2)
    np.testing.assert_array_equal(valid, profile.valid)


def test_a_foreign_cloud_float32_big_endian_x_lateral() -> None:
    """A driver's cloud (the scanCONTROL's: x along the line, z the range, float32; here big
    endian, with padding) reads with axes=("x", "z")."""
    ts = m.typestore()
    PF = ts.types["sensor_msgs/msg/PointField"]
    x = np.array([-0.01, 0.0, 0.01, np.nan], dtype=">f4")
    z = np.array([0.1, 0.102, 0.1, np.nan], dtype=">f4")
    dtype = np.dtype({"names": ["x", "z"], "formats": [">f4", ">f4"], "offsets": [0, 8],
                      "itemsize": 16})  # fmt: skip
    raw = np.zeros(4, dtype=dtype)
    raw["x"], raw["z"] = x, z
    cloud = m.default(
        "sensor_msgs/msg/PointCloud2",
        header=m.header(0.5, "scanner"),
        height=1, width=4, is_bigendian=True, point_step=16, row_step=64, is_dense=False,
        fields=[PF(name="x", offset=0, datatype=7, count=1),
                PF(name="z", offset=8, datatype=7, count=1)],
        data=raw.view(np.uint8).copy(),
    )  # fmt: skip
    cloud = m.decode(m.encode(cloud), "sensor_msgs/msg/PointCloud2")
    profile = m.cloud_profile(cloud, axes=("x", "z"))
    np.testing.assert_array_equal(profile.points_laser[:3, 0], x[:3].astype(float) * 1000.0)
    np.testing.assert_array_equal(profile.valid, [True, True, True, False])
    with pytest.raises(ValueError, match="no field"):
        m.cloud_profile(cloud)  # no y field


def test_quaternions_agree_with_scipy_and_invert() -> None:
    rng = np.random.default_rng(3)
    rotations = Rotation.random(200, random_state=rng).as_matrix()
    flips = [np.eye(3), np.diag([1.0, -1, -1]), np.diag([-1.0, 1, -1]), np.diag([-1.0, -1, 1])]
    rotations = np.concatenate([rotations, flips])
    for R in rotations:
        q = np.array(m.quaternion(R))
        ref = Rotation.from_matrix(R).as_quat()
        assert min(np.abs(q - ref).max(), np.abs(q + ref).max()) < 1e-12
        np.testing.assert_allclose(m.rotation(q), R, atol=1e-12)


def test_tf_message_round_trips() -> None:
    rng = np.random.default_rng(11)
    chain = []
    for parent, child in (("world", "base"), ("base", "tcp"), ("tcp", "sensor")):
        T = np.eye(4)
        T[:3, :3] = Rotation.random(random_state=rng).as_matrix()
        T[:3, 3] = rng.uniform(-500, 500, 3)
        chain.append((parent, child, T))
    data = m.encode(m.tf_message(chain, 2.0))
    other = _independent("tf2_msgs/msg/TFMessage", data)
    assert [t.child_frame_id for t in other.transforms] == ["base", "tcp", "sensor"]
    assert other.transforms[0].transform.translation.x == chain[0][2][0, 3] / 1000.0
    back = m.tf_chain(m.decode(data, "tf2_msgs/msg/TFMessage"))
    for (p, c, T), (p2, c2, T2) in zip(chain, back, strict=True):
        assert (p, c) == (p2, c2)
        np.testing.assert_allclose(T2, T, atol=1e-9)


def test_stamps_clock_and_float() -> None:
    assert (m.stamp(0.123456789).sec, m.stamp(0.123456789).nanosec) == (0, 123456789)
    assert (m.stamp(2.5).sec, m.stamp(2.5).nanosec) == (2, 500_000_000)
    assert m.seconds(m.stamp(3.75)) == 3.75
    other = _independent("rosgraph_msgs/msg/Clock", m.encode(m.clock(12.001)))
    assert (other.clock.sec, other.clock.nanosec) == (12, 1_000_000)
    assert _independent("std_msgs/msg/Float64", m.encode(m.float64(0.25))).data == 0.25


def test_seam_point_and_marker() -> None:
    feature = Feature.found([1.5, 101.25])
    msg = m.seam_point(feature, 0.5)
    other = _independent("geometry_msgs/msg/PointStamped", m.encode(msg))
    assert (other.point.x, other.point.y, other.point.z) == (0.0, 0.0015, 0.10125)
    np.testing.assert_allclose(m.point_laser(msg), [1.5, 101.25], rtol=3e-16)
    assert m.seam_point(Feature.failed("none"), 0.5) is None
    pts = np.array([[0.0, 0.0, 0.0], [10.0, 0.0, 0.0], [20.0, 5.0, 1.0]])
    marker = m.seam_marker(pts)
    other = _independent("visualization_msgs/msg/Marker", m.encode(marker))
    assert other.type == 4 and other.header.frame_id == "world"  # LINE_STRIP
    assert [(p.x, p.y, p.z) for p in other.points] == [tuple(p / 1000) for p in pts]
    np.testing.assert_allclose(m.marker_points(marker), pts, atol=1e-12)
    # Humble's Marker has fewer fields: the same call builds it
    humble = m.seam_marker(pts, distro="humble")
    assert m.decode(m.encode(humble, "humble"), "visualization_msgs/msg/Marker", "humble").type == 4


@pytest.mark.parametrize("bits", [8, 10, 12])
def test_image_round_trips(bits: int) -> None:
    rng = np.random.default_rng(bits)
    levels = 2**bits - 1
    pixels = (rng.integers(0, levels + 1, (6, 9)) / levels).astype(np.float32)
    msg = m.image_message(pixels, 0.04, bit_depth=bits)
    other = _independent("sensor_msgs/msg/Image", m.encode(msg))
    assert other.encoding == ("mono8" if bits == 8 else "mono16")
    assert (other.height, other.width) == (6, 9)
    back = m.image_pixels(m.decode(m.encode(msg), "sensor_msgs/msg/Image"))
    # mono8 keeps 8-bit levels exactly; mono16 is within half a 16-bit step
    tol = 1e-7 if bits == 8 else 0.5 / 65535 + 1e-7
    np.testing.assert_allclose(back, pixels, atol=tol, rtol=0)


def test_topics_and_frames_in_one_place() -> None:
    assert set(m.FRAMES.values()) == {fr.WORLD, fr.BASE, fr.FLANGE, fr.TCP, fr.SENSOR}
    names = [t.name for t in m.TOPICS.values()]
    assert len(names) == len(set(names))
    ts = m.typestore()
    for topic in m.TOPICS.values():
        assert topic.type in ts.types
    assert sorted(m.REASON_CODES) == [int(r) for r in Reason]


def test_observer_sees_every_frame_and_changes_nothing() -> None:
    """Seam mode (paper-verification, short): the observer's frames are the run's frames
    (frames.csv's times and seam points), the run's numbers are those of an unobserved run,
    and the TF chain composes to the sensor pose."""
    scene = st.load_scene("paper-verification", overrides={"seam.length_mm": 20.0})
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.loop import run

    plain = run(build_parts(scene))
    log = fr.FrameLog()
    parts = fr.observe(build_parts(scene), log)
    seen = run(parts)
    f = seen.trace.frames
    assert len(log.frames) == len(f["t_capture_s"]) > 3
    np.testing.assert_array_equal([fr_.t_s for fr_ in log.frames], f["t_capture_s"])
    np.testing.assert_array_equal(seen.trace.tcp_world, plain.trace.tcp_world)
    for frame, found, point in zip(log.frames, f["found"], f["point_world"], strict=True):
        assert bool(frame.feature) == found
        assert len(frame.profile) == 1 and bool(frame.profile.valid[0]) == found
        if found:
            np.testing.assert_array_equal(frame.feature.point_world, point)
            np.testing.assert_allclose(frame.profile.points_world[0], point, atol=1e-9)
        chain = fr.frame_chain(parts.robot, frame.T_world_sensor)
        assert [(p, c) for p, c, _ in chain] == [("world", "base"), ("base", "tcp"),
                                                 ("tcp", "sensor")]  # fmt: skip
        np.testing.assert_allclose(
            frames.compose(*(T for _, _, T in chain)), frame.T_world_sensor, atol=1e-9
        )
    assert math.isfinite(seen.summary["max_error_mm"])


def test_an_arms_chain_has_its_flange() -> None:
    """On a UR10e the chain is world -> base -> flange -> tcp -> sensor; the torch on the
    flange is the arm's tool, and the links compose to the sensor pose of every frame."""
    pytest.importorskip("pinocchio")
    arm = {"robot.model": "ur10e", "tracker.name": "trajectory",
           "robot.base_origin_mm": [200.0, -700.0, 0.0], "seam.length_mm": 20.0}  # fmt: skip
    scene = st.load_scene("paper-verification", overrides=arm)
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.loop import run

    log = fr.FrameLog()
    parts = fr.observe(build_parts(scene), log)
    run(parts)
    assert len(log.frames) > 3
    for frame in log.frames:
        chain = fr.frame_chain(parts.robot, frame.T_world_sensor)
        assert [c for _, c, _ in chain] == ["base", "flange", "tcp", "sensor"]
        np.testing.assert_array_equal(chain[2][2], parts.robot.kinematics.T_flange_tcp)
        np.testing.assert_allclose(
            frames.compose(*(T for _, _, T in chain)), frame.T_world_sensor, atol=1e-9
        )
        back = m.tf_chain(m.decode(m.encode(m.tf_message(chain, frame.t_s)), m.TOPICS["tf"].type))
        np.testing.assert_allclose(
            frames.compose(*(T for _, _, T in back)), frame.T_world_sensor, atol=1e-9
        )
