"""The two-plate search, compiled: the plates of a profile and the pair of runs the two-plate
extractors (:mod:`seamtrack.features.plates.extractor`) read.

:func:`two_plates` finds the plates (plate lines, runs, the square butt's test for an open
gap between pieces of one plate line), their neighbours and the extractors' choice of the
pair of runs in one call, on the profile's pieces held as a table of arrays (:class:`Pieces`):
as Python on ``Line`` objects it was some hundreds of small operations per profile, most of an
extractor's time once the segmentation is compiled. The plate lines' groups are
:func:`seamtrack.features.lines.collinear_members`' and the runs' refits
:func:`seamtrack.features._segmentation.fit_line`'s, computed the same way; what lies between two
runs is :func:`seamtrack.features.plates._between_plates.hole`'s.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray, IntArray
from seamtrack.features.line_geometry import LineThrough, Point, fit_line
from seamtrack.features.plates._between_plates import NO_HOLE, Hole, Scale, hole
from seamtrack.features.plates._plate_lines import PlateLimits, plate_pieces, span
from seamtrack.features.plates._two_lines import (
    PieceLines,
    PieceSpans,
    RunEnd,
    line_end,
    piece_line,
    steps,
    two_lines_share,
)
from seamtrack.jit import KERNEL

#: :class:`PlateLimits` and :class:`~seamtrack.features.plates._between_plates.Scale` as plain
#: tuples (what :func:`two_plates` takes from Python).
PlainLimits = tuple[int, float, float, float, bool, float, float, float, float]
PlainScale = tuple[float, float, float]

#: Kinds of run (:class:`Run`): one piece as it is, a refit of its pieces' inliers, or its
#: pieces' inliers measured on their plate's line (a stub).
PIECE, FIT, ON = 0, 1, 2


class Pieces(NamedTuple):
    """The profile's pieces as segmentation left them: ``members`` and ``along`` concatenate
    their inliers' positions (in the kept points) and coordinates along their lines,
    ``counts`` are their numbers of inliers, ``lines`` their lines."""

    members: IntArray
    along: FloatArray
    counts: IntArray
    lines: PieceLines


class RunLine(NamedTuple):
    """A run's line (:func:`_run_line`): its kind (:data:`PIECE`, :data:`FIT`, :data:`ON`),
    the line, its rms (FIT only, else 0), its inliers and their coordinates along it."""

    kind: int
    line: LineThrough
    rms: float
    inliers: IntArray
    t: FloatArray


class Run(NamedTuple):
    """One of the pair of runs chosen: its kind (:data:`PIECE`, :data:`FIT`, :data:`ON`),
    its first piece, its plate line's anchor piece, its number of inliers, its line, its rms
    (FIT only), and where it ends facing the other run (a visible corner, else half a step
    beyond its end inlier)."""

    kind: int
    first_piece: int
    anchor: int
    n_inliers: int
    line: LineThrough
    rms: float
    end: Point


class PlatePair(NamedTuple):
    """The pair of runs a two-plate extractor reads (``found``: a pair qualifies), ``left``
    before ``right`` in column order; whether what lies between them is an open gap (square
    butt only), what lies between them (:class:`~seamtrack.features.plates._between_plates.Hole`),
    the step from ``left`` down to ``right`` (lap only; > 0: ``right`` is deeper), and the
    share of the surface points the two-plate model explains (each plate running on to the
    profile's end, what lies between them left out;
    :func:`seamtrack.features.base.explained`)."""

    found: bool
    left: Run
    right: Run
    is_open: bool
    hole: Hole
    step: float
    share: float


_NO_RUN = Run(-1, -1, -1, 0, LineThrough(0.0, 0.0, 0.0, 0.0), 0.0, Point(0.0, 0.0))


@numba.njit(**KERNEL, error_model="numpy")
def _along(points: FloatArray, idx: IntArray, line: LineThrough) -> FloatArray:
    """Coordinates of ``points[idx]`` along a line."""
    cy, cz, dy, dz = line
    t = np.empty(idx.shape[0])
    for i in range(idx.shape[0]):
        t[i] = (points[idx[i], 0] - cy) * dy + (points[idx[i], 1] - cz) * dz
    return t


@numba.njit(**KERNEL, error_model="numpy")
def _run_line(
    points: FloatArray,
    pieces: Pieces,
    offsets: IntArray,
    t_first: FloatArray,
    t_last: FloatArray,
    members: IntArray,
    anchor: int,
    min_plate_mm: float,
) -> RunLine:
    """A run's line from its pieces ``members`` (of the plate line whose anchor is
    ``anchor``): a long piece as it is (:data:`PIECE`), else a refit of the pieces' inliers
    when they span ``min_plate_mm`` (:data:`FIT`), else those inliers measured on the
    anchor's line (:data:`ON`, a stub)."""
    p0 = members[0]
    if members.shape[0] == 1 and t_last[p0] - t_first[p0] >= min_plate_mm:
        a, b = offsets[p0], offsets[p0 + 1]
        own = piece_line(pieces.lines, p0)
        return RunLine(PIECE, own, 0.0, pieces.members[a:b].copy(), pieces.along[a:b].copy())
    total = 0
    for q in members:
        total += offsets[q + 1] - offsets[q]
    idx = np.empty(total, dtype=np.int64)
    c = 0
    for q in members:
        for k in range(offsets[q], offsets[q + 1]):
            idx[c] = pieces.members[k]
            c += 1
    if span(pieces.lines, t_first, t_last, anchor, members) >= min_plate_mm:
        cy, cz, dy, dz, rms, t = fit_line(points, idx)
        return RunLine(FIT, LineThrough(cy, cz, dy, dz), rms, idx, t)
    on = piece_line(pieces.lines, anchor)
    return RunLine(ON, on, 0.0, idx, _along(points, idx, on))


