"""MCAP recordings (``seamtrack run --record``) read back with mcap-ros2-support's decoder, and
the importer (PointCloud2 profiles from an MCAP file or a ROS 2 bag into the real-data layout).

The recorded run is a short mesh-mode one (paper-v-groove, a 20 mm groove, 512 rays); the
run's own profiles come from an in-process run of the same scene seen by the frame observer.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("mcap_ros2")
pytest.importorskip("rosbags")

from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from seamtrack.bench.extractors import load_real_set, load_real_sets
from seamtrack.bridge import frames as fr
from seamtrack.bridge import messages as m
from seamtrack.bridge.importer import read_scans, write_real_set
from seamtrack.bridge.record import Recorder
from seamtrack.cli.main import main
from seamtrack.cli.recording import recorded_run
from seamtrack.geometry import frames
from seamtrack.simulation.assemble import build_parts
from seamtrack.simulation.loop import run
from seamtrack.simulation.scene import load_scene

SHORT = ["workpiece.params.seam_length_mm=20", "sensor.rays=512"]
SHORT_DICT = {"workpiece.params.seam_length_mm": 20.0, "sensor.rays": 512}


def _read(path: Path) -> dict[str, list[tuple[int, object]]]:
    """Every message by topic: (log time ns, decoded message), with mcap-ros2-support."""
    out: dict[str, list[tuple[int, object]]] = {}
    with path.open("rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for _, channel, message, decoded in reader.iter_decoded_messages(log_time_order=True):
            out.setdefault(channel.topic, []).append((message.log_time, decoded))
    return out


@pytest.fixture(scope="module")
def recorded(tmp_path_factory: pytest.TempPathFactory):
    tmp = tmp_path_factory.mktemp("mcap")
    sets = [a for kv in SHORT for a in ("--set", kv)]
    code = main(["run", "paper-v-groove", *sets, "--out", str(tmp / "run"), "--no-plot", "-q",
                 "--record", str(tmp / "run.mcap")])  # fmt: skip
    assert code == 0
    scene = load_scene("paper-v-groove", SHORT_DICT)
    log = fr.FrameLog()
    parts = build_parts(scene)
    result = run(fr.observe(parts, log))
    return tmp, _read(tmp / "run.mcap"), log.frames, parts, result


def test_every_frame_has_its_cloud_tf_and_clock(recorded) -> None:
    tmp, topics, frames_seen, _, result = recorded
    table = np.genfromtxt(tmp / "run" / "frames.csv", delimiter=",", names=True)
    n = len(table)
    assert n == len(frames_seen) == result.summary["frames"] > 100
    for topic in ("/clock", "/tf", "/seamtrack/profile"):
        assert len(topics[topic]) == n, topic
    clock_s = np.array([m.seconds(msg.clock) for _, msg in topics["/clock"]])
    np.testing.assert_allclose(clock_s, table["t_capture_s"], atol=5e-7)  # the CSV's 6 decimals
    log_ns = [ns for ns, _ in topics["/seamtrack/profile"]]
    assert log_ns == [round(f.t_s * 1e9) for f in frames_seen]


def test_profiles_equal_the_runs_bit_for_bit(recorded) -> None:
    _, topics, frames_seen, _, _ = recorded
    for (_, cloud), frame in zip(topics["/seamtrack/profile"], frames_seen, strict=True):
        assert cloud.header.frame_id == "sensor" and cloud.width == len(frame.profile) == 512
        raw = np.frombuffer(bytes(cloud.data), dtype=m.POINT_DTYPE)
        # the message holds the run's profile / 1000 exactly (NaN where the profile is NaN)
        np.testing.assert_array_equal(raw["y"], frame.profile.points_laser[:, 0] / 1000.0)
        np.testing.assert_array_equal(raw["z"], frame.profile.points_laser[:, 1] / 1000.0)
        np.testing.assert_array_equal(raw["reason"], frame.profile.reason)
        points, valid = m.cloud_arrays(cloud)
        np.testing.assert_array_equal(valid, frame.profile.valid)
        np.testing.assert_allclose(points, frame.profile.points_laser, rtol=3e-16, atol=0)


def test_seam_points_through_tf_equal_frames_csv(recorded) -> None:
    """The recorded seam point (sensor frame) taken to the world by the recorded TF chain is
    frames.csv's seam point."""
    tmp, topics, _, _, _ = recorded
    table = np.genfromtxt(tmp / "run" / "frames.csv", delimiter=",", names=True)
    found = table["found"] > 0
    tf_at = {ns: msg for ns, msg in topics["/tf"]}
    points = topics["/seamtrack/seam_point"]
    assert len(points) == int(found.sum()) > 50
    world_csv = np.column_stack([table["x_mm"], table["y_mm"], table["z_mm"]])[found]
    for (ns, point), expected in zip(points, world_csv, strict=True):
        chain = m.tf_chain(tf_at[ns])
        assert [c for _, c, _ in chain] == ["base", "tcp", "sensor"]
        T_world_sensor = frames.compose(*(T for _, _, T in chain))
        p = T_world_sensor @ np.array([0.0, point.point.y * 1000, point.point.z * 1000, 1.0])
        np.testing.assert_allclose(p[:3], expected, atol=2e-6)


