"""The synthetic profile generator against independent geometry."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from seamtrack.features.synthetic import JOINTS, Imperfections, synthetic_profile
from seamtrack.sensing.profiles import Reason
from seamtrack.sensing.sensor import preset

SENSOR = preset("paper")
IDEAL = dataclasses.replace(SENSOR, quantize=False)
TILTS = [(0.0, 0.0), (15.0, 0.0), (0.0, -15.0), (-12.0, 9.0), (15.0, 15.0)]


def _world(profile):
    return profile.points_world[profile.valid]


@pytest.mark.parametrize(("pitch_deg", "roll_deg"), TILTS)
def test_v_groove_points_lie_on_the_analytic_planes(pitch_deg, roll_deg):
    # Top z = 0, bevels at half the included angle from the vertical, root faces at |y| = g/2.
    g, r, t, angle = 1.0, 1.0, 8.0, 60.0
    profile, truth = synthetic_profile(
        "v-groove",
        IDEAL,
        pitch_deg=pitch_deg,
        roll_deg=roll_deg,
        lateral_offset_mm=0.7,
        gap_mm=g,
        root_face_mm=r,
        thickness_mm=t,
        included_angle_deg=angle,
    )
    p = _world(profile)
    y, z = np.abs(p[:, 1]), p[:, 2]
    tan_half = math.tan(math.radians(angle / 2))
    on_top = np.abs(z) < 1e-9
    on_bevel = np.abs((y - g / 2) - (t - r - z) * tan_half) < 1e-9
    on_root = (np.abs(y - g / 2) < 1e-9) & (z >= t - r - 1e-9)
    assert np.all(on_top | on_bevel | on_root)
    assert on_bevel.sum() > 100
    # The seam point is the root centre at depth t - r, on the laser plane, on the seam line.
    assert truth.seam_world[1:] == pytest.approx([0.0, t - r], abs=1e-9)
    seam_laser = np.linalg.inv(truth.T_world_sensor) @ np.r_[truth.seam_world, 1.0]
    assert seam_laser[0] == pytest.approx(0.0, abs=1e-9)
    assert seam_laser[1:3] == pytest.approx(truth.seam_laser, abs=1e-9)
    w2 = g / 2 + (t - r) * tan_half
    edges_world = np.array(
        [(truth.T_world_sensor @ np.r_[0.0, e, 1.0])[1:3] for e in truth.edges_laser]
    )
    assert edges_world == pytest.approx(np.array([[-w2, 0.0], [w2, 0.0]]), abs=1e-9)
    assert truth.gap_mm == g


@pytest.mark.parametrize(("pitch_deg", "roll_deg"), TILTS)
def test_fillet_corner_is_where_both_faces_meet(pitch_deg, roll_deg):
    profile, truth = synthetic_profile(
        "fillet", IDEAL, pitch_deg=pitch_deg, roll_deg=roll_deg, web_angle_deg=90.0
    )
    p = _world(profile)
    # Faces z = -|y| (rising towards the sensor at 45 deg).
    assert np.abs(p[:, 2] + np.abs(p[:, 1])) == pytest.approx(0.0, abs=1e-9)
    assert truth.seam_world[1:] == pytest.approx([0.0, 0.0], abs=1e-12)
    # Intersect the two face lines fitted in the laser plane: the corner is the seam point.
    pts = profile.valid_points
    left, right = (
        pts[pts[:, 0] < truth.seam_laser[0] - 0.5],
        pts[pts[:, 0] > truth.seam_laser[0] + 0.5],
    )
    (a1, b1), (a2, b2) = np.polyfit(*left.T, 1), np.polyfit(*right.T, 1)
    y = (b2 - b1) / (a1 - a2)
    assert [y, a1 * y + b1] == pytest.approx(truth.seam_laser, abs=1e-6)


def test_pitch_stretches_range_and_roll_turns_the_profile():
    flat0, _ = synthetic_profile("flat", IDEAL)
    pitched, _ = synthetic_profile("flat", IDEAL, pitch_deg=15.0)
    rolled, _ = synthetic_profile("flat", IDEAL, roll_deg=10.0)
    z0 = IDEAL.range_center_mm
    assert flat0.valid_points[:, 1] == pytest.approx(z0, abs=1e-9)
    # Pitch turns the sensor about the reference point, which stays at range z0; the section
    # stays level, and depths below the surface stretch by 1 / cos(pitch).
    assert pitched.valid_points[:, 1] == pytest.approx(z0, abs=1e-9)
    _, groove = synthetic_profile(
        "v-groove", IDEAL, pitch_deg=15.0, thickness_mm=8.0, root_face_mm=1.0
    )
    assert groove.seam_laser[1] - z0 == pytest.approx(7.0 / math.cos(math.radians(15)))
    # Roll: the plate line turns by the roll angle in the laser plane.
    slope = np.polyfit(*rolled.valid_points.T, 1)[0]
    assert math.degrees(math.atan(slope)) == pytest.approx(-10.0, abs=1e-6)


def test_quantized_profile_sits_on_pixel_centres_and_inside_the_field_of_view():
    profile, _ = synthetic_profile("v-groove", SENSOR, roll_deg=5.0)
    y, z = profile.valid_points.T
    assert SENSOR.in_field_of_view(y, z).all()
    y_again, z_again = SENSOR.measure(y, z)
    assert np.allclose(y_again, y, atol=1e-9) and np.allclose(z_again, z, atol=1e-9)
    assert len(profile) == SENSOR.pixels_v
    assert (profile.reason[~profile.valid] != Reason.VALID).all()


def test_square_butt_gap_lets_rays_through_and_walls_are_too_grazing():
    profile, truth = synthetic_profile("square-butt", SENSOR, gap_mm=1.0)
    assert (profile.reason == Reason.MISS).sum() > 50
    assert truth.edges_laser[:, 0] == pytest.approx([-0.5, 0.5])


@pytest.mark.parametrize("joint", JOINTS)
def test_imperfections_are_seeded_and_reproducible(joint):
    imp = Imperfections(
        noise_mm=0.05,
        outlier_fraction=0.05,
        dropout_runs=3,
        reflection_probability=1.0,
        tack_probability=0.5,
        bead_height_mm=0.0,
    )
    a, ta = synthetic_profile(
        joint, SENSOR, rng=np.random.default_rng(7), rays=512, imperfections=imp
    )
    b, _tb = synthetic_profile(
        joint, SENSOR, rng=np.random.default_rng(7), rays=512, imperfections=imp
    )
    assert np.array_equal(a.points_laser, b.points_laser, equal_nan=True)
    assert ta.reflection and (a.reason == Reason.DROPOUT).any()


def test_a_false_reflection_lies_1_to_4_mm_off_the_surface_even_among_outliers():
    """The reflection is anchored on the true surface, never on an outlier next to it."""
    ideal = dataclasses.replace(SENSOR, quantize=False)
    clean, _ = synthetic_profile("flat", ideal, rays=512)
    span = 0.0
    for seed in range(40):
        args = dict(rng=np.random.default_rng(seed), rays=512)
        lit = Imperfections(outlier_fraction=0.5)
        base, _ = synthetic_profile("flat", ideal, imperfections=lit, **args)
        args["rng"] = np.random.default_rng(seed)  # the same outliers, then the reflection
        with_reflection = dataclasses.replace(lit, reflection_probability=1.0)
        shown, truth = synthetic_profile("flat", ideal, imperfections=with_reflection, **args)
        same = (shown.points_laser == base.points_laser) | np.isnan(base.points_laser)
        cols = np.flatnonzero(~same.all(axis=1) & shown.valid & clean.valid)
        assert truth.reflection and cols.size >= 3
        # A flat plate at z_L = z0: the reflection line sits 1-4 mm off it at its anchor and
        # tilts by at most 45 deg over its own width.
        width = np.ptp(shown.points_laser[cols, 0])
        off = np.abs(shown.points_laser[cols, 1] - clean.points_laser[cols, 1])
        assert off.max() <= 4.0 + width + 1e-9 and off.min() >= 1.0 - width - 1e-9
        span = max(span, width)
    assert span < 1.5  # the bound above is tight enough to mean something


def test_random_imperfections_need_a_generator():
    with pytest.raises(ValueError, match="Generator"):
        synthetic_profile("flat", SENSOR, imperfections=Imperfections(noise_mm=0.1))


def test_bead_cap_hides_the_groove_and_keeps_the_ground_truth():
    clean, truth = synthetic_profile("v-groove", IDEAL)
    capped, truth_capped = synthetic_profile(
        "v-groove", IDEAL, imperfections=Imperfections(bead_height_mm=1.5, bead_width_mm=12.0)
    )
    assert truth_capped.seam_laser == pytest.approx(truth.seam_laser)
    # The crown stands 1.5 mm in front of the plate surface (range z0 - 1.5).
    assert capped.valid_points[:, 1].min() == pytest.approx(IDEAL.range_center_mm - 1.5, abs=1e-3)
    assert capped.valid_points[:, 1].max() < clean.valid_points[:, 1].max() - 5.0


def test_lap_seam_is_under_the_top_sheet_edge():
    _profile, truth = synthetic_profile("lap", IDEAL, thickness_mm=2.0, gap_mm=0.5)
    edge_world = truth.T_world_sensor @ np.r_[0.0, truth.edges_laser[0], 1.0]
    assert edge_world[1:3] == pytest.approx([0.0, -2.5])
    assert truth.seam_world[1:] == pytest.approx([0.0, 0.0])
    assert truth.gap_mm == 0.5


def test_unknown_joint_or_parameter_is_refused():
    with pytest.raises(ValueError, match="unknown joint"):
        synthetic_profile("butt", SENSOR)
    with pytest.raises(ValueError, match="no parameter"):
        synthetic_profile("fillet", SENSOR, gap_mm=1.0)


@pytest.mark.parametrize(("pitch_deg", "roll_deg"), TILTS)
def test_raised_block_points_lie_on_its_faces_and_it_has_no_seam(pitch_deg, roll_deg):
    """Plate z = 0, top z = -h for |y| <= w / 2, walls leaning in by the draft angle."""
    w, h, draft = 4.0, 6.0, 5.0
    profile, truth = synthetic_profile(
        "block",
        IDEAL,
        pitch_deg=pitch_deg,
        roll_deg=roll_deg,
        width_mm=w,
        height_mm=h,
        draft_deg=draft,
    )
    p = _world(profile)
    y, z = np.abs(p[:, 1]), p[:, 2]
    foot = w / 2 + h * math.tan(math.radians(draft))
    on_plate = (np.abs(z) < 1e-9) & (y >= foot - 1e-9)
    on_top = (np.abs(z + h) < 1e-9) & (y <= w / 2 + 1e-9)
    on_wall = np.abs(y - (w / 2 + (z + h) * math.tan(math.radians(draft)))) < 1e-9
    assert np.all(on_plate | on_top | on_wall)
    assert on_top.sum() > 100 and on_plate.sum() > 100
    assert not truth.has_seam and truth.edges_laser.shape == (0, 2)
