"""Two-plate joints (square butt, lap): what lies between two plates.

Both extractors gather the pieces on one line into a plate however short they are (a stub cut
off by a false reflection stays on its plate) and read what lies between two plates: open
space (no points, walls, or a bottom far behind), a false reflection (a stray line cut off both
plates by jumps: its columns are unknown, not gap), or a surface attached to a plate. Where a
reflection covers a plate's edge, the edge is estimated under it. Registered in
:mod:`seamtrack.features.extractors` as ``"square-butt"`` and ``"lap"``.

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import cast

import numpy as np

from seamtrack.features.arrays import FloatArray, IntArray
from seamtrack.features.base import ExtractorBase
from seamtrack.features.line_geometry import LineThrough, Point
from seamtrack.features.lines import Segments
from seamtrack.features.plates._between_plates import Scale
from seamtrack.features.plates._plate_lines import PlateLimits
from seamtrack.features.plates._two_plate_search import (
    FIT,
    PIECE,
    PlainLimits,
    PlainScale,
    two_plates,
)
from seamtrack.sensing.profiles import Feature, Profile


@dataclass(frozen=True)
class _Hole:
    """What lies between two consecutive plate runs
    (:func:`seamtrack.features.plates._between_plates.hole`).

    ``open_mm``: how much of the stretch between their ends (along the left run's line)
    nothing covers: columns with no point (the laser fell through a gap or into a shadow), a
    wall, or a bottom far behind both plates. A false reflection's columns are unknown, not
    open. ``left`` / ``right``: where a stray line covers a run's end, the best estimate of
    its edge; None where the end is seen.
    """

    open_mm: float
    left: Point | None
    right: Point | None


@dataclass(frozen=True)
class _Pair:
    """The two plate runs a two-plate extractor chose (``a`` left of ``b`` in column
    order) as lines, where ``a`` ends and ``b`` starts (a visible corner, else half a step
    beyond the last inlier), what lies between them, whether it is an open gap, the step
    from ``a`` down to ``b`` (lap only; > 0: b is deeper), the confidence of the two lines
    (:func:`seamtrack.features.base.line_confidence`) and the share of the profile the model
    of a two-plate joint explains (each plate running on to the profile's end; what lies
    between them left out)."""

    a: LineThrough
    b: LineThrough
    end_a: Point
    start_b: Point
    hole: _Hole
    is_open: bool
    step: float
    confidence: float
    share: float


def _table(seg: Segments) -> tuple[IntArray, FloatArray, FloatArray, IntArray]:
    """The segmentation's table of pieces (:attr:`~seamtrack.features.lines.Segments.table`),
    built from its ``Line`` objects when it kept none."""
    if seg.table is not None:
        index, along, fits, bounds = seg.table
        return index, along, fits, bounds
    pieces = seg.lines
    fits = np.array(
        [(*ln.centroid, *ln.direction, ln.rms, ln.t[0], ln.t[-1]) for ln in pieces],
        dtype=np.float64,
    ).reshape(-1, 7)
    counts = [len(ln.index) for ln in pieces]
    return (
        np.concatenate([ln.index for ln in pieces]).astype(np.int64),
        np.concatenate([ln.t for ln in pieces]).astype(np.float64),
        fits,
        np.concatenate([[0], np.cumsum(counts)]).astype(np.int64),
    )


def _rms(seg: Segments, kind: int, piece: int, anchor: int, refit_rms: float) -> float:
    """A run's rms: its piece's, its refit's, or (a stub measured on its plate's line) the
    plate line's anchor's."""
    if kind == PIECE:
        return seg.line(piece).rms
    return refit_rms if kind == FIT else seg.line(anchor).rms


def _pair(
    seg: Segments,
    ex: SquareButtExtractor | LapExtractor,
    butt: bool,
    min_opening: float = 0.0,
) -> _Pair | None:
    """The plates of a profile and the pair of consecutive runs the extractor reads (None:
    no pair qualifies): :func:`seamtrack.features.plates._two_plate_search.two_plates` on the
    pieces as a table of arrays.

    Flat pieces (within ``max_tilt_deg`` of the y axis) that lie on one line form a plate
    line, however short each piece is (a stub cut off a plate by a reflection stays on its
    plate); a line spanning ``min_plate_mm`` is a plate. Column order then gives runs:
    consecutive pieces of one plate line stay one run unless (square butt) the hole between
    them is an open gap, so a reflection or a dropout never splits a plate. A plate line
    that shows only briefly between two stretches of another, or not parallel to it, or
    (square butt) ``min_bottom_mm`` behind it, is no plate there. A run long enough is its
    own line (two plates a hair out of line keep their heights); a stub is measured on its
    plate's line. Of the consecutive near-parallel runs whose facing ends lie within
    ``max_gap_mm``, a square butt takes the widest opening (an open gap before one a stray
    line covers), a lap the best supported pair with a step.
    """
    limits = PlateLimits(
        min_points=int(ex.min_points),
        min_plate_mm=float(ex.min_plate_mm),
        max_tilt_deg=float(ex.max_tilt_deg),
        max_gap_mm=float(ex.max_gap_mm),
        butt=butt,
        min_opening=float(min_opening),
        min_open_mm=float(getattr(ex, "min_open_mm", 0.0)),
        min_bottom_mm=float(getattr(ex, "min_bottom_mm", math.inf)),
        min_step_mm=float(getattr(ex, "min_step_mm", 0.0)),
    )
    scale = Scale(float(seg.tol), float(seg.spacing), float(seg.sigma))
    index, along, fits, bounds = _table(seg)
    # Plain tuples and arrays: numba types them at once (named tuples in Python, slowly).
    r = two_plates(
        seg.points, index, along, fits, bounds, seg.stray, cast(PlainLimits, tuple(limits)),
        cast(PlainScale, tuple(scale)),
    )  # fmt: skip
    if not r.found:
        return None
    hole = _Hole(
        r.open_mm,
        Point(r.left_hidden_y, r.left_hidden_z) if r.left_hidden else None,
        Point(r.right_hidden_y, r.right_hidden_z) if r.right_hidden else None,
    )
    rms_left = _rms(seg, r.left_kind, r.left_piece, r.left_anchor, r.left_rms)
    rms_right = _rms(seg, r.right_kind, r.right_piece, r.right_anchor, r.right_rms)
    # As base.line_confidence of the two runs' lines.
    explained = (0 + r.left_count + r.right_count) / max(len(seg.points), 1)
    fit = max(0.0, 1.0 - max(rms_left, rms_right) / seg.tol)
    conf = min(max(float(0.5 * explained + 0.5 * fit), 0.0), 1.0)  # NaN stays NaN
    return _Pair(
        LineThrough(r.left_cy, r.left_cz, r.left_dy, r.left_dz),
        LineThrough(r.right_cy, r.right_cz, r.right_dy, r.right_dz),
        Point(r.left_end_y, r.left_end_z),
        Point(r.right_end_y, r.right_end_z),
        hole,
        r.is_open,
        r.step,
        conf,
        r.share,
    )


def _foot(point: Point, line: LineThrough) -> Point:
    """``point`` projected normally onto ``line``."""
    py, pz = point
    cy, cz, dy, dz = line
    h = (py - cy) * -dz + (pz - cz) * dy
    return Point(py - h * -dz, pz - h * dy)


def _ray_hit(point: Point, line: LineThrough) -> Point | None:
    """Where the ray from the emitter (the origin) through ``point`` crosses ``line``, or
    None when (nearly) parallel (:func:`seamtrack.features.lines.intersect` of the ray and
    the line)."""
    py, pz = point
    norm = max(math.hypot(py, pz), 1e-300)
    uy, uz = py / norm, pz / norm
    by, bz, bdy, bdz = line
    d = uy * bdz - uz * bdy
    if abs(d) < 1e-9:
        return None
    s = ((by - 0.0) * bdz - (bz - 0.0) * bdy) / d
    return Point(0.0 + s * uy, 0.0 + s * uz)


@dataclass(frozen=True)
class SquareButtExtractor(ExtractorBase):
    """Square butt: two plates side by side with a gap and/or a high-low step between them.
    Seam: the midpoint of the two plate edges.

    Between two plates on one line the gap must be open over ``min_open_mm``: no points
    there (the laser falls through), walls, or a bottom at least ``min_bottom_mm`` behind
    (a backing). A stray line nearer the plates (a false reflection) is unknown, not gap: a
    plate interrupted only by one is a single plate. Where such a line covers a plate's
    edge, the edge is put in the middle of the covered stretch (confidence halved).
    """

    name: str = "square-butt"
    min_gap_mm: float = 0.3
    max_gap_mm: float = 6.0
    min_plate_mm: float = 1.0
    max_tilt_deg: float = 40.0
    min_open_mm: float = 0.15
    min_bottom_mm: float = 5.0
    max_step_ratio: float = 2.0

    def _extract(self, profile: Profile, seg: Segments) -> Feature | tuple[Feature, float]:
        min_opening = max(self.min_gap_mm, 3 * seg.tol)
        found = _pair(seg, self, True, min_opening)
        if found is None:
            return Feature.failed("no gap or step between two plates", joint=self.name)
        a, b, hole = found.a, found.b, found.hole
        # A run's edge: its corner or end, or where a stray line covers its end, the estimate
        # under it (on the run's line).
        ea = found.end_a if hole.left is None else _foot(hole.left, a)
        eb = found.start_b if hole.right is None else _foot(hole.right, b)
        _, _, dy, dz = a
        (ey_a, ez_a), (ey_b, ez_b) = ea, eb
        gap = abs((ey_b - ey_a) * dy + (ez_b - ez_a) * dz)
        step = abs((ey_b - ey_a) * -dz + (ez_b - ez_a) * dy)
        if step > self.max_step_ratio * max(gap, self.min_gap_mm):
            return Feature.failed(
                f"not a square butt: a step of {step:.2f} mm over a {gap:.2f} mm gap is an "
                "edge standing on a plate (a lap)",
                joint=self.name,
            )
        wrong = self._implausible(gap=gap)
        if wrong is not None:
            return wrong
        sure = found.is_open and hole.left is None and hole.right is None
        conf = found.confidence * (1.0 if sure else 0.5)
        feature = self._found(
            profile,
            np.array([0.5 * (ey_a + ey_b), 0.5 * (ez_a + ez_b)]),
            confidence=conf,
            edges_laser=np.array([ea, eb]),
            gap_mm=gap,
        )
        return feature, found.share


@dataclass(frozen=True)
class LapExtractor(ExtractorBase):
    """Lap: two parallel sheets with a step. Seam: the top sheet's edge projected normally
    onto the lower sheet (the corner where the edge meets it). Edge: the top sheet's edge.

    A sheet interrupted by a false reflection or a dropout stays one sheet. Where a stray
    line covers the top sheet's edge, the lower sheet's visible end gives the corner (or,
    when the corner lies in the edge's shadow, the ray over that end gives the edge); where
    it covers the lower sheet's end, the top edge's foot does (confidence halved).
    """

    name: str = "lap"
    min_step_mm: float = 0.3
    max_gap_mm: float = 3.0
    min_plate_mm: float = 2.0
    max_tilt_deg: float = 40.0

    def _extract(self, profile: Profile, seg: Segments) -> Feature | tuple[Feature, float]:
        found = _pair(seg, self, False)
        if found is None:
            return Feature.failed("no step between two parallel sheets", joint=self.name)
        a, b, step, hole = found.a, found.b, found.step, found.hole
        wrong = self._implausible(depth=abs(step))
        if wrong is not None:
            return wrong
        # The top sheet's edge and the lower sheet's end, seen (a corner or an end) or hidden
        # (the estimate under a stray line, on the run's line).
        top, lower, at_end = (a, b, True) if step > 0 else (b, a, False)
        top_seen, lower_seen = (
            (found.end_a, found.start_b) if at_end else (found.start_b, found.end_a)
        )
        top_hidden, lower_hidden = (hole.left, hole.right) if at_end else (hole.right, hole.left)
        # Away from the top sheet, along the lower one.
        away_y, away_z = (lower.dy, lower.dz) if at_end else (-lower.dy, -lower.dz)
        if top_hidden is None:
            edge = top_seen
            foot = _foot(edge, lower)
            # The ray over the top edge (from the emitter at the origin) lands on the lower
            # sheet at `shadow`: beyond the foot (away from the top sheet) the corner is in
            # shadow and the foot is the best estimate; otherwise the lower sheet is seen up
            # to the corner.
            shadow = _ray_hit(edge, lower)
            if lower_hidden is not None or (
                shadow is not None
                and (shadow.y - foot.y) * away_y + (shadow.z - foot.z) * away_z > 0.0
            ):
                seam = foot
            else:
                seam = lower_seen
        elif lower_hidden is None:
            # The lower sheet's visible end is the corner, or (in the edge's shadow) where
            # the ray over the hidden top edge lands.
            end = lower_seen
            over = _ray_hit(end, top)
            seam = end
            edge = _foot(top_hidden, top)
            if over is not None:
                landing = _foot(over, lower)
                if (landing.y - end.y) * away_y + (landing.z - end.z) * away_z < 0.0:
                    edge, seam = over, landing
        else:
            edge = _foot(top_hidden, top)
            seam = _foot(edge, lower)
        sure = top_hidden is None and lower_hidden is None
        feature = self._found(
            profile,
            np.array(seam),
            confidence=found.confidence * (1.0 if sure else 0.5),
            edges_laser=np.array([edge]),
        )
        return feature, found.share