class PieceIndex(NamedTuple):
    """The pieces' table as the search reads it: where each piece's inliers start in
    ``pieces.members`` (``offsets``, one more than the pieces), each kept point's piece
    (``owner``, -1 for none), each piece's number of inliers, its first and last inlier's
    coordinates along its line, and its first inlier."""

    offsets: IntArray
    owner: IntArray
    n_inliers: IntArray
    t_first: FloatArray
    t_last: FloatArray
    first: IntArray


@numba.njit(**KERNEL, error_model="numpy")
def _piece_index(m: int, pieces: Pieces) -> PieceIndex:
    nl = pieces.lines.cy.shape[0]
    offsets = np.zeros(nl + 1, dtype=np.int64)
    for j in range(nl):
        offsets[j + 1] = offsets[j] + pieces.counts[j]
    owner = np.full(m, -1, dtype=np.int64)
    count = np.empty(nl, dtype=np.int64)
    t_first = np.empty(nl)
    t_last = np.empty(nl)
    first = np.empty(nl, dtype=np.int64)
    for j in range(nl):
        a, b = offsets[j], offsets[j + 1]
        count[j] = b - a
        t_first[j], t_last[j] = pieces.along[a], pieces.along[b - 1]
        first[j] = pieces.members[a]
        for k in range(a, b):
            owner[pieces.members[k]] = j
    return PieceIndex(offsets, owner, count, t_first, t_last, first)


class Facing(NamedTuple):
    """Two pieces of one plate line facing each other across a stretch: the left piece at
    its last inlier and the right one at its first (on the plate line), those inliers (kept
    points ``lo`` and ``hi``), and the opening between their edges (half a step beyond each)."""

    left: RunEnd
    right: RunEnd
    lo: int
    hi: int
    opening: float


@numba.njit(**KERNEL, error_model="numpy")
def _facing(
    points: FloatArray, pieces: Pieces, offsets: IntArray, on: LineThrough, left: int, right: int
) -> Facing:
    """Pieces ``left`` and ``right`` of the plate line ``on`` at their facing ends (the
    steps from their last and first ten inliers)."""
    li = pieces.members[max(offsets[left], offsets[left + 1] - 11) : offsets[left + 1]]
    ri = pieces.members[offsets[right] : min(offsets[right + 1], offsets[right] + 11)]
    tl = _along(points, li, on)
    tr = _along(points, ri, on)
    step_l = steps(tl).last
    step_r = steps(tr).first
    t_l, t_r = tl[-1], tr[0]
    el, er = t_l + 0.5 * step_l, t_r - 0.5 * step_r
    cy, cz, dy, dz = on
    gap = (cy + er * dy - (cy + el * dy)) * dy + (cz + er * dz - (cz + el * dz)) * dz
    return Facing(RunEnd(on, t_l, step_l), RunEnd(on, t_r, step_r), li[-1], ri[0], gap)


class RunTable(NamedTuple):
    """The runs (consecutive pieces of one plate line): their pieces ``pl[lo:hi]``, their
    kinds and refits' rms, their lines, where their inliers lie along them
    (:class:`~seamtrack.features.plates._two_lines.PieceSpans`), and their first and last
    inliers (kept points)."""

    lo: IntArray
    hi: IntArray
    kind: IntArray
    rms: FloatArray
    lines: PieceLines
    spans: PieceSpans
    first_inlier: IntArray
    last_inlier: IntArray


