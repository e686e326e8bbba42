"""The fill state: sections of CAD grooves, deposition along the torch's path, the fill mesh."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seamtrack.errors import SceneError
from seamtrack.workpiece.beads import BEAD_KINDS, BeadShape, bead_area_mm2, polygon_area_mm2
from seamtrack.workpiece.fill import FillState

TAN30 = math.tan(math.radians(30))


def analytic_state(length=20.0, thickness=20.0, gap=2.0, spacing=0.5, flat=False) -> FillState:
    """A straight seam along +X with an analytic V-groove (root gap on a backing) or a plate."""
    s = np.arange(0.0, length + 1e-9, spacing)
    frames = np.tile(np.eye(4), (len(s), 1, 1))
    frames[:, 0, 3] = s
    y = np.arange(-25.0, 25.0 + 1e-9, 0.05)
    if flat:
        # A plate with a shallow 1 mm step either side, so the state finds "top corners".
        z = np.where(np.abs(y) < 18.0, 0.0, 1.0)
    else:
        half = gap / 2 + thickness * TAN30
        z = np.clip((np.abs(y) - gap / 2) / TAN30, 0.0, thickness)
        assert half < 25
    return FillState.from_profiles(s, frames, y, np.repeat(z[None, :], len(s), axis=0))


def straight_path(length=20.0, lateral=None, n=401):
    x = np.linspace(-1.0, length + 1.0, n)
    y = np.zeros(n) if lateral is None else lateral(x)
    return np.column_stack([x, y, np.full(n, 15.0)])


def laid_areas(state: FillState, pass_index: int) -> np.ndarray:
    return np.array(
        [
            polygon_area_mm2(state.beads[pass_index].polygon(state.y_mm, i))
            for i in range(state.n_stations)
        ]
    )


@pytest.mark.parametrize("kind", BEAD_KINDS)
def test_area_conserved_per_station_flat_groove_and_on_beads(kind) -> None:
    shape = BeadShape(kind, 3.0)
    # The torch slows down along the seam: v(x) from 8 to 4 mm/s, a fatter bead at the end.
    path = straight_path()
    speed = np.interp(path[:, 0], [0, 20], [8.0, 4.0])
    area = bead_area_mm2(1.2, 8000 / 60, speed, 0.97)
    for flat in (True, False):
        state = analytic_state(flat=flat)
        expected = bead_area_mm2(1.2, 8000 / 60, np.interp(state.s_mm, [0, 20], [8.0, 4.0]), 0.97)
        for p, offset in enumerate((0.0, -2.5, 2.5)):  # the second and third sit on the first
            state = state.deposit(path, area, shape, offset_mm=offset)
            got = laid_areas(state, p)
            assert got == pytest.approx(expected, rel=0.01)
            assert state.beads[p].area_mm2 == pytest.approx(expected, rel=0.01)


def test_remaining_area_falls_by_each_bead() -> None:
    state = analytic_state()
    groove = 2 * 20 + 20 * 20 * TAN30
    assert state.remaining_area_mm2() == pytest.approx(groove, rel=2e-3)
    empty = state.reinforcement_mm()
    assert empty[:, 0] == pytest.approx(-20.0, abs=1e-9)  # the root, 20 mm below the top line
    assert empty[:, 1] == pytest.approx(0.0, abs=0.1)  # the top corners
    path = straight_path()
    area = np.full(len(path), 25.0)
    before = state.remaining_area_mm2()
    state = state.deposit(path, area, BeadShape())
    assert before - state.remaining_area_mm2() == pytest.approx(25.0, rel=1e-6)
    assert np.all(state.reinforcement_mm()[:, 0] > -20.0 + 1.0)  # the root is covered


def test_bead_follows_the_torchs_actual_path() -> None:
    state = analytic_state()

    def wander(x):
        return 0.8 * np.sin(2 * np.pi * x / 20.0)

    state = state.deposit(straight_path(lateral=wander), np.full(401, 20.0), BeadShape())
    np.testing.assert_allclose(state.beads[0].y_centre_mm, wander(state.s_mm), atol=1e-3)
    # The bead's apex sits near the path (a bead in a V centres on the V, so check the toes
    # move with the torch: left toe further left where the torch is left).
    toes = state.beads[0].toes
    assert np.corrcoef(toes[:, 0, 0], wander(state.s_mm))[0, 1] > 0.9


def test_wall_bead_wets_it_and_a_bead_away_leaves_a_notch() -> None:
    # A flat-bottomed groove (narrow gap, vertical-ish walls at |y| = 6).
    s = np.arange(0.0, 10.0 + 1e-9, 0.5)
    frames = np.tile(np.eye(4), (len(s), 1, 1))
    frames[:, 0, 3] = s
    y = np.arange(-15.0, 15.0 + 1e-9, 0.05)
    z = np.clip((np.abs(y) - 6.0) / math.tan(math.radians(4)), 0.0, 25.0)
    state = FillState.from_profiles(s, frames, y, np.repeat(z[None], len(s), 0))
    path = straight_path(10.0)
    area = np.full(len(path), 18.0)
    wall = state.deposit(path, area, BeadShape(), offset_mm=-4.5)
    middle = state.deposit(path, area, BeadShape(), offset_mm=0.0)
    assert np.all(wall.sidewall_margin_mm()[:, 0] <= 0)
    margin = middle.sidewall_margin_mm()[:, 0]
    w, _ = BeadShape().flat_size(18.0)
    assert margin == pytest.approx(6.0 - w / 2, abs=0.06)  # the flat-plate toe on the floor
    # The 7 points see the notch: the bottom corner stays at the wall's foot.
    points = middle.groove_points(5)
    assert points[1] == pytest.approx([-6.0, 0.0], abs=0.06)


def test_bead_outside_the_groove_is_refused() -> None:
    state = analytic_state()
    with pytest.raises(SceneError, match="offset_mm"):
        state.deposit(straight_path(), np.full(401, 20.0), BeadShape(), offset_mm=30.0)


@pytest.fixture(scope="module")
def v_part():
    from seamtrack.workpiece.loader import load_workpiece

    return load_workpiece(
        "cad/v_groove.py",
        tolerance_mm=0.02,
        plate_thickness_mm=20.0,
        root_gap_mm=2.0,
        root_face_mm=1.0,
        seam_length_mm=40.0,
    )


def test_sections_of_cad_v_groove_match_the_analytic_groove(v_part) -> None:
    state = FillState.from_mesh(v_part.mesh, v_part.seam)
    assert np.all(np.diff(state.s_mm) <= 0.5 + 1e-9)
    bevel = 19.0 * TAN30
    for i in (0, state.n_stations // 2, state.n_stations - 1):
        pts = state.groove_points(i)
        assert pts[0] == pytest.approx([-1 - bevel, 20.0], abs=0.03)
        assert pts[6] == pytest.approx([1 + bevel, 20.0], abs=0.03)
        assert pts[1] == pytest.approx([-1.0, 0.0], abs=0.06)  # root gap 2 mm on the backing
        assert pts[5] == pytest.approx([1.0, 0.0], abs=0.06)
        # The walls: 30 deg off vertical (60 deg included).
        y, z = state.y_mm, state.base_z[i]
        on_wall = (y < -2) & (z > 3) & (z < 17)
        slope = np.polyfit(y[on_wall], z[on_wall], 1)[0]
        assert math.degrees(math.atan(-1 / slope)) == pytest.approx(30.0, abs=0.1)
    assert state.remaining_area_mm2() == pytest.approx(2 * 20 + bevel * 19, rel=2e-3)


def test_fill_mesh_ray_cast_sees_the_state_surface(v_part) -> None:
    import trimesh

    from seamtrack.sensing.raycast import RayCaster

    state = FillState.from_mesh(v_part.mesh, v_part.seam)
    path = np.column_stack([np.linspace(-1, 41, 200), np.zeros(200), np.full(200, 15.0)])
    for offset in (0.0, -3.0, 3.0):
        state = state.deposit(path, np.full(200, 24.0), BeadShape(), offset_mm=offset)
    joined = trimesh.util.concatenate([v_part.mesh, state.mesh()])
    caster = RayCaster.from_mesh(joined)
    for i in (5, 40, 71):
        T = state.T_world_station[i]
        ys = np.linspace(-13.0, 13.0, 131)
        origins = T[:3, 3] + np.outer(ys, T[:3, 1]) + 40.0 * T[:3, 2]
        hits = caster.first_hit(origins, np.repeat(-T[None, :3, 2], len(ys), axis=0))
        assert hits.hit.all()
        z_hit = (hits.points - T[:3, 3]) @ T[:3, 2]
        z_state = np.interp(ys, state.y_mm, state.surface_z[i])
        # Beads where the state has them, the part where it has none (sealed seam, no slip).
        np.testing.assert_allclose(z_hit, z_state, atol=0.03)
    assert np.any(state.surface_z - state.base_z > 1.0)


@pytest.mark.parametrize(
    ("script", "params", "check"),
    [
        ("cad/narrow_gap.py", {"seam_length_mm": 30.0}, "narrow"),
        ("cad/v_groove_varying.py", {}, "varying"),
    ],
)
def test_new_cad_grooves_have_their_designed_sections(script, params, check) -> None:
    from seamtrack.workpiece.loader import load_workpiece

    part = load_workpiece(script, tolerance_mm=0.02, **params)
    state = FillState.from_mesh(part.mesh, part.seam)
    if check == "narrow":
        top = 6.0 + 25.0 * math.tan(math.radians(4))
        for i in (0, state.n_stations // 2):
            pts = state.groove_points(i)
            assert pts[0] == pytest.approx([-top, 25.0], abs=0.03)
            assert pts[6] == pytest.approx([top, 25.0], abs=0.03)
            assert pts[1] == pytest.approx([-6.0, 0.0], abs=0.06)
            assert pts[5] == pytest.approx([6.0, 0.0], abs=0.06)
        assert state.remaining_area_mm2() == pytest.approx((12.0 + 2 * top) / 2 * 25, rel=2e-3)
    else:
        bevel = 19.0 * TAN30
        gap = 4.0 + 2.0 * np.sin(2 * np.pi * state.s_mm / 300.0)
        width = state.top_corners[:, 1, 0] - state.top_corners[:, 0, 0]
        np.testing.assert_allclose(width, gap + 2 * bevel, atol=0.06)
        np.testing.assert_allclose(state.remaining_area_mm2(), gap * 20 + bevel * 19, rtol=3e-3)
        assert width.max() - width.min() == pytest.approx(4.0, abs=0.1)


def test_groove_points_of_a_partly_filled_v() -> None:
    state = analytic_state()
    path = straight_path()
    state = state.deposit(path, np.full(len(path), 30.0), BeadShape())
    every = state.all_groove_points()
    assert every.shape == (state.n_stations, 7, 2)
    np.testing.assert_allclose(every[7], state.groove_points(7))
    pts = every[7]
    # The bottom corners lie on the walls (z = (|y| - 1) / tan 30) where the bead's toes are,
    # the bottom points on the bead (above the root), all in order left to right.
    for corner in (pts[1], pts[5]):
        assert corner[1] == pytest.approx((abs(corner[0]) - 1.0) / TAN30, abs=0.1)
    assert np.all(np.diff(pts[:, 0]) >= 0)
    assert np.all(pts[2:5, 1] > 1.0)
    toes = state.beads[0].toes[7]
    assert pts[1, 0] == pytest.approx(toes[0, 0], abs=0.06)
    assert pts[5, 0] == pytest.approx(toes[1, 0], abs=0.06)


def test_sections_of_a_curved_v_groove_keep_its_shape() -> None:
    from seamtrack.workpiece.loader import load_workpiece

    part = load_workpiece(
        "cad/v_groove.py",
        tolerance_mm=0.02,
        plate_thickness_mm=20.0,
        root_gap_mm=2.0,
        path="arc",
        arc_radius_mm=150.0,
        seam_length_mm=60.0,
    )
    state = FillState.from_mesh(part.mesh, part.seam)
    bevel = 19.0 * TAN30
    np.testing.assert_allclose(state.top_corners[:, 0, 0], -1 - bevel, atol=0.03)
    np.testing.assert_allclose(state.top_corners[:, 1, 0], 1 + bevel, atol=0.03)
    np.testing.assert_allclose(state.remaining_area_mm2(), 2 * 20 + bevel * 19, rtol=5e-3)
    path = part.seam.interpolate(np.linspace(0, part.seam.length_mm, 300)) + [0, 0, 15.0]
    state = state.deposit(path, np.full(300, 24.0), BeadShape())
    laid = laid_areas(state, 0)
    assert laid == pytest.approx(24.0, rel=1e-6)
    np.testing.assert_allclose(state.beads[0].y_centre_mm, 0.0, atol=0.01)


def _sheet(state: FillState):
    """The empty groove's top surface as a triangle sheet (a stand-in for the part's mesh)."""
    import trimesh

    m, k = state.base_z.shape
    T = state.T_world_station
    verts = (
        T[:, None, :3, 3]
        + T[:, None, :3, 1] * state.y_mm[None, :, None]
        + T[:, None, :3, 2] * state.base_z[:, :, None]
    ).reshape(-1, 3)
    ii, kk = np.meshgrid(np.arange(m - 1), np.arange(k - 1), indexing="ij")
    a = (ii * k + kk).ravel()
    faces = np.concatenate(
        [np.column_stack([a, a + k, a + 1]), np.column_stack([a + 1, a + k, a + k + 1])]
    )
    return trimesh.Trimesh(verts, faces, process=False)


def test_sensor_rays_see_the_notch_a_bead_away_from_the_wall_leaves() -> None:
    import trimesh

    from seamtrack.sensing.raycast import RayCaster

    s = np.arange(0.0, 10.0 + 1e-9, 0.5)
    frames = np.tile(np.eye(4), (len(s), 1, 1))
    frames[:, 0, 3] = s
    y = np.arange(-15.0, 15.0 + 1e-9, 0.05)
    z = np.clip((np.abs(y) - 6.0) / math.tan(math.radians(4)), 0.0, 25.0)
    state = FillState.from_profiles(s, frames, y, np.repeat(z[None], len(s), 0))
    path = straight_path(10.0)
    state = state.deposit(path, np.full(len(path), 18.0), BeadShape(), offset_mm=0.0)
    caster = RayCaster.from_mesh(trimesh.util.concatenate([_sheet(state), state.mesh()]))
    i = 10
    T = state.T_world_station[i]
    ys = np.linspace(-7.5, 7.5, 151)
    origins = T[:3, 3] + np.outer(ys, T[:3, 1]) + 40.0 * T[:3, 2]
    hits = caster.first_hit(origins, np.repeat(-T[None, :3, 2], len(ys), axis=0))
    z_hit = (hits.points - T[:3, 3]) @ T[:3, 2]
    np.testing.assert_allclose(z_hit, np.interp(ys, y, state.surface_z[i]), atol=0.02)
    toe = state.beads[0].toes[i, 0, 0]
    notch = (ys > -6.0 + 0.1) & (ys < toe - 0.1)
    assert notch.sum() >= 5
    np.testing.assert_allclose(z_hit[notch], 0.0, atol=1e-3)  # the floor shows between wall and toe
    assert z_hit[np.argmin(np.abs(ys))] > 2.0  # the bead's crown
