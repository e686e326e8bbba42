"""What lies between two plate runs (:func:`hole`), compiled: the inner loop of the two-plate
extractors (:mod:`seamtrack.features.plates.extractor`).

Done as numpy calls on the few dozen points of a hole, its masks, medians and stretches were
some hundred small array operations per profile, whose per-call overhead was most of the
extractor's time, and more on the profiles with reflections or outliers (one pass per piece
and per run of loose points). The arithmetic is that of the numpy formulation (the same
formulas, medians as numpy takes them), so results agree to rounding. Booleans are passed to
callees at run time: a literal True or False compiles a copy of the callee per value.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray, IntArray
from seamtrack.features.line_geometry import LineThrough, Point, fit_points
from seamtrack.features.plates._two_lines import (
    PieceLines,
    RunEnd,
    angle,
    kept,
    median,
    towards,
)
from seamtrack.jit import KERNEL

#: A gap's wall or a lap's edge face stands at least this steep on the plates (as
#: :data:`seamtrack.features.lines.WALL_DEG`, rad).
_WALL = math.radians(65.0)
#: A gap's bottom (a backing seen through the gap) lies within this angle of the plates (rad).
_BOTTOM = math.radians(10.0)
#: A piece within this angle of a plate is plate where it lies on the plate's line (rad).
_PLATE = math.radians(20.0)


class Scale(NamedTuple):
    """The profile's scale: the segmentation's tolerance, the ray spacing and the noise
    (mm)."""

    tol: float
    spacing: float
    sigma: float


class HiddenEdge(NamedTuple):
    """A run's edge under a stray line: ``hidden`` (a stray line covers the run's end) and,
    when it is, ``at``, the best estimate of the edge."""

    hidden: bool
    at: Point


class Hole(NamedTuple):
    """What lies between two plate runs: ``open_mm``, how much of the stretch between their
    ends nothing covers, and the left and the right run's edges where stray lines hide
    them."""

    open_mm: float
    left: HiddenEdge
    right: HiddenEdge


class Stretches(NamedTuple):
    """Of the stretches of consecutive kept points: the first one's start, the last one's
    end (along a line), and the positions of the points of the first or of the last one."""

    start: float
    end: float
    part: IntArray


class EdgeUnder(NamedTuple):
    """Where a run's edge lies under a stray line: ``found`` (a stray line touches the
    run's end) and ``t``, its coordinate along the run's line."""

    found: bool
    t: float


#: A seen edge; a hole nothing covers that hides no edge.
_SEEN = HiddenEdge(False, Point(0.0, 0.0))
NO_HOLE = Hole(0.0, _SEEN, _SEEN)


@numba.njit(**KERNEL, error_model="numpy", inline="always")
def _breaks(k: IntArray, t: FloatArray, i: int, spacing: float) -> bool:
    """Whether a stretch of consecutive kept points (positions ``k``, at ``t`` along the line)
    ends before ``k[i]``: another point or a jump of three spacings between it and ``k[i - 1]``."""
    return k[i] - k[i - 1] > 1 or abs(t[k[i]] - t[k[i - 1]]) > 3.0 * spacing


@numba.njit(**KERNEL, error_model="numpy")
def _stretch_ends(keep: NDArray[np.bool_], t: FloatArray, spacing: float, first: bool) -> Stretches:
    """Of the stretches of consecutive kept points (broken by another point or a jump of
    three spacings along the line): the first one's start, the last one's end, and the
    positions of the points of the first (``first``) or of the last stretch."""
    k = kept(keep)
    n = k.shape[0]
    hi_first = n
    for i in range(1, n):
        if _breaks(k, t, i, spacing):
            hi_first = i
            break
    lo_last = 0
    for i in range(n - 1, 0, -1):
        if _breaks(k, t, i, spacing):
            lo_last = i
            break
    t0 = t[k[0]]
    for i in range(1, hi_first):
        x = t[k[i]]
        if x < t0 or math.isnan(x):
            t0 = x if not math.isnan(t0) else t0
    t1 = t[k[lo_last]]
    for i in range(lo_last + 1, n):
        x = t[k[i]]
        if x > t1 or math.isnan(x):
            t1 = x if not math.isnan(t1) else t1
    part = k[0:hi_first].copy() if first else k[lo_last:n].copy()
    return Stretches(t0 - 0.5 * spacing, t1 + 0.5 * spacing, part)


@numba.njit(**KERNEL, error_model="numpy")
def _covered(keep: NDArray[np.bool_], t: FloatArray, spacing: float, ta: float, tb: float) -> float:
    """Summed length along the line of the stretches of consecutive kept points, clipped to
    ``[ta, tb]`` (NaN propagates, as numpy's reductions do)."""
    k = kept(keep)
    n = k.shape[0]
    total = 0.0
    i = 0
    while i < n:
        j = i + 1
        while j < n and not _breaks(k, t, j, spacing):
            j += 1
        lo = t[k[i]]
        hi = t[k[i]]
        for r in range(i + 1, j):
            x = t[k[r]]
            if math.isnan(x) or math.isnan(lo):
                lo = math.nan
                hi = math.nan
            else:
                lo = min(lo, x)
                hi = max(hi, x)
        t0 = lo - 0.5 * spacing
        t1 = hi + 0.5 * spacing
        right = math.nan if math.isnan(t1) or math.isnan(tb) else min(t1, tb)
        left = math.nan if math.isnan(t0) or math.isnan(ta) else max(t0, ta)
        w = right - left
        total += w if not w < 0.0 else 0.0
        i = j
    return total


@numba.njit(**KERNEL, error_model="numpy")
def _hidden_edge(
    part: IntArray,
    t: FloatArray,
    on_line: NDArray[np.bool_],
    stray: NDArray[np.bool_],
    t_end: float,
    spacing: float,
    at_end: bool,
) -> EdgeUnder:
    """Where a run's edge lies when the covered stretch next to it (``part``, from the run's
    end outwards) holds a stray line: the middle of the stray line's stretch along the run's
    line (the edge may lie anywhere under it), or, when the plate shows again beyond it, the
    last plate point seen (half a spacing on); up to the first point of anything else (the
    other plate, a surface); not found when no stray line touches the run's end."""
    stop = part.shape[0]
    for i in range(part.shape[0]):
        if not (on_line[part[i]] or stray[part[i]]):
            stop = i
            break
    s_last = -1
    p_last = -1
    for i in range(stop):
        if stray[part[i]]:
            s_last = i
        if on_line[part[i]]:
            p_last = i
    if s_last < 0:
        return EdgeUnder(False, 0.0)
    sign = 1.0 if at_end else -1.0
    if p_last >= 0 and p_last > s_last:
        return EdgeUnder(True, t[part[p_last]] + sign * 0.5 * spacing)
    return EdgeUnder(True, 0.5 * (t_end + t[part[s_last]] + sign * 0.5 * spacing))


class NearPlates(NamedTuple):
    """The points of a hole against the plates' two lines: signed offsets towards each (the
    side of the line its normal points to), their sizes, the nearer one, and ``plate`` (within
    the tolerance of either)."""

    towards_a: FloatArray
    towards_b: FloatArray
    off_a: FloatArray
    off_b: FloatArray
    off: FloatArray
    plate: NDArray[np.bool_]


@numba.njit(**KERNEL, error_model="numpy")
def _near_plates(q: FloatArray, la: LineThrough, lb: LineThrough, tol: float) -> NearPlates:
    n = q.shape[0]
    towards_a = np.empty(n)
    towards_b = np.empty(n)
    off_a = np.empty(n)
    off_b = np.empty(n)
    off = np.empty(n)
    plate = np.empty(n, dtype=np.bool_)
    for i in range(n):
        towards_a[i] = towards(la, q[i, 0], q[i, 1])
        towards_b[i] = towards(lb, q[i, 0], q[i, 1])
        off_a[i] = abs(towards_a[i])
        off_b[i] = abs(towards_b[i])
        x, y = off_a[i], off_b[i]
        off[i] = math.nan if math.isnan(x) or math.isnan(y) else min(x, y)
        plate[i] = off[i] <= tol
    return NearPlates(towards_a, towards_b, off_a, off_b, off, plate)


@numba.njit(**KERNEL, error_model="numpy")
def _highest(off: FloatArray, members: IntArray) -> float:
    """The largest offset of ``members`` (NaN as numpy's ``max`` takes it: the first NaN
    wins)."""
    top = -math.inf
    for r in range(members.shape[0]):
        x = off[members[r]]
        if x > top or math.isnan(x):
            top = x if not math.isnan(top) else top
    return top


@numba.njit(**KERNEL, error_model="numpy")
def _median_of(v: FloatArray, members: IntArray) -> float:
    w = np.empty(members.shape[0])
    for r in range(members.shape[0]):
        w[r] = v[members[r]]
    return median(w)


@numba.njit(**KERNEL, error_model="numpy")
def _pieces_cover(
    own: IntArray,
    pieces: PieceLines,
    near: NearPlates,
    la: LineThrough,
    lb: LineThrough,
    tol: float,
    min_bottom_mm: float,
    butt: bool,
) -> NDArray[np.bool_]:
    """Which points of the hole the pieces in it cover: all but a wall going down into a gap
    and a bottom ``min_bottom_mm`` behind both plates; a piece crossing a plate's line at an
    angle is no plate where it does (``near.plate`` cleared there)."""
    n = own.shape[0]
    ady, adz = la[2], la[3]
    cover = np.zeros(n, dtype=np.bool_)
    present = np.zeros(pieces.cy.shape[0], dtype=np.bool_)
    for i in range(n):
        if own[i] >= 0:
            present[own[i]] = True
    for j in range(pieces.cy.shape[0]):
        if not present[j]:
            continue
        members = np.flatnonzero(own == j)
        rel = angle(pieces.dy[j], pieces.dz[j], ady, adz)
        if rel >= _WALL and _highest(near.off, members) >= 2 * tol:
            if not butt or _median_of(near.towards_a, members) < 0.0:
                continue  # a wall going down into a gap
        if rel <= _BOTTOM:
            cy, cz = pieces.cy[j], pieces.cz[j]
            x = towards(la, cy, cz)
            y = towards(lb, cy, cz)
            if -(y if y > x else x) >= min_bottom_mm:
                continue
        for k in members:
            if rel > _PLATE:
                near.plate[k] = False
            cover[k] = True
    return cover


@numba.njit(**KERNEL, error_model="numpy")
def _loose_cover(
    q: FloatArray,
    own: IntArray,
    near: NearPlates,
    ady: float,
    adz: float,
    tol: float,
    min_bottom_mm: float,
    butt: bool,
) -> NDArray[np.bool_]:
    """Which points of the hole the runs of three or more points in no piece and off the
    plates cover: all but those far behind both plates, and a wall standing off them (in a
    butt joint: one going down into the gap)."""
    n = own.shape[0]
    cover = np.zeros(n, dtype=np.bool_)
    loose = np.flatnonzero((own < 0) & ~near.plate[:n])
    nloose = loose.shape[0]
    if nloose < 3:
        return cover
    s = 0
    while s < nloose:
        e = s + 1
        while e < nloose and loose[e] - loose[e - 1] <= 1:
            e += 1
        part = loose[s:e]
        behind = np.empty(e - s)
        for r in range(e - s):
            x, y = near.towards_a[part[r]], near.towards_b[part[r]]
            behind[r] = -(math.nan if math.isnan(x) or math.isnan(y) else max(x, y))
        if not median(behind) >= min_bottom_mm and e - s >= 3:
            _, _, uy, uz, _ = fit_points(q, part, part.shape[0])
            yes = angle(uy, uz, ady, adz) < _WALL
            if not yes:
                yes = _highest(near.off, part) < 2 * tol
            if not yes and butt:
                yes = _median_of(near.towards_a, part) > 0.0
            if yes:
                for r in range(e - s):
                    cover[part[r]] = True
        s = e
    return cover


@numba.njit(**KERNEL, error_model="numpy")
def _stray(
    points: FloatArray,
    lo: int,
    hi: int,
    cover: NDArray[np.bool_],
    plate: NDArray[np.bool_],
    scale: Scale,
) -> NDArray[np.bool_]:
    """The covering points that are no plate and lie between jumps (a line cut off both
    plates: a false reflection), from the jumps between consecutive points of the hole, its
    plates' ends included."""
    tol, spacing, sigma = scale
    n = hi - lo - 1
    m = n + 1
    cut = np.empty(m, dtype=np.bool_)
    big = max(6 * spacing, 2 * tol, 0.1)
    held = max(6 * spacing, 4 * sigma, 0.1)
    for i in range(m):
        dy = points[lo + i + 1, 0] - points[lo + i, 0]
        dz = points[lo + i + 1, 1] - points[lo + i, 1]
        d = math.hypot(dy, dz)
        cut[i] = d > (held if i == 0 or i == m - 1 else big)
    stray = np.zeros(n, dtype=np.bool_)
    cuts = np.flatnonzero(cut)
    if cuts.shape[0] == 0:
        return stray
    k0, k1 = cuts[0], cuts[-1]
    for i in range(n):
        st = cover[i] and not plate[i]
        if not cut[0] and i < k0:
            st = False
        if not cut[m - 1] and i >= k1:
            st = False
        stray[i] = st
    return stray


@numba.njit(**KERNEL, error_model="numpy")
def _along(q: FloatArray, line: LineThrough) -> FloatArray:
    """Each point's position along ``line`` where the ray from the sensor's origin through it
    meets the line."""
    cy, cz, dy, dz = line
    n = q.shape[0]
    t = np.empty(n)
    normal = cy * -dz + cz * dy
    for i in range(n):
        s_ = normal / (q[i, 0] * -dz + q[i, 1] * dy)
        t[i] = (q[i, 0] * s_ - cy) * dy + (q[i, 1] * s_ - cz) * dz
    return t


@numba.njit(**KERNEL, error_model="numpy")
def hole(
    points: FloatArray,
    owner: IntArray,
    pieces: PieceLines,
    a: RunEnd,
    b: RunEnd,
    lo: int,
    hi: int,
    scale: Scale,
    min_bottom_mm: float,
    butt: bool,
) -> Hole:
    """What lies between run ``a``'s last inlier (kept point ``lo``) and run ``b``'s first
    (``hi``).

    ``open_mm``: how much of the stretch between their ends (along ``a``) nothing covers.
    Points on a plate's line (leftovers too short for a piece, a corner piece's end) are
    plate: no opening, no stray line. What covers the hole: the plates and any surface but
    a wall (steep on the plates, reaching off them behind them) or a bottom
    ``min_bottom_mm`` behind both plates (a backing seen through a gap); a line crossing a
    plate's line at an angle is no plate where it does. Points in no piece off the plates:
    stray points (fewer than three in a row), walls and a bottom far behind cover nothing;
    other runs of three or more do. ``butt``: between two plates of a butt joint, a wall
    rising in front of the plates covers (a raised part, not a gap's wall) and points in no
    piece hardly off a plate are plate (a mark, where the laser did not fall through); a
    lap's edge face rises in front of its lower sheet. A surface that runs on from a plate
    without a jump (a tack, an edge face, a chamfer) is part of the part; a line cut off
    both plates by jumps (a false reflection) is stray: its columns are unknown, not open,
    and over a plate's end it may hide the edge (:func:`_hidden_edge`). A plate holds on to
    its surface more tightly (noise, not the split tolerance) than the surface holds
    together: a stray line ends next to a plate only by chance.

    Run ``a`` at its last inlier, run ``b`` at its first (the step there:
    :meth:`~seamtrack.features.lines.Line.step`). ``owner``: each kept point's piece (of
    ``pieces``), -1 for none.
    """
    la, lb = a.line, b.line
    acy, acz, ady, adz = la
    bcy, bcz, bdy, bdz = lb
    tol, spacing = scale.tol, scale.spacing
    sp_a = max(a.step, spacing)
    sp_b = max(b.step, spacing)
    ta = a.t + 0.5 * a.step
    tb_b = b.t - 0.5 * b.step
    tb = (bcy + tb_b * bdy - acy) * ady + (bcz + tb_b * bdz - acz) * adz
    width = tb - ta
    if hi - lo < 2:
        return Hole(width, _SEEN, _SEEN)
    q = points[lo + 1 : hi]
    own = owner[lo + 1 : hi]
    near = _near_plates(q, la, lb, tol)
    cover = _pieces_cover(own, pieces, near, la, lb, tol, min_bottom_mm, butt)
    if butt:
        for i in range(q.shape[0]):
            if own[i] < 0 and near.off[i] <= 3.0 * tol:
                near.plate[i] = True
    loose = _loose_cover(q, own, near, ady, adz, tol, min_bottom_mm, butt)
    anything = False
    for i in range(q.shape[0]):
        cover[i] = cover[i] or loose[i] or near.plate[i]
        anything = anything or cover[i]
    if not anything:
        return Hole(width, _SEEN, _SEEN)
    stray = _stray(points, lo, hi, cover, near.plate, scale)
    qa = _along(q, la)
    covered = _covered(cover, qa, sp_a, ta, tb)
    left = right = _SEEN
    if stray.any():
        on_a = np.empty(q.shape[0], dtype=np.bool_)
        on_b = np.empty(q.shape[0], dtype=np.bool_)
        for i in range(q.shape[0]):
            on_a[i] = near.plate[i] and near.off_a[i] <= tol
            on_b[i] = near.plate[i] and near.off_b[i] <= tol
        # Runtime flags: a literal True or False would compile a copy of the callee each.
        at_end, at_start = butt | True, butt & False
        first = _stretch_ends(cover, qa, sp_a, at_end)
        if first.start <= ta + 2.0 * sp_a:
            under = _hidden_edge(first.part, qa, on_a, stray, ta, sp_a, at_end)
            left = HiddenEdge(under.found, Point(acy + under.t * ady, acz + under.t * adz))
        qb = _along(q, lb)
        last = _stretch_ends(cover, qb, sp_b, at_start)
        if last.end >= tb_b - 2.0 * sp_b:
            back = last.part[::-1].copy()
            under = _hidden_edge(back, qb, on_b, stray, tb_b, sp_b, at_start)
            right = HiddenEdge(under.found, Point(bcy + under.t * bdy, bcz + under.t * bdz))
    rest = width - covered
    return Hole(rest if rest > 0.0 else 0.0, left, right)
