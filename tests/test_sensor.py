"""The sensor model against hand-derived values of Eq. 1-8 and their inverses."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from seamtrack.errors import SensorGeometryError
from seamtrack.sensing.sensor import LaserLineSensor, preset

# A round-number sensor for hand computation: b = 50, lambda = 10, theta = 30 deg,
# H = 4, V = 6, 1000 x 500 pixels.
HAND = dict(
    baseline_mm=50.0,
    angle_rad=math.radians(30.0),
    focal_length_mm=10.0,
    chip_h_mm=4.0,
    chip_v_mm=6.0,
    pixels_h=1000,
    pixels_v=500,
)


def test_eq4_to_eq8_match_hand_derived_values() -> None:
    s = LaserLineSensor(**HAND)
    sin, cos = 0.5, math.sqrt(3) / 2
    # Eq. 4: D = 4 b lambda H / (4 lambda^2 sin^2 - H^2 cos^2) = 8000 / (100 - 12) = 90.909...
    assert s.depth_of_field_mm == pytest.approx(
        4 * 50 * 10 * 4 / (4 * 100 * sin**2 - 16 * cos**2), rel=1e-14
    )
    assert s.depth_of_field_mm == pytest.approx(8000 / 88, rel=1e-14)
    # Eq. 5, 6: F = 2 b V / (2 lambda sin -+ H cos)
    assert s.fov_far_mm == pytest.approx(600 / (10 - 4 * cos), rel=1e-14)
    assert s.fov_near_mm == pytest.approx(600 / (10 + 4 * cos), rel=1e-14)
    # Eq. 7, 8
    assert s.depth_resolution_mm == pytest.approx(8000 / 88 / 1000, rel=1e-14)
    near, far = s.lateral_resolution_range_mm
    assert near == pytest.approx(s.fov_near_mm / 500) and far == pytest.approx(s.fov_far_mm / 500)
    # The depth of field is the difference of the range limits (Eq. 3 at x_c = -+H/2).
    assert s.range_far_mm - s.range_near_mm == pytest.approx(s.depth_of_field_mm, rel=1e-12)
    # The optical axis (x_c = 0) meets the laser at b / tan(theta).
    assert s.triangulate(0.0, 0.0)[1] == pytest.approx(50 / math.tan(math.radians(30)))


def test_eq2_eq3_hand_point() -> None:
    s = LaserLineSensor(**HAND)
    # x_c = 1, z_c = 2: den = cos30 + 10 sin30 = 5.866; y = 100/den; z = 50 (10 cos - sin)/den
    den = math.cos(math.radians(30)) + 5.0
    y, z = s.triangulate(1.0, 2.0)
    assert y == pytest.approx(100 / den, rel=1e-14)
    assert z == pytest.approx(50 * (10 * math.cos(math.radians(30)) - 0.5) / den, rel=1e-14)


def test_table3_through_eq4_to_eq6(paper_sensor: LaserLineSensor) -> None:
    assert paper_sensor.depth_of_field_mm == pytest.approx(60.0, rel=1e-12)
    assert paper_sensor.fov_near_mm == pytest.approx(18.0, rel=1e-12)
    assert paper_sensor.fov_far_mm == pytest.approx(32.0, rel=1e-12)
    assert paper_sensor.depth_resolution_mm == pytest.approx(0.01, rel=1e-12)
    assert paper_sensor.lateral_resolution_mm == pytest.approx(0.01, rel=1e-12)
    assert math.degrees(paper_sensor.angle_rad) == pytest.approx(16.17, rel=1e-12)


@pytest.mark.parametrize("focal", [8.0, 16.0, 50.0])
@pytest.mark.parametrize(
    "specs",
    [
        dict(
            depth_of_field_mm=60,
            fov_near_mm=18,
            fov_far_mm=32,
            angle_deg=16.17,
            depth_resolution_mm=0.01,
            lateral_resolution_mm=0.01,
        ),
        dict(
            depth_of_field_mm=100,
            fov_near_mm=40,
            fov_far_mm=80,
            angle_deg=25,
            depth_resolution_mm=0.05,
            lateral_resolution_mm=0.05,
        ),
        dict(
            depth_of_field_mm=5,
            fov_near_mm=10,
            fov_far_mm=10.5,
            angle_deg=60,
            depth_resolution_mm=0.001,
            lateral_resolution_mm=0.00205,
        ),
    ],
)
def test_from_specs_round_trips(specs: dict[str, float], focal: float) -> None:
    s = LaserLineSensor.from_specs(focal_length_mm=focal, **specs)
    back = s.specs()
    for key, value in specs.items():
        assert back[key] == pytest.approx(value, rel=1e-9), key


def test_from_specs_rounds_pixels_up_when_not_whole() -> None:
    s = LaserLineSensor.from_specs(
        depth_of_field_mm=60,
        fov_near_mm=18,
        fov_far_mm=32,
        angle_deg=16.17,
        depth_resolution_mm=0.007,
        lateral_resolution_mm=0.01,
    )
    assert s.pixels_h == math.ceil(60 / 0.007)
    assert s.depth_resolution_mm <= 0.007


def test_triangulate_project_round_trip_over_the_whole_chip(paper_sensor: LaserLineSensor) -> None:
    h, v = paper_sensor.chip_h_mm, paper_sensor.chip_v_mm
    xc, zc = np.meshgrid(np.linspace(-h / 2, h / 2, 301), np.linspace(-v / 2, v / 2, 201))
    y, z = paper_sensor.triangulate(xc, zc)
    xc2, zc2 = paper_sensor.project(y, z)
    assert np.max(np.abs(xc2 - xc)) < 1e-12 and np.max(np.abs(zc2 - zc)) < 1e-12
    assert paper_sensor.in_field_of_view(y, z).all()
    # The chip's image is the trapezoid: z in [near, far], |y| <= half width at z.
    assert z.min() == pytest.approx(paper_sensor.range_near_mm)
    assert z.max() == pytest.approx(paper_sensor.range_far_mm)
    assert np.all(np.abs(y) <= paper_sensor.half_width_mm(z) * (1 + 1e-12))


def test_field_of_view_is_the_trapezoid(paper_sensor: LaserLineSensor) -> None:
    s = paper_sensor
    z_mid = 0.5 * (s.range_near_mm + s.range_far_mm)
    w = float(s.half_width_mm(z_mid))
    assert s.in_field_of_view(0.999 * w, z_mid) and not s.in_field_of_view(1.001 * w, z_mid)
    assert not s.in_field_of_view(0.0, s.range_near_mm - 1e-6)
    assert not s.in_field_of_view(0.0, s.range_far_mm + 1e-6)
    assert s.half_width_mm(s.range_near_mm) * 2 == pytest.approx(s.fov_near_mm)
    assert s.half_width_mm(s.range_far_mm) * 2 == pytest.approx(s.fov_far_mm)


def test_local_resolution_is_the_pixel_step_and_averages_to_eq7(
    paper_sensor: LaserLineSensor,
) -> None:
    s = paper_sensor
    pitch_h, pitch_v = s.pixel_pitch_mm
    xc = np.linspace(-s.chip_h_mm / 2, s.chip_h_mm / 2 - pitch_h, 500)
    z0 = s.triangulate(xc, 0.0)[1]
    z1 = s.triangulate(xc + pitch_h, 0.0)[1]
    mid = s.triangulate(xc + pitch_h / 2, 0.0)[1]
    assert np.allclose(np.abs(z1 - z0), s.local_depth_resolution_mm(mid), rtol=1e-6)
    # Near is finer than far; across the range they average to Eq. 7's D / N_H.
    assert s.local_depth_resolution_mm(s.range_near_mm) < s.depth_resolution_mm
    assert s.local_depth_resolution_mm(s.range_far_mm) > s.depth_resolution_mm
    assert s.local_lateral_resolution_mm(s.range_near_mm) == pytest.approx(
        s.lateral_resolution_range_mm[0]
    )
    assert s.local_lateral_resolution_mm(s.range_far_mm) == pytest.approx(
        s.lateral_resolution_range_mm[1]
    )
    dz_c = float(np.diff(s.project(np.array([0.0, 1e-3]), 100.0)[1])[0])
    assert dz_c == pytest.approx(pitch_v * 1e-3 / s.local_lateral_resolution_mm(100.0), rel=1e-9)


def test_quantization_error_within_half_a_local_pixel(paper_sensor: LaserLineSensor) -> None:
    rng = np.random.default_rng(1)
    s = paper_sensor
    z = rng.uniform(s.range_near_mm + 0.1, s.range_far_mm - 0.1, 20000)
    y = rng.uniform(-1, 1, z.size) * 0.95 * s.half_width_mm(z)
    yq, zq = s.measure(y, z)
    assert np.all(np.abs(zq - z) <= 0.5 * s.local_depth_resolution_mm(z) * 1.01 + 1e-9)
    assert np.all(
        np.abs(yq - y)
        <= 0.5 * s.local_lateral_resolution_mm(z) * 1.01 + 0.5 * s.local_depth_resolution_mm(z)
    )
    ideal = dataclasses.replace(s, quantize=False)
    yi, zi = ideal.measure(y, z)
    assert np.array_equal(yi, y) and np.array_equal(zi, z)


@pytest.mark.parametrize(
    "changes, field",
    [
        (dict(chip_h_mm=2 * 10.0 * math.tan(math.radians(30)) + 1e-9), "sensor.chip_h_mm"),
        (dict(angle_rad=math.radians(90)), "sensor.angle_deg"),
        (dict(angle_rad=0.0), "sensor.angle_deg"),
        (dict(baseline_mm=-1.0), "sensor.baseline_mm"),
        (dict(pixels_v=0), "sensor.pixels_v"),
    ],
)
def test_impossible_geometry_is_an_error_that_says_why(
    changes: dict[str, float], field: str
) -> None:
    with pytest.raises(SensorGeometryError) as info:
        LaserLineSensor(**{**HAND, **changes})
    assert info.value.field == field and info.value.fix


def test_eq4_breaks_exactly_where_the_error_says() -> None:
    limit = 2 * 10.0 * math.tan(math.radians(30))
    ok = LaserLineSensor(**{**HAND, "chip_h_mm": limit * (1 - 1e-6)})
    assert ok.depth_of_field_mm > 1e6  # nearly infinite just below the limit


def test_from_specs_rejects_a_narrowing_field_of_view() -> None:
    with pytest.raises(SensorGeometryError, match="fov_far_mm"):
        LaserLineSensor.from_specs(
            depth_of_field_mm=60,
            fov_near_mm=32,
            fov_far_mm=18,
            angle_deg=16.17,
            depth_resolution_mm=0.01,
            lateral_resolution_mm=0.01,
        )


def test_unknown_preset_names_the_choices() -> None:
    with pytest.raises(SensorGeometryError, match="paper"):
        preset("nope")
