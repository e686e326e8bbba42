"""Compiled line geometry of the V searches: a profile's pieces as a table of flat arrays, their
collinear groups, the V (or ridge) pair search and the corners where lines meet.

The family extractors' Python formulation made a handful of numpy calls on 2-vectors per line
and per pair, where each call costs more than the arithmetic; here the same tests run on
scalars, in the same order and with the same floating-point operations, so results do not
change. Every line (a piece of :func:`~seamtrack.features.lines.segment_profile`, a group
refitted on the union of its pieces, an arm cut short at its apex) is a record of a table:

- ``geo[r]``: centroid y, z, unit direction y, z and rms residual;
- ``span[r]``: where its inliers start in the pool and how many there are;
- ``pool_index``, ``pool_t``: the inliers' positions in the kept points and their coordinates
  along the line, record after record;
- ``state``: records and pool entries in use.

Records ``0..n-1`` are the profile's pieces in column order; a record's number is its identity
(a single piece's group is the piece itself, as in the Python code).

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.counts import explained_share, support
from seamtrack.features.kernels import fit_line

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]
#: Radians to degrees as CPython's ``math.degrees`` multiplies.
RAD_TO_DEG = 180.0 / math.pi
#: Pieces within this angle join a collinear group (deg; see ``collinear_members``).
COS_GROUP = math.cos(math.radians(30.0))
#: Lines within this angle meet in no corner (deg; see ``corner_with``).
COS_CORNER = math.cos(math.radians(20.0))
#: A record that is no line.
NONE = -1


@numba.njit(cache=True, nogil=True)
def new_table(
    index: IntArray,
    along: FloatArray,
    centroids: FloatArray,
    directions: FloatArray,
    fits: FloatArray,
) -> tuple[FloatArray, IntArray, IntArray, FloatArray, IntArray]:
    """The table of a profile's ``n`` pieces (see :func:`flat_lines`), with room for ``n``
    groups and two arms cut short."""
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
        geo[k, 0], geo[k, 1] = centroids[2 * k], centroids[2 * k + 1]
        geo[k, 2], geo[k, 3] = directions[2 * k], directions[2 * k + 1]
        geo[k, 4] = fits[k, 0]
        span[k, 0], span[k, 1] = at, int(fits[k, 1])
        at += span[k, 1]
    state = np.zeros(2, dtype=np.int64)
    state[0], state[1] = n, total
    return geo, span, pool_index, pool_t, state


@numba.njit(cache=True, nogil=True)
def surface_of(stray, m):
    """(m,) True for the surface points: not in a detour (``stray``, when it has m entries)."""
    surface = np.ones(m, dtype=np.bool_)
    if stray.shape[0] == m:
        for i in range(m):
            surface[i] = not stray[i]
    return surface


@numba.njit(cache=True, nogil=True)
def explained_of(
    points: FloatArray, stray: NDArray[np.bool_], zones: IntArray, fits: FloatArray, band: float
) -> float:
    """:func:`~seamtrack.features.counts.explained_share` over the surface points (not in a
    detour: ``stray``, when it has an entry per point): the share a joint's model explains."""
    return explained_share(points, surface_of(stray, points.shape[0]), zones, fits, band)


@numba.njit(cache=True, nogil=True)
def owners(owner, span, pool, n):
    """Each kept point's piece (-1: none) into ``owner``."""
    for i in range(owner.shape[0]):
        owner[i] = -1
    for k in range(n):
        for q in range(span[k, 0], span[k, 0] + span[k, 1]):
            owner[pool[q]] = k


@numba.njit(cache=True, nogil=True)
def sort_small(x):
    """Sort ``x`` in place by insertion (stable; few values, or runs already in order: the
    generic sorts cost seconds of compile time for nothing here)."""
    for i in range(1, x.shape[0]):
        v = x[i]
        j = i - 1
        while j >= 0 and x[j] > v:
            x[j + 1] = x[j]
            j -= 1
        x[j + 1] = v
    return x


