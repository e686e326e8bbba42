"""A run as an MCAP recording of ROS 2 messages (``seamtrack run SCENE --record run.mcap``).

Per sensor frame (log time = the frame's simulated capture time) the recording holds
``/clock`` (``rosgraph_msgs/Clock``), ``/tf`` (``tf2_msgs/TFMessage``: world -> base ->
[flange ->] tcp -> sensor), ``/seamtrack/profile`` (``sensor_msgs/PointCloud2`` in the sensor
frame, with the per-point ``reason``), ``/seamtrack/seam_point`` (``geometry_msgs/PointStamped``,
frames with a seam point), ``/seamtrack/seam_truth`` (the same type: where the laser plane
crosses the true seam in the field of view, the frame's label) and, in image mode,
``/seamtrack/image`` (``sensor_msgs/Image``). The true seam is ``/seamtrack/seam``
(``visualization_msgs/Marker``, a LINE_STRIP in the world frame, once at time 0, its channel
marked transient-local: latched), and the tracking error the ``/seamtrack/error``,
``/seamtrack/error/lateral`` and ``/seamtrack/error/vertical`` topics (``std_msgs/Float64``,
m) at the times of ``trace.csv``. Topics, frames and units: :mod:`seamtrack.bridge.messages`.
The file's ``seamtrack`` metadata record names the scene, the extractor and seamtrack's
version.

Schemas are the ROS 2 ``.msg`` definitions (``ros2msg``) and messages CDR (``cdr``), as ``ros2
bag record`` writes them to MCAP: Foxglove opens the file, and ``ros2 bag play`` plays it.
The file is streamed to a temporary name beside the target and renamed when complete: a failed
run leaves nothing, a stopped one (lost seam, stall, limit, wall-clock, Ctrl-C) its recording
up to where it stopped.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
from mcap.writer import CompressionType, Writer

from seamtrack._version import __version__
from seamtrack.bridge import messages as msgs
from seamtrack.bridge.frames import Frame, frame_chain, true_seam_point
from seamtrack.errors import OutputError
from seamtrack.io.output import check_writable

#: rosbag2's QoS of a latched (transient-local) topic, as MCAP channel metadata.
LATCHED_QOS = (
    "- history: 3\n  depth: 0\n  reliability: 1\n  durability: 1\n"
    "  deadline:\n    sec: 2147483647\n    nsec: 4294967295\n"
    "  lifespan:\n    sec: 2147483647\n    nsec: 4294967295\n"
    "  liveliness: 1\n"
    "  liveliness_lease_duration:\n    sec: 2147483647\n    nsec: 4294967295\n"
    "  avoid_ros_namespace_conventions: false\n"
)


def check_record_target(path: str | Path, field: str = "--record") -> Path:
    """Refuse, before a run, a recording target that cannot be written (nothing is created)."""
    target = Path(path)
    if target.suffix.lower() != ".mcap":
        raise OutputError(
            f"{str(target)!r} is not an .mcap file name", field=field, fix="name it like run.mcap"
        )
    if target.is_dir():
        raise OutputError(f"{str(target)!r} is a folder", field=field, fix="give a file path")
    check_writable(target.parent if str(target.parent) else Path("."), field=field)
    return target


class McapOut:
    """An MCAP file of ROS 2 messages, written to a temporary name and renamed by
    :meth:`close` (or removed by :meth:`discard`)."""

    def __init__(self, path: str | Path, compression: str = "zstd") -> None:
        self.target = Path(path)
        folder = self.target.parent if str(self.target.parent) else Path(".")
        self._created: list[Path] = []  # folders made for the file, innermost first
        probe = folder.absolute()
        while not probe.exists():
            self._created.append(probe)
            probe = probe.parent
        folder.mkdir(parents=True, exist_ok=True)
        handle, tmp = tempfile.mkstemp(prefix=".partial-", suffix=".mcap", dir=folder)
        self._tmp = Path(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(handle, 0o666 & ~umask)  # as open() would make it (mkstemp makes it private)
        self._file = os.fdopen(handle, "wb")
        kind = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4}.get(
            compression, CompressionType.NONE
        )
        self._writer = Writer(self._file, compression=kind)
        self._writer.start(profile="ros2", library=f"seamtrack {__version__}")
        self._schemas: dict[str, int] = {}
        self._channels: dict[str, int] = {}
        self._sequence: dict[str, int] = {}
        self.messages = 0

    def channel(self, topic: str, typename: str, latched: bool = False) -> int:
        """The channel of ``topic`` (registered with its schema on first use)."""
        if topic in self._channels:
            return self._channels[topic]
        if typename not in self._schemas:
            self._schemas[typename] = self._writer.register_schema(
                name=typename, encoding="ros2msg", data=msgs.msg_definition(typename).encode()
            )
        metadata = {"offered_qos_profiles": LATCHED_QOS} if latched else {}
        self._channels[topic] = self._writer.register_channel(
            topic=topic,
            message_encoding="cdr",
            schema_id=self._schemas[typename],
            metadata=metadata,
        )
        self._sequence[topic] = 0
        return self._channels[topic]

    def write(self, topic: str, message: Any, t_s: float, latched: bool = False) -> None:
        """One message, logged (and published) at simulated time ``t_s``."""
        channel = self.channel(topic, message.__msgtype__, latched)
        ns = msgs.stamp_ns(t_s)
        self._writer.add_message(
            channel, log_time=ns, data=msgs.encode(message), publish_time=ns,
            sequence=self._sequence[topic],
        )  # fmt: skip
        self._sequence[topic] += 1
        self.messages += 1

    def metadata(self, name: str, data: dict[str, str]) -> None:
        self._writer.add_metadata(name, data)

    def close(self) -> Path:
        """Finish the file and move it to its name."""
        try:
            self._writer.finish()
            self._file.close()
            os.replace(self._tmp, self.target)
        except OSError as exc:
            self.discard()
            raise OutputError(
                f"cannot write {str(self.target)!r}: {exc.strerror or exc}",
                field="--record",
                fix="choose a file you can write to",
            ) from None
        return self.target

    def discard(self) -> None:
        """Remove the unfinished file."""
        if not self._file.closed:
            self._file.close()
        if self._tmp.exists():
            self._tmp.unlink()
        for created in self._created:
            try:
                created.rmdir()  # only if empty
            except OSError:
                break


class Recorder:
    """An :func:`~seamtrack.bridge.frames.observe` callback that records every frame of a run
    (module docstring); :meth:`finish` adds the error series and moves the file into place."""

    def __init__(self, path: str | Path, parts: Any, scene: Any = None) -> None:
        self.out = McapOut(path)
        self.robot = parts.robot
        self.seam, self.sensor = parts.seam, parts.sensor
        self.frames = 0
        meta = {"seamtrack_version": __version__, "extractor": str(parts.extractor_name)}
        if scene is not None:
            meta["scene"] = scene.name
            meta["sensor_mode"] = scene.config.sensor.mode
        self.out.metadata("seamtrack", meta)
        topic = msgs.TOPICS["seam"].name
        self.out.write(topic, msgs.seam_marker(parts.seam.points), 0.0, latched=True)

    def __call__(self, frame: Frame) -> None:
        t = frame.t_s
        chain = frame_chain(self.robot, frame.T_world_sensor)
        sensor = self.sensor
        truth = None if sensor is None else true_seam_point(self.seam, sensor, frame.T_world_sensor)
        for topic, message in msgs.frame_messages(
            t, frame.profile, frame.feature, chain, truth, frame.image
        ):
            self.out.write(topic, message, t)
        self.frames += 1

    def finish(self, result: Any = None, trace_period_s: float = 0.01) -> Path:
        """Write the error series of ``result`` (none for an interrupted run) and close."""
        if result is not None:
            tr = result.trace
            idx = tr.decimated(trace_period_s)
            series = (
                ("error", tr.error_mm),
                ("error_lateral", tr.error_lateral_mm),
                ("error_vertical", tr.error_vertical_mm),
            )
            for t, i in zip(tr.t_s[idx].tolist(), idx.tolist(), strict=True):
                for key, values in series:
                    value = float(values[i]) / msgs.MM_PER_M
                    if np.isfinite(value):
                        self.out.write(msgs.TOPICS[key].name, msgs.float64(value), t)
        return self.out.close()

    def discard(self) -> None:
        self.out.discard()
