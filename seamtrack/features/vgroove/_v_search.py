"""The V search, compiled: a profile's pieces as a table of lines (:class:`LineTable`), their
collinear groups (:func:`groups_of`), the best pair of lines forming a V or a ridge
(:func:`best_pair`), and the corners where lines meet (:func:`corner_with`); :func:`search`
runs the search's steps in order, for the corner extractors (``ExtractorBase._arms``) and the
V-groove model (:mod:`seamtrack.features.vgroove._v_groove_model`).

The family extractors' Python formulation made a handful of numpy calls on 2-vectors per line
and per pair, where each call costs more than the arithmetic; here the same tests run on
scalars, in the same order and with the same floating-point operations, so results do not
change. Every line (a piece of :func:`~seamtrack.features.lines.segment_profile`, a group
refitted on the union of its pieces, an arm cut short at its apex) is a record of a
:class:`LineTable`.

Records ``0..n-1`` are the profile's pieces in column order; a record's number is its identity
(a single piece's group is the piece itself, as in the Python code).

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple, cast

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features._segmentation import (
    FIT_CY,
    FIT_CZ,
    FIT_RMS,
    FIT_UY,
    FIT_UZ,
    PieceTable,
)
from seamtrack.features.arrays import FloatArray, IntArray
from seamtrack.features.counts import explained_share, support
from seamtrack.features.line_geometry import (
    CORNER_MIN_RAD,
    LineThrough,
    Point,
    corner_near,
    fit_line,
    holds,
)
from seamtrack.features.select import sort_small
from seamtrack.jit import KERNEL

#: Radians to degrees as CPython's ``math.degrees`` multiplies.
RAD_TO_DEG = 180.0 / math.pi
#: Pieces within this angle join a collinear group (deg; see ``collinear_members``).
COS_GROUP = math.cos(math.radians(30.0))
#: Lines within this angle meet in no corner (see ``corner_with``).
COS_CORNER = math.cos(CORNER_MIN_RAD)
#: A record that is no line (an int64, not a literal: a literal -1 left in a variable
#: compiles the kernels it is passed to once more for that value, numba's literal dispatch).
NONE = cast(int, np.int64(-1))
#: ``at_end`` for a record's last inlier, and for its first: numpy booleans, which type as
#: ``bool`` (a literal True or False compiles the callee once for each value).
LAST_END = cast(bool, np.bool_(True))
FIRST_END = cast(bool, np.bool_(False))
#: The columns of :attr:`LineTable.geo`.
CY, CZ, UY, UZ, RMS = range(5)
#: The columns of :attr:`LineTable.span`.
START, COUNT = range(2)


class LineTable(NamedTuple):
    """The lines of a V search, one record each (a record's number is its identity).

    ``geo[r]``: centroid y, z, unit direction y, z and rms residual (columns :data:`CY` ..
    :data:`RMS`); ``span[r]``: where its inliers start in ``index``/``along`` and how many
    there are (:data:`START`, :data:`COUNT`); ``index``, ``along``: the inliers' positions
    in the kept points and their coordinates along the line, record after record;
    ``used``: records and pool entries in use.
    """

    geo: FloatArray
    span: IntArray
    index: IntArray  # type: ignore[assignment]  # a field, over tuple.index
    along: FloatArray
    used: IntArray


class Corner(NamedTuple):
    """Where a line ends (y, z) and the record it meets there (:data:`NONE`: none)."""

    y: float
    z: float
    line: int


class VPair(NamedTuple):
    """The best pair of lines forming a V or a ridge: the left and right arms (records, cut
    short at the apex; :data:`NONE`: no pair), the apex (y, z) and the pair's support."""

    left: int
    right: int
    apex_y: float
    apex_z: float
    score: float


class SearchParams(NamedTuple):
    """What the V search looks for: ``sign`` -1 a V opening towards the sensor, +1 a ridge;
    the included angle's range (deg); the farthest an arm may stop short of the apex (mm);
    pieces in no group as arms too; the fewest inliers and the shortest extent (mm) of an
    arm; the expected apex (y, z; a tracker's hint) and how far from it a pair's apex may lie
    across (y) and in range (z) and still be preferred (mm; 0 or NaN: no hint, the
    best-supported pair)."""

    sign: float
    min_deg: float
    max_deg: float
    max_reach: float
    pieces_too: bool
    min_points: int
    min_arm: float
    hint_y: float = math.nan
    hint_z: float = math.nan
    tol_y: float = 0.0
    tol_z: float = 0.0


class Search(NamedTuple):
    """The V search on a profile's pieces (:func:`search`): its table of lines (the pieces
    ``0..n-1``, then the groups and the arms cut short), the groups (records), each kept
    point's piece (-1: none), the surface points (not in a detour) and the best pair."""

    table: LineTable
    groups: IntArray
    owner: IntArray
    surface: NDArray[np.bool_]
    pair: VPair


@numba.njit(**KERNEL)
def new_table(pieces: PieceTable) -> LineTable:
    """The table of a profile's ``n`` pieces, with room for ``n`` groups and two arms cut
    short."""
    index, along, fits, bounds = pieces
    n = fits.shape[0]
    total = index.shape[0]
    cap = 2 * n + 4
    geo = np.zeros((cap, 5))
    span = np.zeros((cap, 2), dtype=np.int64)
    pool_index = np.empty(3 * total + 16, dtype=np.int64)
    pool_t = np.empty(3 * total + 16)
    for k in range(total):
        pool_index[k] = index[k]
        pool_t[k] = along[k]
    at = 0
    for k in range(n):
        geo[k, CY], geo[k, CZ] = fits[k, FIT_CY], fits[k, FIT_CZ]
        geo[k, UY], geo[k, UZ] = fits[k, FIT_UY], fits[k, FIT_UZ]
        geo[k, RMS] = fits[k, FIT_RMS]
        span[k, START], span[k, COUNT] = at, bounds[k + 1] - bounds[k]
        at += span[k, COUNT]
    used = np.zeros(2, dtype=np.int64)
    used[0], used[1] = n, total
    return LineTable(geo, span, pool_index, pool_t, used)


@numba.njit(**KERNEL)
def line_of(geo: FloatArray, r: int) -> LineThrough:
    """Record ``r``'s line (centroid and unit direction) of a :attr:`LineTable.geo`."""
    return LineThrough(geo[r, CY], geo[r, CZ], geo[r, UY], geo[r, UZ])


@numba.njit(**KERNEL)
def surface_of(stray, m):
    """(m,) True for the surface points: not in a detour (``stray``, when it has m entries)."""
    surface = np.ones(m, dtype=np.bool_)
    if stray.shape[0] == m:
        for i in range(m):
            surface[i] = not stray[i]
    return surface


@numba.njit(**KERNEL)
def explained_of(
    points: FloatArray, stray: NDArray[np.bool_], zones: IntArray, fits: FloatArray, band: float
) -> float:
    """:func:`~seamtrack.features.counts.explained_share` over the surface points (not in a
    detour: ``stray``, when it has an entry per point): the share a joint's model explains."""
    return explained_share(points, surface_of(stray, points.shape[0]), zones, fits, band)


@numba.njit(**KERNEL)
def owners(owner, tb, n):
    """Each kept point's piece (-1: none) into ``owner``."""
    span, pool = tb.span, tb.index
    for i in range(owner.shape[0]):
        owner[i] = -1
    for k in range(n):
        for q in range(span[k, START], span[k, START] + span[k, COUNT]):
            owner[pool[q]] = k


@numba.njit(**KERNEL)
def add_fit(points, tb, sel):
    """A new record: the total-least-squares line through ``points[sel]`` (as
    :func:`~seamtrack.features.line_geometry.fit_line`)."""
    geo, span, index, along, used = tb
    r, a, n = used[0], used[1], sel.shape[0]
    f = fit_line(points, sel)
    geo[r, CY], geo[r, CZ], geo[r, UY], geo[r, UZ], geo[r, RMS] = f.cy, f.cz, f.dy, f.dz, f.rms
    span[r, START], span[r, COUNT] = a, n
    for k in range(n):
        index[a + k] = sel[k]
        along[a + k] = f.along[k]
    used[0] = r + 1
    used[1] = a + n
    return r


@numba.njit(**KERNEL)
def first(tb, r):
    """Position of record ``r``'s first inlier."""
    return tb.index[tb.span[r, START]]


@numba.njit(**KERNEL)
def last(tb, r):
    """Position of record ``r``'s last inlier."""
    return tb.index[tb.span[r, START] + tb.span[r, COUNT] - 1]


@numba.njit(**KERNEL)
def t_end(tb, r, at_end):
    """Coordinate of record ``r``'s last (``at_end``) or first inlier along it."""
    a, c = tb.span[r, START], tb.span[r, COUNT]
    return tb.along[a + c - 1] if at_end else tb.along[a]


@numba.njit(**KERNEL)
def step(tb, r, at_end):
    """As ``Line.step``: mean spacing of the last (first) ten inliers along the line."""
    a, c = tb.span[r, START], tb.span[r, COUNT]
    k = min(10, c - 1)
    if k < 1:
        return 0.0
    t = tb.along
    if at_end:
        return abs(t[a + c - 1] - t[a + c - 1 - k]) / k
    return abs(t[a + k] - t[a]) / k


@numba.njit(**KERNEL)
def point(tb, r, t):
    """As ``Line.point``: the point at coordinate ``t`` along record ``r``."""
    g = tb.geo
    return Point(g[r, CY] + t * g[r, UY], g[r, CZ] + t * g[r, UZ])


@numba.njit(**KERNEL)
def end(tb, r, at_end):
    """As ``Line.end``: half a spacing beyond the last (first) inlier."""
    half = 0.5 * step(tb, r, at_end)
    t = t_end(tb, r, LAST_END) + half if at_end else t_end(tb, r, FIRST_END) - half
    return point(tb, r, t)


@numba.njit(**KERNEL)
def dot_dir(tb, r, s):
    """``r.direction @ s.direction``."""
    g = tb.geo
    return g[r, UY] * g[s, UY] + g[r, UZ] * g[s, UZ]


@numba.njit(**KERNEL)
def pmax(a, b):
    """Python's ``max(a, b)`` (NaN handling included)."""
    return b if b > a else a


@numba.njit(**KERNEL)
def pmin(a, b):
    """Python's ``min(a, b)``."""
    return b if b < a else a


@numba.njit(**KERNEL)
def contains(tb, r, i):
    """Whether kept point ``i`` is an inlier of record ``r`` (sorted inliers)."""
    pool = tb.index
    lo, hi = tb.span[r, START], tb.span[r, START] + tb.span[r, COUNT]
    while lo < hi:  # np.searchsorted (left)
        mid = (lo + hi) // 2
        if pool[mid] < i:
            lo = mid + 1
        else:
            hi = mid
    return lo < tb.span[r, START] + tb.span[r, COUNT] and pool[lo] == i


@numba.njit(**KERNEL)
def groups_of(points, tb, n, tol, min_points, min_arm):
    """The collinear groups (as :func:`~seamtrack.features.lines.collinear_groups`, refitted
    on the union
    of their pieces) with at least ``min_points`` inliers over ``min_arm`` (mm), as records."""
    geo, span = tb.geo, tb.span
    order = np.empty(n, dtype=np.int64)  # by count, largest first, stable (as sorted())
    for i in range(n):
        j = i - 1
        while j >= 0 and span[order[j], 1] < span[i, COUNT]:
            order[j + 1] = order[j]
            j -= 1
        order[j + 1] = i
    anchor = np.empty(n, dtype=np.int64)
    size = np.zeros(n, dtype=np.int64)
    member = np.empty(n, dtype=np.int64)
    groups = 0
    for i in order:
        line = line_of(geo, i)
        t0, t1 = t_end(tb, i, FIRST_END), t_end(tb, i, LAST_END)
        joined = -1
        for k in range(groups):
            if holds(line_of(geo, anchor[k]), line, t0, t1, COS_GROUP, tol):
                joined = k
                break
        if joined < 0:
            anchor[groups] = i
            joined = groups
            groups += 1
        size[joined] += 1
        member[i] = joined
    out = np.empty(groups, dtype=np.int64)
    kept = 0
    for k in range(groups):
        if size[k] == 1:
            r = anchor[k]
        else:
            total = 0
            for i in range(n):
                if member[i] == k:
                    total += span[i, COUNT]
            sel = np.empty(total, dtype=np.int64)
            at = 0
            for i in range(n):
                if member[i] == k:
                    a, c = span[i, START], span[i, COUNT]
                    for q in range(c):
                        sel[at + q] = tb.index[a + q]
                    at += c
            r = add_fit(points, tb, sort_small(sel))  # pieces in column order: sorted
        c = span[r, COUNT]
        extent = t_end(tb, r, LAST_END) - t_end(tb, r, FIRST_END) if c else 0.0
        if c >= min_points and extent >= min_arm:
            out[kept] = r
            kept += 1
    return out[:kept]


@numba.njit(**KERNEL)
def _reach(points, tb, g, xy, xz, vy, vz, tol, owner, mark):
    """How near arm ``g`` comes to the apex (x, y), along its direction (vy, vz) from the
    apex. A tenth of a group may lie past it: fragments of the root collinear with a bevel,
    or a bevel's own piece rounding into the root, but none by more than three tolerances
    when its piece also lies ahead (a piece that runs on through the apex crosses the other
    arm: no V there, -inf). ``mark``: (n + 1,) False, scratch, left False."""
    a, c = tb.span[g, START], tb.span[g, COUNT]
    pool = tb.index
    over = 0
    t_min, t_ahead = np.inf, np.inf
    for k in range(a, a + c):
        i = pool[k]
        t = (points[i, 0] - xy) * vy + (points[i, 1] - xz) * vz
        t_min = min(t_min, t)
        if t >= -tol:
            t_ahead = min(t_ahead, t)
            mark[owner[i] + 1] = True
        else:
            over += 1
    through = False
    if 0 < over and 10 * over <= c:
        for k in range(a, a + c):
            i = pool[k]
            t = (points[i, 0] - xy) * vy + (points[i, 1] - xz) * vz
            if t < -tol and mark[owner[i] + 1] and t < -3.0 * tol:
                through = True
    for k in range(a, a + c):
        mark[owner[pool[k]] + 1] = False
    if over == 0:
        return t_min
    if 10 * over > c or through:
        return -np.inf
    return t_ahead


@numba.njit(**KERNEL)
def _short_of(points, tb, r, xy, xz, tol):
    """Record ``r`` without the inliers that lie past the apex (more than a tolerance): the
    arm of a V ends at its apex (a new record, refitted; ``r`` when none or all but one)."""
    geo, span = tb.geo, tb.span
    vy, vz = geo[r, CY] - xy, geo[r, CZ] - xz
    floor = -tol * math.hypot(vy, vz)
    a, c = span[r, START], span[r, COUNT]
    keep = np.empty(c, dtype=np.bool_)
    kept = 0
    for k in range(c):
        i = tb.index[a + k]
        keep[k] = (points[i, 0] - xy) * vy + (points[i, 1] - xz) * vz >= floor
        kept += keep[k]
    if kept == c or kept < 2:
        return r
    sel = np.empty(kept, dtype=np.int64)
    kept = 0
    for k in range(c):
        if keep[k]:
            sel[kept] = tb.index[a + k]
            kept += 1
    return add_fit(points, tb, sel)


@numba.njit(**KERNEL)
def _candidates(tb, groups, n, min_points, min_arm):
    """The groups, then the pieces in no group that could be arms: at least ``min_points``
    inliers over at least ``min_arm`` (mm)."""
    extra = np.empty(n, dtype=np.int64)
    e = 0
    for k in range(n):
        grouped = False
        for r in groups:
            grouped = grouped or r == k
        c = tb.span[k, COUNT]
        if grouped:
            continue
        if c >= min_points and t_end(tb, k, LAST_END) - t_end(tb, k, FIRST_END) >= min_arm:
            extra[e] = k
            e += 1
    cand = np.empty(groups.shape[0] + e, dtype=np.int64)
    for k in range(groups.shape[0]):
        cand[k] = groups[k]
    for k in range(e):
        cand[groups.shape[0] + k] = extra[k]
    return cand


class VApex(NamedTuple):
    """Two records' apex (:func:`_v_apex`): whether they form the V, the apex (``y``, ``z``),
    the left arm's record and unit direction from the apex, then the right's."""

    ok: bool
    y: float
    z: float
    left: int
    left_uy: float
    left_uz: float
    right: int
    right_uy: float
    right_uz: float


@numba.njit(**KERNEL)
def _v_apex(geo, a, b, sign, min_deg, max_deg):
    """Whether records ``a`` and ``b`` form a V (``sign`` -1: opening towards the sensor) or
    a ridge (+1) with an included angle in ``min_deg``..``max_deg`` and a bisector within 45
    deg of the range axis; the apex (y, z), the left arm's record and unit direction from
    the apex, then the right's."""
    ay, az, ady, adz = line_of(geo, a)
    by, bz, bdy, bdz = line_of(geo, b)
    d = ady * bdz - adz * bdy
    if abs(d) < 1e-9:
        return VApex(False, 0.0, 0.0, a, 0.0, 0.0, b, 0.0, 0.0)  # parallel: no apex
    s = ((by - ay) * bdz - (bz - az) * bdy) / d
    xy, xz = ay + s * ady, az + s * adz
    uy, uz, wy, wz = ay - xy, az - xz, by - xy, bz - xz
    nu, nw = max(math.hypot(uy, uz), 1e-300), max(math.hypot(wy, wz), 1e-300)
    uy, uz, wy, wz = uy / nu, uz / nu, wy / nw, wz / nw
    ga, gb = a, b
    if wy < uy:
        uy, uz, wy, wz, ga, gb = wy, wz, uy, uz, b, a
    c = pmin(pmax(uy * wy + uz * wz, -1.0), 1.0)
    angle = math.acos(c) * RAD_TO_DEG
    by_, bz_ = uy + wy, uz + wz
    ok = (
        uy < 0.0 < wy
        and sign * uz > 0
        and sign * wz > 0
        and min_deg <= angle <= max_deg
        and sign * bz_ > 0.7 * math.hypot(by_, bz_)  # bisector within 45 deg
    )
    return VApex(ok, xy, xz, ga, uy, uz, gb, wy, wz)


@numba.njit(**KERNEL)
def _arm_support(points, surface, geo, r, vy, vz, xy, xz, band, tol):
    """The :func:`~seamtrack.features.counts.support` of record ``r`` as an arm leaving the
    apex (``xy``, ``xz``) along (``vy``, ``vz``)."""
    line = line_of(geo, r)
    side = 1.0 if vy * line.dy + vz * line.dz > 0 else -1.0
    x_u = xy * line.dy + xz * line.dz
    return support(points, surface, line, band, x_u, side, tol)


@numba.njit(**KERNEL)
def best_pair(points, surface, owner, tb, groups, n, tol, params):
    """``ExtractorBase._arms``: the best pair of records forming a V (``params.sign`` -1: opening
    towards the sensor) or a ridge (+1), the arms cut short at the apex (:class:`VPair`;
    left :data:`NONE` when no pair does). With a hint (``params.tol_y``, ``tol_z`` > 0), of
    the pairs whose apex lies within the tolerance ellipse about the expected point the
    nearest (in tolerances) is taken; when none does, the best-supported pair, as without a
    hint."""
    geo = tb.geo
    cand = groups
    if params.pieces_too:
        cand = _candidates(tb, groups, n, params.min_points, params.min_arm)
    band = 2.0 * tol
    mark = np.zeros(n + 1, dtype=np.bool_)
    best_a, best_b, best_y, best_z, best_score = NONE, NONE, 0.0, 0.0, 0.0
    hy, hz, tol_y, tol_z = params.hint_y, params.hint_z, params.tol_y, params.tol_z
    hinted = tol_y > 0.0 and tol_z > 0.0 and math.isfinite(hy) and math.isfinite(hz)
    near_a, near_b, near_y, near_z, near_score, near_d = NONE, NONE, 0.0, 0.0, 0.0, 1.0
    g = cand.shape[0]
    for i in range(g):
        for j in range(i + 1, g):
            ok, xy, xz, ga, uy, uz, gb, wy, wz = _v_apex(
                geo, cand[i], cand[j], params.sign, params.min_deg, params.max_deg
            )
            if not ok:
                continue
            na = _reach(points, tb, ga, xy, xz, uy, uz, tol, owner, mark)
            nb = _reach(points, tb, gb, xy, xz, wy, wz, tol, owner, mark)
            if not (-tol <= pmin(na, nb) and pmax(na, nb) <= params.max_reach):
                continue
            score = 0.0
            score += _arm_support(points, surface, geo, ga, uy, uz, xy, xz, band, tol)
            score += _arm_support(points, surface, geo, gb, wy, wz, xy, xz, band, tol)
            if best_a == NONE or score > best_score:
                best_a, best_b, best_y, best_z, best_score = ga, gb, xy, xz, score
            if hinted:
                d_hint = math.hypot((xy - hy) / tol_y, (xz - hz) / tol_z)
                if d_hint <= near_d:
                    near_a, near_b, near_y, near_z, near_score = ga, gb, xy, xz, score
                    near_d = d_hint
    if near_a != NONE:
        best_a, best_b, best_y, best_z, best_score = near_a, near_b, near_y, near_z, near_score
    if best_a == NONE:
        return VPair(NONE, NONE, 0.0, 0.0, 0.0)
    left = _short_of(points, tb, best_a, best_y, best_z, tol)
    right = _short_of(points, tb, best_b, best_y, best_z, tol)
    return VPair(left, right, best_y, best_z, best_score)


@numba.njit(**KERNEL)
def corner_with(tb, line, at_end, others, spacing, tol):
    """Where record ``line`` ends and the record of ``others`` it meets there
    (:class:`Corner`): its crossing with a line that meets it at that end (a visible corner,
    exact; :func:`~seamtrack.features.line_geometry.corner_crossing`), else (:data:`NONE`)
    half a spacing beyond its last inlier (the edge lies between rays)."""
    geo = tb.geo
    cy, cz, dy, dz = line_of(geo, line)
    t_tip = t_end(tb, line, at_end)
    tip_y, tip_z = cy + t_tip * dy, cz + t_tip * dz
    reach = 3.0 * pmax(step(tb, line, at_end), spacing) + tol
    best, best_d, best_y, best_z = NONE, np.inf, 0.0, 0.0
    here = LineThrough(cy, cz, dy, dz)
    for other in others:
        if other == line:
            continue
        there = line_of(geo, other)
        wide = pmax(pmax(step(tb, other, LAST_END), step(tb, other, FIRST_END)), spacing)
        c = corner_near(
            here, tip_y, tip_z, there, t_end(tb, other, FIRST_END), t_end(tb, other, LAST_END),
            COS_CORNER, reach, best_d, 3.0 * wide + tol,
        )  # fmt: skip
        if c.found:
            best, best_d, best_y, best_z = other, c.d, c.y, c.z
    if best == NONE:
        best_y, best_z = end(tb, line, at_end)
    return Corner(best_y, best_z, best)


@numba.njit(**KERNEL)
def search(points, stray, tol, pieces, params):
    """The V search on a profile's pieces (:class:`~seamtrack.features._segmentation.PieceTable`),
    in its steps: the table of lines, each point's piece, the collinear groups, the best
    pair (:class:`Search`)."""
    tb = new_table(pieces)
    n = pieces.fits.shape[0]
    m = points.shape[0]
    surface = surface_of(stray, m)
    owner = np.empty(m, dtype=np.int64)  # each point's piece
    owners(owner, tb, n)
    groups = groups_of(points, tb, n, tol, params.min_points, params.min_arm)
    pair = best_pair(points, surface, owner, tb, groups, n, tol, params)
    return Search(tb, groups, owner, surface, pair)


def pieces_of(seg: Any) -> PieceTable:
    """The :class:`~seamtrack.features._segmentation.PieceTable` of a
    :class:`~seamtrack.features.lines.Segments`: the one segmentation left (``seg.table``),
    else built from its lines."""
    if seg.table is not None:
        return seg.table
    return flat_lines(seg.lines)


def flat_lines(lines: list[Any]) -> PieceTable:
    """A profile's pieces (:class:`~seamtrack.features.lines.Line`, at least one) as a
    :class:`~seamtrack.features._segmentation.PieceTable`."""
    counts = [len(ln.index) for ln in lines]
    fits = np.array(
        [
            (*ln.centroid.tolist(), *ln.direction.tolist(), ln.rms, ln.t[0], ln.t[-1])
            for ln in lines
        ],
        dtype=np.float64,
    )
    return PieceTable(
        np.concatenate([ln.index for ln in lines]).astype(np.intp),
        np.concatenate([ln.t for ln in lines]),
        fits.reshape(-1, 7),
        np.concatenate([[0], np.cumsum(counts)]).astype(np.intp),
    )
