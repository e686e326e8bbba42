"""The groove extractor (issue 25): the 7 points of empty and partly filled grooves, its seam
reference, st.classify on filled grooves, and the other families refusing them.

Oracle: the synthetic grooves' exact geometry (seamtrack.features.synthetic_groove: the empty
groove's analytic corners, beads laid with seamtrack.workpiece.beads, the 7 points read off the
polylines and carried into the laser plane by the profile's pose), profiles drawn with the
real-sensor artefact model."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seamtrack.errors import PluginError
from seamtrack.features.classify import classify
from seamtrack.features.extractors import extractor
from seamtrack.features.synthetic import synthetic_profile
from seamtrack.features.synthetic_groove import (
    GROOVES,
    fill,
    groove,
    groove_points,
    groove_profile,
    remaining_area_mm2,
)
from seamtrack.sensing.sensor import preset

OTHERS = ("v-groove", "square-butt", "fillet", "lap", "outside-corner")


def _profiles(kind, layers, n, seed):
    g = groove(kind)
    out = []
    for i in range(n):
        rng = np.random.default_rng([layers, i, seed])
        s = fill(g, layers, bead_area_mm2=20.0, rng=rng, jitter_mm=0.5)[0] if layers else None
        out.append(
            groove_profile(
                g,
                s,
                rng=rng,
                roll_deg=rng.uniform(-5, 5),
                pitch_deg=rng.uniform(-5, 5),
                lateral_offset_mm=rng.uniform(-2, 2),
            )
        )
    return out


def _errors(kind, layers, n, seed):
    ex = extractor("groove")
    errs, found = [], 0
    for profile, truth in _profiles(kind, layers, n, seed):
        f = ex(profile)
        if f:
            found += 1
            assert f.edges_laser.shape == (7, 2)
            errs.append(np.hypot(*(f.edges_laser - truth.points_laser).T))
    return found, np.array(errs)


# ----------------------------------------------------------------- the synthetic truth
def test_empty_grooves_have_their_analytic_points():
    v = groove("v", angle_deg=60.0, gap_mm=2.0, thickness_mm=20.0)
    w = 1.0 + 20.0 * math.tan(math.radians(30.0))
    pts = groove_points(v)
    assert pts[0] == pytest.approx([-w, 0.0]) and pts[6] == pytest.approx([w, 0.0])
    assert pts[1] == pytest.approx([-1.0, -20.0]) and pts[5] == pytest.approx([1.0, -20.0])
    assert pts[2:5, 1] == pytest.approx([-20.0] * 3)
    assert v.area_mm2 == pytest.approx(0.5 * (2.0 + 2 * w) * 20.0)
    ng = groove("narrow-gap")
    assert groove_points(ng)[1] == pytest.approx([-6.0, -25.0])


def test_each_bead_takes_its_area_from_the_groove():
    """Mass conservation through lay_bead: the remaining area drops by the bead's area."""
    for kind in GROOVES:
        g = groove(kind)
        _, history = fill(g, 2, bead_area_mm2=20.0)
        before = g.area_mm2
        for s in history:
            after = remaining_area_mm2(s, g.top)
            assert before - after == pytest.approx(20.0, rel=1e-6)
            before = after


# ----------------------------------------------------------------- accuracy
#: The draws pooled for a p95: 3 seeds of 20 profiles a fill state (420 point errors). A p95
#: of one seed's 20 profiles (7 of its 140 errors above it) moves with two bad profiles: on
#: seeds 11-22 the narrow gap's and the U's single-seed p95 reach 0.35 and 0.49 mm at a state
#: where every 3-seed pool stays within 0.18 mm (docs/extractors.md).
SEEDS = (11, 12, 13)


def _pooled(kind, layers):
    found, errors = 0, []
    for seed in SEEDS:
        n, e = _errors(kind, layers, 20, seed)
        found, errors = found + n, errors + list(e)
    return found, np.concatenate(errors)


@pytest.mark.parametrize("layers", range(10))
def test_v_groove_points_within_0_2_mm_p95_at_every_fill_state(layers):
    """60 deg V, 20 mm plate, 2 mm root gap on a backing, 0..6 layers of 20 mm^2 beads (the
    last leaves about a third of the groove), 7 and 8 (90 and 50 mm^2 left: the last fill
    layers) and 9 (crowned: the fill's middle 1.4 mm over the plates, a sliver left at a
    wall; a buried wall's foot is its top corner), real-sensor artefacts, tilts +-5 deg:
    every profile found (no crown refused as "a raised part": a spike streak standing out
    of it is no block's side) and the 7 points' errors pooled p95 <= 0.2 mm."""
    found, e = _pooled("v", layers)
    assert found == 20 * len(SEEDS)
    assert np.percentile(e, 95) <= 0.2


