"""Drawing one labelled sample from a spec, and a chunk of them.

Sample ``i`` of a dataset draws from its own generator,
``Generator(PCG64(SeedSequence(seed, spawn_key=(i,))))``, which is
``SeedSequence(seed).spawn(n)[i]``: a sample's bytes depend on the spec, the seed and ``i``
only, never on which worker made it or in which order. Each sample draws, in this order, one
uniform number per choice and per range (:data:`UNIFORMS`), then whatever its noise knobs need.

The profile is the mesh-mode stripe of the sample's joint (:mod:`seamtrack.datasets.kernel`); the
noise knobs are the mesh-mode model with its geometry in numba (:mod:`seamtrack.datasets.noise`).
With ``images``, the camera image of the same joint and pose follows
(:mod:`seamtrack.datasets.images`), from a generator of its own.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seamtrack import constants
from seamtrack.datasets import joints
from seamtrack.datasets.kernel import stripe
from seamtrack.datasets.noise import apply_noise
from seamtrack.datasets.spec import FAMILIES, DatasetSpec
from seamtrack.features import synthetic_groove
from seamtrack.sensing.profiles import Reason
from seamtrack.sensing.scan import StripeNoise, laser_fan
from seamtrack.sensing.sensor import LaserLineSensor, preset

FloatArray = NDArray[np.float64]

#: The spec's ranges drawn for every sample, in draw order, by section.
_DRAWN = (
    ("joint", ("thickness_mm", "groove_angle_deg", "root_face_mm", "gap_mm", "misalignment_mm",
               "web_angle_deg", "corner_angle_deg", "sheet_thickness_mm", "sheet_gap_mm",
               "tack_probability", "tack_height_mm", "tack_width_mm")),
    ("path", ("position_mm",)),
    ("sensor", ("standoff_offset_mm", "lateral_offset_mm", "tilt_deg", "roll_deg", "yaw_deg")),
    ("noise", ("range_sigma_mm", "speckle_sigma_mm", "speckle_correlation_rays", "dropout_rate",
               "secondary_probability", "outlier_fraction")),
)  # fmt: skip


def _stored(section: str, key: str) -> tuple[str, str, str, float]:
    """(section, key, stored name, scale) of a drawn range: an angle is drawn in degrees (the
    spec's unit, ``*_deg``) and stored in radians (``*_rad``), the rest as drawn."""
    if key.endswith("_deg"):
        return section, key, key.removesuffix("_deg") + "_rad", math.pi / 180
    return section, key, key, 1.0


#: Ranges of the spec drawn for every sample, in draw order: (section, key, stored name, scale).
RANGES: tuple[tuple[str, str, str, float], ...] = tuple(
    _stored(section, key) for section, keys in _DRAWN for key in keys
)
#: Choices drawn before the ranges: family, path, material, preset, and the tack's coin.
CHOICES = ("family", "path", "material", "preset", "tack")
UNIFORMS = len(CHOICES) + len(RANGES)

#: Stored per sample in ``params``: every drawn range, then the stand-off (range of the seam
#: point, mm) that the offset gives. A parameter the sample's family does not use is NaN.
PARAM_NAMES = (*(r[2] for r in RANGES), "standoff_mm")
_INDEX = {name: i for i, name in enumerate(PARAM_NAMES)}
_KEYS = tuple(r[1] for r in RANGES)
_USES = {
    "square-butt": {"thickness_mm", "gap_mm", "misalignment_mm"},
    "v-groove": {"thickness_mm", "groove_angle_rad", "root_face_mm", "gap_mm", "misalignment_mm"},
    "fillet": {"web_angle_rad"},
    "lap": {"sheet_thickness_mm", "sheet_gap_mm"},
    "outside-corner": {"corner_angle_rad"},
    "flat": set(),
}
_NOISE_KEYS = dict(_DRAWN)["noise"]

#: Seam frame {S} in the world of a straight seam along +X from the origin, with the part below
#: the torch (world +Z up): x_S = +X, z_S = -Z (into the part), y_S = z_S x x_S = -Y.
_R_WORLD_SEAM = np.diag([1.0, -1.0, -1.0])


def sample_generator(seed: int, index: int) -> np.random.Generator:
    """The generator of sample ``index``: ``SeedSequence(seed).spawn(index + 1)[index]``."""
    return np.random.Generator(np.random.PCG64(np.random.SeedSequence(seed, spawn_key=(index,))))


@functools.lru_cache(maxsize=16)
def _sensor(name: str, quantize: bool) -> LaserLineSensor:
    return preset(name, quantize=quantize)


def pose(
    standoff_mm: float, lateral_offset_mm: float, tilt_rad: float, roll_rad: float, yaw_rad: float
) -> FloatArray:
    """(4, 4) ``T_seam_sensor``: the laser frame in the seam frame.

    With all angles 0 the laser axes are the seam frame's (the laser plane x_L = 0 is normal to
    the seam, z_L points into the part) and the seam point sits at
    ``(y_L, z_L) = (lateral_offset_mm, standoff_mm)``. The sensor then turns about the seam
    point: ``R = Rx(roll) Ry(tilt) Rz(yaw)`` (roll about the seam, tilt leaning along it, yaw
    about the laser axis), so the seam point stays at that laser-plane position.
    """
    cr, sr = math.cos(roll_rad), math.sin(roll_rad)
    ct, st = math.cos(tilt_rad), math.sin(tilt_rad)
    cy, sy = math.cos(yaw_rad), math.sin(yaw_rad)
    # Rx(roll) @ Ry(tilt) @ Rz(yaw), written out (this runs once per sample).
    r = (
        (ct * cy, -ct * sy, st),
        (sr * st * cy + cr * sy, -sr * st * sy + cr * cy, -sr * ct),
        (-cr * st * cy + sr * sy, cr * st * sy + sr * cy, cr * ct),
    )
    oy, oz = -lateral_offset_mm, -standoff_mm
    return np.array([
        [r[0][0], r[0][1], r[0][2], r[0][1] * oy + r[0][2] * oz],
        [r[1][0], r[1][1], r[1][2], r[1][1] * oy + r[1][2] * oz],
        [r[2][0], r[2][1], r[2][2], r[2][1] * oy + r[2][2] * oz],
        [0.0, 0.0, 0.0, 1.0],
    ])  # fmt: skip


def lines_in_laser_plane(T_seam_sensor: FloatArray, yz: FloatArray) -> FloatArray:
    """(m, 2) laser-plane points (y_L, z_L) where the seam-parallel lines through the seam-frame
    points ``yz`` (m, 2) cross the laser plane x_L = 0."""
    R, o = T_seam_sensor[:3, :3], T_seam_sensor[:3, 3]
    p = np.column_stack([np.zeros(len(yz)), yz]) - o
    p[:, 0] -= (p @ R[:, 0]) / R[0, 0]
    return np.asarray((p @ R)[:, 1:])


@dataclass(frozen=True, eq=False)
class Plan:
    """What every sample of a spec shares, worked out once per chunk.

    Attributes
    ----------
    spec : DatasetSpec
    low, span : (len(RANGES),) float
        Each range's min and max - min, in the spec's units.
    cumulative : (families,) float
        Cumulative family weights, normalized to end at 1.
    """

    spec: DatasetSpec
    low: FloatArray
    span: FloatArray
    cumulative: FloatArray

    @classmethod
    def of(cls, spec: DatasetSpec) -> Plan:
        bounds = np.array([getattr(getattr(spec, sec), key) for sec, key, _, _ in RANGES])
        weights = np.array(spec.joint.weights or [1.0] * len(spec.joint.families))
        cumulative = np.cumsum(weights) / weights.sum()
        return cls(spec, bounds[:, 0], bounds[:, 1] - bounds[:, 0], cumulative)


@dataclass(frozen=True)
class Drawn:
    """What one sample drew: the choices (indices into the spec's lists) and every range's
    value in the spec's units, keyed by the spec's key."""

    family: str
    path: int
    material: int
    preset: int
    tack: bool
    values: dict[str, float]


def _pick(u: float, count: int) -> int:
    return min(int(u * count), count - 1)


def draw(plan: Plan, rng: np.random.Generator) -> Drawn:
    """Draw one sample's choices and ranges (:data:`UNIFORMS` uniforms, in a fixed order)."""
    spec = plan.spec
    u = rng.random(UNIFORMS)
    values = dict(zip(_KEYS, (plan.low + u[len(CHOICES) :] * plan.span).tolist(), strict=True))
    family = min(int(np.searchsorted(plan.cumulative, u[0], side="right")),
                 len(spec.joint.families) - 1)  # fmt: skip
    return Drawn(
        family=spec.joint.families[family],
        path=_pick(u[1], len(spec.path.kinds)),
        material=_pick(u[2], len(spec.part.materials)),
        preset=_pick(u[3], len(spec.sensor.presets)),
        tack=bool(u[4] < values["tack_probability"]),
        values=values,
    )


def empty_chunk(spec: DatasetSpec, count: int) -> dict[str, np.ndarray]:
    """The arrays of ``count`` samples (see the README's dataset table), NaN / zero filled;
    with ``spec.images`` those of :func:`seamtrack.datasets.images.empty_images` too."""
    rays = spec.rays
    arrays = {
        "points_laser": np.full((count, rays, 2), np.nan),
        "valid": np.zeros((count, rays), dtype=bool),
        "reason": np.zeros((count, rays), dtype=np.uint8),
        "seam_point_laser": np.full((count, 2), np.nan),
        "features_laser": np.full((count, joints.MAX_FEATURES, 2), np.nan),
        "joint": np.zeros(count, dtype=np.uint8),
        "path": np.zeros(count, dtype=np.uint8),
        "material": np.zeros(count, dtype=np.uint8),
        "preset": np.zeros(count, dtype=np.uint8),
        "tack": np.zeros(count, dtype=bool),
        "params": np.full((count, len(PARAM_NAMES)), np.nan),
        "T_seam_sensor": np.zeros((count, 4, 4)),
        "T_world_seam": np.zeros((count, 4, 4)),
        "index": np.zeros(count, dtype=np.int64),
    }
    if spec.joint.passes[1] > 0:
        arrays["groove_points_laser"] = np.full((count, 7, 2), np.nan)
        arrays["layers"] = np.zeros(count, dtype=np.uint8)
    if spec.images:
        from seamtrack.datasets.images import empty_images

        arrays.update(empty_images(spec, count))
    return arrays


def fill_sample(plan: Plan, index: int, out: dict[str, np.ndarray], row: int) -> None:
    """Draw sample ``index`` and write it into row ``row`` of the chunk arrays ``out``."""
    spec = plan.spec
    rng = sample_generator(spec.seed, index)
    d = draw(plan, rng)
    v = d.values
    sensor = _sensor(spec.sensor.presets[d.preset], spec.sensor.quantize)
    deg = math.pi / 180
    lap = d.family == "lap"
    polylines, seam, features = joints.section(
        d.family,
        thickness_mm=v["sheet_thickness_mm"] if lap else v["thickness_mm"],
        groove_angle_rad=v["groove_angle_deg"] * deg,
        root_face_mm=v["root_face_mm"],
        gap_mm=v["sheet_gap_mm"] if lap else v["gap_mm"],
        misalignment_mm=v["misalignment_mm"],
        web_angle_rad=v["web_angle_deg"] * deg,
        corner_angle_rad=v["corner_angle_deg"] * deg,
    )
    groove7 = None
    if d.family == "v-groove" and spec.joint.passes[1] > 0:
        polylines, groove7, layers = _beads(spec, polylines, features, rng)
        out["layers"][row] = layers
    tack = d.tack and seam is not None
    if tack:
        assert seam is not None
        polylines = [*polylines, joints.tack_mound(seam, v["tack_height_mm"], v["tack_width_mm"])]
    shift = seam if seam is not None else (0.0, 0.0)
    segs = joints.segments(polylines, shift)
    standoff = sensor.range_center_mm + v["standoff_offset_mm"]
    T = pose(standoff, v["lateral_offset_mm"], v["tilt_deg"] * deg, v["roll_deg"] * deg,
             v["yaw_deg"] * deg)  # fmt: skip
    fan = laser_fan(sensor, spec.rays)
    noise_values = {k: v[k] for k in _NOISE_KEYS}
    noisy = any(noise_values[k] > 0 for k in _NOISE_KEYS if k != "speckle_correlation_rays")
    points, reason, t, face, cos_incidence, directions = stripe(
        np.ascontiguousarray(T[:3, 3]), np.ascontiguousarray(T[:3, :3]), fan.directions, segs,
        fan.sensor_params, constants.SHADOW_RAY_OFFSET_MM, bool(sensor.quantize and not noisy),
    )  # fmt: skip
    if noisy:
        hits = (points, reason, t, face, cos_incidence, directions)
        points, reason = apply_noise(sensor, segs, T, hits, StripeNoise(**noise_values), rng)
    out["points_laser"][row] = points
    out["reason"][row] = reason
    out["valid"][row] = reason == Reason.VALID
    if seam is not None:
        sy, sz = shift
        moved = [(0.0, 0.0)] + [(y - sy, z - sz) for y, z in features]
        on_plane = lines_in_laser_plane(T, np.array(moved))
        out["seam_point_laser"][row] = on_plane[0]
        out["features_laser"][row, : len(features)] = on_plane[1:]
        if groove7 is not None:
            moved7 = [(y - sy, z - sz) for y, z in groove7]
            out["groove_points_laser"][row] = lines_in_laser_plane(T, np.array(moved7))
    out["joint"][row] = FAMILIES.index(d.family)
    out["path"][row] = d.path
    out["material"][row] = d.material
    out["preset"][row] = d.preset
    out["tack"][row] = tack
    params = out["params"][row]
    uses = _USES[d.family]
    for section, key, name, scale in RANGES:
        if section != "joint" or name in uses or (tack and name.startswith("tack")):
            params[_INDEX[name]] = v[key] * scale
    params[_INDEX["tack_probability"]] = v["tack_probability"]
    params[_INDEX["standoff_mm"]] = standoff
    out["T_seam_sensor"][row] = T
    T_world_seam = np.eye(4)
    T_world_seam[:3, :3] = _R_WORLD_SEAM
    T_world_seam[0, 3] = v["position_mm"]
    out["T_world_seam"][row] = T_world_seam
    out["index"][row] = index
    if spec.images:
        from seamtrack.datasets.images import fill_image

        fill_image(spec, index, sensor, spec.part.materials[d.material], segs, T, out, row)


def _beads(
    spec: DatasetSpec,
    polylines: list[list[tuple[float, float]]],
    features: list[tuple[float, float]],
    rng: np.random.Generator,
) -> tuple[list[list[tuple[float, float]]], list[tuple[float, float]], int]:
    """Lay a drawn number of layers of beads in a V-groove section (joint frame, z into the
    part): the new section, the groove's 7 points and the layers. The root gap is closed by
    the root pass (the two plates' chains joined at their bottoms)."""
    lo, hi = spec.joint.passes
    layers = int(rng.integers(int(math.ceil(lo)), int(math.floor(hi)) + 1))
    area = float(rng.uniform(*spec.joint.bead_area_mm2))
    left, right = polylines
    station = np.array([(y, -z) for y, z in [*left, *right]])
    top = np.array([(y, -z) for y, z in features[:2]])
    foot = np.array([(y, -z) for y, z in features[2:4]])
    if layers == 0:  # the empty groove: the bottom points span the root opening
        g = synthetic_groove.Groove("v", station, top, foot, {})
        s = np.array([(y, -z) for y, z in [*left[:-1], *right[1:]]])
        pts = synthetic_groove.groove_points(g, s)
        return polylines, [(float(y), float(-z)) for y, z in pts], 0
    g = synthetic_groove.Groove("v", station, top, foot, {})
    s = synthetic_groove.fill(g, layers, bead_area_mm2=area, rng=rng, jitter_mm=0.3)[0]
    pts = synthetic_groove.groove_points(g, s)
    section = [[(float(y), float(-z)) for y, z in s]]
    return section, [(float(y), float(-z)) for y, z in pts], layers


def generate(spec: DatasetSpec, start: int, count: int) -> dict[str, np.ndarray]:
    """Samples ``start .. start + count - 1`` as arrays (first axis: the sample)."""
    out = empty_chunk(spec, count)
    plan = Plan.of(spec)
    for row in range(count):
        fill_sample(plan, start + row, out, row)
    return out
