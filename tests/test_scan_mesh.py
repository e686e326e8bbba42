"""Mesh-mode stripe profiles (seamtrack.sensing.scan.scan_mesh): clips, occlusion, noise knobs,
files."""

from __future__ import annotations

import csv
import dataclasses
import itertools
import subprocess
import sys

import numpy as np
import pytest
import trimesh
from test_raycast import SECTIONS, extruded_mesh, posed

from seamtrack.bench.raycast_precision import analytic_first_hit
from seamtrack.geometry import frames
from seamtrack.io.profiles import write_profile_csv
from seamtrack.sensing.profiles import Feature, Profile, Reason
from seamtrack.sensing.raycast import RayCaster
from seamtrack.sensing.scan import (
    StripeNoise,
    laser_fan,
    ray_caster,
    scan_mesh,
    secondary_reflection_points,
    stripe_hits,
)
from seamtrack.sensing.sensor import preset
from seamtrack.viz.plots import plot_profile_png

pytestmark = pytest.mark.embree

SENSOR = preset("paper")
IDEAL = dataclasses.replace(SENSOR, quantize=False)
LOOK_DOWN = frames.look_rotation([0.0, 0.0, -1.0], [1.0, 0.0, 0.0])


def plate(z: float = 0.0, tilt_rad: float = 0.0, size: float = 200.0) -> trimesh.Trimesh:
    """A square plate through (0, 0, z), tilted about the world x axis."""
    c, s = np.cos(tilt_rad), np.sin(tilt_rad)
    corners = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]) * 0.5 * size
    corners = corners @ np.array([[1, 0, 0], [0, c, -s], [0, s, c]]).T + [0, 0, z]
    return trimesh.Trimesh(corners, [[0, 1, 2], [0, 2, 3]], process=False)


def distance_to_section(points_yz: np.ndarray, section: np.ndarray) -> np.ndarray:
    """(n,) distance of (y, z) points to a polyline (k, 2)."""
    best = np.full(len(points_yz), np.inf)
    for a, b in itertools.pairwise(section):
        ab = b - a
        u = np.clip(((points_yz - a) @ ab) / (ab @ ab), 0.0, 1.0)
        best = np.minimum(best, np.linalg.norm(points_yz - (a + u[:, None] * ab), axis=1))
    return best


# ----------------------------------------------------------------------------- accuracy
@pytest.mark.parametrize("name", sorted(SECTIONS))
@pytest.mark.parametrize("offset", [0.0, 1e5])
def test_quantized_points_lie_within_the_local_depth_resolution(name: str, offset: float) -> None:
    """The laser plane crosses the part's x exactly, so the section is the stripe's truth."""
    T_world_part = posed(offset)[0]
    mesh = extruded_mesh(SECTIONS[name], T_world_part)
    T_part_sensor = frames.make(LOOK_DOWN, [0.0, 0.4, SENSOR.range_center_mm])
    T_world_sensor = T_world_part @ T_part_sensor
    profile = scan_mesh(SENSOR, mesh, T_world_sensor)
    assert len(profile) == SENSOR.pixels_v
    pts = profile.valid_points
    assert len(pts) > SENSOR.pixels_v // 2
    # Laser frame (y_L, z_L) -> section frame (y, z): y = 0.4 - y_L, z = z0 - z_L.
    section_pts = np.column_stack([0.4 - pts[:, 0], SENSOR.range_center_mm - pts[:, 1]])
    error = distance_to_section(section_pts, SECTIONS[name])
    assert (error <= SENSOR.local_depth_resolution_mm(pts[:, 1])).all()


# ----------------------------------------------------------------------------- occlusion
GROOVE = np.array([[-40.0, 0.0], [-1.8, 0.0], [0.0, -10.0], [1.8, 0.0], [40.0, 0.0]])