# The quantized wide sensor with 800 rays, as on multipass-varying-gap: its pixel steps split a
# plate or a wall into pieces. (root gap, lateral offset, roll, standoff); the first three put a
# plate's last step between it and the wall (the plate ended 1.3 mm short of its corner, or its
# short outer piece stood alone), the fourth split a wall 3.1 mm under its corner (the scan
# pass of that job: its lower piece was taken for fill, the bottom 10 mm up the wall).
QUANTIZED_V = [
    (4.16, 1.643, 0.175, 91.116),
    (4.481, -1.5, -0.604, 94.47),
    (4.034, 2.873, 0.548, 89.0),
    (5.419, 2.309, 0.328, 92.364),
]


def _quantized_v(gap, offset, roll, standoff):
    g = groove("v", angle_deg=60.0, gap_mm=gap, thickness_mm=20.0)
    return groove_profile(g, rng=np.random.default_rng(0), artefacts=None, sensor=preset("wide"),
                          rays=800, lateral_offset_mm=offset, roll_deg=roll,
                          standoff_mm=standoff)  # fmt: skip


@pytest.mark.parametrize("case", QUANTIZED_V)
def test_a_quantized_empty_vs_steps_are_plate_and_wall(case):
    """An empty V with a 4-5.4 mm root gap, pixel-quantized (no other artefact): the 7
    points within 0.1 mm of the analytic ones (a plate's step is plate, a wall's pieces one
    wall)."""
    profile, truth = _quantized_v(*case)
    f = extractor("groove")(profile)
    assert f and np.hypot(*(f.edges_laser - truth.points_laser).T).max() <= 0.1


def test_quantized_empty_vs_at_random_poses():
    """60 empty Vs, root gap 2-6 mm, offset +-3 mm, roll +-3 deg, standoff 85-95 mm, quantized:
    every profile found, its 7 points within 0.1 mm."""
    rng = np.random.default_rng(7)
    for _ in range(60):
        case = (rng.uniform(2, 6), rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(85, 95))
        profile, truth = _quantized_v(*case)
        f = extractor("groove")(profile)
        assert f, case
        assert np.hypot(*(f.edges_laser - truth.points_laser).T).max() <= 0.1, case


def test_a_wide_layers_two_beads_leave_a_valley_not_a_wall_foot():
    """The V filled 7 layers deep, then a wide layer's first two beads (16 mm^2, width 2x
    height) against the walls: a 4 mm deep valley between them and a notch at each wall.
    The valley is fill surface (the middle bottom point in it, within 0.3 mm on 18 of 20
    profiles) and a bottom corner the wall's foot in its notch, on the wall's line (within
    1 mm on 19 of 20; before, 3 profiles put it on the bead's flank, 1.7-2 mm off)."""
    from seamtrack.workpiece import beads

    g = groove("v")
    s = fill(g, 7, bead_area_mm2=20.0)[0]
    pts = groove_points(g, s)
    shape = beads.BeadShape(kind="parabola", width_to_height=2.0)
    width = 2.0 * math.sqrt(16.0 / (2 / 3 * 2.0))
    for y in (pts[1][0] + 0.4 * width, pts[5][0] - 0.4 * width):
        s = np.asarray(beads.lay_bead(s, float(y), 16.0, shape))
    y = np.linspace(pts[1][0] + 0.4 * width, pts[5][0] - 0.4 * width, 400)
    z = np.interp(y, s[:, 0], s[:, 1])
    assert z.max() - z.min() > 3.5  # the valley
    ex = extractor("groove")
    middle, corners = [], []
    for i in range(20):
        rng = np.random.default_rng([i, 99])
        profile, truth = groove_profile(g, s, rng=rng, roll_deg=rng.uniform(-5, 5),
                                        pitch_deg=rng.uniform(-5, 5),
                                        lateral_offset_mm=rng.uniform(-2, 2))  # fmt: skip
        f = ex(profile)
        assert f
        e = np.hypot(*(f.edges_laser - truth.points_laser).T)
        middle.append(e[3])
        corners.append(max(e[1], e[5]))
    assert np.sum(np.array(middle) <= 0.3) >= 18
    assert np.sum(np.array(corners) <= 1.0) >= 19


def test_a_crowned_fill_reports_its_area_signed():
    """The crowned V (9 layers), real-sensor artefacts: the remaining area is the signed area
    between the top corners' line and the surface (metal above the line counts against it),
    within 2 mm^2 (a low flat block, 2 mm over the plates, passes for such a cap: open)."""
    g = groove("v")
    s = fill(g, 9, bead_area_mm2=20.0)[0]
    profile, truth = groove_profile(g, s, rng=np.random.default_rng(0))
    f = extractor("groove")(profile)
    (y0, _), (y1, _) = g.top
    y = np.linspace(y0, y1, 4001)
    signed = float(np.trapezoid(-np.interp(y, s[:, 0], s[:, 1]), y))  # plates' top at z = 0
    assert signed < 0.5 * truth.area_mm2  # crowned: more metal above the line than gap below
    assert f and f.area_mm2 == pytest.approx(signed, abs=2.0)


