"""Exposure control and the relative detector threshold (issue 27.1): the default camera and
detector find the stripe on a matte plate at every tilt to 70 deg (against the analytic plane
section), keep a bright aluminium plate's stripe under saturation, auto-exposure converges, the
multi-exposure merge never saturates a column one of its exposures kept, bad values refused."""

from __future__ import annotations

import numpy as np
import pytest

from seamtrack.bench.camera import GRID
from seamtrack.bench.camera_exposure import (
    SENSOR,
    down,
    exposure_tilt,
    mirror_tilt_deg,
    plate,
    stripe_errors,
)
from seamtrack.errors import SensorGeometryError
from seamtrack.geometry import frames
from seamtrack.sensing.camera import Camera
from seamtrack.sensing.peaks import column_thresholds, detect

pytestmark = pytest.mark.embree

#: Without speckle the range error is the chip's (shot, read noise, 10 bits): a few um.
CHIP_TOLERANCE_MM = 0.02
#: With speckle (f/8, the default 0.2 mm line on the full chip) the centroid's error is the
#: speckle's, p95 about 0.25-0.4 mm over these tilts (issue 27.2 studies its size).
SPECKLE_TOLERANCE_MM = 0.5


def _normal(axis: str, tilt: float) -> np.ndarray:
    roll, pitch = (tilt, 0.0) if axis == "roll" else (0.0, tilt)
    return frames.from_xyz_rpy_deg([0, 0, 0], [roll, pitch, 0])[:3, 2]


@pytest.mark.parametrize("axis", ["roll", "pitch"])
@pytest.mark.parametrize("tilt", [0.0, 35.0, 55.0, 70.0])
def test_default_detector_finds_the_matte_stripe_at_every_tilt(axis, tilt) -> None:
    roll, pitch = (tilt, 0.0) if axis == "roll" else (0.0, tilt)
    # The default camera without speckle: every stripe column found, on the analytic plane.
    image = SENSOR.render(plate(roll, pitch), down(), camera=Camera(speckle=False),
                          material="mill-scale steel", seed=1)  # fmt: skip
    error = stripe_errors(image, detect(image.pixels), _normal(axis, tilt))
    assert np.isfinite(error).all()
    assert np.percentile(error, 95) <= CHIP_TOLERANCE_MM
    # The old absolute threshold 0.1 loses the dim stripe at the steep tilts (the test can fail).
    if tilt >= 55.0:
        old = stripe_errors(image, detect(image.pixels, threshold=0.1), _normal(axis, tilt))
        assert np.mean(np.isfinite(old)) < 0.5


@pytest.mark.parametrize("tilt", [0.0, 70.0])
def test_default_camera_with_speckle_finds_the_stripe(tilt) -> None:
    row = exposure_tilt("pitch", tilt, "mill-scale steel")
    assert row["found"] >= 0.99 and row["p95_error_mm"] <= SPECKLE_TOLERANCE_MM


def test_aluminium_at_its_mirror_angle_stays_below_saturation() -> None:
    # Pitched by half the triangulation angle, the plate mirrors the laser into the camera.
    row = exposure_tilt("pitch", mirror_tilt_deg(), "bright aluminium")
    assert row["fixed_saturated"] > 0.05  # a single exposure saturates the stripe
    assert row["saturated"] <= 0.05 and row["found"] >= 0.99


def test_auto_exposure_converges_on_its_target() -> None:
    # The signal is linear in the exposure: from a saturated first frame the peak reaches its
    # target within a few frames (ideal camera: the peak is the light, no noise).
    cam = Camera.ideal(**GRID, exposure_mode="auto", target_peak=0.6)
    part, pose = plate(0.0, mirror_tilt_deg()), down()
    exposure, peaks = cam.exposure, []
    for _ in range(8):
        image = SENSOR.render(part, pose, camera=cam, material="bright aluminium",
                              exposure=exposure)  # fmt: skip
        assert image.exposure == pytest.approx(exposure)
        peaks.append(image.peak)
        exposure = cam.next_exposure(image.exposure, image.peak)
    assert peaks[0] >= 1.0  # saturated at the fixed exposure
    on_target = [abs(p - 0.6) <= 0.02 for p in peaks]
    assert on_target.index(True) <= 5 and all(on_target[on_target.index(True) :])


def test_multi_exposure_never_saturates_a_column_one_exposure_kept() -> None:
    # No speckle, shot or read noise: each exposure's readout is a deterministic scaling of the
    # same light (a fixed-exposure render draws its speckle anew), so the merge can be compared
    # column by column with fixed exposures.
    fields = dict(GRID, speckle=False, shot_noise=False, read_noise_e=0.0)
    part, pose = plate(0.0, mirror_tilt_deg()), down()
    multi_cam = Camera(**fields)
    merged = SENSOR.render(part, pose, camera=multi_cam, material="bright aluminium", seed=3)
    singles = []
    for factor in multi_cam.exposure_set:
        cam = Camera(**fields, exposure_mode="fixed", exposure=0.5 * factor)
        singles.append(SENSOR.render(part, pose, camera=cam, material="bright aluminium",
                                     seed=3).pixels)  # fmt: skip
    kept = np.array([p.max(axis=0) < 1.0 for p in singles])  # (exposures, columns)
    assert kept.any(axis=0).sum() > kept[0].sum()  # the shorter exposures keep more columns
    merged_ok = merged.pixels.max(axis=0) < 1.0
    assert merged_ok[kept.any(axis=0)].all()
    longest = np.argmax(kept, axis=0)  # the longest exposure that kept each column
    for col in np.flatnonzero(kept.any(axis=0))[::37]:
        np.testing.assert_allclose(merged.pixels[:, col], singles[longest[col]][:, col],
                                   atol=1.5 / 1023)  # fmt: skip


def test_relative_threshold_finds_none_in_a_column_of_noise() -> None:
    rng = np.random.default_rng(0)
    image = 0.01 + 0.002 * rng.standard_normal((200, 50))
    image[100, :25] += 0.05  # a dim stripe in half the columns
    rows = detect(image.astype(np.float32))
    assert np.isfinite(rows[:25]).all() and np.isnan(rows[25:]).all()
    assert (column_thresholds(image)[25:] > image[:, 25:].max(axis=0)).all()


@pytest.mark.parametrize(
    ("fields", "field"),
    [
        ({"exposure_mode": "hdr"}, "sensor.camera.exposure_mode"),
        ({"target_peak": 1.5}, "sensor.camera.target_peak"),
        ({"target_peak": 0.0}, "sensor.camera.target_peak"),
        ({"exposure_set": ()}, "sensor.camera.exposure_set"),
        ({"exposure_set": (1.0, 2.0)}, "sensor.camera.exposure_set"),
        ({"exposure_set": (0.5, 0.1)}, "sensor.camera.exposure_set"),
        ({"exposure_set": (1.0, 0.1, 0.2)}, "sensor.camera.exposure_set"),
        ({"exposure_set": (1.0, float("nan"))}, "sensor.camera.exposure_set"),
    ],
)
def test_bad_exposure_values_name_the_field(fields, field) -> None:
    with pytest.raises(SensorGeometryError) as info:
        Camera(**fields)
    assert info.value.field == field and info.value.fix


def test_bad_detector_values_are_refused() -> None:
    image = np.zeros((10, 4), dtype=np.float32)
    for kwargs in ({"relative": 1.0}, {"relative": -0.1}, {"noise_sigmas": -1.0}):
        with pytest.raises(ValueError):
            detect(image, **kwargs)
