"""The dataset's fast noise knobs are the mesh-mode model: the same result as
:func:`seamtrack.sensing.stripe.apply_stripe_noise` on the same stripe with the same
generator, the mesh-mode function seeing the extruded section through a stand-in for its ray
caster."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from numpy.typing import NDArray

from seamtrack import constants
from seamtrack.datasets import joints
from seamtrack.datasets.generate import pose
from seamtrack.datasets.kernel import first_hits, stripe
from seamtrack.datasets.noise import apply_noise
from seamtrack.sensing.scan import StripeHits, StripeNoise, laser_fan
from seamtrack.sensing.sensor import preset
from seamtrack.sensing.stripe import apply_stripe_noise

FloatArray = NDArray[np.float64]


class ExtrudedSection:  # the ray caster of the mesh-mode noise model, for an extrusion
    """The extruded section seen through the parts of a ray caster the noise models use
    (``face_normals``, ``local_origin``, ``first_hit``, ``line_of_sight_blocked``).

    Parameters
    ----------
    segs : (k, 4) float
        ``(y0, z0, y1, z1)`` in the seam frame (here the world frame of the profile).
    """

    def __init__(self, segs: FloatArray):
        self.segs = segs
        e = segs[:, 2:] - segs[:, :2]
        length = np.hypot(e[:, 0], e[:, 1])
        self.face_normals = (
            np.column_stack([np.zeros(len(segs)), -e[:, 1], e[:, 0]]) / length[:, None]
        )
        self.local_origin = np.zeros(3)

    def first_hit(self, origins: FloatArray, directions: FloatArray) -> SimpleNamespace:
        """First hits; ``normals`` turned to face the ray origin (as the ray caster's)."""
        o = np.ascontiguousarray(origins, dtype=np.float64).reshape(-1, 3)
        d = np.ascontiguousarray(directions, dtype=np.float64).reshape(-1, 3)
        t, seg = first_hits(o, d, self.segs, np.full(len(o), np.inf))
        hit = seg >= 0
        points = np.where(hit[:, None], o + np.where(hit, t, 0.0)[:, None] * d, np.nan)
        normals = self.face_normals[np.where(hit, seg, 0)]
        normals = np.where((np.einsum("ij,ij->i", normals, d) > 0)[:, None], -normals, normals)
        return SimpleNamespace(hit=hit, points=points, normals=np.where(hit[:, None], normals,
                                                                         np.nan))  # fmt: skip

    def line_of_sight_blocked(
        self, points: FloatArray, target: FloatArray, *,
        offset_mm: float = constants.SHADOW_RAY_OFFSET_MM,
    ) -> NDArray[np.bool_]:  # fmt: skip
        """True where the segment from a point to ``target`` (3,) crosses the section."""
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        to_target = np.asarray(target, dtype=np.float64).reshape(3) - p
        length = np.linalg.norm(to_target, axis=1)
        d = to_target / length[:, None]
        start = np.ascontiguousarray(p + offset_mm * d)
        _, seg = first_hits(start, np.ascontiguousarray(d), self.segs,
                            np.maximum(length - offset_mm, 0.0))  # fmt: skip
        return np.asarray(seg >= 0)


KNOBS = [
    StripeNoise(range_sigma_mm=0.02),
    StripeNoise(speckle_sigma_mm=0.02, speckle_correlation_rays=5.0),
    StripeNoise(dropout_rate=0.3),
    StripeNoise(secondary_probability=0.8),
    StripeNoise(outlier_fraction=0.1),
    StripeNoise(
        range_sigma_mm=0.01,
        speckle_sigma_mm=0.01,
        dropout_rate=0.05,
        secondary_probability=0.3,
        outlier_fraction=0.02,
    ),
]


@pytest.mark.parametrize("quantize", [True, False])
@pytest.mark.parametrize("noise", KNOBS, ids=repr)
@pytest.mark.parametrize("family", ["v-groove", "fillet", "lap"])
def test_fast_noise_is_the_mesh_mode_model(family: str, noise: StripeNoise, quantize: bool):
    sensor = preset("paper", quantize=quantize)
    params = {"thickness_mm": 8.0, "groove_angle_rad": math.radians(70.0), "root_face_mm": 1.0,
              "gap_mm": 1.0, "misalignment_mm": 0.3, "web_angle_rad": math.radians(90.0),
              "corner_angle_rad": 1.5}  # fmt: skip
    polylines, seam, _ = joints.section(family, **params)
    assert seam is not None
    segs = joints.segments(polylines, seam)
    T = pose(sensor.range_center_mm + 5.0, 1.0, math.radians(6.0), math.radians(-9.0), 0.05)
    fan = laser_fan(sensor, 1024)
    hits = stripe(T[:3, 3].copy(), T[:3, :3].copy(), fan.directions, segs, fan.sensor_params,
                  constants.SHADOW_RAY_OFFSET_MM, False)  # fmt: skip
    points, reason = apply_noise(sensor, segs, T, hits, noise, np.random.default_rng(7))
    p, r, t, face, cos_incidence, directions = hits
    as_mesh = StripeHits(points_laser=p, reason=r, distance_mm=t, face=face,
                         cos_incidence=cos_incidence, directions_local=directions,
                         origin_local=T[:3, 3].copy())  # fmt: skip
    ref_points, ref_reason = apply_stripe_noise(sensor, ExtrudedSection(segs), T, as_mesh, noise,
                                                 np.random.default_rng(7))  # fmt: skip
    same = reason == ref_reason
    assert same.mean() >= 0.998
    valid = (reason == 0) & (ref_reason == 0)
    gap = np.abs(points[valid] - ref_points[valid]).max(axis=1)
    assert np.mean(gap < 1e-9) >= 0.998  # a pixel boundary may fall either way, rarely
    assert gap.max() < 0.05
    if noise.secondary_probability > 0:
        assert (reason == 0).sum() > 0
