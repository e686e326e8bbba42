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
    _BOTTOM_DEG,
    _PLATE_DEG,
    _WALL_DEG,
    Line,
    Segments,
    _angle,
    _fit,
    _on,
    _ray_t,
    _towards_sensor,
    collinear_members,
    corner_or_end,
    intersect,
)
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


def _stretches(
    keep: NDArray[np.bool_], t: FloatArray, spacing: float
) -> tuple[FloatArray, FloatArray, list[NDArray[np.intp]]]:
    """The stretches of consecutive kept points, broken by another point or by missing
    columns: their starts and ends along a line (``t``: where the points' columns cross it),
    and the positions of the points of the first and of the last stretch."""
    k = np.flatnonzero(keep)
    if not k.size:
        return np.empty(0), np.empty(0), []
    tk = t[k]
    starts = np.flatnonzero((np.diff(k) > 1) | (np.abs(np.diff(tk)) > 3.0 * spacing)) + 1
    starts = np.concatenate([[0], starts])
    t0 = np.minimum.reduceat(tk, starts) - 0.5 * spacing
    t1 = np.maximum.reduceat(tk, starts) + 0.5 * spacing
    ends = [*starts[1:].tolist(), len(k)]
    return t0, t1, [k[i:j] for i, j in ((starts[0], ends[0]), (starts[-1], ends[-1]))]


def _hidden_edge(
    line: Line,
    part: NDArray[np.intp],
    t: FloatArray,
    on_line: NDArray[np.bool_],
    stray: NDArray[np.bool_],
    t_end: float,
    spacing: float,
    at_end: bool,
) -> FloatArray | None:
    """Where a run's edge lies when the covered stretch next to it (``part``, from the run's
    end outwards) holds a stray line: the middle of the stray line's stretch along the run's
    line (the edge may lie anywhere under it), or, when the plate shows again beyond it, the
    last plate point seen. None when no stray line touches the run's end."""
    seen = on_line[part] | stray[part]
    stop = int(np.argmin(seen)) if not seen.all() else len(part)
    part = part[:stop]  # up to the first point of anything else (the other plate, a surface)
    s = np.flatnonzero(stray[part])
    if not s.size:
        return None
    p = np.flatnonzero(on_line[part])
    sign = 1.0 if at_end else -1.0
    if p.size and p[-1] > s[-1]:
        return line.point(float(t[part[p[-1]]]) + sign * 0.5 * spacing)
    return line.point(0.5 * (t_end + float(t[part[s[-1]]]) + sign * 0.5 * spacing))