def visible_analytic(points: np.ndarray, camera: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Visibility of part-frame points from ``camera`` over the extruded GROOVE, and the margin.

    The segment point -> camera clears the surface iff it passes above the section at every
    break point of the section it spans (the surface is piecewise linear in y). The margin is
    the smallest clearance (mm); near-zero margins are grazing lines of sight.
    """
    visible = np.ones(len(points), dtype=bool)
    margin = np.full(len(points), np.inf)
    for y_break, z_break in GROOVE[1:-1]:
        s = (y_break - points[:, 1]) / (camera[1] - points[:, 1])
        inside = (s > 1e-9) & (s < 1.0)
        z_line = points[:, 2] + s * (camera[2] - points[:, 2])
        clearance = np.where(inside, z_line - z_break, np.inf)
        visible &= clearance > 0
        margin = np.minimum(margin, np.abs(clearance))
    return visible, margin


def test_groove_wall_hides_the_far_wall_as_the_analytic_visibility_says() -> None:
    """A narrow V-groove, the sensor turned 70 deg about its laser axis: the camera looks in
    from the side, so the near wall's edge hides part of the far wall and the root."""
    sensor = dataclasses.replace(IDEAL, max_incidence_rad=np.radians(89.9))
    mesh = extruded_mesh(GROOVE, np.eye(4), length=120.0, n_along=25)
    yaw = frames.look_rotation([0.0, 0.0, -1.0], [np.cos(1.22), np.sin(1.22), 0.0])
    T_world_sensor = frames.make(yaw, [0.0, 0.0, SENSOR.range_center_mm - 5.0])
    rays = 2001
    profile = scan_mesh(sensor, mesh, T_world_sensor, rays=rays)
    fan = frames.apply_vectors(T_world_sensor, laser_fan(sensor, rays).directions)
    lit = analytic_first_hit(GROOVE, np.eye(4), T_world_sensor[:3, 3], fan, length=120.0)
    camera = frames.apply(T_world_sensor, sensor.camera_center_laser)
    visible, margin = visible_analytic(lit, camera)
    assert profile.reason is not None
    candidates = np.isin(profile.reason, [Reason.VALID, Reason.OCCLUDED]) & (margin > 1e-3)
    hidden = profile.reason == Reason.OCCLUDED
    assert (hidden[candidates] == ~visible[candidates]).all()
    assert 0.05 * rays < hidden.sum() < 0.5 * rays
    assert (candidates | ~np.isin(profile.reason, [Reason.VALID, Reason.OCCLUDED])).sum() >= (
        rays - 2
    )


@pytest.mark.parametrize("offset", [0.0, 1e3, 1e4, 1e5])
def test_no_visible_point_is_dropped_on_a_flat_plate(offset: float) -> None:
    T_world_part, _ = posed(offset, seed=4)
    mesh = extruded_mesh(SECTIONS["flat"], T_world_part, n_along=41, n_per_segment=40)
    T_part_sensor = frames.make(
        frames.look_rotation([0.2, 0.1, -1.0], [1.0, 0.0, 0.2]), [0.0, 0.0, SENSOR.range_center_mm]
    )
    for sensor in (SENSOR, IDEAL):
        profile = scan_mesh(sensor, mesh, T_world_part @ T_part_sensor, rays=4000)
        assert profile.reason is not None
        assert not (profile.reason == Reason.OCCLUDED).any()
        assert (profile.reason == Reason.VALID).sum() > 3000


# ----------------------------------------------------------------------------- extremes
def test_a_profile_that_misses_the_part_is_all_misses() -> None:
    T_world_sensor = frames.make(LOOK_DOWN, [500.0, 0.0, 90.0])
    profile = scan_mesh(SENSOR, plate(), T_world_sensor, rays=64)
    assert profile.reason is not None
    assert (profile.reason == Reason.MISS).all() and not profile.valid.any()
    assert profile.valid_points.shape == (0, 2) and np.isnan(profile.points_laser).all()


def test_a_part_across_the_far_end_of_the_depth_of_field() -> None:
    """A tilted plate: the stripe's far half lies beyond the depth of field."""
    far = SENSOR.range_far_mm
    T_world_sensor = frames.make(LOOK_DOWN, [0.0, 0.0, far])
    profile = scan_mesh(IDEAL, plate(tilt_rad=np.radians(20.0)), T_world_sensor, rays=501)
    assert profile.reason is not None
    hits = profile.reason != Reason.MISS
    assert hits.all()
    y, z = profile.points_laser.T
    inside = IDEAL.in_field_of_view(y, z)
    assert (profile.valid == inside).all()
    assert (profile.reason[~inside] == Reason.OUT_OF_RANGE).all()
    assert 50 < inside.sum() < 450
    assert np.isfinite(profile.valid_points).all()


def test_grazing_light_is_clipped_by_the_incidence_limit() -> None:
    tilt = np.radians(79.0)
    T_world_sensor = frames.make(LOOK_DOWN, [0.0, 0.0, SENSOR.range_center_mm])
    wall = plate(tilt_rad=tilt, size=400.0)
    profile = scan_mesh(SENSOR, wall, T_world_sensor, rays=201)
    assert profile.reason is not None
    lit = profile.reason != Reason.MISS
    normal_laser = LOOK_DOWN.T @ np.array([0.0, -np.sin(tilt), np.cos(tilt)])
    incidence = np.arccos(np.abs(laser_fan(SENSOR, 201).directions @ normal_laser))
    in_view = SENSOR.in_field_of_view(*profile.points_laser.T)
    clipped = lit & in_view & (incidence > SENSOR.max_incidence_rad + 1e-9)
    kept = lit & in_view & (incidence < SENSOR.max_incidence_rad - 1e-9)
    assert clipped.any() and kept.any()
    assert (profile.reason[clipped] == Reason.INCIDENCE).all()
    assert (profile.reason[kept] == Reason.VALID).all()
    assert (profile.reason[lit & ~in_view] == Reason.OUT_OF_RANGE).all()


def test_part_types_and_defaults() -> None:
    mesh = plate(z=0.0)
    T_world_sensor = frames.make(LOOK_DOWN, [0.0, 0.0, SENSOR.range_center_mm])

    @dataclasses.dataclass
    class Workpiece:
        mesh: trimesh.Trimesh

    a = scan_mesh(SENSOR, mesh, T_world_sensor, rays=33, t_s=1.5)
    b = scan_mesh(SENSOR, Workpiece(mesh), T_world_sensor, rays=33)
    c = scan_mesh(SENSOR, RayCaster.from_mesh(mesh), T_world_sensor, rays=33)
    assert ray_caster(Workpiece(mesh)) is ray_caster(mesh)
    np.testing.assert_array_equal(a.points_laser, b.points_laser)
    np.testing.assert_array_equal(a.points_laser, c.points_laser)
    assert a.t_s == 1.5 and a.valid[1:-1].all()  # the fan is wider than the far trapezoid
    np.testing.assert_allclose(a.points_world[:, 2], 0.0, atol=SENSOR.depth_resolution_mm)
    with pytest.raises(TypeError):
        scan_mesh(SENSOR, "not a mesh", T_world_sensor)
    with pytest.raises(ValueError, match="rng"):
        scan_mesh(SENSOR, mesh, T_world_sensor, noise=StripeNoise(range_sigma_mm=0.1))


def test_seam_mode_imports_neither_embree_nor_numba() -> None:
    code = (
        "import sys, seamtrack.sensing.scan; "
        "assert not {'embreex', 'numba', 'trimesh'} & set(sys.modules), sys.modules.keys()"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=300)


# ----------------------------------------------------------------------------- noise knobs
def flat_at(z: float) -> tuple[trimesh.Trimesh, np.ndarray]:
    return plate(), frames.make(LOOK_DOWN, [0.0, 0.0, z])


@pytest.mark.parametrize("where", ["center", "far"])
def test_range_noise_has_the_configured_sigma(where: str) -> None:
    sigma = 0.05
    z0 = SENSOR.range_center_mm if where == "center" else SENSOR.range_far_mm - 3.0
    mesh, T_world_sensor = flat_at(z0)
    rng = np.random.default_rng(7)
    profile = scan_mesh(
        IDEAL, mesh, T_world_sensor, rays=100_000, noise=StripeNoise(range_sigma_mm=sigma), rng=rng
    )
    z = profile.valid_points[:, 1]
    assert len(z) > 90_000
    expected = sigma * float(
        SENSOR.local_depth_resolution_mm(z0)
        / SENSOR.local_depth_resolution_mm(SENSOR.range_center_mm)
    )
    assert np.std(z - z0) == pytest.approx(expected, rel=0.05)


def test_speckle_is_correlated_along_the_stripe() -> None:
    mesh, T_world_sensor = flat_at(SENSOR.range_center_mm)
    noise = StripeNoise(speckle_sigma_mm=0.03, speckle_correlation_rays=10.0)
    profile = scan_mesh(
        IDEAL, mesh, T_world_sensor, rays=50_000, noise=noise, rng=np.random.default_rng(2)
    )
    dz = profile.valid_points[:, 1] - SENSOR.range_center_mm
    assert np.std(dz) == pytest.approx(0.03, rel=0.1)
    lag1 = np.corrcoef(dz[:-1], dz[1:])[0, 1]
    assert lag1 == pytest.approx(np.exp(-1 / (4 * 10.0**2)), abs=0.02)


DROPOUT_RATE = 0.1


@pytest.fixture(scope="module")
def dropout_by_tilt() -> dict[float, tuple[np.ndarray, np.ndarray]]:
    """Per plate tilt: which rays were dropped, among those a clean scan sees, and their
    incidence cosines (the clean scan's geometry)."""
    out = {}
    T_world_sensor = frames.make(LOOK_DOWN, [0.0, 0.0, SENSOR.range_center_mm])
    for tilt_deg in (0.0, 45.0, 70.0):
        wall = plate(tilt_rad=np.radians(tilt_deg), size=400.0)
        rays = 40_000
        clean = stripe_hits(SENSOR, ray_caster(wall), T_world_sensor, rays)
        profile = scan_mesh(
            SENSOR,
            wall,
            T_world_sensor,
            rays=rays,
            noise=StripeNoise(dropout_rate=DROPOUT_RATE),
            rng=np.random.default_rng(1),
        )
        seen = clean.reason == Reason.VALID
        out[tilt_deg] = (profile.reason[seen] == Reason.DROPOUT, clean.cos_incidence[seen])
    return out


def test_dropout_grows_with_incidence(dropout_by_tilt) -> None:
    """The same stripe on a plate tilted 0, 45 and 70 deg: each tilt loses more rays than the
    one before, by more than 4 sampling sigmas (no model of how much: the tilts are compared)."""
    lost = [(d.mean(), d.size) for d, _ in dropout_by_tilt.values()]
    for (a, na), (b, nb) in itertools.pairwise(lost):
        assert b - a > 4 * np.sqrt(a * (1 - a) / na + b * (1 - b) / nb)


def test_dropout_at_normal_incidence_is_the_configured_rate(dropout_by_tilt) -> None:
    """On the flat plate, the rays within 2.5 deg of the normal lose ``dropout_rate``."""
    dropped, cos_incidence = dropout_by_tilt[0.0]
    normal = dropped[cos_incidence > np.cos(np.radians(2.5))]
    assert normal.size > 1000
    sigma = np.sqrt(DROPOUT_RATE * (1 - DROPOUT_RATE) / normal.size)
    assert abs(normal.mean() - DROPOUT_RATE) < 4 * sigma


def test_outlier_fraction() -> None:
    fraction = 0.05
    z0 = SENSOR.range_center_mm
    mesh, T_world_sensor = flat_at(z0)
    profile = scan_mesh(
        IDEAL,
        mesh,
        T_world_sensor,
        rays=100_000,
        noise=StripeNoise(outlier_fraction=fraction),
        rng=np.random.default_rng(5),
    )
    far = np.abs(profile.valid_points[:, 1] - z0) > 0.5
    # A spurious peak is uniform in x_c; it lands > 0.5 mm off with this probability.
    x_hi, _ = SENSOR.project(0.0, z0 - 0.5)
    x_lo, _ = SENSOR.project(0.0, z0 + 0.5)
    p_far = 1.0 - (x_hi - x_lo) / SENSOR.chip_h_mm
    assert far.mean() == pytest.approx(fraction * p_far, rel=0.06)


def test_secondary_reflection_is_the_mirrored_point_in_a_v_groove() -> None:
    """Laser plane across a straight groove: the reflection stays in the plane, so the false
    point is the second lit point itself, found analytically from the mirror law."""
    section = SECTIONS["v_groove"]
    mesh = extruded_mesh(section, np.eye(4))
    T_world_sensor = frames.make(LOOK_DOWN, [0.0, 0.0, SENSOR.range_center_mm - 8.0])
    hits = stripe_hits(IDEAL, ray_caster(mesh), T_world_sensor, 401, quantize=False)
    false_points, seen = secondary_reflection_points(IDEAL, ray_caster(mesh), T_world_sensor, hits)
    assert seen.any()
    lit = frames.apply(T_world_sensor, np.column_stack([np.zeros(401), hits.points_laser]))
    on_flat = np.abs(lit[:, 2]) < 1e-9
    assert not seen[on_flat].any()
    for i in np.flatnonzero(seen)[::20]:
        d = hits.directions_local[i]
        n = ray_caster(mesh).face_normals[hits.face[i]]
        r = d - 2 * (d @ n) * n
        q = analytic_first_hit(section, np.eye(4), lit[i] + 1e-6 * r, r[None])[0]
        expected = frames.apply(frames.invert(T_world_sensor), q)[1:]
        np.testing.assert_allclose(false_points[i], expected, atol=1e-6)
    profile = scan_mesh(
        SENSOR,
        mesh,
        T_world_sensor,
        rays=401,
        noise=StripeNoise(secondary_probability=1.0),
        rng=np.random.default_rng(0),
    )
    assert profile.valid[seen].all()


def test_noise_is_reproducible_from_the_seed() -> None:
    mesh = extruded_mesh(SECTIONS["v_groove"], np.eye(4))
    T_world_sensor = frames.make(LOOK_DOWN, [0.0, 0.0, SENSOR.range_center_mm - 8.0])
    noise = StripeNoise(
        range_sigma_mm=0.02,
        speckle_sigma_mm=0.01,
        dropout_rate=0.05,
        secondary_probability=0.3,
        outlier_fraction=0.01,
    )
    a, b = (
        scan_mesh(
            SENSOR, mesh, T_world_sensor, rays=500, noise=noise, rng=np.random.default_rng(11)
        )
        for _ in range(2)
    )
    np.testing.assert_array_equal(a.points_laser, b.points_laser)
    np.testing.assert_array_equal(a.reason, b.reason)
    assert not StripeNoise() and noise
    with pytest.raises(ValueError):
        StripeNoise(dropout_rate=1.5)


# ----------------------------------------------------------------------------- files
def test_profile_csv_and_png(tmp_path) -> None:  # type: ignore[no-untyped-def]
    mesh = extruded_mesh(SECTIONS["v_groove"], np.eye(4))
    T_world_sensor = frames.make(LOOK_DOWN, [0.0, 0.0, SENSOR.range_center_mm - 8.0])
    profile = scan_mesh(SENSOR, mesh, T_world_sensor, rays=300)
    path = write_profile_csv(profile, tmp_path / "out" / "profile.csv")
    with path.open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 300
    assert {r["reason"] for r in rows} <= {r.name for r in Reason}
    i = int(np.flatnonzero(profile.valid)[0])
    assert float(rows[i]["z_L_mm"]) == profile.points_laser[i, 1]
    assert float(rows[i]["z_mm"]) == pytest.approx(profile.points_world[i, 2])
    feature = Feature.found([0.0, SENSOR.range_center_mm], T_world_sensor)
    png = plot_profile_png(profile, tmp_path / "profile.png", feature=feature)
    assert png.stat().st_size > 1000


def test_profile_png_legend_markers_are_small(tmp_path, monkeypatch) -> None:
    """The legend draws every entry at LEGEND_MARKER_PT, however large the marker in the plot
    (the seam-point cross is 10 pt there): legible, and no legend entry covers the plot."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from seamtrack.viz.plots import LEGEND_MARKER_PT

    y = np.linspace(-5.0, 5.0, 101)
    profile = Profile(np.column_stack([y, 80.0 + np.abs(y)]))
    edges = np.array([[-5.0, 85.0], [5.0, 85.0]])
    feature = Feature.found([0.0, 80.0], None, edges_laser=edges)
    figures = []
    monkeypatch.setattr(plt, "close", figures.append)
    plot_profile_png(profile, tmp_path / "p.png", feature=feature)
    (ax,) = figures[0].axes
    sizes = [h.get_markersize() for h in ax.get_legend().legend_handles]
    assert len(sizes) == 3 and all(s == LEGEND_MARKER_PT for s in sizes)
    assert max(line.get_markersize() for line in ax.get_lines()) == 10  # the plot keeps its size
    monkeypatch.undo()
    plt.close("all")
