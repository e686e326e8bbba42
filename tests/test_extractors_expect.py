"""Expectations of the family extractors (``expect={...}``, the scene's [extractor.expect]):
validated at construction, refusing implausible answers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seamtrack.errors import PluginError
from seamtrack.features.expect import Expect, parse_expect
from seamtrack.features.extractors import extractor
from seamtrack.features.synthetic import line_in_laser_plane, synthetic_profile
from seamtrack.sensing.sensor import preset

SENSOR = preset("paper")


@pytest.mark.parametrize(
    ("name", "expect", "key"),
    [
        ("v-groove", {"angel_deg": 60}, "angel_deg"),
        ("v-groove", {"angle_deg": 180}, "angle_deg"),
        ("v-groove", {"angle_deg": 60, "angle_tol_deg": 0}, "angle_tol_deg"),
        ("v-groove", {"depth_tol_mm": 1.0}, "depth_tol_mm"),
        ("v-groove", {"gap_mm": -1.0}, "gap_mm"),
        ("v-groove", {"gap_mm": True}, "gap_mm"),
        ("v-groove", {"gap_mm": "1"}, "gap_mm"),
        ("v-groove", {"depth_mm": math.nan}, "depth_mm"),
        ("fillet", {"gap_mm": 1.0}, "gap_mm"),
        ("square-butt", {"angle_deg": 90}, "angle_deg"),
        ("lap", {"gap_mm": 0.5}, "gap_mm"),
    ],
)
def test_bad_expectations_raise_plugin_error_naming_the_key(name, expect, key):
    with pytest.raises(PluginError) as info:
        extractor(name, expect=expect)
    assert info.value.field == f"extractor.expect.{key}" and info.value.fix


def test_expect_must_be_a_table():
    with pytest.raises(PluginError) as info:
        extractor("v-groove", expect=60)
    assert info.value.field == "extractor.expect"


def test_degrees_at_the_edge_radians_inside():
    e = parse_expect({"angle_deg": 60, "angle_tol_deg": 5, "gap_mm": 1}, "v-groove")
    assert isinstance(e, Expect)
    assert e.angle == pytest.approx(math.pi / 3) and e.angle_tol == pytest.approx(math.pi / 36)
    assert e.gap_tol_mm == 0.5 and not e.gapless  # the default tolerance
    assert parse_expect({"gap_mm": 0.2}, "v-groove").gapless


def _v(**params):
    return synthetic_profile("v-groove", SENSOR, roll_deg=6.0, pitch_deg=4.0, **params)


def test_v_groove_angle_expectation():
    """A 90 deg groove: expected 60 +- 10 deg it is refused as implausible (its two bevels
    are the only V), expected 90 +- 5 deg it is found."""
    profile, truth = _v(included_angle_deg=90.0)
    refused = extractor("v-groove", expect={"angle_deg": 60, "angle_tol_deg": 10})(profile)
    assert not refused and refused.reason
    found = extractor("v-groove", expect={"angle_deg": 90, "angle_tol_deg": 5})(profile)
    assert found and np.hypot(*(found.point_laser - truth.seam_laser)) < 0.02


def test_v_groove_depth_expectation():
    """The root centre lies thickness - root face (7 mm) below the plates in the joint frame;
    pitched by 4 deg, 7 / cos(4 deg) along the laser plane."""
    profile, _ = _v()
    depth = 7.0 / math.cos(math.radians(4.0))
    assert extractor("v-groove", expect={"depth_mm": depth, "depth_tol_mm": 0.05})(profile)
    refused = extractor("v-groove", expect={"depth_mm": 3.0, "depth_tol_mm": 1.0})(profile)
    assert not refused and "depth" in refused.reason


def test_v_groove_expected_without_gap_reports_the_bevels_intersection():
    """A 1 mm gap read as gapless: the seam point is the bevels' intersection, (g / 2) /
    tan(30 deg) below the root centre in the joint frame."""
    profile, truth = _v(gap_mm=1.0)
    g, half = 1.0, math.radians(30.0)
    apex_joint = np.array([[0.0, 7.0 + 0.5 * g / math.tan(half)]])
    apex = line_in_laser_plane(truth.T_world_sensor, apex_joint)[0]
    f = extractor("v-groove", expect={"gap_mm": 0.0})(profile)
    assert f and np.hypot(*(f.point_laser - apex)) < 0.02 and f.gap_mm == 0.0
    plain = extractor("v-groove")(profile)
    assert np.hypot(*(plain.point_laser - truth.seam_laser)) < 0.02


def test_square_butt_gap_expectation():
    profile, _ = synthetic_profile("square-butt", SENSOR, gap_mm=1.0, roll_deg=5.0)
    assert extractor("square-butt", expect={"gap_mm": 1.0, "gap_tol_mm": 0.1})(profile)
    refused = extractor("square-butt", expect={"gap_mm": 3.0})(profile)
    assert not refused and "gap" in refused.reason


def test_lap_step_expectation():
    profile, _ = synthetic_profile("lap", SENSOR, thickness_mm=2.0, roll_deg=-4.0)
    assert extractor("lap", expect={"depth_mm": 2.0, "depth_tol_mm": 0.1})(profile)
    assert not extractor("lap", expect={"depth_mm": 5.0})(profile)


@pytest.mark.parametrize(
    ("name", "joint"), [("fillet", "fillet"), ("outside-corner", "outside-corner")]
)
def test_corner_angle_expectation(name, joint):
    profile, _ = synthetic_profile(joint, SENSOR, roll_deg=3.0)
    assert extractor(name, expect={"angle_deg": 90, "angle_tol_deg": 2})(profile)
    assert not extractor(name, expect={"angle_deg": 120, "angle_tol_deg": 5})(profile)


# ----------------------------------------------------------- the scene's [extractor.expect]
SHORT_GROOVE = {"workpiece.params.seam_length_mm": 20.0, "sensor.rays": 512}


def _seam_point_at(parts, s_mm: float):
    tcp = parts.seam.interpolate([s_mm])[0]
    T_world_sensor = parts.robot.T_world_sensor(parts.robot.q_from_world(tcp))
    return parts.scan(T_world_sensor, 0.0)[1]


def test_scene_expectation_reaches_the_extractor_and_refuses_a_wrong_groove():
    """paper-v-groove's bevels meet at 60 deg: expected so, the seam point is found; expected
    at 90 +- 5 deg, no pair of bevels in 85-95 deg forms the joint and the stripe is refused."""
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.scene import load_scene

    right = build_parts(
        load_scene("paper-v-groove", {**SHORT_GROOVE, "extractor.expect": {"angle_deg": 60}})
    )
    assert right.extract.expect == parse_expect({"angle_deg": 60}, "v-groove")
    assert _seam_point_at(right, 5.0)
    wrong = build_parts(
        load_scene(
            "paper-v-groove",
            {**SHORT_GROOVE, "extractor.expect": {"angle_deg": 90, "angle_tol_deg": 5}},
        )
    )
    assert wrong.extract.expect.angle == pytest.approx(math.radians(90))
    assert not _seam_point_at(wrong, 5.0)


@pytest.mark.parametrize(
    ("overrides", "field"),
    [
        ({"extractor.expect": {"angel_deg": 60}}, "extractor.expect.angel_deg"),
        (
            {"extractor.expect": {"gap_mm": 1}, "extractor.name": "fillet"},
            "extractor.expect.gap_mm",
        ),
        ({"extractor.expect": {"angle_deg": 60}, "extractor.name": "generic"}, "extractor.expect"),
    ],
)
def test_a_bad_scene_expectation_is_refused_when_the_scene_loads(overrides, field):
    from seamtrack.errors import SeamtrackError
    from seamtrack.simulation.scene import load_scene

    with pytest.raises(SeamtrackError) as info:
        load_scene("paper-v-groove", {**SHORT_GROOVE, "extractor.name": "v-groove", **overrides})
    assert info.value.field == field and info.value.fix
