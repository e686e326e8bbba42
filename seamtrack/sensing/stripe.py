"""A mesh-mode stripe before and after the realism knobs: the noiseless stripe's hits
(:class:`StripeHits`, from :func:`seamtrack.sensing.scan.stripe_hits`) and the knobs
(:class:`StripeNoise`: dropout, specular secondary reflections, range noise, speckle and
spurious peaks, each drawn from the run's seeded Generator) applied to them
(:func:`apply_stripe_noise`, called by :func:`seamtrack.sensing.scan.scan_mesh`;
:mod:`seamtrack.datasets.noise` reuses the chip's steps on extruded sections).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Annotated

import numpy as np
from annotated_types import Gt, Le
from numpy.typing import ArrayLike, NDArray

from seamtrack import constants
from seamtrack.params import Fraction, NonNegative
from seamtrack.sensing.profiles import Reason

if TYPE_CHECKING:
    from seamtrack.sensing.raycast import RayCaster
    from seamtrack.sensing.sensor_geometry import SensorGeometry

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class StripeNoise:
    """Seeded realism knobs for mesh-mode profiles; every knob is off (0) by default.

    Applied in this order to the points that survived the geometric clips: dropout, the
    secondary reflection, range noise and speckle, outliers; then the pixel quantization.
    Range noise, speckle and outliers act on the chip coordinate x_c (where the stripe's peak
    is detected), so the triangulated point moves along the camera's line of sight like a real
    sensor's does.

    Attributes
    ----------
    range_sigma_mm : float
        Gaussian peak-detection noise, as its range (z_L) standard deviation at the centre of
        the depth of field. A constant sigma on the chip, it grows with range like the local
        depth resolution: sigma(z) = range_sigma_mm * res(z) / res(z_center).
    speckle_sigma_mm : float
        Laser speckle: the same kind of range error, but correlated along the stripe.
    speckle_correlation_rays : float
        Correlation length of the speckle, in fan rays (Gaussian kernel's standard deviation;
        with ``rays = pixels_v`` that is about one chip pixel per ray).
    dropout_rate : float
        Probability that a point is lost (``Reason.DROPOUT``) at normal incidence. The returned
        light falls as cos(incidence) (a Lambertian surface) and fully developed speckle makes
        the intensity exponential, so a fixed detection threshold loses a point with
        probability p(theta) = 1 - (1 - dropout_rate) ** (1 / cos(theta)).
    secondary_probability : float
        The classic false stripe of grooves: the laser reflects specularly at the lit point,
        lights a second point of the part, and when the camera sees that point the sensor
        triangulates it as if it lay on the laser plane (the camera ray through it, cut by
        x_L = 0). The ray's reported point is replaced by that false point with this
        probability (the peak detector chose the reflection).
    outlier_fraction : float
        Fraction of valid points replaced by a spurious peak (spatter, ambient light): a uniform
        random x_c on the chip at the same lateral column z_c.
    """

    range_sigma_mm: NonNegative = 0.0
    speckle_sigma_mm: NonNegative = 0.0
    speckle_correlation_rays: Annotated[float, Gt(0), Le(1e4)] = 8.0
    dropout_rate: Fraction = 0.0
    secondary_probability: Fraction = 0.0
    outlier_fraction: Fraction = 0.0

    def __post_init__(self) -> None:
        for key in ("range_sigma_mm", "speckle_sigma_mm"):
            if not getattr(self, key) >= 0:
                raise ValueError(f"StripeNoise.{key} must be >= 0")
        if not self.speckle_correlation_rays > 0:
            raise ValueError("StripeNoise.speckle_correlation_rays must be > 0")
        for key in ("dropout_rate", "secondary_probability", "outlier_fraction"):
            if not 0.0 <= getattr(self, key) <= 1.0:
                raise ValueError(f"StripeNoise.{key} must lie in [0, 1]")

    def __bool__(self) -> bool:
        return any(getattr(self, k) > 0 for k in (
            "range_sigma_mm", "speckle_sigma_mm", "dropout_rate", "secondary_probability",
            "outlier_fraction"))  # fmt: skip


@dataclass(frozen=True, eq=False)
class StripeHits:
    """Everything :func:`~seamtrack.sensing.scan.scan_mesh` knows about one stripe before the
    noise models.

    Attributes
    ----------
    points_laser : (n, 2) float
        (y_L, z_L): measured (quantized if the sensor quantizes and no noise is configured) where
        ``reason == 0``; the true lit point where the point was clipped; NaN on a miss.
    reason : (n,) uint8
        :class:`~seamtrack.sensing.profiles.Reason` codes.
    distance_mm : (n,) float
        Emitter to lit point along each ray; NaN on a miss.
    face : (n,) int64
        Triangle lit by each ray; -1 on a miss.
    cos_incidence : (n,) float
        |cos| of the angle between the laser ray and the face normal.
    directions_local : (n, 3) float
        The rays in the caster's local frame (= world directions).
    origin_local : (3,) float
        The emitter in the caster's local frame.
    """

    points_laser: NDArray[np.float64]
    reason: NDArray[np.uint8]
    distance_mm: NDArray[np.float64]
    face: NDArray[np.int64]
    cos_incidence: NDArray[np.float64]
    directions_local: NDArray[np.float64]
    origin_local: NDArray[np.float64]


def apply_stripe_noise(
    sensor: SensorGeometry,
    caster: RayCaster,
    T_world_sensor: NDArray[np.float64],
    hits: StripeHits,
    noise: StripeNoise,
    rng: np.random.Generator,
) -> tuple[NDArray[np.float64], NDArray[np.uint8]]:
    """The knobs of :class:`StripeNoise` on unquantized stripe hits; returns (points, reason)."""
    points = hits.points_laser.copy()
    reason = hits.reason.copy()
    n = len(reason)
    if noise.dropout_rate > 0:
        idx = np.flatnonzero(reason == Reason.VALID)
        p_lost = dropout_probability(noise.dropout_rate, hits.cos_incidence[idx])
        reason[idx[rng.random(len(idx)) < p_lost]] = Reason.DROPOUT
    if noise.secondary_probability > 0:
        false_points, seen = secondary_reflection_points(sensor, caster, T_world_sensor, hits)
        take = seen & (rng.random(n) < noise.secondary_probability)
        points[take] = false_points[take]
        reason[take] = Reason.VALID
    idx = np.flatnonzero(reason == Reason.VALID)
    x_c, z_c = sensor.project(points[idx, 0], points[idx, 1])
    x_c = chip_noise(sensor, noise, x_c, idx, n, rng)
    y, z = sensor.triangulate(x_c, z_c)
    inside = sensor.in_field_of_view(y, z)
    y, z = sensor.measure(y, z)
    points[idx, 0] = y
    points[idx, 1] = z
    reason[idx[~inside]] = Reason.OUT_OF_RANGE
    return points, reason


def chip_noise(
    sensor: SensorGeometry,
    noise: StripeNoise,
    x_c: NDArray[np.float64],
    idx: NDArray[np.intp],
    n: int,
    rng: np.random.Generator,
) -> NDArray[np.float64]:
    """The range noise, speckle and spurious peaks of ``noise`` on the chip rows ``x_c`` (m,)
    (mm) of the valid rays ``idx`` (m,) of an ``n``-ray stripe; returns the new ``x_c``.

    Range noise is white on the chip; its z_L size at the centre of the depth of field is the
    knob, so the chip sigma is that over dz/dx_c there.
    """
    to_chip = sensor.pixel_pitch_mm[0] / float(
        sensor.local_depth_resolution_mm(sensor.range_center_mm)
    )
    if noise.range_sigma_mm > 0:
        x_c = x_c + rng.normal(0.0, noise.range_sigma_mm * to_chip, len(idx))
    if noise.speckle_sigma_mm > 0:
        field = _correlated_normal(n, noise.speckle_correlation_rays, rng)
        x_c = x_c + noise.speckle_sigma_mm * to_chip * field[idx]
    if noise.outlier_fraction > 0:
        spurious = rng.random(len(idx)) < noise.outlier_fraction
        x_c = np.where(spurious, rng.uniform(-0.5, 0.5, len(idx)) * sensor.chip_h_mm, x_c)
    return x_c


def dropout_probability(dropout_rate: float, cos_incidence: ArrayLike) -> NDArray[np.float64]:
    """p(theta) = 1 - (1 - dropout_rate) ** (1 / cos(theta)), see :class:`StripeNoise`.

    Parameters
    ----------
    dropout_rate : float
        Loss probability at normal incidence.
    cos_incidence : (n,) float

    Returns
    -------
    (n,) float
    """
    cos_i = np.clip(np.asarray(cos_incidence, dtype=np.float64), 1e-12, 1.0)
    return np.asarray(-np.expm1(np.log1p(-dropout_rate) / cos_i))


def _correlated_normal(n: int, correlation: float, rng: np.random.Generator) -> FloatArray:
    """(n,) unit-variance Gaussian noise, correlated with a Gaussian kernel of ``correlation``."""
    half = max(1, math.ceil(3.0 * correlation))
    kernel = np.exp(-0.5 * (np.arange(-half, half + 1) / correlation) ** 2)
    kernel /= np.sqrt(np.sum(kernel**2))
    white = rng.standard_normal(n + 2 * half)
    return np.convolve(white, kernel, mode="valid")


def secondary_reflection_points(
    sensor: SensorGeometry,
    caster: RayCaster,
    T_world_sensor: NDArray[np.float64],
    hits: StripeHits,
) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
    """Where the sensor would report each ray's specular secondary reflection.

    The laser ray reflects specularly at its lit point P (r = d - 2 (d.n) n), lights the first
    point Q of the part along r, and if the camera sees Q (Q's lit side faces the camera and the
    line of sight is clear), Q images onto the chip where the laser-plane point
    C + s (Q - C), s = b / (b - x_Q), would: the camera cannot tell them apart.

    Returns
    -------
    points_laser : (n, 2) float
        The false (y_L, z_L); NaN where there is none.
    seen : (n,) bool
        A false point exists and lies in the field of view.
    """
    n = len(hits.reason)
    out = np.full((n, 2), np.nan)
    seen = np.zeros(n, dtype=bool)
    idx = np.flatnonzero(hits.face >= 0)
    if len(idx) == 0:
        return out, seen
    d = hits.directions_local[idx]
    lit_local = hits.origin_local + hits.distance_mm[idx, None] * d
    normal = caster.face_normals[hits.face[idx]]
    reflected = d - 2.0 * np.einsum("ij,ij->i", d, normal)[:, None] * normal
    start = lit_local + caster.local_origin + constants.SHADOW_RAY_OFFSET_MM * reflected
    second = caster.first_hit(start, reflected)
    camera = T_world_sensor[:3, :3] @ sensor.camera_center_laser + T_world_sensor[:3, 3]
    to_camera = camera - second.points
    faces_camera = np.einsum("ij,ij->i", second.normals, to_camera) > 0
    candidate = np.flatnonzero(second.hit & faces_camera)
    visible = ~caster.line_of_sight_blocked(second.points[candidate], camera)
    candidate = candidate[visible]
    q = (second.points[candidate] - T_world_sensor[:3, 3]) @ T_world_sensor[:3, :3]
    b = sensor.baseline_mm
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = b / (b - q[:, 0])
    y, z = scale * q[:, 1], scale * q[:, 2]
    ok = (scale > 0) & sensor.in_field_of_view(y, z)
    rows = idx[candidate[ok]]
    out[rows, 0] = y[ok]
    out[rows, 1] = z[ok]
    seen[rows] = True
    return out, seen
