"""Beads in a cross-section: mass conservation, the three shapes, conforming to a surface."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seamtrack.errors import SceneError
from seamtrack.workpiece.beads import (
    BEAD_KINDS,
    BeadShape,
    bead_area_mm2,
    bead_polygon,
    check_bead_fits,
    groove_capacity_mm2,
    lay_bead,
    lay_beads_on_grid,
    polygon_area_mm2,
)

FLAT = np.array([[-40.0, 0.0], [40.0, 0.0]])


def v_groove(thickness=20.0, angle_deg=60.0, gap=2.0, width=40.0):
    """Analytic V-groove top surface (y, z), root gap on a backing at z = 0."""
    half = thickness * math.tan(math.radians(angle_deg) / 2)
    g = gap / 2
    return np.array(
        [
            [-width, thickness],
            [-g - half, thickness],
            [-g, 0.0],
            [g, 0.0],
            [g + half, thickness],
            [width, thickness],
        ]
    )


def test_bead_area_matches_mass_conservation_example() -> None:
    # d 1.2 mm, 8 m/min, 6 mm/s, 0.97: 0.97 * pi * 0.36 * 133.3 / 6 = 24.38 mm^2
    a = bead_area_mm2(1.2, 8000 / 60, 6.0, 0.97)
    assert a == pytest.approx(0.97 * math.pi * 1.2**2 / 4 * (8000 / 60) / 6.0, rel=1e-12)
    assert a == pytest.approx(24.38, abs=0.01)
    slow = bead_area_mm2(1.2, 8000 / 60, np.array([3.0, 6.0]), 0.97)
    assert slow[0] == pytest.approx(2 * slow[1])  # a torch that slows down lays a fatter bead


@pytest.mark.parametrize(
    ("args", "field"),
    [
        ((1.2, 0.0, 6.0, 0.97), "process.wire_feed_m_min"),
        ((-1.0, 100.0, 6.0, 0.97), "process.wire_diameter_mm"),
        ((1.2, 100.0, math.nan, 0.97), "travel_speed_mm_s"),
        ((1.2, 100.0, 6.0, 1.2), "process.deposition_efficiency"),
    ],
)
def test_bead_area_refuses_bad_input(args, field) -> None:
    with pytest.raises(SceneError) as err:
        bead_area_mm2(*args)
    assert err.value.field == field


def test_shape_refuses_bad_input() -> None:
    with pytest.raises(SceneError, match="process.bead_shape"):
        BeadShape("ellipse")
    with pytest.raises(SceneError, match="width_to_height"):
        BeadShape("parabola", width_to_height=0.0)
    with pytest.raises(SceneError, match="wetting_angle"):
        BeadShape("parabola", wetting_angle_rad=0.5)
    with pytest.raises(SceneError, match="wetting_angle"):
        BeadShape("arc", wetting_angle_rad=2.0)


def test_area_factors_are_the_analytic_integrals() -> None:
    # Integrate each flat-plate profile numerically: A / (w h).
    for kind, expected in (("parabola", 2 / 3), ("cosine", 2 / math.pi)):
        shape = BeadShape(kind, 3.0)
        w, h = 3.0, 1.0
        y = np.linspace(-w / 2, w / 2, 200001)
        z = h + shape.cap(y, w, h)
        assert np.trapezoid(z, y) / (w * h) == pytest.approx(expected, rel=1e-8)
        assert shape.area_factor == pytest.approx(expected)
    # Circular segment: R^2 (phi - sin phi) / 2 with chord w = 2 R sin(phi/2).
    alpha = math.radians(50)
    arc = BeadShape("arc", wetting_angle_rad=alpha)
    r = 2.0
    w, h = 2 * r * math.sin(alpha), r * (1 - math.cos(alpha))
    assert arc.ratio == pytest.approx(w / h)
    assert arc.area_factor * w * h == pytest.approx(r**2 * (2 * alpha - math.sin(2 * alpha)) / 2)


@pytest.mark.parametrize("kind", BEAD_KINDS)
def test_flat_plate_bead_has_its_width_to_height(kind) -> None:
    shape = BeadShape(kind, 3.5)
    new = lay_bead(FLAT, 1.0, 20.0, shape)
    toes = new[new[:, 1] > 0]
    height = new[:, 1].max()
    width = toes[:, 0].max() - toes[:, 0].min()
    assert width / height == pytest.approx(3.5, rel=2e-2)
    assert shape.area_factor * width * height == pytest.approx(20.0, rel=2e-2)
    assert new[np.argmax(new[:, 1]), 0] == pytest.approx(1.0, abs=0.05)


def _surfaces(kind):
    shape = BeadShape(kind, 3.0)
    plate = FLAT
    groove = v_groove()
    layered = lay_bead(lay_bead(groove, -1.5, 20.0, shape), 2.0, 20.0, shape)
    return shape, {"flat": plate, "v-groove": groove, "on beads": layered}


@pytest.mark.parametrize("kind", BEAD_KINDS)
@pytest.mark.parametrize("where", ["flat", "v-groove", "on beads"])
def test_lay_bead_conserves_area(kind, where) -> None:
    shape, surfaces = _surfaces(kind)
    old = surfaces[where]
    for y_centre, area in ((0.0, 24.4), (-3.0, 12.0), (4.0, 30.0)):
        new = lay_bead(old, y_centre, area, shape)
        laid = polygon_area_mm2(bead_polygon(old, new))
        assert laid == pytest.approx(area, rel=1e-6)
        # The old surface stays where the bead is not, and nothing goes below it.
        z_old = np.interp(new[:, 0], old[:, 0], old[:, 1])
        assert np.all(new[:, 1] >= z_old - 1e-9)


def test_grid_beads_conserve_the_nodal_area() -> None:
    y = np.arange(-20.0, 20.0, 0.1)
    groove = v_groove(width=20.0)
    z = np.interp(y, groove[:, 0], groove[:, 1])[None, :].repeat(5, axis=0)
    areas = np.array([10.0, 20.0, 30.0, 40.0, 0.0])
    out = lay_beads_on_grid(y, z, np.array([-2.0, 0.0, 1.0, 3.0, 0.0]), areas, BeadShape())
    nodal = np.trapezoid(out.z_new - z, y, axis=1)
    assert nodal == pytest.approx(areas, rel=1e-6, abs=1e-9)
    assert out.lo[-1] > out.hi[-1]  # no bead where the area is zero


def test_bead_against_wall_wets_it_and_one_away_leaves_a_notch() -> None:
    shape = BeadShape("parabola", 3.0)
    # Narrow groove with vertical-ish walls at y = +-6, floor at 0, 25 mm deep.
    groove = np.array([[-20, 25], [-6.5, 25], [-6, 0], [6, 0], [6.5, 25], [20, 25]], float)
    wall_bead = lay_bead(groove, -4.5, 20.0, shape)
    covered = wall_bead[:, 1] > np.interp(wall_bead[:, 0], *groove.T) + 1e-9
    left = wall_bead[np.flatnonzero(covered)[0] - 1]
    assert left[1] > 0.1  # the toe climbed the wall
    wall_y = -6 - 0.5 * left[1] / 25
    assert left[0] == pytest.approx(wall_y, abs=1e-6)
    away = lay_bead(groove, 0.0, 20.0, shape)
    covered = away[:, 1] > np.interp(away[:, 0], *groove.T) + 1e-9
    left_toe = away[np.flatnonzero(covered)[0] - 1]
    assert left_toe[1] == pytest.approx(0.0, abs=1e-9)  # it sits on the floor
    assert left_toe[0] > -6 + 1.0  # a notch more than 1 mm wide stays at the wall


def test_groove_capacity_and_the_fit_check() -> None:
    groove = v_groove(thickness=20.0, angle_deg=60.0, gap=2.0)
    half = 20 * math.tan(math.radians(30))
    expected = 2 * 20 + 20 * half  # gap rectangle + two triangles
    cap = groove_capacity_mm2(groove, groove[1], groove[4])
    assert cap == pytest.approx(expected, rel=1e-12)
    check_bead_fits(cap - 1, cap)
    with pytest.raises(SceneError, match="larger than the groove"):
        check_bead_fits(cap + 1, cap, field="passes.wire_feed_m_min")


def test_lay_bead_refuses_bad_input() -> None:
    shape = BeadShape()
    with pytest.raises(SceneError, match="y_centre_mm"):
        lay_bead(FLAT, 100.0, 10.0, shape)
    with pytest.raises(SceneError, match="area_mm2"):
        lay_bead(FLAT, 0.0, -1.0, shape)
    with pytest.raises(SceneError, match="surface_yz"):
        lay_bead(FLAT[::-1], 0.0, 1.0, shape)


def test_bead_held_at_a_ridge_keeps_its_area() -> None:
    # A floor, a low ridge, then a deep pocket: a rising cap overflows the ridge with a jump in
    # area; a bead whose area falls in the jump stays on its side (dammed), exact in area.
    surface = np.array(
        [
            [-12, 10],
            [-10, 10],
            [-9.9, 0],
            [2, 0],
            [2.5, 1.0],
            [3, 0.9],
            [3.2, -5],
            [6, -5],
            [6.1, 10],
            [12, 10],
        ],
        float,
    )
    shape = BeadShape("parabola", 3.0)
    y = np.arange(-12.0, 12.0, 0.05)
    z = np.interp(y, surface[:, 0], surface[:, 1])
    dammed = []
    for area in (10.0, 20.0, 30.0):
        new = lay_bead(surface, -1.0, area, shape)
        assert polygon_area_mm2(bead_polygon(surface, new)) == pytest.approx(area, rel=1e-6)
        grid = lay_beads_on_grid(y, z[None], [-1.0], [area], shape)
        assert np.trapezoid(grid.z_new[0] - z, y) == pytest.approx(area, rel=1e-6)
        dammed.append(bool(grid.dammed[0]))
    assert dammed == [False, True, False]
