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

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seamtrack.features.base import Zone, _Base, _confidence, explained
from seamtrack.features.lines import (
    Line,
    Segments,
    _fit,
    _on,
    collinear_members,
    corner_or_end,
)
from seamtrack.features.pkernels import hole, on_ends
from seamtrack.sensing.profiles import Feature, Profile

FloatArray = NDArray[np.float64]
#: Each kept point's piece (-1: none) and the pieces' rows ``(cy, cz, dy, dz)`` (:func:`_owner`).
_Owner = tuple[NDArray[np.int64], FloatArray]


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


def _hole(
    seg: Segments,
    owner: _Owner,
    a: Line,
    b: Line,
    min_bottom_mm: float,
    butt: bool = False,
) -> _Hole:
    """What lies between run ``a``'s last inlier and run ``b``'s first (``owner``: each kept
    point's piece, -1 for none). ``butt``: between two plates of a butt joint, a wall rising
    in front of the plates covers (a raised part, not a gap's wall) and points in no piece
    hardly off a plate are plate (a mark, where the laser did not fall through); a lap's
    edge face rises in front of its lower sheet. See :func:`_hole_between`."""
    return _hole_between(
        seg, owner, _floats(a), float(a.t[-1]), a.step(True), int(a.index[-1]),
        _floats(b), float(b.t[0]), b.step(False), int(b.index[0]), min_bottom_mm, butt,
    )  # fmt: skip


def _hole_between(
    seg: Segments,
    owner: _Owner,
    a: tuple[float, float, float, float],
    a_t: float,
    a_step: float,
    lo: int,
    b: tuple[float, float, float, float],
    b_t: float,
    b_step: float,
    hi: int,
    min_bottom_mm: float,
    butt: bool,
) -> _Hole:
    """:func:`_hole` of a run ending at kept point ``lo`` on line ``a`` (its last inlier's
    coordinate ``a_t`` along it, its step there) and one starting at ``hi`` on line ``b``.

    Points on a plate's line (leftovers too short for a piece, a corner piece's end) are
    plate: no opening, no stray line. What covers the hole (is no opening): the plates and
    any surface but a wall (steep on the plates, reaching off them behind them) or a bottom
    far behind both plates (a backing seen through a gap); a line crossing a plate's line at
    an angle is no plate where it does. Points in no piece off the plates: stray points
    (fewer than three in a row), walls and a bottom far behind cover nothing; other runs of
    three or more do. A surface that runs on from a plate without a jump (a tack, an edge
    face, a chamfer) is part of the part; a line cut off both plates by jumps (a false
    reflection) is stray: its columns are unknown, and over a plate's end it may hide the
    edge (:func:`seamtrack.features.pkernels.hole`, compiled).
    """
    index, rows = owner
    open_mm, left, ly, lz, right, ry, rz = hole(
        seg.points, index, rows, *a, a_t, a_step, *b, b_t, b_step, lo, hi,
        float(seg.tol), float(seg.spacing), float(seg.sigma), float(min_bottom_mm), butt,
    )  # fmt: skip
    return _Hole(
        open_mm, np.array([ly, lz]) if left else None, np.array([ry, rz]) if right else None
    )


@dataclass(frozen=True)
class _Sheets:
    """The plates of a profile: runs of pieces on one plate line, in column order."""

    runs: list[Line]
    groups: list[int]
    owner: _Owner
    others: list[Line]


def _owner(seg: Segments) -> _Owner:
    """The piece each kept point is an inlier of (-1: none), and the pieces' centroids and
    directions as rows ``(cy, cz, dy, dz)``."""
    owner = np.full(len(seg.points), -1, dtype=np.int64)
    rows = np.array([_floats(ln) for ln in seg.lines], dtype=np.float64).reshape(-1, 4)
    for j, ln in enumerate(seg.lines):
        owner[ln.index] = j
    return owner, rows


def _span(line: Line, pieces: list[Line]) -> float:
    """Extent along ``line`` of pieces on it (from their ends)."""
    ly, lz, ldy, ldz = _floats(line)
    t = []
    for p in pieces:
        cy, cz, dy, dz = _floats(p)
        c = (cy - ly) * ldy + (cz - lz) * ldz
        d = dy * ldy + dz * ldz
        t += [c + d * float(p.t[0]), c + d * float(p.t[-1])]
    return max(t) - min(t)


def _cos(a: Line, b: Line) -> float:
    """``|cos|`` of the angle between two lines (see :func:`seamtrack.features.lines._angle`)."""
    (ady, adz), (bdy, bdz) = a.direction.tolist(), b.direction.tolist()
    return abs(ady * bdy + adz * bdz)


