"""Dataset samples against independent geometry: the mesh-mode ray caster on the same extruded
section, the V bottom fitted from each profile's own points, the synthetic profiles' sections,
and the seed of every sample."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from seamtrack.datasets import joints
from seamtrack.datasets.generate import (
    PARAM_NAMES,
    Plan,
    draw,
    generate,
    pose,
    sample_generator,
)
from seamtrack.datasets.kernel import stripe
from seamtrack.datasets.spec import NOISE_OFF, parse_spec
from seamtrack.features.synthetic import joint_section
from seamtrack.sensing.profiles import Reason
from seamtrack.sensing.scan import laser_fan, scan_mesh
from seamtrack.sensing.sensor import preset

PARAMS = {
    "thickness_mm": 8.0,
    "groove_angle_rad": math.radians(60.0),
    "root_face_mm": 1.5,
    "gap_mm": 1.2,
    "misalignment_mm": 0.4,
    "web_angle_rad": math.radians(80.0),
    "corner_angle_rad": math.radians(100.0),
}


def _synthetic_params(family: str) -> dict[str, float]:
    p = PARAMS
    return {
        "square-butt": {
            "gap_mm": p["gap_mm"],
            "misalignment_mm": p["misalignment_mm"],
            "thickness_mm": p["thickness_mm"],
        },
        "v-groove": {
            "included_angle_deg": 60.0,
            "gap_mm": p["gap_mm"],
            "root_face_mm": p["root_face_mm"],
            "thickness_mm": p["thickness_mm"],
            "misalignment_mm": p["misalignment_mm"],
        },
        "fillet": {"web_angle_deg": 80.0},
        "lap": {"thickness_mm": p["thickness_mm"], "gap_mm": p["gap_mm"]},
        "outside-corner": {"corner_angle_deg": 100.0},
        "flat": {},
    }[family]


@pytest.mark.parametrize("family", list(joints.FEATURES))
def test_sections_are_the_synthetic_profiles_joints(family: str) -> None:
    """Same segments and seam point as features.synthetic.joint_section (written separately)."""
    polylines, seam, features = joints.section(family, **PARAMS)
    segs, seam_ref, _, _ = joint_section(family, **_synthetic_params(family))
    ours = joints.segments(polylines, (0.0, 0.0))
    ref = segs.reshape(-1, 4)
    ref = ref[np.hypot(ref[:, 2] - ref[:, 0], ref[:, 3] - ref[:, 1]) > 0]
    np.testing.assert_allclose(ours, ref, atol=1e-12)
    if family == "flat":
        assert seam is None and seam_ref.size == 0
    else:
        np.testing.assert_allclose(seam, seam_ref, atol=1e-12)
    assert len(features) == len(joints.FEATURES[family])
    a, e = ours[:, :2], ours[:, 2:] - ours[:, :2]
    for point in features:  # every feature point lies on the section
        s = np.clip(np.einsum("ij,ij->i", point - a, e) / np.einsum("ij,ij->i", e, e), 0, 1)
        assert np.min(np.hypot(*(a + s[:, None] * e - point).T)) < 1e-12


def _extruded_mesh(segs: np.ndarray, half_length_mm: float = 300.0):  # -> trimesh.Trimesh
    trimesh = pytest.importorskip("trimesh")
    return trimesh.Trimesh(*joints.extruded_mesh(segs, half_length_mm), process=False)


@pytest.mark.embree
@pytest.mark.parametrize(
    ("family", "angles_deg", "lateral_mm", "standoff_offset_mm", "tack"),
    [
        ("v-groove", (0.0, 0.0, 0.0), 0.0, 0.0, False),
        ("v-groove", (8.0, -12.0, 5.0), 2.5, -10.0, False),
        ("square-butt", (-5.0, 15.0, 0.0), -3.0, 12.0, False),
        ("fillet", (10.0, 5.0, -8.0), 1.0, 5.0, False),
        ("lap", (3.0, -20.0, 0.0), 0.5, -5.0, False),
        ("outside-corner", (0.0, 10.0, 0.0), -1.0, 0.0, False),
        ("v-groove", (6.0, 8.0, 0.0), 0.0, 0.0, True),
    ],
)
def test_stripe_agrees_with_scan_mesh_on_the_extruded_section(
    family: str,
    angles_deg: tuple[float, float, float],
    lateral_mm: float,
    standoff_offset_mm: float,
    tack: bool,
) -> None:
    """The exact 2D cast equals Embree + float64 refinement on a mesh of the same extrusion:
    the same reason on every ray but where a ray grazes an edge, and the same pixel (within
    one pixel's size, far below the sensor's 0.01 mm) on every point valid in both."""
    sensor = preset("paper")
    polylines, seam, _ = joints.section(family, **PARAMS)
    assert seam is not None
    if tack:
        polylines = [*polylines, joints.tack_mound(seam, 1.0, 4.0)]
    segs = joints.segments(polylines, seam)
    tilt, roll, yaw = (math.radians(a) for a in angles_deg)
    T = pose(sensor.range_center_mm + standoff_offset_mm, lateral_mm, tilt, roll, yaw)
    rays = 1024
    fan = laser_fan(sensor, rays)
    points, reason, *_ = stripe(T[:3, 3].copy(), T[:3, :3].copy(), fan.directions, segs,
                                fan.sensor_params, 1e-2, True)  # fmt: skip
    profile = scan_mesh(sensor, _extruded_mesh(segs), T, rays=rays)
    same_reason = reason == profile.reason
    assert same_reason.mean() >= 0.995, np.flatnonzero(~same_reason)
    both = (reason == Reason.VALID) & profile.valid
    assert both.sum() > 200
    pixel = sensor.local_depth_resolution_mm(points[both, 1])
    gap = np.hypot(*(points[both] - profile.points_laser[both]).T)
    assert np.all(gap <= pixel + 1e-9), gap.max()
    assert np.median(gap) < 1e-6  # the same pixel on nearly every ray


def _bevel_line(points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Total least-squares line (centroid, unit direction) through (m, 2) points."""
    centroid = points.mean(axis=0)
    _, _, vt = np.linalg.svd(points - centroid)
    return centroid, vt[0]


