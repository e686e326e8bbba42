"""The bridge's per-frame ROS 2 messages written straight to CDR bytes, without building
``rosbags`` message objects: the same bytes as ``rosbags``' serializer gives for the messages
of :mod:`seamtrack.bridge.messages` (tests/test_bridge_cdr.py checks them byte for byte), at a
fraction of the cost (the PointCloud2 of a 1024-point profile is one numpy copy).

Little-endian CDR (XCDR1, as ROS 2 sends it): the 4-byte encapsulation header ``00 01 00 00``,
then the fields in order, each aligned to its own size (at most 8) from the end of the header;
a string is a uint32 length (with its NUL) then its bytes and a NUL; a sequence a uint32 count
then its elements. Units as in :mod:`seamtrack.bridge.messages`: m, m/s, rad; the message
holds seamtrack's mm / 1000.
"""

from __future__ import annotations

import contextlib
import functools
import struct
from collections.abc import Iterable, Iterator
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from seamtrack.bridge import messages
from seamtrack.sensing.profiles import Feature, Profile

#: CDR little-endian encapsulation (representation identifier 0x0001, options 0).
ENCAPSULATION = b"\x00\x01\x00\x00"

_MM = messages.MM_PER_M
_U32 = struct.Struct("<I")
_STAMP = struct.Struct("<iI")
_3D = struct.Struct("<3d")
_4D = struct.Struct("<4d")
_6D = struct.Struct("<6d")
_7D = struct.Struct("<7d")