def test_marker_labels_and_error_series(recorded) -> None:
    tmp, topics, _, parts, _ = recorded
    (ns, marker), *rest = topics["/seamtrack/seam"]
    assert ns == 0 and not rest and marker.type == 4  # once, a LINE_STRIP
    np.testing.assert_allclose(m.marker_points(marker), parts.seam.points, atol=1e-9)
    with (tmp / "run.mcap").open("rb") as fh:
        summary = make_reader(fh).get_summary()
    latched = [c for c in summary.channels.values() if c.topic == "/seamtrack/seam"]
    assert "durability: 1" in latched[0].metadata["offered_qos_profiles"]
    trace = np.genfromtxt(tmp / "run" / "trace.csv", delimiter=",", names=True)
    errors = topics["/seamtrack/error"]
    assert len(errors) == len(trace)
    np.testing.assert_allclose([e.data * 1000 for _, e in errors], trace["error_mm"], atol=5e-7)
    np.testing.assert_allclose([ns * 1e-9 for ns, _ in errors], trace["t_s"], atol=5e-7)
    # the labels: where the laser plane crosses the CAD seam; the extractor's answers lie on
    # them (the v-groove extractor on a clean 512-ray stripe: well under 0.1 mm)
    truths = {ns: m.point_laser(p) for ns, p in topics["/seamtrack/seam_truth"]}
    found = {ns: m.point_laser(p) for ns, p in topics["/seamtrack/seam_point"]}
    both = sorted(set(truths) & set(found))
    assert len(both) > 50
    gaps = [np.hypot(*(truths[k] - found[k])) for k in both]
    assert max(gaps) < 0.1


def test_importer_reads_back_what_the_recorder_wrote(recorded, tmp_path: Path) -> None:
    tmp, topics, frames_seen, _, _ = recorded
    scans = read_scans(tmp / "run.mcap")
    labelled = {ns for ns, _ in topics["/seamtrack/seam_truth"]}
    kept = [f for f in frames_seen if round(f.t_s * 1e9) in labelled]
    assert scans.joint == "v-groove" and len(scans.profiles) == len(kept) > 50
    for profile, frame in zip(scans.profiles, kept, strict=True):
        np.testing.assert_allclose(
            profile.points_laser, frame.profile.points_laser, rtol=3e-16, atol=0
        )
        np.testing.assert_array_equal(profile.reason, frame.profile.reason)
    # the real-data layout, read by the extractors bench's own loader
    write_real_set(scans, tmp_path / "set")
    rs = load_real_set(tmp_path / "set")
    assert rs.joint == "v-groove" and len(rs.profiles) == len(kept)
    np.testing.assert_array_equal(rs.labels, scans.labels)
    for a, b in zip(rs.profiles, scans.profiles, strict=True):
        np.testing.assert_array_equal(a.valid, b.valid)
        np.testing.assert_array_equal(a.valid_points, b.valid_points)
    # and straight from the recording, as the bench reads it (the joint given)
    (direct,) = load_real_sets(tmp / "run.mcap", joint="v-groove")
    assert direct.labels is not None and len(direct.profiles) == len(kept)