@numba.njit(**KERNEL, error_model="numpy")
def _run_table(
    points: FloatArray,
    pieces: Pieces,
    index: PieceIndex,
    plated: Any,
    run_lo: IntArray,
    run_hi: IntArray,
    min_plate_mm: float,
) -> RunTable:
    """Each run's line: a long piece as it is, else a refit of its pieces (long enough) or
    its pieces measured on their plate's line."""
    nr = run_lo.shape[0]
    kind = np.empty(nr, dtype=np.int64)
    rms = np.empty(nr)  # the refits' (FIT only)
    run_lines = PieceLines(np.empty(nr), np.empty(nr), np.empty(nr), np.empty(nr))
    runs = PieceSpans(
        np.empty(nr, dtype=np.int64), np.empty(nr), np.empty(nr), np.empty(nr), np.empty(nr)
    )
    first_inlier = np.empty(nr, dtype=np.int64)
    last_inlier = np.empty(nr, dtype=np.int64)
    for r in range(nr):
        lo, hi = run_lo[r], run_hi[r]
        anchor = plated.anchor[plated.plate[lo]]
        run = _run_line(
            points, pieces, index.offsets, index.t_first, index.t_last, plated.piece[lo:hi],
            anchor, min_plate_mm,
        )  # fmt: skip
        kind[r], rms[r] = run.kind, run.rms
        run_lines.cy[r], run_lines.cz[r], run_lines.dy[r], run_lines.dz[r] = run.line
        at = steps(run.t)
        runs.t_first[r], runs.t_last[r] = run.t[0], run.t[-1]
        runs.step_first[r], runs.step_last[r] = at.first, at.last
        first_inlier[r], last_inlier[r] = run.inliers[0], run.inliers[-1]
        runs.n_inliers[r] = run.inliers.shape[0]
    return RunTable(run_lo, run_hi, kind, rms, run_lines, runs, first_inlier, last_inlier)


class BestPair(NamedTuple):
    """The neighbouring runs ``a`` and ``a + 1`` chosen (``a`` -1: none), what lies between
    them (square butt), whether it is open, and the lap's step."""

    a: int
    hole: Hole
    is_open: bool
    step: float


@numba.njit(**KERNEL, error_model="numpy")
def _best_pair(
    points: FloatArray,
    owner: IntArray,
    lines: PieceLines,
    runs: RunTable,
    plate_of: IntArray,
    limits: PlateLimits,
    scale: Scale,
    holes: list[Hole],
    hole_lo: IntArray,
    hole_hi: IntArray,
) -> BestPair:
    """Neighbouring runs near parallel, their facing ends near; the best pair: a square
    butt's widest opening (an open gap first), a lap's pair with the most inliers across a
    step. ``holes``: those found between pieces while the runs were made (at kept points
    ``hole_lo``/``hole_hi``), reused."""
    max_gap_mm, butt, min_opening = limits.max_gap_mm, limits.butt, limits.min_opening
    ten = math.radians(10.0)
    best = BestPair(-1, NO_HOLE, False, 0.0)
    best_key = 0.0
    spans = runs.spans
    for a in range(runs.lo.shape[0] - 1):
        b = a + 1
        la, lb = piece_line(runs.lines, a), piece_line(runs.lines, b)
        acy, acz, ady, adz = la
        bcy, bcz, bdy, bdz = lb
        if not math.acos(min(1.0, abs(ady * bdy + adz * bdz))) <= ten:
            continue
        ta, tb = spans.t_last[a], spans.t_first[b]
        if (
            not math.hypot(bcy + tb * bdy - (acy + ta * ady), bcz + tb * bdz - (acz + ta * adz))
            <= max_gap_mm
        ):
            continue
        if not butt:
            step = (bcy - acy) * -adz + (bcz - acz) * ady  # > 0: b is deeper
            if plate_of[runs.lo[a]] == plate_of[runs.lo[b]] or abs(step) < max(
                limits.min_step_mm, 3 * scale.tol
            ):
                continue
            score = float(spans.n_inliers[a] + spans.n_inliers[b])
            if score > best_key:
                best_key = score
                best = BestPair(a, NO_HOLE, False, step)
            continue
        ea, eb = ta + 0.5 * spans.step_last[a], tb - 0.5 * spans.step_first[b]
        opening = math.hypot(bcy + eb * bdy - (acy + ea * ady), bcz + eb * bdz - (acz + ea * adz))
        if opening < min_opening:
            continue
        lo, hi = runs.last_inlier[a], runs.first_inlier[b]
        hit = -1
        for k in range(len(holes)):
            if hole_lo[k] == lo and hole_hi[k] == hi:
                hit = k
        between = (
            holes[hit]
            if hit >= 0
            else hole(
                points, owner, lines, RunEnd(la, ta, spans.step_last[a]),
                RunEnd(lb, tb, spans.step_first[b]), lo, hi, scale, limits.min_bottom_mm, butt,
            )
        )  # fmt: skip
        is_open = between.open_mm >= limits.min_open_mm
        if not is_open and not between.left.hidden and not between.right.hidden:
            continue
        if (is_open and not best.is_open) or (is_open == best.is_open and opening > best_key):
            best_key = opening
            best = BestPair(a, between, is_open, 0.0)
    return best


