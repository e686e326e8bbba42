"""The camera bench's parts and oracles, shared by its sections (:mod:`seamtrack.bench.camera`,
:mod:`~seamtrack.bench.camera_exposure`, :mod:`~seamtrack.bench.camera_speckle`): a plate, the
laser pointing down at it, and the laser line's rows on a plane in closed form."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from seamtrack.geometry import frames
from seamtrack.sensing.camera import StripeImage
from seamtrack.sensing.sensor import preset

SENSOR = preset("paper")


def plate(roll_deg: float = 0.0, pitch_deg: float = 0.0, size: float = 300.0) -> Any:
    """A square plate through the world origin, turned about world x then y."""
    import trimesh

    corners = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float) * 0.5 * size
    mesh = trimesh.Trimesh(corners, [[0, 1, 2], [0, 2, 3]], process=False)
    mesh.apply_transform(frames.from_xyz_rpy_deg([0, 0, 0], [roll_deg, pitch_deg, 0]))
    return mesh


def down(range_mm: float | None = None) -> np.ndarray:
    """The laser pointing down at the world origin from ``range_mm`` (default range centre)."""
    z = SENSOR.range_center_mm if range_mm is None else range_mm
    return frames.from_xyz_rpy_deg([0.0, 0.0, z], [180.0, 0.0, 0.0])


def plane_rows(image: StripeImage, normal_world: np.ndarray) -> np.ndarray:
    """Per column, the row of the laser plane's line on the plane through the world origin with
    this normal: closed form from Eq. 2-3 and the plane equation."""
    sensor, T = image.sensor, image.T_world_sensor
    assert T is not None
    n = np.asarray(normal_world) @ T[:3, :3]
    k = float(n @ (T[:3, :3].T @ -T[:3, 3]))
    _, z_c = image.chip_coordinates(np.zeros(image.shape[1]), np.arange(image.shape[1]))
    b, lam = sensor.baseline_mm, sensor.focal_length_mm
    s, c = math.sin(sensor.angle_rad), math.cos(sensor.angle_rad)
    z = (k - n[1] * z_c * b * s / lam) / (n[1] * z_c * c / lam + n[2])
    y = z_c * (z * c + b * s) / lam
    x_c, _ = sensor.project(y, z)
    return (x_c + 0.5 * sensor.chip_h_mm) / sensor.pixel_pitch_mm[0] - 0.5 - image.window[0]