def test_importer_reads_a_ros2_bag_folder(tmp_path: Path) -> None:
    """A ROS 2 bag (sqlite3) of a driver's clouds: x along the line, y = 0, z the range, in
    float32, and PointStamped labels of the same stamps."""
    from rosbags.rosbag2 import Writer

    ts = m.typestore()
    PF = ts.types["sensor_msgs/msg/PointField"]
    rng = np.random.default_rng(5)
    dtype = np.dtype({"names": ["x", "y", "z"], "formats": ["<f4"] * 3, "offsets": [0, 4, 8],
                      "itemsize": 12})  # fmt: skip
    sent, labels = [], []
    with Writer(tmp_path / "bag", version=8) as bag:
        cloud_conn = bag.add_connection(
            "/scanner/cloud", "sensor_msgs/msg/PointCloud2", typestore=ts
        )
        label_conn = bag.add_connection("/labels", "geometry_msgs/msg/PointStamped", typestore=ts)
        for i in range(4):
            raw = np.zeros(50, dtype=dtype)
            raw["x"] = np.linspace(-0.02, 0.02, 50, dtype=np.float32)
            raw["z"] = (0.1 + 0.001 * rng.standard_normal(50)).astype(np.float32)
            t = 0.1 * i
            cloud = m.default(
                "sensor_msgs/msg/PointCloud2", header=m.header(t, "scanner"), height=1, width=50,
                fields=[PF(name=n, offset=o, datatype=7, count=1)
                        for n, o in (("x", 0), ("y", 4), ("z", 8))],
                is_bigendian=False, point_step=12, row_step=600, data=raw.view(np.uint8).copy(),
                is_dense=True,
            )  # fmt: skip
            point = ts.types["geometry_msgs/msg/Point"](x=0.001, y=0.0, z=0.1)
            head = m.header(t, "scanner")
            label = m.default(m.TOPICS["seam_point"].type, header=head, point=point)
            bag.write(cloud_conn, m.stamp_ns(t), m.encode(cloud))
            bag.write(label_conn, m.stamp_ns(t), m.encode(label))
            sent.append(raw)
            labels.append((1.0, 100.0))
    scans = read_scans(tmp_path / "bag", joint="v-groove")
    assert scans.meta["topic"] == "/scanner/cloud" and scans.meta["labels_topic"] == "/labels"
    assert len(scans.profiles) == 4
    for profile, raw in zip(scans.profiles, sent, strict=True):
        np.testing.assert_array_equal(profile.points_laser[:, 0], raw["x"].astype(float) * 1000)
        np.testing.assert_array_equal(profile.points_laser[:, 1], raw["z"].astype(float) * 1000)
    np.testing.assert_allclose(scans.labels, labels, rtol=1e-15)


def test_image_mode_records_the_camera_images(tmp_path: Path) -> None:
    scene = load_scene("v-groove-camera", {"workpiece.params.seam_length_mm": 6.0})
    parts = build_parts(scene)
    log = fr.FrameLog()
    recorder = Recorder(tmp_path / "img.mcap", parts, scene)

    def both(frame: fr.Frame) -> None:
        log(frame)
        recorder(frame)

    result = run(fr.observe(parts, both))
    recorder.finish(result)
    images = _read(tmp_path / "img.mcap")["/seamtrack/image"]
    assert len(images) == len(log.frames) >= 2
    for (_, image), frame in zip(images, log.frames, strict=True):
        assert image.encoding == "mono16"  # a 10-bit camera
        pixels = frame.image.pixels
        assert (image.height, image.width) == pixels.shape
        back = m.image_pixels(image)
        np.testing.assert_allclose(back, pixels, atol=0.5 / 65535 + 1e-7, rtol=0)