def _median(values: list[float]) -> float:
    """numpy's median of a few floats (the mean of the middle two of an even count)."""
    v = sorted(values)
    if any(math.isnan(x) for x in v):
        return math.nan
    n = len(v)
    return v[n // 2] if n % 2 else (v[n // 2 - 1] + v[n // 2]) / 2.0


def _sheets(
    seg: Segments,
    owner: _Owner,
    min_points: int,
    min_plate_mm: float,
    max_tilt_deg: float,
    apart: Callable[[Line, NDArray[np.intp], NDArray[np.intp]], bool] | None,
    behind_mm: float = math.inf,
) -> _Sheets:
    """Plates and where they are interrupted.

    Flat pieces (within ``max_tilt_deg`` of the y axis) that lie on one line form a plate
    line, however short each piece is (a stub cut off a plate by a reflection stays on its
    plate); a line spanning ``min_plate_mm`` is a plate. Column order then gives runs:
    consecutive pieces of one plate line stay one run unless ``apart(line, left, right)``
    says the hole between them is a joint (a square butt's open gap; ``left``, ``right``:
    the facing inliers, measured on the plate's ``line``), so a reflection or a dropout
    never splits a plate. A stretch ``behind_mm`` or more behind the plate on both sides of
    it is no plate either, however wide: it is what a gap shows of the backing.
    """
    tilt = math.radians(max_tilt_deg)
    flat = []
    for ln in seg.lines:
        if ln.count >= min_points:
            dy, dz = ln.direction.tolist()
            if abs(math.atan2(dz, dy)) <= tilt:
                flat.append(ln)
    plates: list[tuple[int, int, Line]] = []  # (group, first inlier, piece)
    groups: list[list[Line]] = []
    for members in collinear_members(seg, flat):
        pieces = [flat[i] for i in members]
        if _span(pieces[0], pieces) >= min_plate_mm:
            plates += [(len(groups), int(p.index[0]), p) for p in pieces]
            groups.append(pieces)
    plates.sort(key=lambda gp: gp[1])
    # Plates follow each other in column order: a plate line that shows only briefly between
    # two stretches of another, or not parallel to it, is no plate there (a reflection lying
    # on its line by chance, a tilted one long enough to pass for a plate).
    # When two such blocks compete (a plate's stub next to the reflection), the smaller goes.
    while True:
        blocks = []
        i = 1
        while i < len(plates) - 1:
            j = i
            while j < len(plates) and plates[j][0] == plates[i][0]:
                j += 1
            if j < len(plates) and plates[i - 1][0] == plates[j][0]:
                block = [p for _, _, p in plates[i:j]]
                host = groups[plates[j][0]][0]
                tilted = math.acos(min(1.0, _cos(block[0], host))) > math.radians(10)
                hy, hz, hdy, hdz = _floats(host)
                flip = not hy * -hdz + hz * hdy < 0  # the sensor on the normal's other side
                heights = []
                for p in block:
                    py, pz = p.centroid.tolist()
                    h = (py - hy) * -hdz + (pz - hz) * hdy
                    heights.append(-h if flip else h)
                behind = -_median(heights) >= behind_mm
                if tilted or behind or _span(groups[plates[i][0]][0], block) < min_plate_mm:
                    blocks.append((sum(p.count for p in block), i, j))
            i = j
        if not blocks:
            break
        _, i, j = min(blocks)
        del plates[i:j]
    runs: list[tuple[int, list[Line]]] = []
    for g, _, piece in plates:
        if runs and runs[-1][0] == g:
            # The hole between the run so far and this piece, on the plate's line (the ends
            # suffice: its last and first inliers and their spacing).
            if apart is None or not apart(
                groups[g][0], runs[-1][1][-1].index[-11:], piece.index[:11]
            ):
                runs[-1][1].append(piece)
                continue
        runs.append((g, [piece]))
    # A run long enough is its own line (two plates a hair out of line keep their heights);
    # a stub is measured on its plate's line.
    out = []
    for g, pieces in runs:
        if len(pieces) == 1 and pieces[0].extent >= min_plate_mm:
            out.append(pieces[0])
            continue
        idx = np.concatenate([p.index for p in pieces])
        if _span(groups[g][0], pieces) >= min_plate_mm:
            out.append(_fit(seg.points, idx))
        else:
            out.append(_on(groups[g][0], idx, seg.points))
    others = [ln for ln in seg.lines if ln.count >= min_points]
    return _Sheets(out, [g for g, _ in runs], owner, others)


def _end(line: Line, at_end: bool) -> tuple[float, float]:
    """:meth:`~seamtrack.features.lines.Line.end` as floats."""
    cy, cz, dy, dz = _floats(line)
    half = 0.5 * line.step(at_end)
    t = float(line.t[-1]) + half if at_end else float(line.t[0]) - half
    return cy + t * dy, cz + t * dz


def _neighbours(sheets: _Sheets, max_gap_mm: float) -> list[tuple[Line, Line, bool]]:
    """Consecutive near-parallel runs (left, right, same plate line) whose facing ends are at
    most ``max_gap_mm`` apart."""
    out = []
    for (a, ga), (b, gb) in itertools.pairwise(zip(sheets.runs, sheets.groups, strict=True)):
        if math.acos(min(1.0, _cos(a, b))) > math.radians(10):
            continue
        acy, acz, ady, adz = _floats(a)
        bcy, bcz, bdy, bdz = _floats(b)
        ta, tb = float(a.t[-1]), float(b.t[0])
        if math.hypot(bcy + tb * bdy - (acy + ta * ady), bcz + tb * bdz - (acz + ta * adz)) <= (
            max_gap_mm
        ):
            out.append((a, b, ga == gb))
    return out


def _edge(
    line: Line, at_end: bool, hidden: FloatArray | None, sheets: _Sheets, seg: Segments
) -> FloatArray:
    """A run's edge: its corner or end, or where a stray line covers its end, the estimate
    of :func:`_hole` (on the run's line)."""
    if hidden is None:
        return corner_or_end(line, at_end, sheets.others, seg)
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

        holes: dict[tuple[int, int], _Hole] = {}
        points = seg.points

        def apart(line: Line, left: NDArray[np.intp], right: NDArray[np.intp]) -> bool:
            g = cy, cz, dy, dz = _floats(line)
            _, t_left, _, step_left = on_ends(points, left, cy, cz, dy, dz)
            t_right, _, step_right, _ = on_ends(points, right, cy, cz, dy, dz)
            # The facing ends (half a step beyond the last inliers), along the line.
            tl, tr = t_left + 0.5 * step_left, t_right - 0.5 * step_right
            if (cy + tr * dy - (cy + tl * dy)) * dy + (cz + tr * dz - (cz + tl * dz)) * dz < (
                min_opening
            ):
                return False
            lo, hi = int(left[-1]), int(right[0])
            hole = _hole_between(seg, owner, g, t_left, step_left, lo, g, t_right, step_right,
                                 hi, self.min_bottom_mm, True)  # fmt: skip
            holes[lo, hi] = hole
            return hole.open_mm >= self.min_open_mm

        owner = _owner(seg)
        sheets = _sheets(seg, owner, self.min_points, self.min_plate_mm, self.max_tilt_deg, apart,
                         behind_mm=self.min_bottom_mm)  # fmt: skip
        best, best_key = None, (False, 0.0)
        for a, b, _ in _neighbours(sheets, self.max_gap_mm):
            (ay, az), (by, bz) = _end(a, True), _end(b, False)
            opening = math.hypot(by - ay, bz - az)
            if opening < min_opening:
                continue
            hole = holes.get((int(a.index[-1]), int(b.index[0])))
            if hole is None:
                hole = _hole(seg, owner, a, b, self.min_bottom_mm, butt=True)
            # An open gap beats one a stray line covers; one a surface covers is none.
            is_open = hole.open_mm >= self.min_open_mm
            if not is_open and hole.left is None and hole.right is None:
                continue
            key = (is_open, opening)
            if key > best_key:
                best, best_key = (a, b, hole), key
        if best is None:
            return Feature.failed("no gap or step between two plates", joint=self.name)
        a, b, hole = best
        ea = _edge(a, True, hole.left, sheets, seg)
        eb = _edge(b, False, hole.right, sheets, seg)
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
        sure = best_key[0] and hole.left is None and hole.right is None
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
        sheets = _sheets(seg, _owner(seg), self.min_points, self.min_plate_mm,
                         self.max_tilt_deg, None)  # fmt: skip
        best, best_score = None, 0.0
        for a, b, same in _neighbours(sheets, self.max_gap_mm):
            acy, acz, ady, adz = _floats(a)
            bcy, bcz = b.centroid.tolist()
            step = (bcy - acy) * -adz + (bcz - acz) * ady  # > 0: b is deeper
            if same or abs(step) < max(self.min_step_mm, 3 * seg.tol):
                continue
            score = float(a.count + b.count)
            if score > best_score:
                best, best_score = (a, b, step), score
        if best is None:
            return Feature.failed("no step between two parallel sheets", joint=self.name)
        a, b, step = best
        wrong = self._implausible(depth=abs(step))
        if wrong is not None:
            return wrong
        hole = _hole(seg, sheets.owner, a, b, math.inf)
        top, lower, at_end = (a, b, True) if step > 0 else (b, a, False)
        top_hidden, lower_hidden = (hole.left, hole.right) if at_end else (hole.right, hole.left)
        # Away from the top sheet, along the lower one.
        away = lower.direction if at_end else -lower.direction
        if top_hidden is None:
            edge = corner_or_end(top, at_end, sheets.others, seg)
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
                seam = corner_or_end(lower, not at_end, sheets.others, seg)
        elif lower_hidden is None:
            # The lower sheet's visible end is the corner, or (in the edge's shadow) where
            # the ray over the hidden top edge lands.
            end = corner_or_end(lower, not at_end, sheets.others, seg)
            over = _ray_hit(end, top)
            seam = end
            edge = _edge(top, at_end, top_hidden, sheets, seg)
            if over is not None and float((_foot(over, lower) - end) @ away) < 0.0:
                edge, seam = over, _foot(over, lower)
        else:
            edge = _edge(top, at_end, top_hidden, sheets, seg)
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