@pytest.mark.parametrize("kind", ["narrow-gap", "u"])
@pytest.mark.parametrize("layers", range(7))
def test_narrow_gap_and_u_points_within_0_2_mm_p95_at_every_fill_state(kind, layers):
    """Narrow gap (walls 4 deg off vertical, 25 mm deep, 12 mm) and U (10 deg walls, 3 mm
    root radius, 8 mm) with 0..6 layers, the V's draw (real-sensor artefacts, tilts +-5 deg,
    offset +-2 mm): every profile found and the 7 points' errors pooled p95 <= 0.2 mm (the
    issue's bound). A corner no ray lights (under a hidden wall, in the notch between a
    bead's flank and the wall) is where the wall's line and the surface's line meet; a
    bead's toe on the U's round, where the round's and the bead's flanks cross."""
    found, e = _pooled(kind, layers)
    assert found == 20 * len(SEEDS)
    assert np.percentile(e, 95) <= 0.2


def test_a_u_grooves_bottom_corner_rides_its_wall_with_the_fill():
    """The U's convention (seamtrack.features.synthetic_groove): the bottom corner is the wall's
    line at the level where the fill meets the round, so the virtual sharp corner for the
    empty groove and a point of the wall's line just above the bead's toe on the round; the
    analytic wall line through the top corner and the virtual foot is the oracle."""
    g = groove("u")
    top, foot = g.top[0], g.foot[0]
    assert groove_points(g)[1] == pytest.approx(foot)
    s = fill(g, 1, bead_area_mm2=20.0)[0]
    corner = groove_points(g, s)[1]
    assert foot[1] < corner[1] < foot[1] + 3.0 * math.cos(math.radians(10.0))  # in the round
    d = foot - top
    off = (corner - top) @ np.array([-d[1], d[0]]) / math.hypot(*d)
    assert abs(off) < 1e-9  # on the wall's line
    y = np.linspace(corner[0], corner[0] + 1.0, 2001)
    assert np.interp(y, s[:, 0], s[:, 1]).min() == pytest.approx(corner[1], abs=0.02)


def test_remaining_area_is_measured():
    """Noise-free: the area of the polygon the extractor reads is within 3 % of the truth."""
    g = groove("v")
    s = fill(g, 3, bead_area_mm2=20.0)[0]
    profile, truth = groove_profile(g, s, rng=np.random.default_rng(0), artefacts=None)
    f = extractor("groove")(profile)
    assert f.area_mm2 == pytest.approx(truth.area_mm2, rel=0.03)


# ----------------------------------------------------------------- reference
@pytest.mark.parametrize(("reference", "row"), [("centre", 3), ("left", 1), ("right", 5)])
def test_the_reference_picks_the_seam_point(reference, row):
    profile, truth = _profiles("v", 2, 1, 5)[0]
    f = extractor("groove", reference=reference)(profile)
    assert f and f.joint == "groove"
    assert f.point_laser == pytest.approx(f.edges_laser[row])
    assert np.hypot(*(f.point_laser - truth.points_laser[row])) <= 0.3


def test_an_unknown_reference_is_refused():
    with pytest.raises(PluginError) as err:
        extractor("groove", reference="middle")
    assert err.value.field == "extractor.reference"


# ----------------------------------------------------------------- which joint
@pytest.mark.parametrize("kind", GROOVES)
def test_classify_names_a_filled_groove_groove(kind):
    profiles = [p for layers in (1, 3) for p, _ in _profiles(kind, layers, 5, 21)]
    assert np.mean([classify(p)[0] == "groove" for p in profiles]) >= 0.9


def test_classify_names_an_empty_v_v_groove_and_a_wide_flat_bottom_groove():
    v = [p for p, _ in _profiles("v", 0, 5, 22)]
    assert all(classify(p)[0] == "v-groove" for p in v)
    ng = [p for p, _ in _profiles("narrow-gap", 0, 5, 22)]
    assert all(classify(p)[0] == "groove" for p in ng)
    assert all(extractor("groove")(p) for p in v)  # asked directly it answers on a V


@pytest.mark.parametrize("kind", GROOVES)
def test_other_families_refuse_a_filled_groove_with_a_reason(kind):
    profiles = [p for layers in (1, 2, 4) for p, _ in _profiles(kind, layers, 6, 23)]
    for name in OTHERS:
        answers = [extractor(name)(p) for p in profiles]
        assert np.mean([bool(f) for f in answers]) <= 0.06, name
        assert all(f.reason for f in answers if not f)


def test_v_groove_says_why_it_refuses_beads():
    answers = [extractor("v-groove")(p) for p, _ in _profiles("v", 2, 6, 24)]
    refused = [f for f in answers if not f]
    assert len(refused) >= 5
    assert all("not a v-groove" in f.reason or "pair of lines" in f.reason for f in refused)


@pytest.mark.parametrize("shape", ["flat", "block", "fillet", "lap", "outside-corner"])
def test_no_groove_where_there_is_none(shape):
    profile, _ = synthetic_profile(shape, preset("paper"), roll_deg=4.0)
    f = extractor("groove")(profile)
    assert not f and f.reason