def _hole(
    seg: Segments,
    owner: NDArray[np.intp],
    a: Line,
    b: Line,
    min_bottom_mm: float,
    butt: bool = False,
) -> _Hole:
    """What lies between run ``a``'s last inlier and run ``b``'s first (``owner``: each kept
    point's piece, -1 for none). ``butt``: between two plates of a butt joint, a wall rising
    in front of the plates covers (a raised part, not a gap's wall) and points in no piece
    hardly off a plate are plate (a mark, where the laser did not fall through); a lap's
    edge face rises in front of its lower sheet."""
    lo, hi = int(a.index[-1]), int(b.index[0])
    sp_a, sp_b = max(a.step(True), seg.spacing), max(b.step(False), seg.spacing)
    ta = float(a.t[-1]) + 0.5 * a.step(True)
    tb_b = float(b.t[0]) - 0.5 * b.step(False)
    tb = float((b.point(tb_b) - a.centroid) @ a.direction)
    width = tb - ta
    if hi - lo < 2:
        return _Hole(width, None, None)
    q = seg.points[lo + 1 : hi]
    own = owner[lo + 1 : hi]
    # Points on a plate's line (leftovers too short for a piece, a corner piece's end) are
    # plate: no opening, no stray line.
    off_a, off_b = np.abs(_towards_sensor(a, q)), np.abs(_towards_sensor(b, q))
    off = np.minimum(off_a, off_b)
    plate = off <= seg.tol
    # What covers the hole (is no opening): the plates and any surface but a wall (steep on
    # the plates, reaching off them behind them) or a bottom far behind both plates (a
    # backing seen through a gap). A line crossing a plate's line at an angle is no plate
    # where it does.
    cover = np.zeros(len(q), dtype=bool)
    wall, bottom = math.radians(_WALL_DEG), math.radians(_BOTTOM_DEG)
    for j in np.unique(own[own >= 0]):
        mine = own == j
        ln = seg.lines[int(j)]
        rel = _angle(ln, a)
        if (
            rel >= wall
            and float(off[mine].max()) >= 2 * seg.tol
            and (not butt or float(np.median(_towards_sensor(a, q[mine]))) < 0.0)
        ):
            continue  # a wall going down into a gap (one rising in front is a raised part)
        if rel <= bottom:
            c = ln.centroid.reshape(1, 2)
            depth = -max(float(_towards_sensor(a, c)[0]), float(_towards_sensor(b, c)[0]))
            if depth >= min_bottom_mm:
                continue
        if rel > math.radians(_PLATE_DEG):
            plate &= ~mine
        cover |= mine
    # Points in no piece off the plates: stray points (fewer than three in a row), walls and
    # a bottom far behind cover nothing; other runs of three or more do, and so do points in
    # no piece hardly off a plate (a dent, a mark: the laser did not fall through there).
    if butt:
        plate |= (own < 0) & (off <= 3.0 * seg.tol)
    loose = np.flatnonzero((own < 0) & ~plate)
    if loose.size >= 3:
        bounds = np.flatnonzero(np.diff(loose) > 1) + 1
        for i, j in zip([0, *bounds.tolist()], [*bounds.tolist(), len(loose)], strict=True):
            part = loose[i:j]
            behind = -np.maximum(_towards_sensor(a, q[part]), _towards_sensor(b, q[part]))
            if float(np.median(behind)) >= min_bottom_mm:
                continue  # a bottom seen through the gap (a backing)
            if j - i >= 3 and (
                _angle(_fit(q, part), a) < wall
                or float(off[part].max()) < 2 * seg.tol
                or (butt and float(np.median(_towards_sensor(a, q[part]))) > 0.0)
            ):
                cover[part] = True
    cover |= plate
    if not cover.any():
        return _Hole(width, None, None)
    # A surface that runs on from a plate without a jump (a tack, an edge face, a chamfer) is
    # part of the part; a line cut off both plates by jumps (a false reflection) is stray:
    # its columns are unknown, and over a plate's end it may hide the edge. A stray line
    # ends next to a plate only by chance, so a plate holds on to its surface more tightly
    # (noise, not the split tolerance) than the surface holds together.
    seq = seg.points[lo : hi + 1]
    d = np.hypot(*np.diff(seq, axis=0).T)
    cut = d > max(6 * seg.spacing, 2 * seg.tol, 0.1)
    held = max(6 * seg.spacing, 4 * seg.sigma, 0.1)
    cut[0], cut[-1] = d[0] > held, d[-1] > held
    stray = cover & ~plate
    if not cut.any():
        stray[:] = False
    else:
        k = np.flatnonzero(cut)
        if not cut[0]:
            stray[: k[0]] = False  # held by the left plate
        if not cut[-1]:
            stray[k[-1] :] = False  # held by the right plate
    qa = _ray_t(a, q)
    t0, t1, (first, _) = _stretches(cover, qa, sp_a)
    covered = float(np.clip(np.minimum(t1, tb) - np.maximum(t0, ta), 0.0, None).sum())
    left = right = None
    if stray.any():
        on_a = plate & (off_a <= seg.tol)
        if t0[0] <= ta + 2.0 * sp_a:
            left = _hidden_edge(a, first, qa, on_a, stray, ta, sp_a, True)
        qb = _ray_t(b, q)
        t0, t1, (_, last) = _stretches(cover, qb, sp_b)
        if t1[-1] >= tb_b - 2.0 * sp_b:
            on_b = plate & (off_b <= seg.tol)
            right = _hidden_edge(b, last[::-1], qb, on_b, stray, tb_b, sp_b, False)
    return _Hole(max(0.0, width - covered), left, right)


@dataclass(frozen=True)
class _Sheets:
    """The plates of a profile: runs of pieces on one plate line, in column order."""

    runs: list[Line]
    groups: list[int]
    owner: NDArray[np.intp]
    others: list[Line]


def _owner(seg: Segments) -> NDArray[np.intp]:
    """The piece each kept point is an inlier of (-1: none)."""
    owner = np.full(len(seg.points), -1, dtype=np.intp)
    for j, ln in enumerate(seg.lines):
        owner[ln.index] = j
    return owner


