"""ROS 2 on Zenoh without ROS: rmw_zenoh's key expressions, liveliness tokens and attachments
(as its design document, ros2/rmw_zenoh docs/design.md, gives them), and the bridge's messages
as ROS 2 CDR (:mod:`seamtrack.bridge.messages`; SI units: m, m/s, rad).

* A topic's key expression: ``<domain_id>/<fully_qualified_name>/<type_name>/<type_hash>``,
  e.g. ``0/chatter/std_msgs::msg::dds_::String_/RIHS01_df66...``; the fully qualified name
  without its leading ``/``, the type name as DDS declares it, the type hash REP-2016's
  ``RIHS01_`` + SHA-256 of the type description.
* A liveliness token: ``@ros2_lv/<domain_id>/<session_id>/<node_id>/<node_id>/NN/<enclave>/
  <namespace>/<node_name>`` for a node, and for a publisher (``MP``) or subscription (``MS``)
  ``@ros2_lv/<domain_id>/<session_id>/<node_id>/<entity_id>/<kind>/<enclave>/<namespace>/
  <node_name>/<mangled_qualified_name>/<type_name>/<type_hash>/<qos>``, names mangled by
  ``/`` -> ``%`` (``%`` alone when empty).
* Each ``put`` carries an attachment: the sequence number (int64 LE), the source timestamp
  (ns since the epoch, int64 LE), the GID's length (one byte, 16) and the 16-byte GID.
"""

from __future__ import annotations

import functools
import hashlib
import math
import struct
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.bridge import cdr, messages

FloatArray = NDArray[np.float64]

#: QoS of every entity the bridge declares, in rmw_zenoh's compact form: reliable, volatile,
#: keep last 10 (its default profile, as in the design document's examples).
DEFAULT_QOS = "::,10:,:,:,,"

POINTCLOUD2 = "sensor_msgs/msg/PointCloud2"
TFMESSAGE = "tf2_msgs/msg/TFMessage"
CLOCK = "rosgraph_msgs/msg/Clock"
POINT_STAMPED = "geometry_msgs/msg/PointStamped"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
TWIST_STAMPED = "geometry_msgs/msg/TwistStamped"
STRING = "std_msgs/msg/String"
POSE_ARRAY = "geometry_msgs/msg/PoseArray"
UINT32 = "std_msgs/msg/UInt32"


def dds_type_name(msgtype: str) -> str:
    """``sensor_msgs/msg/PointCloud2`` -> ``sensor_msgs::msg::dds_::PointCloud2_``."""
    package, kind, name = msgtype.split("/")
    return f"{package}::{kind}::dds_::{name}_"


@functools.cache
def type_hash(msgtype: str) -> str:
    """REP-2016's type hash, ``RIHS01_<sha256 hex>``."""
    return str(messages.typestore().hash_rihs01(msgtype))


def mangle(name: str) -> str:
    return name.replace("/", "%") or "%"


def topic_key(domain_id: int, topic: str, msgtype: str) -> str:
    """The key expression rmw_zenoh publishes ``topic`` (fully qualified) on."""
    return f"{domain_id}/{topic.strip('/')}/{dds_type_name(msgtype)}/{type_hash(msgtype)}"


def node_token(domain_id: int, session_id: str, node_id: int, node: str, namespace: str) -> str:
    return f"@ros2_lv/{domain_id}/{session_id}/{node_id}/{node_id}/NN/%/{mangle(namespace)}/{node}"


def entity_token(
    domain_id: int,
    session_id: str,
    node_id: int,
    entity_id: int,
    kind: str,
    node: str,
    namespace: str,
    topic: str,
    msgtype: str,
    qos: str = DEFAULT_QOS,
) -> str:
    """A publisher's (``MP``) or subscription's (``MS``) liveliness token."""
    return (
        f"@ros2_lv/{domain_id}/{session_id}/{node_id}/{entity_id}/{kind}/%/{mangle(namespace)}/"
        f"{node}/{mangle(topic)}/{dds_type_name(msgtype)}/{type_hash(msgtype)}/{qos}"
    )


def parse_token(key: str) -> dict[str, str] | None:
    """The fields of a liveliness token (None when it is not one)."""
    parts = key.split("/")
    if len(parts) < 9 or parts[0] != "@ros2_lv":
        return None
    names = ["domain", "session", "node_id", "entity_id", "kind", "enclave", "namespace", "node"]
    out = dict(zip(names, parts[1:9], strict=True))
    if len(parts) >= 13:
        out.update(topic=parts[9].replace("%", "/"), type=parts[10], hash=parts[11])
    return out


def gid(seed: str) -> bytes:
    """A 16-byte GID for an entity (stable for its name and session)."""
    return hashlib.sha256(seed.encode()).digest()[:16]


def attachment(seq: int, stamp_ns: int, gid16: bytes) -> bytes:
    return struct.pack("<qqB", seq, stamp_ns, 16) + gid16


# --------------------------------------------------------------------------- messages
# Written straight to CDR (seamtrack.bridge.cdr: the bytes rosbags gives, checked in a test).
def encode_clock(t_s: float) -> bytes:
    return cdr.clock(t_s)


def encode_string(text: str) -> bytes:
    return cdr.string(text)


def encode_uint32(value: int) -> bytes:
    """``std_msgs/UInt32`` (little-endian CDR)."""
    return struct.pack("<4sI", b"\x00\x01\x00\x00", value)


def encode_point(t_s: float, frame_id: str, point_mm: Any) -> bytes:
    """``geometry_msgs/PointStamped`` of a point in mm."""
    return cdr.point_stamped(t_s, frame_id, [float(c) / messages.MM_PER_M for c in point_mm])


def encode_pose(t_s: float, frame_id: str, position_mm: Any, R: FloatArray | None) -> bytes:
    """``geometry_msgs/PoseStamped``: a position (mm) and orientation (identity when None)."""
    position = [float(c) / messages.MM_PER_M for c in position_mm]
    q = (0.0, 0.0, 0.0, 1.0) if R is None else messages.quaternion(R)
    return cdr.pose_stamped(t_s, frame_id, position, q)


def encode_twist(t_s: float, frame_id: str, linear: Any, angular: Any) -> bytes:
    """``geometry_msgs/TwistStamped`` of a linear (m/s) and angular (rad/s) velocity."""
    return cdr.twist_stamped(t_s, frame_id, [float(c) for c in linear], [float(c) for c in angular])


def stamp_ns(stamp: Any) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def deserialize(raw: bytes, msgtype: str) -> Any:
    """CDR bytes decoded into ``msgtype`` (raises ValueError on anything else)."""
    try:
        return messages.decode(raw, msgtype)
    except Exception as exc:  # rosbags raises struct, index, unicode and its own errors
        raise ValueError(f"not a {msgtype} ({exc.__class__.__name__})") from None


def is_finite(*values: float) -> bool:
    return all(map(math.isfinite, values))  # no generator frame: a few us a step less
