"""Real scans in, the other way round: PointCloud2 profiles from an MCAP file or a ROS bag.

:func:`read_scans` reads the ``sensor_msgs/PointCloud2`` profiles of one topic from an MCAP
file (``run.mcap``: what ``seamtrack run --record`` writes, or ``ros2 bag record -s mcap``), a
ROS 2 bag folder (``metadata.yaml`` with ``.db3`` or ``.mcap`` files) or a ROS 1 ``.bag``, with
`rosbags <https://ternaris.gitlab.io/rosbags/>`_' reader, and optionally their labels: a
``geometry_msgs/PointStamped`` topic in the profile's frame, matched to the profiles by header
stamp. :func:`write_real_set` writes them in the real-data layout the extractors bench reads
(``set.json``, ``profiles.npz``, ``labels.csv``: docs/extractors.md, "Real data"), and
``seamtrack extractors bench --real run.mcap`` scores the extractors on them directly.

**Which fields.** A line profiler's cloud lies in a plane through its frame's origin: the
field that is zero at every point is across the plane (x for seamtrack's clouds and the
Keyence driver's, y for the scanCONTROL driver's), the other horizontal one the position along
the line (y_L) and ``z`` the range (z_L); give ``axes`` when that guess does not fit. Lengths
are metres in ROS (``scale`` = 1000 mm per unit); a ``reason`` field (seamtrack's, 0 = valid)
marks the valid points, else every finite point is valid.

**Which topics.** The profile topic: ``topic``, else the only PointCloud2 topic, else
``/seamtrack/profile``. The labels: ``labels``, else ``/seamtrack/seam_truth`` (seamtrack's
truth), else the only PointStamped topic other than ``/seamtrack/seam_point`` (that one is the
recorded extractor's own answer, no label), else none. With labels, only the profiles that have
one are kept. A recording of more than :data:`MAX_POINTS` profile points is refused (a run
stays under 2 GB): bench a part of it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.bridge import messages as msgs
from seamtrack.errors import SeamtrackError
from seamtrack.features.classify import FAMILIES
from seamtrack.io.output import staged
from seamtrack.sensing.profiles import Profile

FloatArray = NDArray[np.float64]

CLOUD = "sensor_msgs/msg/PointCloud2"
POINT = "geometry_msgs/msg/PointStamped"
#: The most profile points a recording may give (about 0.9 GB as profiles): a run stays under
#: 2 GB.
MAX_POINTS = 50_000_000


@dataclass(frozen=True)
class Scans:
    """Profiles read from a recording (:func:`read_scans`)."""

    name: str
    profiles: list[Profile]
    labels: FloatArray | None  # (n, 2) (y_L, z_L) mm, one per profile; None without labels
    joint: str | None  # an extractor family, "none", or None when unknown
    meta: dict[str, Any] = field(default_factory=dict)


def _error(message: str, path: Path, fix: str, where: str) -> SeamtrackError:
    return SeamtrackError(f"{path}: {message}", field=where, fix=fix)


def _normal(typename: str) -> str:
    parts = typename.split("/")
    return f"{parts[0]}/msg/{parts[-1]}" if len(parts) == 2 else typename


def _mcap_metadata(path: Path) -> dict[str, str]:
    """The ``seamtrack`` metadata record of an MCAP file ({} when none)."""
    if path.suffix.lower() != ".mcap" or not path.is_file():
        return {}
    from mcap.reader import make_reader

    try:
        with path.open("rb") as fh:
            for record in make_reader(fh).iter_metadata():
                if record.name == "seamtrack":
                    return dict(record.metadata)
    except Exception:  # a damaged summary: the messages may still read
        return {}
    return {}


def _choose(found: dict[str, str], wanted: str | None, typename: str, what: str, path: Path,
            where: str, preferred: tuple[str, ...] = (), skip: tuple[str, ...] = (),
            required: bool = True) -> str | None:  # fmt: skip
    topics = sorted(t for t, ty in found.items() if ty == typename)
    if wanted is not None:
        if wanted not in topics:
            raise _error(
                f"no {typename} topic {wanted!r} (its {typename} topics: {topics or 'none'})",
                path, f"give one of {topics}" if topics else f"record the {what}", where,
            )  # fmt: skip
        return wanted
    for name in preferred:
        if name in topics:
            return name
    candidates = [t for t in topics if t not in skip]
    if len(candidates) == 1:
        return candidates[0]
    if not required:
        return None
    if not candidates:
        raise _error(f"no {typename} topic in it", path, f"record the {what}", where)
    raise _error(
        f"{len(candidates)} {typename} topics: {candidates}", path,
        f"name the {what} topic (--topic)", where,
    )  # fmt: skip


def _axes(fields: dict[str, NDArray[Any]]) -> tuple[str, str]:
    """The (y_L, z_L) fields of a line profile: the horizontal field that is zero everywhere
    is across the laser plane."""

    def flat(name: str) -> bool:
        values = np.asarray(fields[name], dtype=np.float64) if name in fields else None
        return values is not None and bool(np.all((values == 0) | ~np.isfinite(values)))

    if "z" in fields and "y" in fields and (flat("x") or "x" not in fields):
        return ("y", "z")
    if "z" in fields and "x" in fields and flat("y"):
        return ("x", "z")
    raise ValueError(
        "the profile's points do not lie in the plane x = 0 or y = 0 of their frame "
        f"(fields {sorted(fields)})"
    )


def read_scans(
    path: str | Path,
    topic: str | None = None,
    labels: str | None = None,
    *,
    axes: tuple[str, str] | None = None,
    joint: str | None = None,
    scale: float = msgs.MM_PER_M,
    field_name: str = "--real",
) -> Scans:
    """The profiles (and labels) of a recording (module docstring).

    Raises
    ------
    SeamtrackError
        Not a readable recording, no (or several) profile topics, a label topic that is not
        there, clouds that are not line profiles (field ``field_name``, with a fix).
    """
    from rosbags.highlevel import AnyReader

    p = Path(path)
    if not p.exists():
        raise _error("no such file or folder", p, "give an .mcap file or a bag folder", field_name)
    clouds: list[tuple[int, Profile, tuple[str, str]]] = []
    points: dict[int, tuple[float, float, float]] = {}
    total = 0
    try:
        with AnyReader([p], default_typestore=msgs.typestore()) as reader:
            found = {c.topic: _normal(c.msgtype) for c in reader.connections}
            where = field_name if topic is None else "--topic"
            cloud_topic = _choose(found, topic, CLOUD, "profile", p, where,
                                  preferred=(msgs.TOPICS["profile"].name,))  # fmt: skip
            label_topic = _choose(
                found, labels, POINT, "label", p, field_name if labels is None else "--labels",
                preferred=("/seamtrack/seam_truth",), skip=(msgs.TOPICS["seam_point"].name,),
                required=False,
            )  # fmt: skip
            wanted = [c for c in reader.connections if c.topic in (cloud_topic, label_topic)]
            for connection, _, raw in reader.messages(connections=wanted):
                message: Any = reader.deserialize(raw, connection.msgtype)
                ns = message.header.stamp.sec * 1_000_000_000 + message.header.stamp.nanosec
                if connection.topic != cloud_topic:
                    q = message.point
                    points[ns] = (q.x, q.y, q.z)
                    continue
                profile, use = _profile(message, axes, scale, p, field_name)
                total += len(profile)
                if total > MAX_POINTS:
                    raise _error(
                        f"more than {MAX_POINTS:,} profile points on {cloud_topic}", p,
                        "bench a part of it (e.g. mcap filter --start-secs/--end-secs)",
                        field_name,
                    )  # fmt: skip
                clouds.append((ns, profile, use))
    except SeamtrackError:
        raise
    except Exception as exc:  # a damaged or foreign file may fail anywhere in the reader
        raise _error(
            f"not a readable recording ({exc})", p,
            "give an MCAP file or a ROS bag of PointCloud2 profiles (one cut short: mend it "
            "with the MCAP CLI, mcap recover)", field_name,
        ) from None  # fmt: skip
    if not clouds:
        raise _error(f"no messages on {cloud_topic}", p, "record the profiles", field_name)
    profiles, label_rows = [], []
    for ns, profile, use in clouds:
        if label_topic is not None:
            if ns not in points:
                continue
            label = dict(zip("xyz", points[ns], strict=True))
            label_rows.append((label[use[0]] * scale, label[use[1]] * scale))
        profiles.append(profile)
    if not profiles:
        raise _error(
            f"no profile on {cloud_topic} has a label on {label_topic}", p,
            "label the profiles with PointStamped messages of the same stamps", field_name,
        )  # fmt: skip
    meta: dict[str, Any] = {"source": str(p), "topic": cloud_topic, "labels_topic": label_topic}
    meta["profiles_read"] = len(clouds)
    recorded = _mcap_metadata(p)
    if recorded:
        meta["recorded"] = recorded
    # the recording's ``seamtrack`` metadata may name a family extractor as its joint
    if joint is None and recorded.get("extractor") in FAMILIES:
        joint = recorded["extractor"]
    name = p.stem if p.is_file() else p.name
    table = np.array(label_rows, dtype=np.float64).reshape(-1, 2) if label_topic else None
    return Scans(name, profiles, table, joint, meta)


def _profile(
    cloud: Any, axes: tuple[str, str] | None, scale: float, path: Path, field_name: str
) -> tuple[Profile, tuple[str, str]]:
    try:
        use = axes if axes is not None else _axes(msgs.cloud_fields(cloud))
        return msgs.cloud_profile(cloud, axes=use, scale=scale), use
    except ValueError as exc:
        fix = "give the fields that hold y_L and z_L (axes)"
        raise _error(str(exc), path, fix, field_name) from None


def write_real_set(
    scans: Scans, folder: str | Path, joint: str | None = None, replace: bool = False
) -> Path:
    """Write ``scans`` in the extractors bench's real-data layout into ``folder`` (created):
    ``set.json`` (``joint``, default the scans' or ``"none"``; the source and topics as
    metadata), ``profiles.npz`` (``y_mm``, ``z_mm``: (n, m), NaN-padded where profiles are
    shorter, NaN at invalid points) and, with labels, ``labels.csv``. Staged and moved in
    whole; ``replace``: what ``folder`` held is removed first
    (:func:`seamtrack.io.output.check_fresh`)."""
    with staged(folder, replace) as stage:
        _write_set(scans, stage, joint)
    return Path(folder)


def _write_set(scans: Scans, out: Path, joint: str | None) -> None:
    width = max(len(p) for p in scans.profiles)
    y = np.full((len(scans.profiles), width), np.nan)
    z = np.full_like(y, np.nan)
    for i, profile in enumerate(scans.profiles):
        assert profile.valid is not None
        pts = np.where(profile.valid[:, None], profile.points_laser, np.nan)
        y[i, : len(pts)], z[i, : len(pts)] = pts[:, 0], pts[:, 1]
    kind = joint or scans.joint or "none"
    meta = {"joint": kind, **{k: v for k, v in scans.meta.items() if k != "joint"}}
    (out / "set.json").write_text(json.dumps(meta, indent=2, default=str) + "\n")
    np.savez_compressed(out / "profiles.npz", y_mm=y, z_mm=z)
    if scans.labels is not None and kind != "none":
        rows = [f"{i},{a!r},{b!r}" for i, (a, b) in enumerate(scans.labels.tolist())]
        (out / "labels.csv").write_text("index,y_mm,z_mm\n" + "\n".join(rows) + "\n")
