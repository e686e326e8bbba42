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

import numpy as np
from numpy.typing import NDArray

from seamtrack.features.base import Zone, _Base, _confidence, explained
from seamtrack.features.lines import (
    Line,
    Segments,
    corner_or_end,
)
from seamtrack.features.psheets import FIT, PIECE, two_plates
from seamtrack.sensing.profiles import Feature, Profile

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class _Hole:
    """What lies between two consecutive plate runs (:func:`_hole`).

    ``open_mm``: how much of the stretch between their ends (along the left run's line)
    nothing covers: columns with no point (the laser fell through a gap or into a shadow), a
    wall, or a bottom far behind both plates. A false reflection's columns are unknown, not
    open. ``left`` / ``right``: where a stray line covers a run's end, the best estimate of
    its edge (:func:`_hidden_edge`); None where the end is seen.
    """

    open_mm: float
    left: FloatArray | None
    right: FloatArray | None


def _floats(line: Line) -> tuple[float, float, float, float]:
    """A line's centroid (y, z) and direction (y, z) as floats: the tests on lines below are a
    handful of scalar operations, where numpy's per-call overhead on 2-vectors would
    dominate."""
    (cy, cz), (dy, dz) = line.centroid.tolist(), line.direction.tolist()
    return cy, cz, dy, dz


@dataclass(frozen=True)
class _Pair:
    """The two plate runs a two-plate extractor chose (left, right in column order), what
    lies between them, and for a lap the step from ``a`` down to ``b`` (> 0: b is deeper)."""

    a: Line
    b: Line
    hole: _Hole
    is_open: bool
    step: float


def _run(
    seg: Segments,
    kind: int,
    piece: int,
    anchor: int,
    fit: list[float],
    index: NDArray[np.intp],
    t: FloatArray,
) -> Line:
    """A run's line (:func:`seamtrack.features.psheets.two_plates`): a long piece as it is,
    a refit of its pieces' inliers (``fit``: cy, cz, dy, dz, rms), or those inliers
    measured on the plate's line (``anchor``'s; a stub)."""
    if kind == PIECE:
        return seg.lines[piece]
    if kind == FIT:
        return Line(index, np.array(fit[:2]), np.array(fit[2:4]), t, fit[4])
    line = seg.lines[anchor]
    return Line(index, line.centroid, line.direction, t, line.rms)