class Writer:
    """A CDR little-endian byte string under construction (alignment from the header's end)."""

    __slots__ = ("buf",)

    def __init__(self) -> None:
        self.buf = bytearray(ENCAPSULATION)

    def align(self, n: int) -> None:
        pad = -(len(self.buf) - 4) % n
        if pad:
            self.buf += b"\x00" * pad

    def u32(self, value: int) -> None:
        self.align(4)
        self.buf += _U32.pack(value)

    def u8(self, value: int) -> None:
        self.buf.append(value)

    def string(self, text: str) -> None:
        raw = text.encode()
        self.u32(len(raw) + 1)
        self.buf += raw
        self.buf.append(0)

    def stamp(self, t_s: float) -> None:
        ns = round(t_s * 1e9)
        self.align(4)
        self.buf += _STAMP.pack(ns // 1_000_000_000, ns % 1_000_000_000)

    def header(self, t_s: float, frame_id: str) -> None:
        self.stamp(t_s)
        self.string(frame_id)

    def doubles(self, packer: struct.Struct, *values: float) -> None:
        self.align(8)
        self.buf += packer.pack(*values)

    def octets(self, data: bytes | memoryview) -> None:
        """A ``uint8[]`` sequence."""
        self.u32(len(data))
        self.buf += data

    def bytes(self) -> bytes:
        return bytes(self.buf)


def clock(t_s: float) -> bytes:
    """``rosgraph_msgs/Clock``."""
    w = Writer()
    w.stamp(t_s)
    return w.bytes()


def string(text: str) -> bytes:
    """``std_msgs/String``."""
    w = Writer()
    w.string(text)
    return w.bytes()


def _stamped_doubles(t_s: float, frame_id: str, layout: struct.Struct, *values: float) -> bytes:
    """A message of a header and fixed doubles (``geometry_msgs``' ``*Stamped``): one pack
    into the whole message's layout (:func:`_stamped_layout`)."""
    ns = round(t_s * 1e9)
    whole, name = _stamped_layout(frame_id, layout.size // 8)
    return whole.pack(
        ENCAPSULATION, ns // 1_000_000_000, ns % 1_000_000_000, len(name) + 1, name, *values
    )


@functools.cache
def _stamped_layout(frame_id: str, n: int) -> tuple[struct.Struct, bytes]:
    """The layout of a header in ``frame_id`` and ``n`` doubles, as :class:`Writer` writes it
    (the doubles aligned to 8 from the header's end), and the frame id's bytes."""
    name = frame_id.encode()
    end = 12 + len(name) + 1  # stamp, the string's length, its bytes and NUL
    return struct.Struct(f"<4siII{len(name) + 1}s{-end % 8}x{n}d"), name


def point_stamped(t_s: float, frame_id: str, point_m: Iterable[float]) -> bytes:
    """``geometry_msgs/PointStamped`` of a point already in metres."""
    return _stamped_doubles(t_s, frame_id, _3D, *point_m)


def pose_stamped(
    t_s: float, frame_id: str, position_m: Iterable[float], q: Iterable[float]
) -> bytes:
    """``geometry_msgs/PoseStamped``: a position (m) and a quaternion (x, y, z, w)."""
    return _stamped_doubles(t_s, frame_id, _7D, *position_m, *q)


def twist_stamped(
    t_s: float, frame_id: str, linear: Iterable[float], angular: Iterable[float]
) -> bytes:
    """``geometry_msgs/TwistStamped`` (m/s, rad/s)."""
    return _stamped_doubles(t_s, frame_id, _6D, *linear, *angular)


def tf_message(chain: Iterable[tuple[str, str, ArrayLike]], t_s: float) -> bytes:
    """``tf2_msgs/TFMessage`` of (parent, child, T_parent_child (mm)) links at ``t_s``
    (as :func:`seamtrack.bridge.messages.tf_message`)."""
    links = list(chain)
    w = Writer()
    w.u32(len(links))
    for parent, child, T in links:
        rows = T.tolist() if isinstance(T, np.ndarray) else np.asarray(T, dtype=float).tolist()
        w.header(t_s, parent)
        w.string(child)
        q = messages.quaternion(rows)
        w.doubles(_7D, rows[0][3] / _MM, rows[1][3] / _MM, rows[2][3] / _MM, *q)
    return w.bytes()


def _cloud_prefix() -> bytes:
    """The PointCloud2 fields (PointField sequence), written once."""
    w = Writer()
    w.buf = bytearray()
    fields = messages._FIELDS
    w.buf += _U32.pack(len(fields))
    for name, offset, datatype in fields:
        raw = name.encode()
        w.buf += _U32.pack(len(raw) + 1) + raw + b"\x00"
        w.buf += b"\x00" * (-len(w.buf) % 4) + _U32.pack(offset)
        w.buf += bytes([datatype]) + b"\x00" * 3 + _U32.pack(1)
    return bytes(w.buf)


def profile_cloud(profile: Profile, t_s: float, frame_id: str = messages.FRAMES["sensor"]) -> bytes:
    """A profile as ``sensor_msgs/PointCloud2`` (:func:`seamtrack.bridge.messages.
    profile_cloud`'s layout: x = 0, y, z float64 in m, the uint8 reason; 32 bytes a point)."""
    assert profile.reason is not None and profile.valid is not None
    n = len(profile)
    data = np.zeros(n, dtype=messages.POINT_DTYPE)
    data["y"] = profile.points_laser[:, 0] / _MM
    data["z"] = profile.points_laser[:, 1] / _MM
    data["reason"] = profile.reason
    step = messages.POINT_DTYPE.itemsize
    w = Writer()
    w.header(t_s, frame_id)
    w.u32(1)  # height
    w.u32(n)  # width
    # The fields sequence starts 4-aligned, and each PointField ends 4-aligned: the same bytes
    # wherever the header's frame id leaves it.
    w.buf += _FIELDS_CDR
    w.u8(0)  # is_bigendian
    w.u32(step)
    w.u32(step * n)
    w.octets(data.view(np.uint8).data)
    w.u8(1 if bool(profile.valid.all()) else 0)
    return w.bytes()


_FIELDS_CDR = _cloud_prefix()


def seam_point(feature: Feature, t_s: float, frame_id: str = messages.FRAMES["sensor"]) -> bytes:
    """A found feature's seam point as ``geometry_msgs/PointStamped`` in the sensor frame."""
    y, z = (feature.point_laser / _MM).tolist()
    return point_stamped(t_s, frame_id, (0.0, y, z))


def image(image: Any, t_s: float, frame_id: str = messages.FRAMES["sensor"]) -> bytes:
    """A StripeImage as ``sensor_msgs/Image`` (:func:`seamtrack.bridge.messages.
    stripe_image_message`'s encoding)."""
    m = messages.stripe_image_message(image, t_s)
    w = Writer()
    w.header(t_s, frame_id)
    w.u32(m.height)
    w.u32(m.width)
    w.string(m.encoding)
    w.u8(m.is_bigendian)
    w.u32(m.step)
    w.octets(np.ascontiguousarray(m.data, dtype=np.uint8).data)
    return w.bytes()


# --------------------------------------------------------------------------- reading
_STAMPED_DOUBLES = {"geometry_msgs/msg/PoseStamped": 7, "geometry_msgs/msg/TwistStamped": 6}


def _read_header(raw: bytes) -> tuple[str, memoryview, int, str, int]:
    """(byte order, the body after the encapsulation, stamp in ns, frame id, the offset after
    the header) of a CDR message that starts with a ``std_msgs/Header``; ValueError (or
    struct.error, UnicodeDecodeError) on anything else."""
    if len(raw) < 4 or raw[0] != 0 or raw[1] not in (0, 1):
        raise ValueError("no CDR encapsulation header")
    order = "<" if raw[1] == 1 else ">"
    body = memoryview(raw)[4:]
    sec, nanosec, length = struct.unpack_from(order + "iII", body, 0)
    if length < 1 or 12 + length > len(body) or body[12 + length - 1] != 0:
        raise ValueError("a string that does not fit")
    frame_id = bytes(body[12 : 12 + length - 1]).decode()
    return order, body, sec * 1_000_000_000 + nanosec, frame_id, 12 + length


@contextlib.contextmanager
def _refused_as(msgtype: str) -> Iterator[None]:
    """Every way reading bytes as a ``msgtype`` fails, as one ValueError naming it."""
    try:
        yield
    except struct.error:
        raise ValueError(f"not a {msgtype} (too short)") from None
    except UnicodeDecodeError:
        raise ValueError(f"not a {msgtype} (a frame id that is not UTF-8)") from None
    except ValueError as exc:
        raise ValueError(f"not a {msgtype} ({exc})") from None


def read_stamped(raw: bytes, msgtype: str) -> tuple[int, str, tuple[float, ...]]:
    """A ``geometry_msgs/PoseStamped`` (position, orientation: 7 doubles) or ``TwistStamped``
    (linear, angular: 6) from CDR bytes, either byte order: (stamp in ns, frame id, the
    doubles). Checked as ``rosbags`` checks it (the string inside the data and NUL-ended,
    UTF-8; no more than 3 bytes of padding after the last field); raises ValueError on
    anything else."""
    n = _STAMPED_DOUBLES[msgtype]
    with _refused_as(msgtype):
        order, body, stamp_ns, frame_id, pos = _read_header(raw)
        pos += -pos % 8
        values = struct.unpack_from(f"{order}{n}d", body, pos)
        pos += 8 * n
        if pos + 3 < len(body):
            raise ValueError("bytes after the message")
    return stamp_ns, frame_id, values


def read_pose_array(raw: bytes, most: int) -> tuple[int, str, list[tuple[float, ...]]]:
    """A ``geometry_msgs/PoseArray`` from CDR bytes, either byte order: (stamp in ns, frame
    id, each pose's position and orientation as 7 doubles), at most ``most`` poses; checked
    as :func:`read_stamped` checks; raises ValueError on anything else."""
    msgtype = "geometry_msgs/msg/PoseArray"
    with _refused_as(msgtype):
        order, body, stamp_ns, frame_id, pos = _read_header(raw)
        pos += -pos % 4
        (count,) = struct.unpack_from(order + "I", body, pos)
        pos += 4
        if count > most:
            raise ValueError(f"{count} poses, more than {most}")
        poses = []
        if count:
            pos += -pos % 8
            for _ in range(count):
                poses.append(struct.unpack_from(f"{order}7d", body, pos))
                pos += 56
        if pos + 3 < len(body):
            raise ValueError("bytes after the message")
    return stamp_ns, frame_id, poses