@numba.njit(cache=True, nogil=True)
def add_fit(points, tb, sel):
    """A new record: the total-least-squares line through ``points[sel]`` (as
    :func:`~seamtrack.features.lines._fit`)."""
    geo, span, pool_index, pool_t, state = tb
    r, a, n = state[0], state[1], sel.shape[0]
    cy, cz, uy, uz, rms, t = fit_line(points, sel)
    geo[r, 0], geo[r, 1], geo[r, 2], geo[r, 3], geo[r, 4] = cy, cz, uy, uz, rms
    span[r, 0], span[r, 1] = a, n
    for k in range(n):
        pool_index[a + k] = sel[k]
        pool_t[a + k] = t[k]
    state[0] = r + 1
    state[1] = a + n
    return r


@numba.njit(cache=True, nogil=True)
def first(tb, r):
    """Position of record ``r``'s first inlier."""
    return tb[2][tb[1][r, 0]]


@numba.njit(cache=True, nogil=True)
def last(tb, r):
    """Position of record ``r``'s last inlier."""
    return tb[2][tb[1][r, 0] + tb[1][r, 1] - 1]


@numba.njit(cache=True, nogil=True)
def t_end(tb, r, at_end):
    """Coordinate of record ``r``'s last (``at_end``) or first inlier along it."""
    a, c = tb[1][r, 0], tb[1][r, 1]
    return tb[3][a + c - 1] if at_end else tb[3][a]


@numba.njit(cache=True, nogil=True)
def step(tb, r, at_end):
    """As ``Line.step``: mean spacing of the last (first) ten inliers along the line."""
    a, c = tb[1][r, 0], tb[1][r, 1]
    k = min(10, c - 1)
    if k < 1:
        return 0.0
    t = tb[3]
    if at_end:
        return abs(t[a + c - 1] - t[a + c - 1 - k]) / k
    return abs(t[a + k] - t[a]) / k


@numba.njit(cache=True, nogil=True)
def point(tb, r, t):
    """As ``Line.point``: the point at coordinate ``t`` along record ``r``."""
    g = tb[0]
    return g[r, 0] + t * g[r, 2], g[r, 1] + t * g[r, 3]


@numba.njit(cache=True, nogil=True)
def end(tb, r, at_end):
    """As ``Line.end``: half a spacing beyond the last (first) inlier."""
    half = 0.5 * step(tb, r, at_end)
    t = t_end(tb, r, True) + half if at_end else t_end(tb, r, False) - half
    return point(tb, r, t)


@numba.njit(cache=True, nogil=True)
def dot_dir(tb, r, s):
    """``r.direction @ s.direction``."""
    g = tb[0]
    return g[r, 2] * g[s, 2] + g[r, 3] * g[s, 3]


@numba.njit(cache=True, nogil=True)
def pmax(a, b):
    """Python's ``max(a, b)`` (NaN handling included)."""
    return b if b > a else a


@numba.njit(cache=True, nogil=True)
def pmin(a, b):
    """Python's ``min(a, b)``."""
    return b if b < a else a


@numba.njit(cache=True, nogil=True)
def contains(tb, r, i):
    """Whether kept point ``i`` is an inlier of record ``r`` (sorted inliers)."""
    pool = tb[2]
    lo, hi = tb[1][r, 0], tb[1][r, 0] + tb[1][r, 1]
    while lo < hi:  # np.searchsorted (left)
        mid = (lo + hi) // 2
        if pool[mid] < i:
            lo = mid + 1
        else:
            hi = mid
    return lo < tb[1][r, 0] + tb[1][r, 1] and pool[lo] == i


