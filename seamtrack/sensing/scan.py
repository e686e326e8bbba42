"""Sensing: what the posed sensor measures.

Seam mode (the paper's model, Sec. 2.4 and Fig. 4): the laser plane of the posed sensor crosses
the seam polyline; the crossing inside the field of view and depth of field is the measurement,
pixel-quantized and optionally noisy. No mesh, no ray casting.

Mesh mode (:func:`scan_mesh`): a fan of rays from the laser emitter in the laser plane hits the
part's mesh (Embree, refined in float64: :mod:`seamtrack.sensing.raycast`); each lit point is kept
when
it lies in the trapezoidal field of view and depth of field, is lit at an incidence the sensor
can measure, and the camera sees it (a shadow ray from the point to the camera centre); the
survivors are projected onto the chip and pixel-quantized (Eq. 1-3). Realism knobs
(:class:`StripeNoise`) are off by default. Embree, numba and trimesh are imported on first use,
so seam-mode scenes never load them.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack import constants
from seamtrack.geometry.frames import invert
from seamtrack.geometry.seam import Seam
from seamtrack.sensing.profiles import Feature, Profile, laser_to_world
from seamtrack.sensing.stripe import (  # the stripe's types and knobs, re-exported as before
    StripeHits as StripeHits,
)
from seamtrack.sensing.stripe import StripeNoise as StripeNoise
from seamtrack.sensing.stripe import apply_stripe_noise
from seamtrack.sensing.stripe import chip_noise as chip_noise
from seamtrack.sensing.stripe import dropout_probability as dropout_probability
from seamtrack.sensing.stripe import (
    secondary_reflection_points as secondary_reflection_points,
)

if TYPE_CHECKING:
    from seamtrack.sensing.raycast import RayCaster
    from seamtrack.sensing.sensor_geometry import SensorGeometry

FloatArray = NDArray[np.float64]

#: How a mesh-mode fan is cast (``sensor.fan``): ``"embree"`` (Embree's float32 hits, refined in
#: float64 unless ``refine=False``), ``"section"`` (the laser plane's section of the mesh, exact
#: in float64: :mod:`seamtrack.sensing.section`), ``"auto"`` (:func:`auto_fan`).
FANS = ("embree", "section", "auto")


def auto_fan(rays: int, n_faces: int, refine: bool = True) -> str:
    """The fan ``"auto"`` casts: the plane section where it is the faster, else Embree.

    The section's cost per profile grows with the triangles the plane crosses (about the
    square root of the mesh's count on a part meshed evenly) and little with the rays; the
    Embree fan's grows with the rays. Measured (``docs/mesh-mode.md``): the section is faster
    from about sqrt(triangles) rays up (1024 rays: every part up to ~1M triangles; 256 rays:
    up to ~60k; 64 rays: Embree). ``refine=False`` asks for Embree's float32 hits: Embree.
    """
    if not refine:
        return "embree"
    return "section" if rays * rays >= n_faces else "embree"


@dataclass(frozen=True)
class SeamNoise:
    """Seeded Gaussian noise on a seam-mode measurement (off when both sigmas are 0).

    Attributes
    ----------
    range_sigma_mm : float
        Standard deviation along z_L (range).
    lateral_sigma_mm : float
        Standard deviation along y_L.
    """

    range_sigma_mm: float = 0.0
    lateral_sigma_mm: float = 0.0

    def __bool__(self) -> bool:
        return self.range_sigma_mm > 0 or self.lateral_sigma_mm > 0


def laser_plane_crossings(seam: Seam, T_world_sensor: ArrayLike) -> FloatArray:
    """All crossings of the laser plane x_L = 0 with the seam polyline, in the laser frame.

    Returns
    -------
    crossings : (k, 2) float
        (y_L, z_L) of each crossing, in seam order. A segment lying in the plane contributes
        its end points.
    """
    T_sensor_world = invert(T_world_sensor)
    p = seam.points @ np.ascontiguousarray(T_sensor_world[:3, :3].T) + T_sensor_world[:3, 3]
    x = p[:, 0]
    x0, x1 = x[:-1], x[1:]
    # Half-open test: a vertex exactly on the plane belongs to the segment that starts there,
    # so a polyline through the plane at a vertex is found once, not twice.
    crossing = ((x0 <= 0) & (x1 > 0)) | ((x0 >= 0) & (x1 < 0))
    last_on_plane = x1[-1:] == 0
    idx = np.flatnonzero(crossing)
    t = x0[idx] / (x0[idx] - x1[idx])
    pts = p[idx] + t[:, None] * (p[idx + 1] - p[idx])
    if last_on_plane.any():
        pts = np.vstack([pts, p[-1:]])
    return pts[:, 1:3]


def sense_seam(
    seam: Seam,
    T_world_sensor: ArrayLike,
    sensor: SensorGeometry,
    noise: SeamNoise | None = None,
    rng: np.random.Generator | None = None,
) -> Feature:
    """The paper's seam finding: the seam point the sensor reports at this pose.

    The crossing of the laser plane with the seam that lies in the field of view (nearest the
    centre of the stripe when there are several) is measured: noise is added (if configured)
    and the result is quantized to the sensor's pixels (if ``sensor.quantize``).

    Returns
    -------
    Feature
        Falsy with a reason when the plane does not cross the seam in the field of view.
    """
    crossings = laser_plane_crossings(seam, T_world_sensor)
    if len(crossings) == 0:
        return Feature.failed("the laser plane does not cross the seam", joint="seam")
    y, z = crossings[:, 0], crossings[:, 1]
    inside = sensor.in_field_of_view(y, z)
    if not inside.any():
        return Feature.failed(
            "the seam crossing is outside the field of view / depth of field", joint="seam"
        )
    candidates = np.flatnonzero(inside)
    best = candidates[np.argmin(np.abs(y[candidates]))]
    y_true, z_true = float(y[best]), float(z[best])
    if noise:
        if rng is None:
            raise ValueError("sense_seam: noise needs a seeded numpy Generator (rng)")
        y_true += rng.normal(0.0, noise.lateral_sigma_mm)
        z_true += rng.normal(0.0, noise.range_sigma_mm)
        if not sensor.in_field_of_view(y_true, z_true):
            return Feature.failed(
                "the noisy measurement fell outside the field of view", joint="seam"
            )
    y_m, z_m = sensor.measure(y_true, z_true)
    point = np.array([float(y_m), float(z_m)])
    return Feature(
        point_laser=point,
        point_world=laser_to_world(T_world_sensor, point),
        confidence=1.0,
        joint="seam",
    )


# =========================================================================== mesh mode
@dataclass(frozen=True, eq=False)
class FanRays:
    """The laser fan of a sensor: unit directions in the laser frame, x_L = 0.

    Attributes
    ----------
    directions : (n, 3) float
        (0, sin phi, cos phi), evenly spaced in tan(phi) = y_L / z_L (like the chip's columns)
        over the widest opening of the field-of-view trapezoid (its near end).
    sensor_params : (10,) float
        The sensor as the stripe kernels take it (see :mod:`seamtrack.sensing.raycast`).
    """

    directions: NDArray[np.float64]
    sensor_params: NDArray[np.float64]

    @functools.cached_property
    def section_tans(self) -> tuple[NDArray[np.float64], float, float]:
        """The fan as the plane section takes it, once (``section.fan_tans``)."""
        from seamtrack.sensing.section import fan_tans

        return fan_tans(self.directions)


@functools.lru_cache(maxsize=32)
def laser_fan(sensor: SensorGeometry, rays: int) -> FanRays:
    """The fan of ``rays`` rays spanning the sensor's field of view (cached per sensor)."""
    if rays < 1:
        raise ValueError(f"a laser fan needs at least one ray, got {rays}")
    near = sensor.range_near_mm
    tan_max = float(sensor.half_width_mm(near)) / near
    tan_phi = np.linspace(-tan_max, tan_max, rays) if rays > 1 else np.zeros(1)
    norm = np.sqrt(1.0 + tan_phi**2)
    directions = np.column_stack([np.zeros(rays), tan_phi / norm, 1.0 / norm])
    directions.flags.writeable = False
    params = np.array([
        sensor.baseline_mm, sensor.focal_length_mm, math.sin(sensor.angle_rad),
        math.cos(sensor.angle_rad), sensor.chip_h_mm, sensor.chip_v_mm, sensor.pixels_h,
        sensor.pixels_v, 1.0 + constants.CHIP_EDGE_RTOL, math.cos(sensor.max_incidence_rad),
    ], dtype=np.float64)  # fmt: skip
    params.flags.writeable = False
    return FanRays(directions=directions, sensor_params=params)


def ray_caster(part: Any) -> RayCaster:
    """The (cached) :class:`~seamtrack.sensing.raycast.RayCaster` of a part.

    ``part`` is a prepared ``RayCaster``, a ``trimesh.Trimesh``, or anything with a ``.mesh``
    (a :class:`~seamtrack.workpiece.loader.Workpiece`).
    """
    from seamtrack.sensing.raycast import RayCaster

    if isinstance(part, RayCaster):
        return part
    mesh = getattr(part, "mesh", part)
    if not (hasattr(mesh, "vertices") and hasattr(mesh, "faces")):
        raise TypeError(
            f"cannot scan a {type(part).__name__}: give a trimesh.Trimesh, an "
            "object with a .mesh, or a seamtrack.sensing.raycast.RayCaster"
        )
    return RayCaster.for_mesh(mesh)


def stripe_hits(
    sensor: SensorGeometry,
    caster: RayCaster,
    T_world_sensor: NDArray[np.float64],
    rays: int,
    *,
    refine: bool = True,
    quantize: bool | None = None,
    fan: str = "auto",
) -> StripeHits:
    """The noiseless stripe: fan -> first hits in float64 -> clips -> shadow rays -> pixels.

    The first hits come from Embree refined in float64 (``fan="embree"``) or from the laser
    plane's section of the mesh (``fan="section"``, exact in float64; ``"auto"`` chooses, see
    :func:`auto_fan`). The clips are tested in order (a point gets the first reason that applies):
    MISS, OUT_OF_RANGE (trapezoid and depth of field), INCIDENCE, OCCLUDED (the camera is behind
    the lit face or a shadow ray to the camera centre meets the part). Shadow rays (on Embree)
    are cast only for points that passed the cheaper clips.
    """
    from seamtrack.sensing import kernels

    if fan not in FANS:
        raise ValueError(f"fan must be one of {FANS}, got {fan!r}")
    laser = laser_fan(sensor, rays)
    T = np.asarray(T_world_sensor, dtype=np.float64)
    rotation = np.ascontiguousarray(T[:3, :3])
    origin = T[:3, 3] - caster.local_origin
    do_quantize = bool(sensor.quantize if quantize is None else quantize)
    if fan == "auto":
        fan = auto_fan(rays, caster.n_faces, refine)
    if fan == "section":
        return _section_stripe(caster, laser, rotation, origin, do_quantize)
    packets = caster.packets
    if packets is not None:  # one numba call does it all
        points, reason, t, face, cos_incidence, directions = kernels.fan_stripe_packets(
            packets.lib.intersect8, packets.lib.occluded_query, packets.lib.occluded_width,
            packets.handle, origin, rotation, laser.directions, caster.hit_mesh(bool(refine)),
            bool(refine), constants.BARYCENTRIC_TOL, laser.sensor_params,
            constants.SHADOW_RAY_OFFSET_MM, do_quantize,
        )  # fmt: skip
        return StripeHits(points_laser=points, reason=reason, distance_mm=t, face=face,
                          cos_incidence=cos_incidence, directions_local=directions,
                          origin_local=origin)  # fmt: skip
    directions = laser.directions @ rotation.T
    prim, tfar = caster.cast_local(origin[None], directions)
    t_hit, face_hit, _ = caster.refine_local(origin[None], directions, prim, tfar, refine=refine)
    points, reason, t, face, cos_incidence, chip, shadow_o, shadow_d, shadow_far, shadow_index = (
        kernels.fan_stripe_hits(
            origin, rotation, laser.directions, directions, t_hit, face_hit, caster.face_normals,
            laser.sensor_params, constants.SHADOW_RAY_OFFSET_MM,
        )
    )  # fmt: skip
    blocked = caster.occluded_local(shadow_o, shadow_d, shadow_far)
    kernels.fan_stripe_finish(points, reason, chip, blocked, shadow_index, laser.sensor_params,
                              do_quantize)  # fmt: skip
    return StripeHits(points_laser=points, reason=reason, distance_mm=t, face=face,
                      cos_incidence=cos_incidence, directions_local=directions,
                      origin_local=origin)  # fmt: skip


def _section_args(caster: RayCaster, fan: FanRays) -> tuple[tuple[Any, ...], ...]:
    """What the section's kernels take of a caster and a fan that stays the same from frame
    to frame (before and after the pose; the packets' query), gathered once per fan."""
    args = caster.section_args.get(fan)
    if args is None:
        head = (caster.section, caster.section_mesh)
        tail = (fan.directions, *fan.section_tans, fan.sensor_params,
                constants.SHADOW_RAY_OFFSET_MM)  # fmt: skip
        packets = caster.packets
        query = () if packets is None else (
            packets.lib.occluded_query, packets.lib.occluded_width, packets.handle
        )  # fmt: skip
        args = caster.section_args[fan] = (head, tail, query)
    return args


def _section_stripe(
    caster: RayCaster,
    fan: FanRays,
    rotation: NDArray[np.float64],
    origin: NDArray[np.float64],
    quantize: bool,
) -> StripeHits:
    """:func:`stripe_hits` through the plane section (:mod:`seamtrack.sensing.section`)."""
    from seamtrack.sensing import section

    head, tail, query = _section_args(caster, fan)
    # The last stripe's triangles are cut first (at a frame rate, most of this one's; only
    # after a section large enough to cull): the hierarchy's walk culls behind their hits
    # once it culls. The same hits whatever the seeds (tests/test_section.py).
    seeds = caster.section_seeds
    if query:  # one numba call does it all
        points, reason, t, face, cos_incidence, directions, caster.section_seeds = (
            section.fan_stripe_section_packets(  # type: ignore[call-arg]  # gathered args
                *query, *head, origin, rotation, *tail, quantize, seeds
            )
        )
    else:
        from seamtrack.sensing.kernels import fan_stripe_finish

        (
            points,
            reason,
            t,
            face,
            cos_incidence,
            chip,
            s_o,
            s_d,
            s_far,
            s_index,
            directions,
            caster.section_seeds,
        ) = section.fan_stripe_section(*head, origin, rotation, *tail, seeds)  # type: ignore[call-arg]
        blocked = caster.occluded_local(s_o, s_d, s_far)
        fan_stripe_finish(points, reason, chip, blocked, s_index, fan.sensor_params, quantize)
    return StripeHits(points_laser=points, reason=reason, distance_mm=t, face=face,
                      cos_incidence=cos_incidence, directions_local=directions,
                      origin_local=origin)  # fmt: skip


def scan_mesh(
    sensor: SensorGeometry,
    part: Any,
    T_world_sensor: ArrayLike,
    *,
    rays: int | None = None,
    refine: bool = True,
    noise: StripeNoise | None = None,
    rng: np.random.Generator | None = None,
    t_s: float = float("nan"),
    fan: str = "auto",
) -> Profile:
    """One stripe profile of a meshed part, as the posed sensor reports it.

    Parameters
    ----------
    sensor : SensorGeometry
    part : trimesh.Trimesh, object with ``.mesh``, or RayCaster
        The part, in the world frame. Its Embree scene is built once per mesh and cached.
    T_world_sensor : (4, 4) float
        Pose of the laser frame.
    rays : int, optional
        Rays in the fan (default ``sensor.pixels_v``, one per chip column).
    refine : bool
        Recompute every hit in float64 (default). False keeps Embree's float32 hits (error
        ~1e-5 mm near the local origin, see docs/readme-raycast.md).
    noise : StripeNoise, optional
        Realism knobs; needs ``rng``.
    rng : numpy.random.Generator, optional
    t_s : float
        Capture time stamped on the profile.
    fan : {"auto", "section", "embree"}
        How the fan's first hits are found (:data:`FANS`): the laser plane's section of the
        mesh, exact in float64, or Embree; ``"auto"``: the faster (:func:`auto_fan`).

    Returns
    -------
    Profile
        One point per ray, in fan order (y_L increasing); ``reason`` says why each invalid point
        was lost. Invalid points hold the true lit point (NaN on a miss).
    """
    if noise and rng is None:
        raise ValueError("scan_mesh: noise needs a seeded numpy Generator (rng)")
    caster = ray_caster(part)
    T = np.asarray(T_world_sensor, dtype=np.float64)
    if T.shape != (4, 4):
        raise ValueError(f"T_world_sensor must be (4, 4), got {T.shape}")
    n = sensor.pixels_v if rays is None else int(rays)
    noisy = bool(noise)
    hits = stripe_hits(sensor, caster, T, n, refine=refine, quantize=False if noisy else None,
                       fan=fan)  # fmt: skip
    points, reason = hits.points_laser, hits.reason
    if noisy:
        assert noise is not None and rng is not None
        points, reason = apply_stripe_noise(sensor, caster, T, hits, noise, rng)
    # stripe_hits (and the noise models) leave valid points exactly where reason == VALID, and
    # those finite: the checks of Profile() are not needed on this per-frame path.
    return Profile._trusted(points, reason, T, t_s)
