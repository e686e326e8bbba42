"""Countermeasures against the arc (issue 38): blob and streak rejection in the peak detector,
the seam-point gate in time, the tracker's behaviour on an invalid frame, and the one-word
switch that sets them together. Oracles: synthetic images whose stripe row is known, an
ideal render without the arc, and seam points on a known line."""

from __future__ import annotations

import numpy as np
import pytest

from seamtrack.errors import SceneError
from seamtrack.sensing.peaks import Rejection, detect
from seamtrack.simulation.countermeasures import rejection
from seamtrack.simulation.scene import load_scene

# ----------------------------------------------------------------------------- rejection
ROWS, COLUMNS = 128, 64
STRIPE_SIGMA_PX = 1.2


def _stripe_image(seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A Gaussian stripe (sigma 1.2 px, peak 0.3) on a dark, noisy background; its true row in
    each column."""
    rng = np.random.default_rng(seed)
    columns = np.arange(COLUMNS)
    truth = 60.0 + 0.1 * columns + 0.3 * np.sin(columns / 7.0)
    rows = np.arange(ROWS)[:, None]
    image = 0.3 * np.exp(-0.5 * ((rows - truth[None, :]) / STRIPE_SIGMA_PX) ** 2)
    image += 0.01 + 0.002 * rng.standard_normal(image.shape)
    return image.astype(np.float32), truth


def test_a_wide_blob_and_a_saturated_streak_are_rejected_the_stripe_kept() -> None:
    image, truth = _stripe_image()
    rows = np.arange(ROWS)[:, None]
    blob = slice(20, 28)  # the arc's glow or a blob: 7 times the stripe's width, brighter
    image[:, blob] += 0.5 * np.exp(-0.5 * ((rows - 100.0) / (7 * STRIPE_SIGMA_PX)) ** 2)
    streak = slice(40, 43)  # a spatter streak running along the columns, saturated
    image[8:24, streak] = 1.0
    plain = detect(image, threshold=0.05)
    assert np.all(np.abs(plain[blob] - 100.0) < 2)  # without rejection: the blob is chosen
    assert np.all(np.abs(plain[streak] - 15.5) < 1)  # and the streak
    kept = detect(image, threshold=0.05, reject=Rejection())
    np.testing.assert_allclose(kept, truth, atol=0.15)  # the stripe in every column


def test_a_narrow_run_far_brighter_than_the_stripe_is_rejected() -> None:
    image, truth = _stripe_image(1)
    image *= 0.1  # a dim stripe (peak 0.03) ...
    image[30:33, 10] = 1.0  # ... and a droplet seen head-on, 3 px, 30 times brighter
    assert abs(detect(image, threshold=0.01)[10] - 31.0) < 0.5
    rows = detect(image, threshold=0.01, reject=Rejection())
    assert abs(rows[10] - truth[10]) < 0.2
    kept = detect(image, threshold=0.01, reject=Rejection(max_peak=100.0))  # a looser bound
    assert abs(kept[10] - 31.0) < 0.5


def test_a_given_stripe_width_sets_the_bound() -> None:
    image, truth = _stripe_image(2)
    sigma_sqrt_2pi = STRIPE_SIGMA_PX * np.sqrt(2 * np.pi)  # the Gaussian's equivalent width
    rows = detect(image, threshold=0.05, reject=Rejection(stripe_width_px=sigma_sqrt_2pi))
    np.testing.assert_allclose(rows, truth, atol=0.15)
    # A stripe width half the true one over a factor of 1.5: the stripe itself is too wide.
    narrow = Rejection(max_width=1.5, stripe_width_px=0.5 * sigma_sqrt_2pi)
    assert np.isnan(detect(image, threshold=0.05, reject=narrow)).all()


@pytest.mark.embree
@pytest.mark.parametrize(("roll_deg", "method"), [(0.0, "centroid"), (25.0, "gaussian")])
def test_an_ideal_render_without_the_arc_gives_the_same_rows(roll_deg: float, method: str) -> None:
    from seamtrack.bench.camera import plate
    from seamtrack.geometry import frames
    from seamtrack.sensing.camera import Camera
    from seamtrack.sensing.sensor import preset

    sensor = preset("paper")
    T_down = frames.from_xyz_rpy_deg([0.0, 0.0, sensor.range_center_mm], [180.0, 0.0, 0.0])
    image = sensor.render(plate(roll_deg, 0.0), T_down,
                          camera=Camera.ideal(rows=256, columns=512), seed=0)  # fmt: skip
    plain = detect(image.pixels, method=method)
    assert np.isfinite(plain).mean() > 0.9
    np.testing.assert_array_equal(detect(image.pixels, method=method, reject=Rejection()), plain)


def test_the_scene_keys_reach_the_detector() -> None:
    assert rejection(load_scene("v-groove-camera").config) is None
    on = rejection(load_scene("v-groove-camera", {"sensor.camera.reject": "blobs"}).config)
    assert on == Rejection()
    tight = load_scene("v-groove-camera", {"sensor.camera.reject": "blobs",
                                           "sensor.camera.reject_max_width": 2.0,
                                           "sensor.camera.reject_min_peak": 0.2})  # fmt: skip
    assert rejection(tight.config) == Rejection(max_width=2.0, min_peak=0.2)


@pytest.mark.parametrize(
    ("key", "value"),
    [
        ("sensor.camera.reject", "all"),
        ("sensor.camera.reject_max_width", 0.5),
        ("sensor.camera.reject_max_peak", -3.0),
        ("sensor.camera.reject_min_peak", 1.5),
        ("sensor.camera.reject_stripe_width_px", 0.0),
    ],
)
def test_bad_rejection_keys_name_the_field(key: str, value: object) -> None:
    with pytest.raises(SceneError) as info:
        load_scene("v-groove-camera", {key: value})
    assert info.value.field == key, str(info.value)
    assert info.value.fix
