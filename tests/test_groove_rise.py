"""The groove extractor's reads of a wall's foot and of a raised part
(seamtrack.features.groove._groove_rise, short_walls in seamtrack.features.groove._groove_fit).

Oracles: analytic notches, rounds and steps drawn point by point (u across the groove, v into
it), with seeded noise; a wall's line and its mirror built from known angles."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seamtrack.features.groove._groove_fit import MIRROR_DEG, short_walls
from seamtrack.features.groove._groove_rise import a_step, risen_level
from seamtrack.features.line_geometry import Line

SPACING = 0.028  # mm between points, the wide sensor's 2048 rays
TOL = 0.15


def _side(v_of_d, reach=1.6, noise=0.01, seed=0):
    """A left side's fill surface: u = d from its outer end, v = v_of_d(d) plus noise."""
    d = np.arange(0.0, reach, SPACING)
    rng = np.random.default_rng(seed)
    return d, v_of_d(d) + rng.normal(0.0, noise, len(d))


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize(("tip_in", "outer", "inner"), [(0.2, 3.0, 0.8), (0.3, 1.5, 0.6)])
def test_a_notch_is_read_at_its_tip(seed, tip_in, outer, inner):
    """A bead's toe on a U's round, seen over its last tenths of a millimetre: the outer
    flank (the round) rises ``outer`` times its run to the surface's end, the bead's flank
    ``inner`` times inwards. The level is the tip's within 0.03 mm (three times the points'
    noise), from either flank's slope."""
    tip = 10.0

    def v(d):
        return np.where(d <= tip_in, tip - outer * (tip_in - d), tip - inner * (d - tip_in))

    fu, fv = _side(v, seed=seed)
    level = risen_level(fu, fv, True, SPACING, TOL)
    assert level is not None and abs(level - tip) <= 0.03


@pytest.mark.parametrize("seed", range(3))
def test_a_bare_round_is_read_at_its_flat_bottom(seed):
    """An empty U: a 3 mm round rising from a flat bottom at v = 10 into the wall (the
    surface ends 1.2 mm up the round): the level is the bottom's within 0.02 mm (the flank
    crossing is not asked: the inner side does not rise)."""
    r, bottom, start = 3.0, 10.0, 2.4  # the round meets the bottom at d = start

    def v(d):
        x = np.clip(start - d, 0.0, None)
        return bottom - (r - np.sqrt(np.maximum(r * r - x * x, 0.0)))

    fu, fv = _side(v, reach=4.0, seed=seed)
    level = risen_level(fu, fv, True, SPACING, TOL)
    assert level is not None and level == pytest.approx(bottom, abs=0.02)


def test_a_gentle_rise_and_a_kink_are_no_round():
    """A root bead's concave face rising 0.3 times its run into the wall, and a bead's toe on
    the wall (the surface comes down to it): no level."""
    fu, fv = _side(lambda d: 10.0 - 0.3 * np.clip(0.8 - d, 0.0, None), seed=1)
    assert risen_level(fu, fv, True, SPACING, TOL) is None
    fu, fv = _side(lambda d: 10.0 - 0.5 * d, seed=2)
    assert risen_level(fu, fv, True, SPACING, TOL) is None


def _profile_with(piece):
    """A surface at v = 0 from u = -5 to 5 (0.05 mm apart), with ``piece`` (k, 2) in the
    middle, in profile order."""
    left = np.column_stack([np.arange(-5.0, -0.5, 0.05), np.zeros(90)])
    right = np.column_stack([np.arange(0.55, 5.0, 0.05), np.zeros(89)])
    points = np.vstack([left, piece, right])
    index = np.arange(len(left), len(left) + len(piece))
    return points, index


def test_a_blocks_side_is_a_step_and_a_streak_is_not():
    """A block's side joins the plate's level to the block's 3 mm above; a streak of 12
    points rising 1.5 mm out of a surface that runs on at one level across it is no step."""
    normal = np.array([0.0, 1.0])
    side = np.column_stack([np.linspace(-0.45, 0.5, 12), np.linspace(0.0, -3.0, 12)])
    points, index = _profile_with(side)
    points[index[-1] + 1 :, 1] = -3.0  # the block's top
    assert a_step(points, index, normal, np.zeros(len(points), dtype=bool))
    streak = np.column_stack([np.linspace(-0.45, 0.5, 12), np.linspace(-0.2, -1.7, 12)])
    points, index = _profile_with(streak)
    assert not a_step(points, index, normal, np.zeros(len(points), dtype=bool))


def _wall(top, foot, n=100):
    top, foot = np.asarray(top, float), np.asarray(foot, float)
    d = foot - top
    if d[0] < 0:
        d = -d
    d = d / math.hypot(*d)
    t = np.linspace(-0.5, 0.5, n) * math.hypot(*(foot - top))
    return Line(np.arange(n), 0.5 * (top + foot), d, t, 0.005)


def test_a_short_wall_off_the_others_mirror_gives_way_to_it():
    """A U's walls 10 deg off vertical: the right one seen as a 5 mm piece 4.9 deg off the
    left's mirror (a spike streak along the rays) is taken for hidden; two long walls 3 deg
    apart, or a short one within MIRROR_DEG, are both kept."""
    v = np.array([0.0, 1.0])
    fv = np.full(50, 16.0)  # the fill's level, v into the groove
    a = math.radians(10.0)
    left = _wall((-6.8, 0.0), (-4.0, 16.0))
    right_dir = math.radians(10.0 + 4.9)
    right = _wall((6.8, 0.0), (6.8 - 5.0 * math.sin(right_dir), 5.0 * math.cos(right_dir)))
    assert MIRROR_DEG < 4.9
    assert short_walls((left, right), fv, v) == (left, None)
    long_right = _wall((6.8, 0.0), (6.8 - 16.0 * math.tan(a + math.radians(3.0)), 16.0))
    assert short_walls((left, long_right), fv, v) == (left, long_right)
    near = math.radians(10.0 + 1.0)
    close = _wall((6.8, 0.0), (6.8 - 5.0 * math.sin(near), 5.0 * math.cos(near)))
    assert short_walls((left, close), fv, v) == (left, close)
