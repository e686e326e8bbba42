"""The v-groove extractor under a false reflection: a stray line over a bevel's root end hides
where the bevel ends; the end is put at the depth of the other root end below the plates."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seamtrack.features.extractors import extractor
from seamtrack.features.synthetic import Imperfections, ray_angles, synthetic_profile
from seamtrack.sensing.profiles import Profile
from seamtrack.sensing.sensor import preset

SENSOR = preset("paper")
DETECTED_MM = 0.5
OUTLIERS_AND_REFLECTION = Imperfections(
    noise_mm=0.05, outlier_fraction=0.05, reflection_probability=1.0
)


def _stripe(profile, truth, y0_mm, y1_mm, dz_mm, slope):
    """The profile with the columns aimed at y in [y0, y1] (at the seam's range) replaced by a
    straight false stripe, as the synthetic reflection draws it: anchored on the lit column
    nearest the first (the first may look into the gap), ``dz_mm`` off the surface along z_L
    (> 0: behind it), ``slope`` = dz/dy."""
    phi = ray_angles(SENSOR, len(profile.points_laser))
    zs = float(truth.seam_laser[1])
    cols = np.flatnonzero((zs * np.tan(phi) >= y0_mm) & (zs * np.tan(phi) <= y1_mm))
    points, valid = profile.points_laser.copy(), profile.valid.copy()
    lit = np.flatnonzero(valid)
    y_a, z_a = points[lit[np.argmin(np.abs(lit - cols[0]))]]
    z_a += dz_mm
    t = (z_a - slope * y_a) / (np.cos(phi[cols]) - slope * np.sin(phi[cols]))
    points[cols] = np.column_stack([t * np.sin(phi[cols]), t * np.cos(phi[cols])])
    valid[cols] = True
    return Profile(points, valid=valid, T_world_sensor=profile.T_world_sensor)


def _error(feature, truth):
    return float(np.hypot(*(feature.point_laser - truth.seam_laser)))


# The root corners lie 0.5 mm either side of the seam (gap 1 mm). A stripe from 0.2 to 1.0 mm
# covers a part of the gap, the corner and the bevel's lowest ~0.5 mm.
COVERS = {"left root": (-1.0, -0.2), "right root": (0.2, 1.0), "left, wide": (-1.6, 0.1)}


@pytest.mark.parametrize(("roll_deg", "pitch_deg"), [(0.0, 0.0), (-12.0, 8.0), (15.0, 15.0)])
@pytest.mark.parametrize("covered", sorted(COVERS))
@pytest.mark.parametrize(("dz_mm", "slope"), [(2.0, 0.3), (-2.0, -0.5), (-1.5, 0.8)])
def test_root_end_under_a_reflection_is_put_at_the_other_ends_depth(
    covered, roll_deg, pitch_deg, dz_mm, slope
):
    """Noise-free: the hidden root corner is found again to the sensor's resolution (the
    bevel's line and the other corner's depth are exact); confidence is halved. Before, the
    bevel ended where the stripe began: 0.37-1.95 mm off."""
    clean, truth = synthetic_profile("v-groove", SENSOR, roll_deg=roll_deg, pitch_deg=pitch_deg)
    sure = extractor("v-groove")(clean)
    y0, y1 = COVERS[covered]
    ys = float(truth.seam_laser[0])
    feature = extractor("v-groove")(_stripe(clean, truth, ys + y0, ys + y1, dz_mm, slope))
    assert feature and _error(feature, truth) <= 0.02
    assert feature.confidence <= 0.5 * sure.confidence + 1e-9


@pytest.mark.parametrize(("dz_mm", "slope"), [(2.0, 0.3), (-2.0, -0.5), (3.0, 0.0)])
def test_reflection_in_the_gap_changes_nothing(dz_mm, slope):
    """A stripe over the middle of the gap covers no bevel: both root corners are seen."""
    clean, truth = synthetic_profile("v-groove", SENSOR, roll_deg=10.0, pitch_deg=-5.0)
    sure = extractor("v-groove")(clean)
    ys = float(truth.seam_laser[0])
    feature = extractor("v-groove")(_stripe(clean, truth, ys - 0.3, ys + 0.3, dz_mm, slope))
    assert feature and _error(feature, truth) <= 0.01
    assert feature.confidence == pytest.approx(sure.confidence, abs=0.02)


@pytest.mark.parametrize("misalignment_mm", [-1.0, 1.5])
def test_hidden_root_end_with_high_low_plates(misalignment_mm):
    """Each root corner lies at one depth below its own plate: a high-low joint keeps it."""
    clean, truth = synthetic_profile(
        "v-groove", SENSOR, roll_deg=-6.0, pitch_deg=4.0, misalignment_mm=misalignment_mm
    )
    ys = float(truth.seam_laser[0])
    feature = extractor("v-groove")(_stripe(clean, truth, ys + 0.2, ys + 1.0, -2.0, 0.3))
    assert feature and _error(feature, truth) <= 0.02


def test_gapless_v_with_a_reflection_at_the_apex():
    clean, truth = synthetic_profile("v-groove", SENSOR, roll_deg=8.0, gap_mm=0.0, root_face_mm=0.0)
    ys = float(truth.seam_laser[0])
    feature = extractor("v-groove")(_stripe(clean, truth, ys + 0.05, ys + 0.8, 2.0, 0.2))
    assert feature and _error(feature, truth) <= 0.05


def _campaign(imperfections, n, seed, rays=None):
    rng = np.random.default_rng(seed)
    ex = extractor("v-groove")
    errors = []
    for _ in range(n):
        profile, truth = synthetic_profile(
            "v-groove",
            SENSOR,
            rng=rng,
            imperfections=imperfections,
            pitch_deg=rng.uniform(-15, 15),
            roll_deg=rng.uniform(-15, 15),
            lateral_offset_mm=rng.uniform(-3, 3),
            **({} if rays is None else {"rays": rays}),
        )
        f = ex(profile)
        errors.append(_error(f, truth) if f else math.inf)
    return np.array(errors)


@pytest.mark.parametrize(("seed", "rays"), [(12, None), (21, 1024)])
def test_v_groove_with_outliers_and_a_reflection_detects_98_percent(seed, rays):
    """Must-show 2 with a margin: 95 % was the bar, the extractor sat at 95.0 % in the bench
    (every miss a root end under the reflection)."""
    errors = _campaign(OUTLIERS_AND_REFLECTION, 200, seed, rays)
    assert np.mean(errors <= DETECTED_MM) >= 0.98
    assert np.percentile(errors[np.isfinite(errors)], 95) <= 0.1
