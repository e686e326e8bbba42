"""ROS 2 messages without ROS: seamtrack's objects as ROS 2 messages, CDR bytes and back.

Messages are built with `rosbags <https://ternaris.gitlab.io/rosbags/>`_'s type store for ROS 2
Jazzy (:data:`DISTRO`; ``typestore("humble")`` for Humble) and serialized to little-endian CDR,
the bytes a ROS 2 node sends and an MCAP file stores.

**Units and frames.** ROS speaks metres and seconds (REP 103): every length in a message is
seamtrack's millimetres divided by :data:`MM_PER_M`, stored as float64; reading a message back
multiplies by it (the same value to 1 ulp; the message holds ``mm / 1000`` bit for bit). Times
are simulated seconds as ``builtin_interfaces/Time`` (nanosecond resolution). Frame ids are in
:data:`FRAMES`, topics in :data:`TOPICS`: the one place both are written down.

**The profile** is a ``sensor_msgs/PointCloud2`` in the ``sensor`` frame, one point per sensor
column in column order (height 1): ``x`` = 0 (the laser plane), ``y`` = y_L, ``z`` = z_L (the
range), FLOAT64, and ``reason`` (UINT8): the :class:`~seamtrack.sensing.profiles.Reason` code
of the point (:data:`REASON_CODES`). Invalid points keep the coordinates the profile holds
(NaN where the ray hit nothing). ``point_step`` is 32 bytes (25 used, 7 padding, so the doubles
stay aligned); ``is_dense`` is true when every point is valid.

Needs the ``ros`` extra (``pip install seamtrack[ros]``); nothing of seamtrack's core imports
this module.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from rosbags.typesys import Stores, get_typestore
from rosbags.typesys.store import Typestore

from seamtrack.sensing.profiles import Feature, Profile, Reason

FloatArray = NDArray[np.float64]

#: The ROS 2 distribution whose message definitions are used (``rosbags`` store name).
DISTRO = "jazzy"
_STORES = {"jazzy": Stores.ROS2_JAZZY, "humble": Stores.ROS2_HUMBLE}

#: Millimetres per metre: seamtrack speaks mm, ROS messages metres.
MM_PER_M = 1000.0

#: The per-point ``reason`` field of a profile's PointCloud2: code -> meaning (the
#: :class:`~seamtrack.sensing.profiles.Reason` codes; 0 is the only valid one).
REASON_CODES: dict[int, str] = {
    int(Reason.VALID): "valid: a measured stripe point",
    int(Reason.MISS): "no hit: the laser ray hit nothing",
    int(Reason.OCCLUDED): "occluded: the camera cannot see the lit point",
    int(Reason.OUT_OF_RANGE): "out of the field of view or the depth of field",
    int(Reason.INCIDENCE): "grazing incidence beyond the sensor's limit: too dim",
    int(Reason.DROPOUT): "dropout: lost to the noise model, or no peak in an image column",
    int(Reason.SPIKE): "spike: an isolated point off its neighbours (specular)",
    int(Reason.REFLECTION): "reflection: a multipath streak off the surface's line",
}


@dataclass(frozen=True)
class Topic:
    """A topic seamtrack publishes (``seamtrack serve``) or records (``--record``)."""

    name: str
    type: str  # the ROS 2 type, e.g. "sensor_msgs/msg/PointCloud2"
    frame_id: str  # the header's frame ("" when the message has no header)
    what: str


#: Frame ids of the robot's chain: world -> base -> (flange ->) tcp -> sensor.
FRAMES = {
    "world": "world",  # the scene's world frame
    "base": "base",  # the robot's base (a gantry's axes, an arm's base link)
    "flange": "flange",  # an arm's tool flange (arms only)
    "tcp": "tcp",  # the torch's tool centre point
    "sensor": "sensor",  # the laser frame: x across the laser plane, z along the range
}

#: Every topic, in one place.
TOPICS = {
    "profile": Topic(
        "/seamtrack/profile",
        "sensor_msgs/msg/PointCloud2",
        FRAMES["sensor"],
        "the stripe profile of each sensor frame (x = 0, y = y_L, z = z_L, reason)",
    ),
    "tf": Topic(
        "/tf",
        "tf2_msgs/msg/TFMessage",
        "",
        "the robot's frame chain at each sensor frame (world, base, [flange,] tcp, sensor)",
    ),
    "clock": Topic("/clock", "rosgraph_msgs/msg/Clock", "", "simulated time, per sensor frame"),
    "seam_point": Topic(
        "/seamtrack/seam_point",
        "geometry_msgs/msg/PointStamped",
        FRAMES["sensor"],
        "the seam point the extractor found (frames with a seam point only)",
    ),
    "seam_truth": Topic(
        "/seamtrack/seam_truth",
        "geometry_msgs/msg/PointStamped",
        FRAMES["sensor"],
        "where the laser plane crosses the true seam in the field of view (the label)",
    ),
    "image": Topic(
        "/seamtrack/image",
        "sensor_msgs/msg/Image",
        FRAMES["sensor"],
        "image mode: the camera image (mono8 up to 8 bits, else mono16 scaled to full range)",
    ),
    "seam": Topic(
        "/seamtrack/seam",
        "visualization_msgs/msg/Marker",
        FRAMES["world"],
        "the true seam as a LINE_STRIP, once (latched)",
    ),
    "error": Topic(
        "/seamtrack/error",
        "std_msgs/msg/Float64",
        "",
        "tracking error: distance from the torch to the seam (m), per sensor frame",
    ),
    "error_lateral": Topic(
        "/seamtrack/error/lateral",
        "std_msgs/msg/Float64",
        "",
        "tracking error across the seam (m, signed), per sensor frame",
    ),
    "error_vertical": Topic(
        "/seamtrack/error/vertical",
        "std_msgs/msg/Float64",
        "",
        "tracking error along the torch normal (m, signed), per sensor frame",
    ),
}


# --------------------------------------------------------------------------- the type store
@functools.cache
def typestore(distro: str = DISTRO) -> Typestore:
    """The ``rosbags`` type store of a ROS 2 distribution (``"jazzy"`` or ``"humble"``)."""
    try:
        return get_typestore(_STORES[distro])
    except KeyError:
        raise ValueError(f"no ROS 2 distribution {distro!r}; use one of {list(_STORES)}") from None


def msg_definition(typename: str, distro: str = DISTRO) -> str:
    """The ``.msg`` text of a type with its dependencies (MCAP's ``ros2msg`` schema encoding)."""
    return typestore(distro).generate_msgdef(typename, ros_version=2)[0]


def encode(message: Any, distro: str = DISTRO) -> bytes:
    """A message object to little-endian CDR bytes (with the 4-byte encapsulation header)."""
    return bytes(typestore(distro).serialize_cdr(message, message.__msgtype__, little_endian=True))


def decode(data: bytes | memoryview, typename: str, distro: str = DISTRO) -> Any:
    """CDR bytes to a message object of ``typename``."""
    return typestore(distro).deserialize_cdr(data, typename)


class _Types:
    """Attribute access to a store's message classes: ``_Types(ts).Header``."""

    def __init__(self, ts: Typestore) -> None:
        t = ts.types
        self.Time = t["builtin_interfaces/msg/Time"]
        self.Duration = t["builtin_interfaces/msg/Duration"]
        self.Header = t["std_msgs/msg/Header"]
        self.Float64 = t["std_msgs/msg/Float64"]
        self.ColorRGBA = t["std_msgs/msg/ColorRGBA"]
        self.Point = t["geometry_msgs/msg/Point"]
        self.PointStamped = t["geometry_msgs/msg/PointStamped"]
        self.Vector3 = t["geometry_msgs/msg/Vector3"]
        self.Quaternion = t["geometry_msgs/msg/Quaternion"]
        self.Pose = t["geometry_msgs/msg/Pose"]
        self.Transform = t["geometry_msgs/msg/Transform"]
        self.TransformStamped = t["geometry_msgs/msg/TransformStamped"]
        self.TFMessage = t["tf2_msgs/msg/TFMessage"]
        self.Clock = t["rosgraph_msgs/msg/Clock"]
        self.PointField = t["sensor_msgs/msg/PointField"]
        self.PointCloud2 = t["sensor_msgs/msg/PointCloud2"]
        self.Image = t["sensor_msgs/msg/Image"]
        self.ts = ts


@functools.cache
def _cached_types(distro: str) -> _Types:
    return _Types(typestore(distro))


def default(typename: str, distro: str = DISTRO, **values: Any) -> Any:
    """A message of ``typename`` with ``values`` and every other field zero, empty or default
    (fields differ between distributions: Jazzy's Marker has more than Humble's)."""
    ts = typestore(distro)
    _, fields = ts.fielddefs[typename]
    kwargs: dict[str, Any] = {}
    for name, desc in fields:
        if name in values:
            kwargs[name] = values.pop(name)
        else:
            kwargs[name] = _zero(ts, desc)
    if values:
        raise TypeError(f"{typename} has no field(s) {sorted(values)}")
    return ts.types[typename](**kwargs)


_NUMPY = {
    "bool": np.bool_, "byte": np.uint8, "char": np.uint8, "int8": np.int8, "uint8": np.uint8,
    "int16": np.int16, "uint16": np.uint16, "int32": np.int32, "uint32": np.uint32,
    "int64": np.int64, "uint64": np.uint64, "float32": np.float32, "float64": np.float64,
}  # fmt: skip


def _zero(ts: Typestore, desc: Any) -> Any:
    kind, arg = desc[0], desc[1]
    if kind == 1:  # BASE: (name, limit)
        name = arg[0]
        return "" if name == "string" else (False if name == "bool" else 0)
    if kind == 2:  # NAME: a nested message
        return _nested(ts, arg)
    sub, count = arg  # ARRAY (3) of fixed size, SEQUENCE (4)
    if sub[0] == 1 and sub[1][0] in _NUMPY:
        return np.zeros(count if kind == 3 else 0, dtype=_NUMPY[sub[1][0]])
    return [_zero(ts, sub) for _ in range(count)] if kind == 3 else []


def _nested(ts: Typestore, typename: str) -> Any:
    _, fields = ts.fielddefs[typename]
    return ts.types[typename](**{name: _zero(ts, desc) for name, desc in fields})


# --------------------------------------------------------------------------- time, poses
def stamp(t_s: float, distro: str = DISTRO) -> Any:
    """Simulated seconds as ``builtin_interfaces/Time`` (rounded to the nanosecond). The
    messages of one frame share one object (do not change it)."""
    return _stamp(float(t_s), distro)


@functools.lru_cache(maxsize=16)
def _stamp(t_s: float, distro: str) -> Any:
    ns = round(t_s * 1e9)
    return _cached_types(distro).Time(sec=ns // 1_000_000_000, nanosec=ns % 1_000_000_000)


def seconds(time: Any) -> float:
    """``builtin_interfaces/Time`` (or a header's stamp) to seconds."""
    return time.sec + time.nanosec * 1e-9


def stamp_ns(t_s: float) -> int:
    """Simulated seconds as integer nanoseconds (MCAP's log time)."""
    return round(t_s * 1e9)


def header(t_s: float, frame_id: str, distro: str = DISTRO) -> Any:
    return _cached_types(distro).Header(stamp=stamp(t_s, distro), frame_id=frame_id)


def quaternion(R: ArrayLike) -> tuple[float, float, float, float]:
    """A rotation matrix (or a pose: its rotation) to a unit quaternion (x, y, z, w), w >= 0
    (Shepperd's method)."""
    rows = R.tolist() if isinstance(R, np.ndarray) else np.asarray(R, dtype=np.float64).tolist()
    (a, b, c), (d, e, f), (g, h, i) = (row[:3] for row in rows[:3])
    trace = a + e + i
    if trace > 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        x, y, z, w = (h - f) / s, (c - g) / s, (d - b) / s, 0.25 * s
    elif a > e and a > i:
        s = 2.0 * math.sqrt(1.0 + a - e - i)
        x, y, z, w = 0.25 * s, (b + d) / s, (c + g) / s, (h - f) / s
    elif e > i:
        s = 2.0 * math.sqrt(1.0 + e - a - i)
        x, y, z, w = (b + d) / s, 0.25 * s, (f + h) / s, (c - g) / s
    else:
        s = 2.0 * math.sqrt(1.0 + i - a - e)
        x, y, z, w = (c + g) / s, (f + h) / s, 0.25 * s, (d - b) / s
    n = math.sqrt(x * x + y * y + z * z + w * w)
    sign = -1.0 if w < 0 else 1.0
    return (sign * x / n, sign * y / n, sign * z / n, sign * w / n)


def rotation(q: Sequence[float]) -> FloatArray:
    """A quaternion (x, y, z, w) to a rotation matrix."""
    x, y, z, w = (float(v) for v in q)
    n = x * x + y * y + z * z + w * w
    s = 2.0 / n if n > 0 else 0.0
    return np.array(
        [
            [1 - s * (y * y + z * z), s * (x * y - z * w), s * (x * z + y * w)],
            [s * (x * y + z * w), 1 - s * (x * x + z * z), s * (y * z - x * w)],
            [s * (x * z - y * w), s * (y * z + x * w), 1 - s * (x * x + y * y)],
        ]
    )


def transform_stamped(
    T_parent_child: ArrayLike, parent: str, child: str, t_s: float, distro: str = DISTRO
) -> Any:
    """A pose (4, 4, mm) as ``geometry_msgs/TransformStamped`` (m): the child in the parent."""
    ty = _cached_types(distro)
    rows = np.asarray(T_parent_child, dtype=np.float64).tolist()
    tx, tyy, tz = rows[0][3] / MM_PER_M, rows[1][3] / MM_PER_M, rows[2][3] / MM_PER_M
    qx, qy, qz, qw = quaternion(rows)
    return ty.TransformStamped(
        header=header(t_s, parent, distro),
        child_frame_id=child,
        transform=ty.Transform(
            translation=ty.Vector3(x=tx, y=tyy, z=tz),
            rotation=ty.Quaternion(x=qx, y=qy, z=qz, w=qw),
        ),
    )


def pose_matrix(transform: Any) -> FloatArray:
    """``geometry_msgs/Transform`` (or a TransformStamped) to a (4, 4) pose in mm."""
    tr = getattr(transform, "transform", transform)
    T = np.eye(4)
    q = tr.rotation
    T[:3, :3] = rotation((q.x, q.y, q.z, q.w))
    T[:3, 3] = np.array((tr.translation.x, tr.translation.y, tr.translation.z)) * MM_PER_M
    return T


def tf_message(
    chain: Iterable[tuple[str, str, ArrayLike]], t_s: float, distro: str = DISTRO
) -> Any:
    """``tf2_msgs/TFMessage`` of (parent, child, T_parent_child) links at ``t_s``."""
    links = [transform_stamped(T, parent, child, t_s, distro) for parent, child, T in chain]
    return _cached_types(distro).TFMessage(transforms=links)


def tf_chain(message: Any) -> list[tuple[str, str, FloatArray]]:
    """The (parent, child, T_parent_child (mm)) links of a ``tf2_msgs/TFMessage``."""
    return [(t.header.frame_id, t.child_frame_id, pose_matrix(t)) for t in message.transforms]


def clock(t_s: float, distro: str = DISTRO) -> Any:
    """``rosgraph_msgs/Clock`` at simulated time ``t_s``."""
    return _cached_types(distro).Clock(clock=stamp(t_s, distro))


def float64(value: float, distro: str = DISTRO) -> Any:
    """``std_msgs/Float64``."""
    return _cached_types(distro).Float64(data=float(value))


# --------------------------------------------------------------------------- profiles
#: The profile's PointCloud2 point layout: x, y, z float64 then the uint8 reason (32 bytes).
POINT_DTYPE = np.dtype(
    {"names": ["x", "y", "z", "reason"], "formats": ["<f8", "<f8", "<f8", "u1"],
     "offsets": [0, 8, 16, 24], "itemsize": 32}
)  # fmt: skip
_FIELDS = (("x", 0, 8), ("y", 8, 8), ("z", 16, 8), ("reason", 24, 2))  # name, offset, datatype

#: PointField datatype codes to numpy types (sensor_msgs/PointField).
FIELD_TYPES = {1: "i1", 2: "u1", 3: "i2", 4: "u2", 5: "i4", 6: "u4", 7: "f4", 8: "f8"}


@functools.cache
def _point_fields(distro: str) -> list[Any]:
    ty = _cached_types(distro)
    return [ty.PointField(name=nm, offset=off, datatype=dt, count=1) for nm, off, dt in _FIELDS]


def profile_cloud(
    profile: Profile, t_s: float | None = None, frame_id: str = FRAMES["sensor"],
    distro: str = DISTRO,
) -> Any:  # fmt: skip
    """A :class:`Profile` as ``sensor_msgs/PointCloud2`` (module docstring); stamped with
    ``t_s`` (default the profile's capture time, 0 when unknown)."""
    ty = _cached_types(distro)
    if t_s is None:
        t_s = profile.t_s if math.isfinite(profile.t_s) else 0.0
    n = len(profile)
    data = np.zeros(n, dtype=POINT_DTYPE)
    data["y"] = profile.points_laser[:, 0] / MM_PER_M
    data["z"] = profile.points_laser[:, 1] / MM_PER_M
    assert profile.reason is not None and profile.valid is not None
    data["reason"] = profile.reason
    fields = _point_fields(distro)  # shared by every cloud, never changed
    return ty.PointCloud2(
        header=header(t_s, frame_id, distro),
        height=1,
        width=n,
        fields=fields,
        is_bigendian=False,
        point_step=POINT_DTYPE.itemsize,
        row_step=POINT_DTYPE.itemsize * n,
        data=data.view(np.uint8),
        is_dense=bool(profile.valid.all()),
    )


def _uint8(data: Any) -> NDArray[np.uint8]:
    """A ``uint8[]`` field as an array (rosbags gives arrays, other decoders bytes)."""
    if isinstance(data, (bytes, bytearray, memoryview)):
        return np.frombuffer(data, dtype=np.uint8)
    return np.asarray(data, dtype=np.uint8)


def cloud_fields(cloud: Any) -> dict[str, NDArray[Any]]:
    """Every scalar field of a ``sensor_msgs/PointCloud2`` as a flat array (row-major over
    height x width), in its own type; any layout, either byte order."""
    order = ">" if cloud.is_bigendian else "<"
    names, formats, offsets = [], [], []
    for f in cloud.fields:
        if f.datatype not in FIELD_TYPES or f.count < 1:
            continue
        names.append(f.name)
        formats.append(order + FIELD_TYPES[f.datatype])
        offsets.append(f.offset)
    dtype = np.dtype(
        {"names": names, "formats": formats, "offsets": offsets, "itemsize": cloud.point_step}
    )
    n = cloud.height * cloud.width
    raw = _uint8(cloud.data)
    if cloud.height > 1 and cloud.row_step != cloud.width * cloud.point_step:
        rows = raw[: cloud.height * cloud.row_step].reshape(cloud.height, cloud.row_step)
        raw = np.ascontiguousarray(rows[:, : cloud.width * cloud.point_step]).ravel()
    if raw.size < n * cloud.point_step:
        raise ValueError(
            f"PointCloud2 holds {raw.size} bytes, {n} points of {cloud.point_step} need more"
        )
    points = np.frombuffer(raw[: n * cloud.point_step].tobytes(), dtype=dtype)
    return {name: points[name] for name in names}


def cloud_profile(
    cloud: Any, axes: tuple[str, str] = ("y", "z"), scale: float = MM_PER_M
) -> Profile:
    """A ``sensor_msgs/PointCloud2`` back to a :class:`Profile` (the laser frame, mm).

    ``axes`` name the fields that hold y_L (across the stripe) and z_L (range), ``scale`` the
    mm per unit of the message (1000: metres). A ``reason`` field gives the per-point codes
    (valid where 0 and finite); without one, the finite points are valid. The capture time
    is the header's stamp; the profile has no pose (``T_world_sensor``: use TF).
    """
    fields = cloud_fields(cloud)
    missing = [a for a in axes if a not in fields]
    if missing:
        raise ValueError(f"the PointCloud2 has no field(s) {missing}; it has {sorted(fields)}")
    points = np.column_stack(
        [np.asarray(fields[a], dtype=np.float64) * scale for a in axes]
    ).reshape(-1, 2)
    reason = fields.get("reason")
    if reason is not None:
        codes = np.asarray(reason).astype(np.uint8)
        return Profile(points, valid=codes == 0, reason=codes, t_s=seconds(cloud.header.stamp))
    return Profile(points, t_s=seconds(cloud.header.stamp))


def cloud_arrays(cloud: Any) -> tuple[FloatArray, NDArray[np.bool_]]:
    """A profile's PointCloud2 as (n, 2) (y_L, z_L) points (mm) and the (n,) valid mask."""
    profile = cloud_profile(cloud)
    assert profile.valid is not None
    return profile.points_laser, profile.valid


# --------------------------------------------------------------------------- seam point, seam
def seam_point(
    feature: Feature, t_s: float, frame_id: str = FRAMES["sensor"], distro: str = DISTRO
) -> Any | None:
    """A found feature's seam point as ``geometry_msgs/PointStamped`` in the sensor frame
    (x = 0, y = y_L, z = z_L; m); None for a frame without a seam point."""
    if not feature:
        return None
    ty = _cached_types(distro)
    y, z = (feature.point_laser / MM_PER_M).tolist()
    return ty.PointStamped(header=header(t_s, frame_id, distro), point=ty.Point(x=0.0, y=y, z=z))


def point_laser(message: Any) -> FloatArray:
    """A ``geometry_msgs/PointStamped`` (or Point) in the sensor frame to (y_L, z_L) in mm."""
    p = getattr(message, "point", message)
    return np.array((p.y, p.z)) * MM_PER_M


def seam_marker(
    points_world: ArrayLike,
    t_s: float = 0.0,
    width_mm: float = 1.0,
    color: tuple[float, float, float, float] = (1.0, 0.6, 0.0, 1.0),
    distro: str = DISTRO,
) -> Any:
    """The seam polyline (world frame, mm) as a ``visualization_msgs/Marker`` LINE_STRIP
    (namespace ``seamtrack``, id 0, in the world frame, no lifetime: it stays)."""
    ty = _cached_types(distro)
    pts = np.asarray(points_world, dtype=np.float64).reshape(-1, 3) / MM_PER_M
    marker_type: Any = ty.ts.types["visualization_msgs/msg/Marker"]
    return default(
        "visualization_msgs/msg/Marker",
        distro,
        header=header(t_s, FRAMES["world"], distro),
        ns="seamtrack",
        id=0,
        type=marker_type.LINE_STRIP,
        action=marker_type.ADD,
        pose=ty.Pose(
            position=ty.Point(x=0.0, y=0.0, z=0.0),
            orientation=ty.Quaternion(x=0.0, y=0.0, z=0.0, w=1.0),
        ),
        scale=ty.Vector3(x=width_mm / MM_PER_M, y=0.0, z=0.0),
        color=ty.ColorRGBA(r=color[0], g=color[1], b=color[2], a=color[3]),
        points=[ty.Point(x=x, y=y, z=z) for x, y, z in pts.tolist()],
    )


def marker_points(marker: Any) -> FloatArray:
    """A Marker's points as (n, 3) in mm."""
    return np.array([(p.x, p.y, p.z) for p in marker.points]).reshape(-1, 3) * MM_PER_M


# --------------------------------------------------------------------------- images
def image_message(
    pixels: ArrayLike, t_s: float, bit_depth: int | None = None,
    frame_id: str = FRAMES["sensor"], distro: str = DISTRO,
) -> Any:  # fmt: skip
    """A camera image (a fraction of full scale per pixel, as :class:`~seamtrack.sensing.
    camera.StripeImage` ``.pixels``) as ``sensor_msgs/Image``: ``mono8`` for a bit depth up to
    8, else ``mono16`` (None: 16); the fraction scaled to the encoding's full range."""
    px = np.clip(np.asarray(pixels, dtype=np.float64), 0.0, 1.0)
    if px.ndim != 2:
        raise ValueError(f"an image has shape (rows, columns), got {px.shape}")
    wide = bit_depth is None or bit_depth > 8
    top, dtype, encoding = (65535, "<u2", "mono16") if wide else (255, "u1", "mono8")
    values = np.rint(px * top).astype(dtype)
    rows, cols = values.shape
    return _cached_types(distro).Image(
        header=header(t_s, frame_id, distro),
        height=rows,
        width=cols,
        encoding=encoding,
        is_bigendian=0,
        step=cols * values.itemsize,
        data=np.ascontiguousarray(values).view(np.uint8).ravel(),
    )


def stripe_image_message(image: Any, t_s: float | None = None, distro: str = DISTRO) -> Any:
    """A :class:`~seamtrack.sensing.camera.StripeImage` as ``sensor_msgs/Image`` (its pixels,
    its camera's bit depth; stamped with ``t_s``, default the image's capture time)."""
    if t_s is None:
        t_s = image.t_s if math.isfinite(image.t_s) else 0.0
    return image_message(image.pixels, t_s, image.camera.bit_depth, distro=distro)


def image_pixels(image: Any) -> NDArray[np.float32]:
    """A ``mono8``/``mono16`` ``sensor_msgs/Image`` back to (rows, columns) fractions of full
    scale."""
    if image.encoding not in ("mono8", "mono16", "8UC1", "16UC1"):
        raise ValueError(f"image encoding {image.encoding!r}; expected mono8 or mono16")
    wide = image.encoding in ("mono16", "16UC1")
    dtype = np.dtype(">u2" if image.is_bigendian else "<u2") if wide else np.dtype("u1")
    raw = _uint8(image.data)[: image.height * image.step]
    rows = raw.reshape(image.height, image.step)[:, : image.width * dtype.itemsize]
    values = np.ascontiguousarray(rows).view(dtype)
    return (values / (65535.0 if wide else 255.0)).astype(np.float32)


# --------------------------------------------------------------------------- one frame
def frame_messages(
    t_s: float,
    profile: Profile,
    feature: Feature,
    chain: Iterable[tuple[str, str, ArrayLike]],
    truth: ArrayLike | None = None,
    image: Any = None,
    distro: str = DISTRO,
) -> list[tuple[str, Any]]:
    """The (topic, message) pairs of one sensor frame, in the order they are sent: ``/clock``,
    ``/tf`` (the (parent, child, T_parent_child) ``chain``), the profile, the seam point (when
    the feature has one), the true seam crossing ``truth`` ((y_L, z_L) mm, when given) and the
    camera image (a StripeImage, when given). :mod:`seamtrack.bridge.record` records these."""
    out = [
        (TOPICS["clock"].name, clock(t_s, distro)),
        (TOPICS["tf"].name, tf_message(chain, t_s, distro)),
        (TOPICS["profile"].name, profile_cloud(profile, t_s, distro=distro)),
    ]
    point = seam_point(feature, t_s, distro=distro)
    if point is not None:
        out.append((TOPICS["seam_point"].name, point))
    if truth is not None:
        label = seam_point(Feature.found(truth), t_s, distro=distro)
        out.append((TOPICS["seam_truth"].name, label))
    if image is not None:
        out.append((TOPICS["image"].name, stripe_image_message(image, t_s, distro)))
    return out
