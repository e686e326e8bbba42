"""The V search's compiled line table (seamtrack.features.vgroove._v_search) against the Python
geometry it replaces in the V extractors (seamtrack.features.lines.collinear_groups; corner_with,
written here in plain Python; Line.step and Line.end), on synthetic profiles of every joint with
noise, outliers, dropouts, false reflections and tacks."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numpy.typing import NDArray

from seamtrack.features.line_geometry import Line
from seamtrack.features.lines import Segments, collinear_groups, segment_profile
from seamtrack.features.synthetic import Imperfections, synthetic_profile
from seamtrack.features.vgroove import _v_search as vs
from seamtrack.sensing.sensor import preset

FloatArray = NDArray[np.float64]
_JOINTS = ("v-groove", "square-butt", "fillet", "lap", "outside-corner")


def corner_with(
    line: Line, at_end: bool, others: list[Line], seg: Segments
) -> tuple[FloatArray, Line | None]:
    """The reference (plain Python on :class:`Line`) of the compiled corner search: where
    ``line`` ends and the neighbour it meets there: its crossing with a line of ``others``
    that meets it at that end (a visible corner, exact), else half a spacing beyond its
    last inlier (the edge lies between rays) and None."""
    # Scalars, not numpy: a handful of tests per neighbour, where numpy's per-call overhead
    # would dominate (the extractors call this four times per profile).
    cy, cz, dy, dz, t_first, t_last = line.scalars
    t_tip = t_last if at_end else t_first
    tip_y, tip_z = cy + t_tip * dy, cz + t_tip * dz
    reach = 3.0 * max(line.step(at_end), seg.spacing) + seg.tol
    cos_min = math.cos(math.radians(20))
    best, best_d, best_line = None, math.inf, None
    for other in others:
        if other is line:
            continue
        ocy, ocz, ody, odz, o_first, o_last = other.scalars
        if abs(dy * ody + dz * odz) > cos_min:
            continue  # within 20 deg: no corner
        det = dy * odz - dz * ody
        if abs(det) < 1e-9:
            continue
        s = ((ocy - cy) * odz - (ocz - cz) * ody) / det
        xy, xz = cy + s * dy, cz + s * dz
        d = math.hypot(xy - tip_y, xz - tip_z)
        if d > reach or d >= best_d:
            continue
        near_other = min(
            math.hypot(ocy + t * ody - xy, ocz + t * odz - xz) for t in (o_first, o_last)
        )
        reach_other = 3.0 * max(other.step(True), other.step(False), seg.spacing) + seg.tol
        if near_other <= reach_other:
            best, best_d, best_line = (xy, xz), d, other
    if best is None:
        return line.end(at_end), None
    return np.array(best), best_line


def _segments(joint: str, seed: int) -> Segments:
    rng = np.random.default_rng(seed)
    imperfections = Imperfections(
        noise_mm=0.03,
        outlier_fraction=0.01,
        dropout_runs=2,
        reflection_probability=0.5,
        tack_probability=0.3,
    )
    profile, _ = synthetic_profile(joint, preset("paper"), rng=rng, imperfections=imperfections)
    seg = segment_profile(profile)
    assert isinstance(seg, Segments), seg
    return seg


def _table(seg: Segments) -> vs.LineTable:
    return vs.new_table(vs.flat_lines(seg.lines))


def _line(tb: vs.LineTable, r: int) -> Line:
    a, c = tb.span[r, vs.START], tb.span[r, vs.COUNT]
    return Line(
        tb.index[a : a + c],
        tb.geo[r, vs.CY : vs.CZ + 1],
        tb.geo[r, vs.UY : vs.UZ + 1],
        tb.along[a : a + c],
        tb.geo[r, vs.RMS],
    )


@pytest.mark.parametrize("joint", _JOINTS)
@pytest.mark.parametrize("seed", range(4))
def test_groups_equal_collinear_groups(joint: str, seed: int) -> None:
    """The table's groups are collinear_groups' lines with enough inliers over min_arm mm,
    in the same order, with the same inliers and the same fits."""
    seg = _segments(joint, seed)
    expected = [g for g in collinear_groups(seg) if g.count >= 8 and g.extent >= 0.5]
    tb = _table(seg)
    records = vs.groups_of(seg.points, tb, len(seg.lines), seg.tol, 8, 0.5)
    assert len(records) == len(expected)
    for r, g in zip(records, expected, strict=True):
        line = _line(tb, int(r))
        np.testing.assert_array_equal(line.index, g.index)
        np.testing.assert_allclose(line.centroid, g.centroid, rtol=0, atol=1e-12)
        np.testing.assert_allclose(line.direction, g.direction, rtol=0, atol=1e-12)
        np.testing.assert_allclose(line.t, g.t, rtol=0, atol=1e-12)


@pytest.mark.parametrize("joint", _JOINTS)
@pytest.mark.parametrize("seed", range(4))
def test_corner_with_equals_python_corner_with(joint: str, seed: int) -> None:
    """Every piece's corner at either end among the pieces, as the Python corner_with finds it:
    the same neighbour and the same point; and the pieces' ends (Line.end)."""
    seg = _segments(joint, seed)
    tb = _table(seg)
    others = np.arange(len(seg.lines), dtype=np.int64)
    for k, line in enumerate(seg.lines):
        for at_end in (False, True):
            point, met = corner_with(line, at_end, seg.lines, seg)
            corner = vs.corner_with(tb, k, at_end, others, seg.spacing, seg.tol)
            assert corner.line == next((i for i, ln in enumerate(seg.lines) if ln is met), -1)
            np.testing.assert_allclose([corner.y, corner.z], point, rtol=0, atol=1e-12)
            np.testing.assert_allclose(vs.end(tb, k, at_end), line.end(at_end), atol=1e-12)