def _pair(
    seg: Segments,
    ex: SquareButtExtractor | LapExtractor,
    butt: bool,
    min_opening: float = 0.0,
) -> _Pair | None:
    """The plates of a profile and the pair of consecutive runs the extractor reads (None:
    no pair qualifies): :func:`seamtrack.features.psheets.two_plates` on the pieces as flat
    arrays.

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
    lines = seg.lines
    counts = np.array([len(ln.index) for ln in lines], dtype=np.int64)
    index = np.concatenate([ln.index for ln in lines])
    along = np.concatenate([ln.t for ln in lines])
    geo = np.concatenate([x for ln in lines for x in (ln.centroid, ln.direction)])
    ints, out, a_index, a_t, b_index, b_t = two_plates(
        seg.points, index, along, counts, geo, int(ex.min_points), float(ex.min_plate_mm),
        float(ex.max_tilt_deg), float(ex.max_gap_mm), float(seg.tol), float(seg.spacing),
        float(seg.sigma), butt, float(min_opening),
        float(getattr(ex, "min_open_mm", 0.0)), float(getattr(ex, "min_bottom_mm", math.inf)),
        float(getattr(ex, "min_step_mm", 0.0)),
    )  # fmt: skip
    (ra, _, kind_a, kind_b, piece_a, piece_b, anchor_a, anchor_b, _, _,
     is_open, left, right) = ints.tolist()  # fmt: skip
    if ra < 0:
        return None
    floats = out.tolist()
    open_mm, ly, lz, ry, rz, step = floats[:6]
    hole = _Hole(
        open_mm, np.array([ly, lz]) if left else None, np.array([ry, rz]) if right else None
    )
    return _Pair(
        _run(seg, kind_a, piece_a, anchor_a, floats[6:11], a_index, a_t),
        _run(seg, kind_b, piece_b, anchor_b, floats[11:16], b_index, b_t),
        hole,
        bool(is_open),
        step,
    )


def _edge(
    line: Line, at_end: bool, hidden: FloatArray | None, others: list[Line], seg: Segments
) -> FloatArray:
    """A run's edge: its corner or end, or where a stray line covers its end, the estimate
    of :func:`_hole` (on the run's line)."""
    if hidden is None:
        return corner_or_end(line, at_end, others, seg)
    return _foot(hidden, line)


@dataclass(frozen=True)
class SquareButtExtractor(_Base):
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
        others = [ln for ln in seg.lines if ln.count >= self.min_points]
        ea = _edge(a, True, hole.left, others, seg)
        eb = _edge(b, False, hole.right, others, seg)
        _, _, dy, dz = _floats(a)
        (ey_a, ez_a), (ey_b, ez_b) = ea.tolist(), eb.tolist()
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
        conf = _confidence([a, b], seg) * (1.0 if sure else 0.5)
        feature = self._found(
            profile, 0.5 * (ea + eb), confidence=conf, edges_laser=np.array([ea, eb]), gap_mm=gap
        )
        return feature, explained(seg, _two_plates(seg, a, b))


@dataclass(frozen=True)
class LapExtractor(_Base):
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
        others = [ln for ln in seg.lines if ln.count >= self.min_points]
        top, lower, at_end = (a, b, True) if step > 0 else (b, a, False)
        top_hidden, lower_hidden = (hole.left, hole.right) if at_end else (hole.right, hole.left)
        # Away from the top sheet, along the lower one.
        away = lower.direction if at_end else -lower.direction
        if top_hidden is None:
            edge = corner_or_end(top, at_end, others, seg)
            foot = _foot(edge, lower)
            # The ray over the top edge (from the emitter at the origin) lands on the lower
            # sheet at `shadow`: beyond the foot (away from the top sheet) the corner is in
            # shadow and the foot is the best estimate; otherwise the lower sheet is seen up
            # to the corner.
            shadow = _ray_hit(edge, lower)
            if lower_hidden is not None or (
                shadow is not None and float((shadow - foot) @ away) > 0.0
            ):
                seam = foot
            else:
                seam = corner_or_end(lower, not at_end, others, seg)
        elif lower_hidden is None:
            # The lower sheet's visible end is the corner, or (in the edge's shadow) where
            # the ray over the hidden top edge lands.
            end = corner_or_end(lower, not at_end, others, seg)
            over = _ray_hit(end, top)
            seam = end
            edge = _edge(top, at_end, top_hidden, others, seg)
            if over is not None and float((_foot(over, lower) - end) @ away) < 0.0:
                edge, seam = over, _foot(over, lower)
        else:
            edge = _edge(top, at_end, top_hidden, others, seg)
            seam = _foot(edge, lower)
        sure = top_hidden is None and lower_hidden is None
        feature = self._found(
            profile,
            seam,
            confidence=_confidence([a, b], seg) * (1.0 if sure else 0.5),
            edges_laser=edge.reshape(1, 2),
        )
        return feature, explained(seg, _two_plates(seg, a, b))


def _two_plates(seg: Segments, a: Line, b: Line) -> list[Zone]:
    """The model of a two-plate joint: each plate runs on to the profile's end; what lies
    between them (a gap, its walls, an edge face) is left out."""
    lo, hi = int(a.index[-1]) + 1, int(b.index[0])
    return [(0, lo, a), (lo, hi, None), (max(hi, lo), len(seg.points), b)]


def _foot(point: FloatArray, line: Line) -> FloatArray:
    """``point`` projected normally onto ``line``."""
    py, pz = point.tolist()
    cy, cz, dy, dz = _floats(line)
    h = (py - cy) * -dz + (pz - cz) * dy
    return np.array([py - h * -dz, pz - h * dy])


def _ray_hit(point: FloatArray, line: Line) -> FloatArray | None:
    """Where the ray from the emitter (the origin) through ``point`` crosses ``line``
    (``intersect(_ray(point), line)``, in floats), or None when (nearly) parallel."""
    py, pz = point.tolist()
    norm = max(math.hypot(py, pz), 1e-300)
    uy, uz = py / norm, pz / norm
    by, bz, bdy, bdz = _floats(line)
    d = uy * bdz - uz * bdy
    if abs(d) < 1e-9:
        return None
    s = ((by - 0.0) * bdz - (bz - 0.0) * bdy) / d
    return np.array([0.0 + s * uy, 0.0 + s * uz])