def _sheets(
    seg: Segments,
    owner: NDArray[np.intp],
    min_points: int,
    min_plate_mm: float,
    max_tilt_deg: float,
    apart: Callable[[Line, Line], bool] | None,
    behind_mm: float = math.inf,
) -> _Sheets:
    """Plates and where they are interrupted.

    Flat pieces (within ``max_tilt_deg`` of the y axis) that lie on one line form a plate
    line, however short each piece is (a stub cut off a plate by a reflection stays on its
    plate); a line spanning ``min_plate_mm`` is a plate. Column order then gives runs:
    consecutive pieces of one plate line stay one run unless ``apart(left, right)`` says
    the hole between them is a joint (a square butt's open gap), so a reflection or a
    dropout never splits a plate. A stretch ``behind_mm`` or more behind the plate on both
    sides of it is no plate either, however wide: it is what a gap shows of the backing.
    """
    tilt = math.radians(max_tilt_deg)
    flat = [
        ln
        for ln in seg.lines
        if ln.count >= min_points and abs(math.atan2(ln.direction[1], ln.direction[0])) <= tilt
    ]

    def span(line: Line, pieces: list[Line]) -> float:
        """Extent along ``line`` of pieces on it (from their ends)."""
        t = []
        for p in pieces:
            c = float((p.centroid - line.centroid) @ line.direction)
            d = float(p.direction @ line.direction)
            t += [c + d * float(p.t[0]), c + d * float(p.t[-1])]
        return max(t) - min(t)

    plates: list[tuple[int, Line]] = []
    groups: list[list[Line]] = []
    for members in collinear_members(seg, flat):
        pieces = [flat[i] for i in members]
        if span(pieces[0], pieces) >= min_plate_mm:
            plates += [(len(groups), p) for p in pieces]
            groups.append(pieces)
    plates.sort(key=lambda gp: int(gp[1].index[0]))
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
                block = [p for _, p in plates[i:j]]
                host = groups[plates[j][0]][0]
                tilted = _angle(block[0], host) > math.radians(10)
                centres = np.array([p.centroid for p in block])
                behind = -float(np.median(_towards_sensor(host, centres))) >= behind_mm
                if tilted or behind or span(groups[plates[i][0]][0], block) < min_plate_mm:
                    blocks.append((sum(p.count for p in block), i, j))
            i = j
        if not blocks:
            break
        _, i, j = min(blocks)
        del plates[i:j]
    runs: list[tuple[int, list[Line]]] = []
    for g, piece in plates:
        if runs and runs[-1][0] == g:
            # The hole between the run so far and this piece, on the plate's line (the ends
            # suffice: its last and first inliers and their spacing).
            if apart is None or not apart(
                _on(groups[g][0], runs[-1][1][-1].index[-11:], seg.points),
                _on(groups[g][0], piece.index[:11], seg.points),
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
        if span(groups[g][0], pieces) >= min_plate_mm:
            out.append(_fit(seg.points, idx))
        else:
            out.append(_on(groups[g][0], idx, seg.points))
    others = [ln for ln in seg.lines if ln.count >= min_points]
    return _Sheets(out, [g for g, _ in runs], owner, others)


def _neighbours(sheets: _Sheets, max_gap_mm: float) -> list[tuple[Line, Line, bool]]:
    """Consecutive near-parallel runs (left, right, same plate line) whose facing ends are at
    most ``max_gap_mm`` apart."""
    out = []
    for (a, ga), (b, gb) in itertools.pairwise(zip(sheets.runs, sheets.groups, strict=True)):
        if (
            _angle(a, b) <= math.radians(10)
            and float(np.hypot(*(b.point(float(b.t[0])) - a.point(float(a.t[-1]))))) <= max_gap_mm
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

        def apart(left: Line, right: Line) -> bool:
            if float((right.end(False) - left.end(True)) @ left.direction) < min_opening:
                return False
            hole = _hole(seg, owner, left, right, self.min_bottom_mm, butt=True)
            holes[int(left.index[-1]), int(right.index[0])] = hole
            return hole.open_mm >= self.min_open_mm

        owner = _owner(seg)
        sheets = _sheets(seg, owner, self.min_points, self.min_plate_mm, self.max_tilt_deg, apart,
                         behind_mm=self.min_bottom_mm)  # fmt: skip
        best, best_key = None, (False, 0.0)
        for a, b, _ in _neighbours(sheets, self.max_gap_mm):
            opening = float(np.hypot(*(b.end(False) - a.end(True))))
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
        gap = abs(float((eb - ea) @ a.direction))
        step = abs(float((eb - ea) @ a.normal))
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
            step = float((b.centroid - a.centroid) @ a.normal)  # > 0: b is deeper
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
            shadow = intersect(_ray(edge), lower)
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
            over = intersect(_ray(end), top)
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
    return point - float((point - line.centroid) @ line.normal) * line.normal


def _ray(point: FloatArray) -> Line:
    """The ray from the emitter (the origin) through ``point``, as a line."""
    u = point / max(float(np.hypot(*point)), 1e-300)
    return Line(np.empty(0, np.intp), np.zeros(2), u, np.empty(0), 0.0)