def test_a_stopped_run_keeps_its_recording(tmp_path: Path) -> None:
    """A run that stops on its time limit is written whole; one interrupted (Ctrl-C) after
    two frames keeps those two frames; one that fails leaves nothing (not even the folders
    made for the file)."""
    scene = load_scene("paper-verification", {"simulation.time_limit_s": 3.0})
    path = tmp_path / "stalled.mcap"
    result = recorded_run(str(path), scene, build_parts(scene), False)
    assert result.summary["status"] == "stalled"
    assert len(_read(path)["/clock"]) == result.summary["frames"] > 0

    def interrupting(after: int, exc: BaseException):
        parts = build_parts(scene)
        count = [0]
        sense = parts.sense

        def stop(*args, **kwargs):
            if count[0] == after:
                raise exc
            count[0] += 1
            return sense(*args, **kwargs)

        import dataclasses

        return dataclasses.replace(parts, sense=stop)

    path = tmp_path / "stopped.mcap"
    with pytest.raises(KeyboardInterrupt):
        recorded_run(str(path), scene, interrupting(2, KeyboardInterrupt()), False)
    assert len(_read(path)["/clock"]) == 2
    path = tmp_path / "new" / "folders" / "failed.mcap"
    with pytest.raises(RuntimeError):
        recorded_run(str(path), scene, interrupting(2, RuntimeError("boom")), False)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["stalled.mcap", "stopped.mcap"]


@pytest.mark.parametrize(
    ("target", "words"),
    [
        ("run.txt", "not an .mcap file name"),
        ("folder.mcap", "is a folder"),
        ("afile/run.mcap", "is a file"),
    ],
)
def test_bad_record_paths_are_refused_before_the_run(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], target: str, words: str
) -> None:
    (tmp_path / "folder.mcap").mkdir()
    (tmp_path / "afile").write_text("x")
    before = sorted(tmp_path.iterdir())
    code = main(["run", "paper-verification", "--out", str(tmp_path / "out"),
                 "--record", str(tmp_path / target)])  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and err[0].startswith("seamtrack: error: --record: ")
    assert words in err[0]
    assert sorted(tmp_path.iterdir()) == before  # nothing written