def _farthest_from_chord(points: np.ndarray) -> tuple[int, float]:
    a, b = points[0], points[-1]
    d = (b - a) / np.hypot(*(b - a))
    distance = np.abs((points[:, 0] - a[0]) * d[1] - (points[:, 1] - a[1]) * d[0])
    far = int(np.argmax(distance))
    return far, float(distance[far])


def _pieces(points: np.ndarray, count: int) -> list[int]:
    """Split a polyline's points into ``count`` straight pieces: split the piece whose point
    lies farthest from its chord, at that point, until there are ``count`` (a greedy
    Douglas-Peucker). Returns the corner indices, both ends included."""
    corners = [0, len(points) - 1]
    while len(corners) < count + 1:
        best = max(
            (
                _farthest_from_chord(points[a : b + 1]) + (a,)
                for a, b in itertools.pairwise(corners)
            ),
            key=lambda x: x[1],
        )
        corners = sorted([*corners, best[2] + best[0]])
    return corners


def _meet(a: tuple[np.ndarray, np.ndarray], b: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    (c1, d1), (c2, d2) = a, b
    s, _ = np.linalg.solve(np.column_stack([d1, -d2]), c2 - c1)  # c1 + s d1 = c2 + u d2
    return c1 + s * d1


def v_corners(points: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The V bottom and the two top edges of a V-groove profile, from its points alone: split
    the profile into its four straight pieces (plate, bevel, bevel, plate), fit a line to each
    without 4 points at either end (a corner that falls between two rays may be placed a few
    rays off), intersect neighbouring lines."""
    _, left_edge, bottom, right_edge, end = _pieces(points, 4)
    margin = 4
    assert min(bottom - left_edge, right_edge - bottom) > 5 * margin, "a bevel is not in view"
    assert min(left_edge, end - right_edge) > 5 * margin, "a plate is not in view"
    lines = [
        _bevel_line(points[a + margin : b - margin])
        for a, b in itertools.pairwise([0, left_edge, bottom, right_edge, end])
    ]
    return _meet(lines[1], lines[2]), _meet(lines[0], lines[1]), _meet(lines[2], lines[3])


def v_bottom(points: np.ndarray) -> np.ndarray:
    return v_corners(points)[0]


def test_v_groove_seam_point_is_the_bottom_of_the_fitted_bevels() -> None:
    """Noise off, no gap, no misalignment: the seam point label equals the meeting point of
    the two bevel lines fitted to each (pixel-quantized) profile, within 0.01 mm, on every
    sample of a set drawn over angles, thicknesses, stand-offs, lateral offsets, tilts, rolls
    and yaws; and the labelled top edges are where the fitted plate and bevel lines meet."""
    spec = parse_spec(
        {
            "rays": 1024,
            "joint": {
                "families": ["v-groove"],
                "gap_mm": 0.0,
                "misalignment_mm": 0.0,
                "groove_angle_deg": [50.0, 75.0],  # both bevels in view, lit within 80 deg
                "thickness_mm": [4.0, 8.0],
                "root_face_mm": [0.0, 2.0],
            },
            "sensor": {
                "standoff_offset_mm": [-10.0, 15.0],  # the plates in the depth of field
                "lateral_offset_mm": [-2.0, 2.0],
                "tilt_deg": [-10.0, 10.0],
                "roll_deg": [-10.0, 10.0],
                "yaw_deg": [-10.0, 10.0],
            },
            "noise": NOISE_OFF,
        }
    )
    data = generate(spec, 0, 150)
    errors, edge_errors = [], []
    for i in range(150):
        valid = data["valid"][i]
        bottom, left, right = v_corners(data["points_laser"][i][valid])
        errors.append(np.hypot(*(bottom - data["seam_point_laser"][i])))
        edges = data["features_laser"][i][:2]  # left_edge, right_edge
        edge_errors += [np.hypot(*(left - edges[0])), np.hypot(*(right - edges[1]))]
    errors_mm = np.array(errors)
    assert max(edge_errors) <= 0.01, max(edge_errors)
    assert errors_mm.max() <= 0.01, (errors_mm.argmax(), errors_mm.max())
    print(f"V bottom vs label: max {errors_mm.max():.5f}, median {np.median(errors_mm):.5f} mm;"
          f" top edges: max {max(edge_errors):.5f} mm")  # fmt: skip
    # The oracle can fail: a label moved by 0.02 mm along z_L is caught.
    moved = data["seam_point_laser"][0] + [0.0, 0.02]
    bottom0 = v_bottom(data["points_laser"][0][data["valid"][0]])
    assert np.hypot(*(bottom0 - moved)) > 0.01


def test_sample_seeds_are_seed_sequence_spawns() -> None:
    children = np.random.SeedSequence(42).spawn(6)
    for i in (0, 5):
        ours = sample_generator(42, i).random(4)
        theirs = np.random.Generator(np.random.PCG64(children[i])).random(4)
        np.testing.assert_array_equal(ours, theirs)


def test_labels_follow_the_drawn_pose() -> None:
    """The seam point sits at (lateral offset, stand-off) in the laser plane: the sensor
    turns about it; the pose matrix is a rotation; unused parameters are NaN."""
    spec = parse_spec({"noise": NOISE_OFF, "joint": {"families": ["fillet", "flat"]}})
    data = generate(spec, 10, 40)
    col = {name: i for i, name in enumerate(PARAM_NAMES)}
    for i in range(40):
        T = data["T_seam_sensor"][i]
        np.testing.assert_allclose(T[:3, :3] @ T[:3, :3].T, np.eye(3), atol=1e-12)
        p = data["params"][i]
        if data["joint"][i] == 5:  # flat: no seam
            assert np.isnan(data["seam_point_laser"][i]).all()
            assert np.isnan(p[col["web_angle_rad"]])
            continue
        expected = [p[col["lateral_offset_mm"]], p[col["standoff_mm"]]]
        np.testing.assert_allclose(data["seam_point_laser"][i], expected, atol=1e-9)
        # the emitter is where T puts it: the seam point (seam-frame origin) is at range
        np.testing.assert_allclose(np.linalg.norm(T[:3, 3]), np.hypot(*expected), rtol=1e-12)
        assert np.isnan(p[col["groove_angle_rad"]])
        assert 70.0 <= math.degrees(p[col["web_angle_rad"]]) <= 110.0


def test_draws_cover_the_ranges_and_the_weights() -> None:
    spec = parse_spec({"joint": {"families": ["v-groove", "lap"], "weights": [3.0, 1.0],
                                 "gap_mm": [0.5, 1.5]}})  # fmt: skip
    plan = Plan.of(spec)
    drawn = [draw(plan, sample_generator(0, i)) for i in range(2000)]
    share = np.mean([d.family == "v-groove" for d in drawn])
    assert 0.72 < share < 0.78  # 3:1
    gaps = np.array([d.values["gap_mm"] for d in drawn])
    assert 0.5 <= gaps.min() < 0.51 and 1.49 < gaps.max() <= 1.5


def test_noise_knobs_reach_the_profile() -> None:
    """dropout_rate = 1 loses every point; range noise moves points but not the labels."""
    quiet = generate(parse_spec({"noise": NOISE_OFF}), 0, 5)
    lost = generate(parse_spec({"noise": {**NOISE_OFF, "dropout_rate": 1.0}}), 0, 5)
    assert not lost["valid"].any() and (lost["reason"] == Reason.DROPOUT).any()
    noisy = generate(parse_spec({"noise": {**NOISE_OFF, "range_sigma_mm": 0.05}}), 0, 5)
    np.testing.assert_array_equal(noisy["seam_point_laser"], quiet["seam_point_laser"])
    both = noisy["valid"] & quiet["valid"]
    moved = np.abs(noisy["points_laser"][both] - quiet["points_laser"][both]).max()
    assert 0.05 < moved < 1.0
