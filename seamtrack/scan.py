"""Sensing: what the posed sensor measures.

Seam mode (the paper's model, Sec. 2.4 and Fig. 4): the laser plane of the posed sensor crosses
the seam polyline; the crossing inside the field of view and depth of field is the measurement,
pixel-quantized and optionally noisy. No mesh, no ray casting.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .frames import invert
from .profiles import Feature, laser_to_world
from .seam import Seam
from .sensor import LaserLineSensor

FloatArray = NDArray[np.float64]


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
    p = seam.points @ T_sensor_world[:3, :3].T + T_sensor_world[:3, 3]
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
    sensor: LaserLineSensor,
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
        return Feature.failed("the seam crossing is outside the field of view / depth of field",
                              joint="seam")
    candidates = np.flatnonzero(inside)
    best = candidates[np.argmin(np.abs(y[candidates]))]
    y_true, z_true = float(y[best]), float(z[best])
    if noise:
        if rng is None:
            raise ValueError("sense_seam: noise needs a seeded numpy Generator (rng)")
        y_true += rng.normal(0.0, noise.lateral_sigma_mm)
        z_true += rng.normal(0.0, noise.range_sigma_mm)
        if not sensor.in_field_of_view(y_true, z_true):
            return Feature.failed("the noisy measurement fell outside the field of view",
                                  joint="seam")
    y_m, z_m = sensor.measure(y_true, z_true)
    point = np.array([float(y_m), float(z_m)])
    return Feature(point_laser=point, point_world=laser_to_world(T_world_sensor, point),
                   confidence=1.0, joint="seam")