@numba.njit(cache=True, nogil=True)
def groups_of(points, tb, n, tol, min_points, min_arm):
    """The collinear groups (as :func:`~seamtrack.features.lines.collinear_groups`, refitted
    on the union
    of their pieces) with at least ``min_points`` inliers over ``min_arm`` (mm), as records."""
    geo, span = tb[0], tb[1]
    order = np.empty(n, dtype=np.int64)  # by count, largest first, stable (as sorted())
    for i in range(n):
        j = i - 1
        while j >= 0 and span[order[j], 1] < span[i, 1]:
            order[j + 1] = order[j]
            j -= 1
        order[j + 1] = i
    anchor = np.empty(n, dtype=np.int64)
    size = np.zeros(n, dtype=np.int64)
    member = np.empty(n, dtype=np.int64)
    groups = 0
    for i in order:
        cy, cz, dy, dz = geo[i, 0], geo[i, 1], geo[i, 2], geo[i, 3]
        t0, t1 = t_end(tb, i, False), t_end(tb, i, True)
        e0y, e0z, e1y, e1z = cy + t0 * dy, cz + t0 * dz, cy + t1 * dy, cz + t1 * dz
        joined = -1
        for k in range(groups):
            a = anchor[k]
            ay, az, ady, adz = geo[a, 0], geo[a, 1], geo[a, 2], geo[a, 3]
            if (
                abs(ady * dy + adz * dz) >= COS_GROUP
                and abs((e0y - ay) * -adz + (e0z - az) * ady) <= tol
                and abs((e1y - ay) * -adz + (e1z - az) * ady) <= tol
            ):
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
                    total += span[i, 1]
            sel = np.empty(total, dtype=np.int64)
            at = 0
            for i in range(n):
                if member[i] == k:
                    a, c = span[i, 0], span[i, 1]
                    for q in range(c):
                        sel[at + q] = tb[2][a + q]
                    at += c
            r = add_fit(points, tb, sort_small(sel))  # pieces in column order: sorted
        c = span[r, 1]
        extent = t_end(tb, r, True) - t_end(tb, r, False) if c else 0.0
        if c >= min_points and extent >= min_arm:
            out[kept] = r
            kept += 1
    return out[:kept]


@numba.njit(cache=True, nogil=True)
def _reach(points, tb, g, xy, xz, vy, vz, tol, owner, mark):
    """How near arm ``g`` comes to the apex (x, y), along its direction (vy, vz) from the
    apex. A tenth of a group may lie past it: fragments of the root collinear with a bevel,
    or a bevel's own piece rounding into the root, but none by more than three tolerances
    when its piece also lies ahead (a piece that runs on through the apex crosses the other
    arm: no V there, -inf). ``mark``: (n + 1,) False, scratch, left False."""
    a, c = tb[1][g, 0], tb[1][g, 1]
    pool = tb[2]
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


@numba.njit(cache=True, nogil=True)
def _short_of(points, tb, r, xy, xz, tol):
    """Record ``r`` without the inliers that lie past the apex (more than a tolerance): the
    arm of a V ends at its apex (a new record, refitted; ``r`` when none or all but one)."""
    geo, span = tb[0], tb[1]
    vy, vz = geo[r, 0] - xy, geo[r, 1] - xz
    floor = -tol * math.hypot(vy, vz)
    a, c = span[r, 0], span[r, 1]
    keep = np.empty(c, dtype=np.bool_)
    kept = 0
    for k in range(c):
        i = tb[2][a + k]
        keep[k] = (points[i, 0] - xy) * vy + (points[i, 1] - xz) * vz >= floor
        kept += keep[k]
    if kept == c or kept < 2:
        return r
    sel = np.empty(kept, dtype=np.int64)
    kept = 0
    for k in range(c):
        if keep[k]:
            sel[kept] = tb[2][a + k]
            kept += 1
    return add_fit(points, tb, sel)