@numba.njit(**KERNEL, error_model="numpy")
def _two_plates(
    points: FloatArray,
    pieces: Pieces,
    stray: NDArray[np.bool_],
    limits: PlateLimits,
    scale: Scale,
) -> PlatePair:
    """The two plates of a square butt (``limits.butt``) or a lap, as the extractors choose
    them, from the profile's kept ``points`` and its ``pieces``; ``stray``: the
    segmentation's detour points (left out of the explained share)."""
    butt = limits.butt
    tol, spacing = scale.tol, scale.spacing
    lines = pieces.lines
    index = _piece_index(points.shape[0], pieces)
    offsets = index.offsets
    plated = plate_pieces(
        lines, index.n_inliers, index.t_first, index.t_last, index.first, limits, tol
    )
    pg, pl, plate_anchor = plated.plate, plated.piece, plated.anchor
    n = pg.shape[0]
    # Runs: consecutive pieces of one plate line, unless (square butt) an open gap lies
    # between them. Holes found on the way are kept for the pair chosen below.
    run_lo = np.empty(n + 1, dtype=np.int64)
    run_hi = np.empty(n + 1, dtype=np.int64)
    nr = 0
    hole_lo = np.empty(n + 1, dtype=np.int64)  # the holes found: their ends (kept points)
    hole_hi = np.empty(n + 1, dtype=np.int64)
    holes: list[Hole] = []
    for p in range(n):
        if nr > 0 and pg[run_lo[nr - 1]] == pg[p]:
            join = True
            if butt:
                on = piece_line(lines, plate_anchor[pg[p]])
                facing = _facing(points, pieces, offsets, on, pl[p - 1], pl[p])
                if not facing.opening < limits.min_opening:
                    between = hole(
                        points, index.owner, lines, facing.left, facing.right, facing.lo,
                        facing.hi, scale, limits.min_bottom_mm, butt,
                    )  # fmt: skip
                    hole_lo[len(holes)], hole_hi[len(holes)] = facing.lo, facing.hi
                    holes.append(between)
                    join = not between.open_mm >= limits.min_open_mm
            if join:
                run_hi[nr - 1] = p + 1
                continue
        run_lo[nr], run_hi[nr] = p, p + 1
        nr += 1
    runs = _run_table(points, pieces, index, plated, run_lo[:nr], run_hi[:nr], limits.min_plate_mm)
    best = _best_pair(points, index.owner, lines, runs, pg, limits, scale, holes, hole_lo, hole_hi)
    if best.a < 0:
        return PlatePair(False, _NO_RUN, _NO_RUN, False, best.hole, 0.0, 0.0)
    a, b = best.a, best.a + 1
    spans = runs.spans
    la, lb = piece_line(runs.lines, a), piece_line(runs.lines, b)
    at_a = RunEnd(la, spans.t_last[a], spans.step_last[a])  # a at its last inlier
    at_b = RunEnd(lb, spans.t_first[b], spans.step_first[b])  # b at its first
    best_hole = best.hole
    if not butt:
        best_hole = hole(
            points, index.owner, lines, at_a, at_b, runs.last_inlier[a], runs.first_inlier[b],
            scale, math.inf, butt,
        )  # fmt: skip
    # The runs' ends (a visible corner or half a step beyond the last inlier), the share of
    # the profile the model (each plate running on to the profile's end) explains.
    # Runtime flags: a literal True or False would compile a copy of the callee each.
    at_end, at_start = butt | True, butt & False
    piece_a = pl[runs.lo[a]] if runs.kind[a] == PIECE else -1
    piece_b = pl[runs.lo[b]] if runs.kind[b] == PIECE else -1
    nl = lines.cy.shape[0]
    step_first = np.empty(nl)
    step_last = np.empty(nl)
    for j in range(nl):
        step_first[j], step_last[j] = steps(pieces.along[offsets[j] : offsets[j + 1]])
    pieces_spans = PieceSpans(index.n_inliers, index.t_first, index.t_last, step_first, step_last)
    min_points = limits.min_points
    end_a = line_end(la, at_a, at_end, piece_a, lines, pieces_spans, min_points, spacing, tol)
    start_b = line_end(lb, at_b, at_start, piece_b, lines, pieces_spans, min_points, spacing, tol)
    explained = two_lines_share(
        points, stray, runs.last_inlier[a] + 1, runs.first_inlier[b], la, lb, 3.0 * tol
    )
    left = Run(
        runs.kind[a], pl[runs.lo[a]], plate_anchor[pg[runs.lo[a]]], spans.n_inliers[a], la,
        runs.rms[a], end_a,
    )  # fmt: skip
    right = Run(
        runs.kind[b], pl[runs.lo[b]], plate_anchor[pg[runs.lo[b]]], spans.n_inliers[b], lb,
        runs.rms[b], start_b,
    )  # fmt: skip
    return PlatePair(True, left, right, best.is_open, best_hole, best.step, explained)


