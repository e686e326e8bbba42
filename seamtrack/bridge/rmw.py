"""ROS 2 on Zenoh without ROS: rmw_zenoh's key expressions, liveliness tokens and attachments
(as its design document, ros2/rmw_zenoh docs/design.md, gives them), and the bridge's messages
as ROS 2 CDR (``rosbags``; SI units: m, m/s, rad).

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


@functools.cache
def typestore() -> Any:
    from rosbags.typesys import Stores, get_typestore

    return get_typestore(Stores.ROS2_JAZZY)


def dds_type_name(msgtype: str) -> str:
    """``sensor_msgs/msg/PointCloud2`` -> ``sensor_msgs::msg::dds_::PointCloud2_``."""
    package, kind, name = msgtype.split("/")
    return f"{package}::{kind}::dds_::{name}_"


@functools.cache
def type_hash(msgtype: str) -> str:
    """REP-2016's type hash, ``RIHS01_<sha256 hex>``."""
    return str(typestore().hash_rihs01(msgtype))


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
def _time(t_s: float) -> Any:
    Time = typestore().types["builtin_interfaces/msg/Time"]
    ns = int(round(t_s * 1e9))
    return Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def stamp_ns(stamp: Any) -> int:
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def _header(t_s: float, frame_id: str) -> Any:
    return typestore().types["std_msgs/msg/Header"](stamp=_time(t_s), frame_id=frame_id)


def _vector(v: Any) -> Any:
    x, y, z = (float(c) for c in v)
    return typestore().types["geometry_msgs/msg/Vector3"](x=x, y=y, z=z)


def quaternion(R: FloatArray) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation matrix."""
    from scipy.spatial.transform import Rotation

    x, y, z, w = Rotation.from_matrix(R).as_quat()
    return float(x), float(y), float(z), float(w)


def serialize(msg: Any, msgtype: str) -> bytes:
    return bytes(typestore().serialize_cdr(msg, msgtype))


def clock(t_s: float) -> bytes:
    return serialize(typestore().types[CLOCK](clock=_time(t_s)), CLOCK)


def string(text: str) -> bytes:
    return serialize(typestore().types[STRING](data=text), STRING)


def point_stamped(t_s: float, frame_id: str, point_mm: Any) -> bytes:
    x, y, z = (float(c) / 1000.0 for c in point_mm)
    types = typestore().types
    point = types["geometry_msgs/msg/Point"](x=x, y=y, z=z)
    msg = types[POINT_STAMPED](header=_header(t_s, frame_id), point=point)
    return serialize(msg, POINT_STAMPED)


def pose_stamped(t_s: float, frame_id: str, position_mm: Any, R: FloatArray | None) -> bytes:
    types = typestore().types
    x, y, z = (float(c) / 1000.0 for c in position_mm)
    qx, qy, qz, qw = (0.0, 0.0, 0.0, 1.0) if R is None else quaternion(R)
    pose = types["geometry_msgs/msg/Pose"](
        position=types["geometry_msgs/msg/Point"](x=x, y=y, z=z),
        orientation=types["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw),
    )
    return serialize(types[POSE_STAMPED](header=_header(t_s, frame_id), pose=pose), POSE_STAMPED)


def twist_stamped(t_s: float, frame_id: str, linear: Any, angular: Any) -> bytes:
    types = typestore().types
    twist = types["geometry_msgs/msg/Twist"](linear=_vector(linear), angular=_vector(angular))
    msg = types[TWIST_STAMPED](header=_header(t_s, frame_id), twist=twist)
    return serialize(msg, TWIST_STAMPED)


def tf_message(t_s: float, chain: list[tuple[str, str, FloatArray]]) -> bytes:
    """The transforms ``(parent, child, T_parent_child)`` (mm) as one ``TFMessage``."""
    types = typestore().types
    transforms = []
    for parent, child, T in chain:
        qx, qy, qz, qw = quaternion(T[:3, :3])
        transform = types["geometry_msgs/msg/Transform"](
            translation=_vector(np.asarray(T[:3, 3]) / 1000.0),
            rotation=types["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw),
        )
        transforms.append(
            types["geometry_msgs/msg/TransformStamped"](
                header=_header(t_s, parent), child_frame_id=child, transform=transform
            )
        )
    return serialize(types[TFMESSAGE](transforms=transforms), TFMESSAGE)


def pointcloud2(t_s: float, frame_id: str, points_laser: FloatArray | None, reason: Any) -> bytes:
    """A stripe profile as ``PointCloud2`` in the sensor frame: x = 0 (the laser plane),
    y, z from the profile (m, float64, NaN where invalid), and ``reason`` (uint8, the
    :class:`~seamtrack.sensing.profiles.Reason` code); one row, in column order."""
    types = typestore().types
    PointField = types["sensor_msgs/msg/PointField"]
    n = 0 if points_laser is None else len(points_laser)
    record = np.dtype(
        {"names": ["x", "y", "z", "reason"], "formats": ["<f8", "<f8", "<f8", "u1"],
         "offsets": [0, 8, 16, 24], "itemsize": 32}
    )  # fmt: skip
    data = np.zeros(n, dtype=record)
    if points_laser is not None and n:
        data["y"] = points_laser[:, 0] / 1000.0
        data["z"] = points_laser[:, 1] / 1000.0
        data["reason"] = reason
    fields = [
        PointField(name=name, offset=off, datatype=kind, count=1)
        for name, off, kind in (
            ("x", 0, PointField.FLOAT64),
            ("y", 8, PointField.FLOAT64),
            ("z", 16, PointField.FLOAT64),
            ("reason", 24, PointField.UINT8),
        )
    ]
    msg = types[POINTCLOUD2](
        header=_header(t_s, frame_id),
        height=1,
        width=n,
        fields=fields,
        is_bigendian=False,
        point_step=32,
        row_step=32 * n,
        data=data.view(np.uint8),
        is_dense=False,
    )
    return serialize(msg, POINTCLOUD2)


def deserialize(raw: bytes, msgtype: str) -> Any:
    """CDR bytes decoded into ``msgtype`` (raises ValueError on anything else)."""
    try:
        return typestore().deserialize_cdr(raw, msgtype)
    except Exception as exc:  # rosbags raises struct, index, unicode and its own errors
        raise ValueError(f"not a {msgtype} ({exc.__class__.__name__})") from None


def is_finite(*values: float) -> bool:
    return all(math.isfinite(v) for v in values)