@numba.njit(cache=True, nogil=True)
def arms(
    points,
    surface,
    owner,
    tb,
    groups,
    n,
    sign,
    min_deg,
    max_deg,
    max_reach,
    tol,
    pieces_too,
    min_points,
    min_arm,
):
    """``_Base._arms``: the best pair of records forming a V (``sign`` -1: opening towards the
    sensor) or a ridge (+1): (left, right, apex y, z, score), the arms cut short at the apex;
    left -1 when no pair does."""
    geo = tb[0]
    cand = groups
    if pieces_too:
        extra = np.empty(n, dtype=np.int64)
        e = 0
        for k in range(n):
            grouped = False
            for r in groups:
                grouped = grouped or r == k
            c = tb[1][k, 1]
            if grouped:
                continue
            if c >= min_points and t_end(tb, k, True) - t_end(tb, k, False) >= min_arm:
                extra[e] = k
                e += 1
        cand = np.empty(groups.shape[0] + e, dtype=np.int64)
        for k in range(groups.shape[0]):
            cand[k] = groups[k]
        for k in range(e):
            cand[groups.shape[0] + k] = extra[k]
    band = 2.0 * tol
    mark = np.zeros(n + 1, dtype=np.bool_)
    best_a, best_b, best_y, best_z, best_score = NONE, NONE, 0.0, 0.0, 0.0
    g = cand.shape[0]
    for i in range(g):
        a = cand[i]
        ay, az, ady, adz = geo[a, 0], geo[a, 1], geo[a, 2], geo[a, 3]
        for j in range(i + 1, g):
            b = cand[j]
            by, bz, bdy, bdz = geo[b, 0], geo[b, 1], geo[b, 2], geo[b, 3]
            d = ady * bdz - adz * bdy
            if abs(d) < 1e-9:
                continue  # parallel: no apex
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
            if not (
                uy < 0.0 < wy
                and sign * uz > 0
                and sign * wz > 0
                and min_deg <= angle <= max_deg
                and sign * bz_ > 0.7 * math.hypot(by_, bz_)  # bisector within 45 deg
            ):
                continue
            na = _reach(points, tb, ga, xy, xz, uy, uz, tol, owner, mark)
            nb = _reach(points, tb, gb, xy, xz, wy, wz, tol, owner, mark)
            if not (-tol <= pmin(na, nb) and pmax(na, nb) <= max_reach):
                continue
            score = 0.0
            for r, vy, vz in ((ga, uy, uz), (gb, wy, wz)):
                gy, gz, gdy, gdz = geo[r, 0], geo[r, 1], geo[r, 2], geo[r, 3]
                side = 1.0 if vy * gdy + vz * gdz > 0 else -1.0
                x_u = xy * gdy + xz * gdz
                score += support(points, surface, gy, gz, gdy, gdz, band, x_u, side, tol)
            if best_a == NONE or score > best_score:
                best_a, best_b, best_y, best_z, best_score = ga, gb, xy, xz, score
    if best_a == NONE:
        return NONE, NONE, 0.0, 0.0, 0.0
    left = _short_of(points, tb, best_a, best_y, best_z, tol)
    right = _short_of(points, tb, best_b, best_y, best_z, tol)
    return left, right, best_y, best_z, best_score