class PairReading(NamedTuple):
    """:class:`PlatePair` for a caller in Python, its fields flattened (``left_line`` ->
    ``left_cy``, ...): numba boxes every named tuple of a result by a Python call, some
    microseconds for the dozen nested in a :class:`PlatePair`."""

    found: bool
    is_open: bool
    step: float
    share: float
    open_mm: float
    left_hidden: bool
    left_hidden_y: float
    left_hidden_z: float
    right_hidden: bool
    right_hidden_y: float
    right_hidden_z: float
    left_kind: int
    left_piece: int
    left_anchor: int
    left_count: int
    left_cy: float
    left_cz: float
    left_dy: float
    left_dz: float
    left_rms: float
    left_end_y: float
    left_end_z: float
    right_kind: int
    right_piece: int
    right_anchor: int
    right_count: int
    right_cy: float
    right_cz: float
    right_dy: float
    right_dz: float
    right_rms: float
    right_end_y: float
    right_end_z: float


@numba.njit(**KERNEL, error_model="numpy")
def two_plates(
    points: FloatArray,
    index: IntArray,
    along: FloatArray,
    fits: FloatArray,
    bounds: IntArray,
    stray: NDArray[np.bool_],
    limits: PlainLimits,
    scale: PlainScale,
) -> PairReading:
    """The two plates of a square butt or a lap, as the extractors choose them
    (:func:`_two_plates`), for a caller in Python: the pieces as the segmentation's table
    (:attr:`seamtrack.features.lines.Segments.table`: ``index``, ``along``, ``fits`` a row
    per piece (centroid y, z, direction y, z, rms, first and last coordinate), ``bounds``),
    ``limits`` and ``scale`` as plain tuples of :class:`PlateLimits`' and
    :class:`~seamtrack.features.plates._between_plates.Scale`'s fields (numba types a named tuple
    argument in Python on every call, some microseconds; plain ones and arrays at once), the
    result flattened (:class:`PairReading`)."""
    n = bounds.shape[0] - 1
    counts = np.empty(n, dtype=np.int64)
    lines = PieceLines(np.empty(n), np.empty(n), np.empty(n), np.empty(n))
    for j in range(n):
        counts[j] = bounds[j + 1] - bounds[j]
        cy, cz, dy, dz, _rms, _t_first, _t_last = fits[j]
        lines.cy[j], lines.cz[j], lines.dy[j], lines.dz[j] = cy, cz, dy, dz
    pieces = Pieces(index, along, counts, lines)
    pair = _two_plates(points, pieces, stray, PlateLimits(*limits), Scale(*scale))
    left, right, between = pair.left, pair.right, pair.hole
    return PairReading(
        pair.found, pair.is_open, pair.step, pair.share, between.open_mm,
        between.left.hidden, between.left.at.y, between.left.at.z,
        between.right.hidden, between.right.at.y, between.right.at.z,
        left.kind, left.first_piece, left.anchor, left.n_inliers,
        left.line.cy, left.line.cz, left.line.dy, left.line.dz, left.rms, left.end.y, left.end.z,
        right.kind, right.first_piece, right.anchor, right.n_inliers,
        right.line.cy, right.line.cz, right.line.dy, right.line.dz, right.rms,
        right.end.y, right.end.z,
    )  # fmt: skip