def test_missing_extra_names_the_pip_install(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setitem(sys.modules, "mcap_ros2", None)  # import mcap_ros2 -> ImportError
    code = main(["run", "paper-verification", "--out", str(tmp_path / "out"),
                 "--record", str(tmp_path / "run.mcap")])  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1
    assert "--record" in err[0] and "pip install 'seamtrack[ros]'" in err[0]
    code = main(["extractors", "bench", "--real", str(tmp_path / "run.mcap"),
                 "--out", str(tmp_path / "bench")])  # fmt: skip
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "pip install 'seamtrack[ros]'" in err[0]
    assert list(tmp_path.iterdir()) == []


def test_a_run_without_record_imports_no_ros_library(tmp_path: Path) -> None:
    code = (
        "import sys\n"
        "from seamtrack.cli.main import main\n"
        f"assert main(['run', 'paper-verification', '--set', 'seam.length_mm=10', '-q', "
        f"'--no-plot', '--out', {str(tmp_path / 'out')!r}]) == 0\n"
        "mods = ('rosbags', 'mcap', 'mcap_ros2', 'zenoh', 'zmq', 'seamtrack.bridge.messages')\n"
        "print(sorted(m for m in mods if m in sys.modules))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "[]"
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["frames"] > 0


def test_importer_refuses_more_points_than_memory_allows(
    recorded, monkeypatch: pytest.MonkeyPatch
) -> None:
    from seamtrack.bridge import importer
    from seamtrack.errors import SeamtrackError

    tmp = recorded[0]
    monkeypatch.setattr(importer, "MAX_POINTS", 3 * 512)
    with pytest.raises(SeamtrackError, match="more than 1,536 profile points") as info:
        read_scans(tmp / "run.mcap")
    assert info.value.field == "--real"


def test_messages_are_in_time_order_in_the_file(recorded) -> None:
    """Issue 43 item 6: a reader in file order (not sorting by log time) never goes back in
    time, and it meets the error series among the frames, not after them; every channel has
    the QoS profile ``ros2 bag record`` writes (reliable; latched only the seam marker)."""
    tmp, topics, _, _, _ = recorded
    times, order = [], []
    with (tmp / "run.mcap").open("rb") as fh:
        reader = make_reader(fh)
        for _, channel, message in reader.iter_messages(log_time_order=False):
            times.append(message.log_time)
            order.append(channel.topic)
        channels = list(reader.get_summary().channels.values())
    assert np.all(np.diff(times) >= 0)
    first_error = order.index("/seamtrack/error")
    assert first_error < order.index("/clock") + 10  # with the first frames, not at the end
    assert len(order) == sum(len(v) for v in topics.values())
    for channel in channels:
        qos = channel.metadata["offered_qos_profiles"]
        assert "reliability: 1" in qos, channel.topic
        durability = 1 if channel.topic == "/seamtrack/seam" else 2
        assert f"durability: {durability}\n" in qos, channel.topic


def test_a_recording_starts_at_the_given_epoch(recorded, tmp_path: Path) -> None:
    """``--record-epoch``: the same messages, every log time and stamp moved by the epoch
    (whole nanoseconds: no float rounding of 1.7e9 s), the payloads otherwise unchanged."""
    _, topics, _, _, _ = recorded
    epoch_s = "1767225600.000000123"
    epoch_ns = 1767225600_000000123
    sets = [a for kv in SHORT for a in ("--set", kv)]
    record = ["--record", str(tmp_path / "at.mcap"), "--record-epoch", epoch_s]
    code = main(["run", "paper-v-groove", *sets, "--out", str(tmp_path / "run"), "--no-plot",
                 "-q", *record])  # fmt: skip
    assert code == 0
    moved = _read(tmp_path / "at.mcap")
    assert moved.keys() == topics.keys()

    def stamp_ns(msg) -> int:
        return msg.sec * 1_000_000_000 + msg.nanosec

    for topic, rows in topics.items():
        assert [ns + epoch_ns for ns, _ in rows] == [ns for ns, _ in moved[topic]], topic
    for (ns, clock), (ns2, clock2) in zip(topics["/clock"], moved["/clock"], strict=True):
        assert stamp_ns(clock.clock) == ns and stamp_ns(clock2.clock) == ns2
    for (_, tf), (_, tf2) in zip(topics["/tf"], moved["/tf"], strict=True):
        for a, b in zip(tf.transforms, tf2.transforms, strict=True):
            assert stamp_ns(b.header.stamp) - stamp_ns(a.header.stamp) == epoch_ns
            assert a.transform.translation.x == b.transform.translation.x
    for (_, a), (_, b) in zip(topics["/seamtrack/profile"], moved["/seamtrack/profile"],
                              strict=True):  # fmt: skip
        assert stamp_ns(b.header.stamp) - stamp_ns(a.header.stamp) == epoch_ns
        assert bytes(a.data) == bytes(b.data)


def test_a_recording_is_never_written_over_without_force(recorded, tmp_path: Path) -> None:
    """An earlier recording is replaced only with --force (and then whole: it decodes as the
    new run's); a file that is not MCAP never (catalogue: 'record onto ...')."""
    tmp, topics, _, _, _ = recorded
    sets = [a for kv in SHORT for a in ("--set", kv)]
    target = tmp_path / "run.mcap"
    target.write_bytes((tmp / "run.mcap").read_bytes()[:-100])  # an earlier, damaged one
    args = ["run", "paper-v-groove", *sets, "--no-plot", "-q", "--record", str(target)]
    assert main([*args, "--out", str(tmp_path / "a")]) == 2
    assert not (tmp_path / "a").exists()
    assert main([*args, "--out", str(tmp_path / "b"), "--force"]) == 0
    again = _read(target)
    assert {k: len(v) for k, v in again.items()} == {k: len(v) for k, v in topics.items()}
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".partial-")]