@numba.njit(cache=True, nogil=True)
def corner_with(tb, line, at_end, others, spacing, tol):
    """As :func:`~seamtrack.features.lines.corner_with`: where record ``line`` ends and the
    record of ``others`` it meets
    there (y, z, record; -1: none, the end half a spacing beyond the last inlier)."""
    geo = tb[0]
    cy, cz, dy, dz = geo[line, 0], geo[line, 1], geo[line, 2], geo[line, 3]
    t_tip = t_end(tb, line, at_end)
    tip_y, tip_z = cy + t_tip * dy, cz + t_tip * dz
    reach = 3.0 * pmax(step(tb, line, at_end), spacing) + tol
    best, best_d, best_y, best_z = NONE, np.inf, 0.0, 0.0
    for other in others:
        if other == line:
            continue
        ocy, ocz, ody, odz = geo[other, 0], geo[other, 1], geo[other, 2], geo[other, 3]
        if abs(dy * ody + dz * odz) > COS_CORNER:
            continue  # within 20 deg: no corner
        det = dy * odz - dz * ody
        if abs(det) < 1e-9:
            continue
        s = ((ocy - cy) * odz - (ocz - cz) * ody) / det
        xy, xz = cy + s * dy, cz + s * dz
        d = math.hypot(xy - tip_y, xz - tip_z)
        if d > reach or d >= best_d:
            continue
        o_first, o_last = t_end(tb, other, False), t_end(tb, other, True)
        near = pmin(
            math.hypot(ocy + o_first * ody - xy, ocz + o_first * odz - xz),
            math.hypot(ocy + o_last * ody - xy, ocz + o_last * odz - xz),
        )
        wide = pmax(pmax(step(tb, other, True), step(tb, other, False)), spacing)
        if near <= 3.0 * wide + tol:
            best, best_d, best_y, best_z = other, d, xy, xz
    if best == NONE:
        best_y, best_z = end(tb, line, at_end)
    return best_y, best_z, best


@numba.njit(cache=True, nogil=True)
def arm_pair(points, stray, tol, index, along, centroids, directions, fits, params):
    """``_Base._arms`` on the profile's pieces (:func:`flat_lines`: ``index`` .. ``fits``):
    the groups, then the best pair (left, right, apex y, z, score; left -1: none) and the
    table of lines that holds them. ``params``: sign (-1: a V, 1: a ridge), min and max
    included angle (deg), max reach (mm), pieces as arms (0/1), min points, min arm (mm)."""
    sign, min_deg, max_deg, max_reach = params[0], params[1], params[2], params[3]
    pieces_too, min_points, min_arm = params[4] != 0, int(params[5]), params[6]
    tb = new_table(index, along, centroids, directions, fits)
    n = fits.shape[0]
    m = points.shape[0]
    surface = surface_of(stray, m)
    owner = np.empty(m, dtype=np.int64)  # each point's piece
    span, pool = tb[1], tb[2]
    owners(owner, span, pool, n)
    groups = groups_of(points, tb, n, tol, min_points, min_arm)
    left, right, y, z, score = arms(
        points,
        surface,
        owner,
        tb,
        groups,
        n,
        sign,
        min_deg,
        max_deg,
        max_reach,
        tol,
        pieces_too,
        min_points,
        min_arm,
    )
    return left, right, y, z, score, tb


def pieces_of(seg: Any) -> tuple[IntArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """:func:`flat_lines` of a :class:`~seamtrack.features.lines.Segments`' pieces, from the
    arrays segmentation left (``seg.table``) when it has them."""
    if seg.table is None:
        return flat_lines(seg.lines)
    index, along, fits, bounds = seg.table
    counts = np.diff(bounds)
    return (
        index,
        along,
        fits[:, 0:2].ravel(),
        fits[:, 2:4].ravel(),
        np.column_stack((fits[:, 4], counts)),
    )


def flat_lines(
    lines: list[Any],
) -> tuple[IntArray, FloatArray, FloatArray, FloatArray, FloatArray]:
    """A profile's pieces (:class:`~seamtrack.features.lines.Line`, at least one) as flat
    arrays: inliers' positions and coordinates, piece after piece; centroids and directions
    (y, z per piece); rms residual and inlier count per piece."""
    index, along, centroids, directions, fits = [], [], [], [], []
    for ln in lines:
        index.append(ln.index)
        along.append(ln.t)
        centroids.append(ln.centroid)
        directions.append(ln.direction)
        fits.append((ln.rms, len(ln.index)))
    geo = np.concatenate(centroids + directions)  # one call for both
    n = 2 * len(lines)
    return (
        np.concatenate(index),
        np.concatenate(along),
        geo[:n],
        geo[n:],
        np.array(fits, dtype=np.float64),
    )
