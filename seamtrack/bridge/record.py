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

Every message is in the file in time order (log time; the frames' messages before the error
series' at the same time), so a reader in file order never goes back in time: the error
series are known only when the run ends, so the frames are streamed to an uncompressed
temporary file and merged with them, once, into the final (zstd) file. Every channel carries
its QoS profile as ``ros2 bag record`` writes it (``offered_qos_profiles``: reliable and
volatile, the latched marker transient-local). The clock starts at ``epoch_ns`` (default 0,
1970; ``--record-epoch``): every log time and every header stamp is the simulated time plus
it.

Schemas are the ROS 2 ``.msg`` definitions (``ros2msg``) and messages CDR (``cdr``), as ``ros2
bag record`` writes them to MCAP: Foxglove opens the file, and ``ros2 bag play`` plays it.
The file is streamed to a temporary name beside the target and renamed when complete: a failed
run leaves nothing, a stopped one (lost seam, stall, limit, wall-clock, Ctrl-C) its recording
up to where it stopped.
"""

from __future__ import annotations

import dataclasses
import heapq
import os
import struct
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
from mcap.writer import CompressionType, Writer

from seamtrack._version import __version__
from seamtrack.bridge import messages as msgs
from seamtrack.bridge.frames import Frame, frame_chain, true_seam_point
from seamtrack.errors import OutputError
from seamtrack.io.output import check_writable

#: The first bytes of every MCAP file (the format's magic, version 0).
MCAP_MAGIC = b"\x89MCAP0\r\n"


def _qos(durability: int) -> str:
    """rosbag2's ``offered_qos_profiles`` YAML of one publisher (history unknown, depth 0,
    reliable, the durability given, deadline/lifespan/lease infinite, liveliness automatic),
    as ``ros2 bag record`` writes it into MCAP channel metadata (Humble's encoding)."""
    return (
        f"- history: 3\n  depth: 0\n  reliability: 1\n  durability: {durability}\n"
        "  deadline:\n    sec: 2147483647\n    nsec: 4294967295\n"
        "  lifespan:\n    sec: 2147483647\n    nsec: 4294967295\n"
        "  liveliness: 1\n"
        "  liveliness_lease_duration:\n    sec: 2147483647\n    nsec: 4294967295\n"
        "  avoid_ros_namespace_conventions: false\n"
    )


#: rosbag2's QoS of a latched (transient-local) topic, as MCAP channel metadata.
LATCHED_QOS = _qos(1)
#: rosbag2's QoS of every other topic: a default publisher's, reliable and volatile.
VOLATILE_QOS = _qos(2)

#: The largest epoch a recording may start at: ROS 2 time's seconds are an int32, and a
#: run's simulated time must fit after it (a day and more of slack).
MAX_EPOCH_S = 2**31 - 1 - 10**6


def check_record_target(path: str | Path, field: str = "--record", force: bool = False) -> Path:
    """Refuse, before a run, a recording target that cannot be written (nothing is created),
    and one that exists: an earlier MCAP file is replaced only with ``force``, any other file
    never."""
    target = Path(path)
    if target.suffix.lower() != ".mcap":
        raise OutputError(
            f"{str(target)!r} is not an .mcap file name", field=field, fix="name it like run.mcap"
        )
    if target.is_dir():
        raise OutputError(f"{str(target)!r} is a folder", field=field, fix="give a file path")
    if target.exists() or target.is_symlink():
        if not _is_mcap(target):
            raise OutputError(
                f"{str(target)!r} exists and is not an MCAP file",
                field=field,
                fix="give a new file name (seamtrack never replaces a file it did not write)",
            )
        if not force:
            raise OutputError(
                f"{str(target)!r} exists",
                field=field,
                fix="add --force to replace it, or give a new file name",
            )
    check_writable(target.parent if str(target.parent) else Path("."), field=field)
    return target


def _is_mcap(path: Path) -> bool:
    """Whether ``path`` is a file that starts with MCAP's magic bytes."""
    try:
        with path.open("rb") as f:
            return f.read(len(MCAP_MAGIC)) == MCAP_MAGIC
    except OSError:
        return False


class McapOut:
    """An MCAP file of ROS 2 messages, written to a temporary name and renamed by
    :meth:`close` (or removed by :meth:`discard`)."""

    def __init__(self, path: str | Path, compression: str = "zstd", epoch_ns: int = 0) -> None:
        self.target = Path(path)
        self.epoch_ns = int(epoch_ns)
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
        metadata = {"offered_qos_profiles": LATCHED_QOS if latched else VOLATILE_QOS}
        self._channels[topic] = self._writer.register_channel(
            topic=topic,
            message_encoding="cdr",
            schema_id=self._schemas[typename],
            metadata=metadata,
        )
        self._sequence[topic] = 0
        return self._channels[topic]

    def write(self, topic: str, message: Any, t_s: float, latched: bool = False) -> None:
        """One message, logged (and published) at simulated time ``t_s`` (its stamps and the
        log time moved to the epoch)."""
        message = at_epoch(message, self.epoch_ns)
        ns = msgs.stamp_ns(t_s) + self.epoch_ns
        self.write_encoded(topic, message.__msgtype__, msgs.encode(message), ns, latched)

    def write_encoded(
        self, topic: str, typename: str, data: bytes, log_time_ns: int, latched: bool = False
    ) -> None:
        """One message's CDR bytes, logged at ``log_time_ns`` (already at the epoch)."""
        channel = self.channel(topic, typename, latched)
        self._writer.add_message(
            channel, log_time=log_time_ns, data=data, publish_time=log_time_ns,
            sequence=self._sequence[topic],
        )  # fmt: skip
        self._sequence[topic] += 1
        self.messages += 1

    def metadata(self, name: str, data: dict[str, str]) -> None:
        self._writer.add_metadata(name, data)

    def close(self) -> Path:
        """Finish the file and move it to its name."""
        try:
            if not self._file.closed:
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


def at_epoch(message: Any, epoch_ns: int) -> Any:
    """``message`` with every ``builtin_interfaces/Time`` in it (header stamps, a clock, a TF
    message's transforms) moved ``epoch_ns`` later; the message itself when 0."""
    if not epoch_ns:
        return message
    if message.__msgtype__ == "builtin_interfaces/msg/Time":
        ns = message.sec * 1_000_000_000 + message.nanosec + epoch_ns
        return type(message)(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)
    changes: dict[str, Any] = {}
    for f in dataclasses.fields(message):
        value = getattr(message, f.name)
        if hasattr(value, "__msgtype__"):
            moved = at_epoch(value, epoch_ns)
            if moved is not value:
                changes[f.name] = moved
        elif isinstance(value, list) and value and hasattr(value[0], "__msgtype__"):
            changes[f.name] = [at_epoch(v, epoch_ns) for v in value]
    if not changes:
        return message
    return dataclasses.replace(message, **changes)


#: A spooled message's head: log time (ns), topic index, data length.
_HEAD = struct.Struct("<qHI")

#: ``std_msgs/Float64`` in little-endian CDR: the encapsulation header, then the double.
_FLOAT64_CDR = b"\x00\x01\x00\x00"


class _Spool:
    """Encoded messages in the order they come, in an anonymous temporary file (gone with the
    process, whatever ends it): the frames of a run, before the error series are known."""

    def __init__(self, folder: Path) -> None:
        self._file = tempfile.TemporaryFile(dir=folder)
        self.topics: list[tuple[str, str, bool]] = []  # (topic, type, latched) by index
        self._index: dict[str, int] = {}

    def add(self, topic: str, typename: str, data: bytes, log_time_ns: int, latched: bool) -> None:
        k = self._index.get(topic)
        if k is None:
            k = self._index[topic] = len(self.topics)
            self.topics.append((topic, typename, latched))
        self._file.write(_HEAD.pack(log_time_ns, k, len(data)))
        self._file.write(data)

    def __iter__(self) -> Iterator[tuple[int, str, str, bytes, bool]]:
        """(log time, topic, type, data, latched) in the order added."""
        f = self._file
        f.flush()
        f.seek(0)
        while head := f.read(_HEAD.size):
            t_ns, k, n = _HEAD.unpack(head)
            topic, typename, latched = self.topics[k]
            yield t_ns, topic, typename, f.read(n), latched

    def close(self) -> None:
        self._file.close()


class Recorder:
    """An :func:`~seamtrack.bridge.frames.observe` callback that records every frame of a run
    (module docstring); :meth:`finish` adds the error series in time order and moves the file
    into place. ``epoch_ns``: the recording's clock at the run's t = 0 (default 1970).

    The frames are spooled (CDR bytes, :class:`_Spool`) while the run goes, and written into
    the MCAP file once, merged with the error series, when it ends."""

    def __init__(self, path: str | Path, parts: Any, scene: Any = None, epoch_ns: int = 0) -> None:
        self.epoch_ns = int(epoch_ns)
        self.out = McapOut(path, epoch_ns=self.epoch_ns)
        self._spool = _Spool(self.out.target.parent if str(self.out.target.parent) else Path("."))
        self.robot = parts.robot
        self.seam, self.sensor = parts.seam, parts.sensor
        self.frames = 0
        meta = {"seamtrack_version": __version__, "extractor": str(parts.extractor_name)}
        if scene is not None:
            meta["scene"] = scene.name
            meta["sensor_mode"] = scene.config.sensor.mode
        if self.epoch_ns:
            meta["epoch_ns"] = str(self.epoch_ns)
        self.out.metadata("seamtrack", meta)
        topic = msgs.TOPICS["seam"].name
        self._add(topic, msgs.seam_marker(parts.seam.points), 0.0, latched=True)

    def _add(self, topic: str, message: Any, t_s: float, latched: bool = False) -> None:
        message = at_epoch(message, self.epoch_ns)
        ns = msgs.stamp_ns(t_s) + self.epoch_ns
        self._spool.add(topic, message.__msgtype__, msgs.encode(message), ns, latched)

    def __call__(self, frame: Frame) -> None:
        t = frame.t_s
        chain = frame_chain(self.robot, frame.T_world_sensor)
        sensor = self.sensor
        truth = None if sensor is None else true_seam_point(self.seam, sensor, frame.T_world_sensor)
        for topic, message in msgs.frame_messages(
            t, frame.profile, frame.feature, chain, truth, frame.image
        ):
            self._add(topic, message, t)
        self.frames += 1

    def finish(self, result: Any = None, trace_period_s: float = 0.01) -> Path:
        """Write the frames, merged in time order with the error series of ``result`` (none
        after a ``KeyboardInterrupt``), and move the file into place."""
        extra: list[tuple[int, str, str, bytes, bool]] = []
        if result is not None:
            tr = result.trace
            idx = tr.decimated(trace_period_s)
            series = (
                ("error", tr.error_mm),
                ("error_lateral", tr.error_lateral_mm),
                ("error_vertical", tr.error_vertical_mm),
            )
            kind = msgs.TOPICS["error"].type
            for t, i in zip(tr.t_s[idx].tolist(), idx.tolist(), strict=True):
                ns = msgs.stamp_ns(t) + self.epoch_ns
                for key, values in series:
                    value = float(values[i]) / msgs.MM_PER_M
                    if np.isfinite(value):  # the CDR of std_msgs/Float64, as encode() makes it
                        data = _FLOAT64_CDR + struct.pack("<d", value)
                        extra.append((ns, msgs.TOPICS[key].name, kind, data, False))
        try:
            # frames first at equal times (a stable merge of two time-ordered streams)
            for t_ns, topic, kind, data, latched in heapq.merge(
                self._spool, extra, key=lambda row: row[0]
            ):
                self.out.write_encoded(topic, kind, data, t_ns, latched)
            return self.out.close()
        except BaseException:
            self.out.discard()
            raise
        finally:
            self._spool.close()

    def discard(self) -> None:
        self._spool.close()
        self.out.discard()
