"""The V-groove's root, compiled (:class:`seamtrack.features.vgroove.extractor.VGrooveExtractor`):
what lies between and beyond the bevels' lower ends, on the line table of the V search
(:class:`seamtrack.features.vgroove._v_search.LineTable`: the profile's pieces, their groups, the
arms). The bevels are a :class:`Bevels` (two records and the apex), their lower ends a
:class:`RootEnds`.

These were the extractor's Python helpers (``_covered_end``, ``_continued``, ...): compiled with
the same tests in the same order and the same floating-point operations, so results do not
change. Lines are records of the table (numbers; -1: none); points are passed as scalars.

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray, IntArray
from seamtrack.features.line_geometry import Point
from seamtrack.features.lines import WALL_DEG
from seamtrack.features.select import sort_small
from seamtrack.features.vgroove._v_search import (
    COUNT,
    CY,
    CZ,
    FIRST_END,
    LAST_END,
    NONE,
    START,
    UY,
    UZ,
    contains,
    dot_dir,
    end,
    first,
    last,
    pmax,
    pmin,
    point,
    step,
    t_end,
)
from seamtrack.jit import KERNEL

#: A piece steeper than this on the plates is a wall (a root face).
COS_WALL = math.cos(math.radians(WALL_DEG))
#: A piece within this angle of a bevel is part of it (deg).
COS_ARM = math.cos(math.radians(15.0))
#: A plate within this angle of its bevel is a piece of the bevel (deg; ``_level``).
COS_LEVEL = math.cos(math.radians(20.0))


class Bevels(NamedTuple):
    """A V's two bevels (records of the line table; the left one first in column order)
    and their lines' crossing, the apex (y, z)."""

    left: int
    right: int
    apex_y: float
    apex_z: float


class RootEnds(NamedTuple):
    """The bevels' lower ends: left (y, z) and right (y, z)."""

    ly: float
    lz: float
    ry: float
    rz: float


class Root(NamedTuple):
    """The bevels' lower ends, whether a stray line covered one, and whether they are sure
    (not put at the other's depth or in the middle of a covered stretch)."""

    ends: RootEnds
    covered: bool
    sure: bool


class KeptPoints(NamedTuple):
    """A segmented profile's kept points (n, 2) in column order, the points of its detours
    (``stray``), the points' columns in the profile and the bounds of the runs between jumps:
    :class:`~seamtrack.features.lines.Segments`' arrays, as the v-groove's model reads them."""

    points: FloatArray
    stray: NDArray[np.bool_]
    columns: IntArray
    runs: IntArray


class CoveredEnd(NamedTuple):
    """Whether a stray line covers a bevel's root end, and the stretch along the bevel
    (coordinates, from the end outwards) where the end may lie (0, 0: not covered)."""

    covered: bool
    t0: float
    t1: float


#: A root end in plain view.
SEEN = CoveredEnd(False, 0.0, 0.0)


@numba.njit(**KERNEL)
def plate_depth(tb, plate, qy, qz):
    """Depth of (qy, qz) behind record ``plate``'s line (away from the sensor, at the
    origin)."""
    g = tb.geo
    cy, cz, dy, dz = g[plate, CY], g[plate, CZ], g[plate, UY], g[plate, UZ]
    ny, nz = -dz, dy
    if not cy * ny + cz * nz > 0:
        ny, nz = -ny, -nz
    return (qy - cy) * ny + (qz - cz) * nz


@numba.njit(**KERNEL)
def _off(tb, r, qy, qz):
    """Distance of (qy, qz) from record ``r``'s line."""
    g = tb.geo
    return abs((qy - g[r, CY]) * -g[r, UZ] + (qz - g[r, CZ]) * g[r, UY])


@numba.njit(**KERNEL)
def _along(tb, r, qy, qz):
    """``(q - r.centroid) @ r.direction``."""
    g = tb.geo
    return (qy - g[r, CY]) * g[r, UY] + (qz - g[r, CZ]) * g[r, UZ]


@numba.njit(**KERNEL)
def _flat_dot(tb, r, plate):
    """``abs(r.direction @ flat)``, flat: ``plate``'s direction, else (1, 0)."""
    g = tb.geo
    if plate == NONE:
        return abs(g[r, UY] * 1.0 + g[r, UZ] * 0.0)
    return abs(g[r, UY] * g[plate, UY] + g[r, UZ] * g[plate, UZ])


@numba.njit(**KERNEL)
def continued(points, tb, n, arm, at_end, ay, az, ey, ez, tol):
    """Where bevel ``arm`` ends when pieces beyond its last (``at_end``, else first) inlier,
    towards the apex (ay, az), lie on its line (within 15 deg and two tolerances: the bevel
    goes on past spikes or a dropout): the farthest such point; else (ey, ez)
    (:class:`~seamtrack.features.vgroove._v_search.Point`)."""
    t_apex = _along(tb, arm, ay, az)
    t_stop = t_end(tb, arm, at_end)
    best = t_stop
    span, pool = tb.span, tb.index
    for k in range(n):
        if abs(dot_dir(tb, k, arm)) < COS_ARM:
            continue
        if _off(tb, arm, tb.geo[k, CY], tb.geo[k, CZ]) > 2.0 * tol:
            continue
        lo, hi = np.inf, -np.inf
        for j in range(span[k, START], span[k, START] + span[k, COUNT]):
            t = _along(tb, arm, points[pool[j], 0], points[pool[j], 1])
            lo, hi = min(lo, t), max(hi, t)
        if at_end and lo > t_stop and hi <= t_apex + tol:
            best = pmax(best, hi)
        elif not at_end and hi < t_stop and lo >= t_apex - tol:
            best = pmin(best, lo)
    if best == t_stop:
        return Point(ey, ez)
    return point(tb, arm, best)


@numba.njit(**KERNEL)
def _next_piece(tb, n, i, at_end):
    """The first of the ``n`` pieces beyond point ``i`` (``at_end``: after it in column
    order, else the last before it); :data:`NONE` when there is none."""
    piece = NONE
    for k in range(n):
        if at_end and first(tb, k) > i:
            return k
        if not at_end and last(tb, k) < i:
            piece = k
    return piece


@numba.njit(**KERNEL)
def _ray_step(points, tb, line, at_end):
    """The median angle (rad) between the rays of neighbouring points over the last 11
    inliers of ``line`` at its end (``at_end``, else at its start); 0 with one point."""
    a, c = tb.span[line, START], tb.span[line, COUNT]
    own = tb.index[a + max(c - 11, 0) : a + c] if at_end else tb.index[a : a + min(c, 11)]
    steps = np.empty(max(own.shape[0] - 1, 0))
    for k in range(steps.shape[0]):
        steps[k] = abs(
            math.atan2(points[own[k + 1], 0], points[own[k + 1], 1])
            - math.atan2(points[own[k], 0], points[own[k], 1])
        )
    return sort_small(steps)[steps.shape[0] // 2] if steps.shape[0] else 0.0


@numba.njit(**KERNEL)
def _runs_on(points, tb, other, far, s, phi_far, dphi, tol, held):
    """Whether the point after ``far`` (direction ``s``) lies on ``other`` (within two
    tolerances), its ray within 3.5 ray steps ``dphi`` of ``far``'s (angle ``phi_far``) and
    within ``held`` of it: the piece runs on into the other bevel without a jump."""
    nxt = far + s
    if not 0 <= nxt < points.shape[0]:
        return False
    return (
        _off(tb, other, points[nxt, 0], points[nxt, 1]) <= 2.0 * tol
        and abs(math.atan2(points[nxt, 0], points[nxt, 1]) - phi_far) <= 3.5 * dphi
        and math.hypot(points[nxt, 0] - points[far, 0], points[nxt, 1] - points[far, 1]) <= held
    )


@numba.njit(**KERNEL)
def _shown_again(points, tb, line, far, s, tol):
    """How many points after ``far`` (direction ``s``; at most 400) lie on ``line`` again,
    within ``tol``."""
    again, at = 0, far + s
    if s > 0 or far > 0:
        while (
            0 <= at < points.shape[0]
            and again < 400
            and _off(tb, line, points[at, 0], points[at, 1]) <= tol
        ):
            again += 1
            at += s
    return again


@numba.njit(**KERNEL)
def covered_end(points, tb, n, line, at_end, other, plate, tol, spacing, sigma):
    """Where along bevel ``line`` its root end may lie when a stray line covers the columns
    beyond its last seen point (``at_end``: its last inlier, else its first): a
    :class:`CoveredEnd` (:data:`SEEN` when the end is seen).

    The end is covered when the first piece beyond it lies in the next columns (at most two
    columns lost, at most two points off the line in between), is no wall (steep on
    ``plate``: a root face) and no part of ``other`` (the other bevel), and does not run on
    into ``other`` without a jump: a false reflection, in front of or behind the surface,
    which hides where the bevel really ends. Lost columns (the gap, a shadow) hide nothing.
    (t0, t1) are coordinates along the line, from the end outwards: from the last point seen
    to where the ray of the stray piece's last point crosses the line; or, when at least
    three points beyond the piece lie on the line again (the bevel shows beyond the
    reflection), from there to the last of them (which may already lie on a root face that
    leaves the line at a small angle). Ends are half a spacing out.
    """
    s = 1 if at_end else -1
    i = last(tb, line) if at_end else first(tb, line)
    piece = _next_piece(tb, n, i, at_end)
    if piece == NONE:
        return SEEN
    near = first(tb, piece) if at_end else last(tb, piece)
    far = last(tb, piece) if at_end else first(tb, piece)
    if contains(tb, other, near):
        return SEEN  # the other bevel (no gap) or a piece of it
    dphi = _ray_step(points, tb, line, at_end)
    phi_i = math.atan2(points[i, 0], points[i, 1])
    phi_near = math.atan2(points[near, 0], points[near, 1])
    phi_far = math.atan2(points[far, 0], points[far, 1])
    lo, hi = min(i, near) + 1, max(i, near)
    lost = abs(phi_near - phi_i) / dphi - max(hi - lo, 0) - 1 if dphi > 0 else np.inf
    if lost > 2.5:
        return SEEN
    off = 0
    for j in range(lo, hi):
        off += _off(tb, line, points[j, 0], points[j, 1]) > 2.0 * tol
    if off > 2:
        return SEEN  # lost columns (the gap, a shadow) or another surface first
    if _flat_dot(tb, piece, plate) <= COS_WALL:
        return SEEN  # a wall: a root face
    if _runs_on(
        points, tb, other, far, s, phi_far, dphi, tol, pmax(pmax(6.0 * spacing, 4.0 * sigma), 0.1)
    ):
        return SEEN  # runs on into the other bevel: part of the part
    half = s * 0.5 * pmax(step(tb, line, at_end), spacing)
    g = tb.geo
    cy, cz, dy, dz = g[line, CY], g[line, CZ], g[line, UY], g[line, UZ]
    qy, qz = points[far, 0], points[far, 1]
    ray = (cy * -dz + cz * dy) / (qy * -dz + qz * dy)  # _ray_t: the ray's crossing
    t_far = (qy * ray - cy) * dy + (qz * ray - cz) * dz + half
    # Beyond the stray piece the bevel may show again.
    again = _shown_again(points, tb, line, far, s, tol)
    if again >= 3:
        q = far + s * again
        return CoveredEnd(True, t_far, _along(tb, line, points[q, 0], points[q, 1]) + half)
    return CoveredEnd(True, t_end(tb, line, at_end) + half, t_far)


@numba.njit(**KERNEL)
def at_depth(tb, line, plate, depth, s0, s1):
    """The point of ``line`` at ``depth`` behind ``plate``, kept within the stretch s0..s1
    (coordinates along the line; a :class:`~seamtrack.features.vgroove._v_search.Point`)."""
    g = tb.geo
    ny, nz = -g[plate, UZ], g[plate, UY]
    if not g[plate, CY] * ny + g[plate, CZ] * nz > 0:
        ny, nz = -ny, -nz
    rate = g[line, UY] * ny + g[line, UZ] * nz
    lo, hi = pmin(s0, s1), pmax(s0, s1)
    if abs(rate) < 1e-6:
        return point(tb, line, s0)
    t = (depth - plate_depth(tb, plate, g[line, CY], g[line, CZ])) / rate
    return point(tb, line, pmin(pmax(t, lo), hi))


@numba.njit(**KERNEL)
def level(tb, bevels, ends, plate_l, plate_r, gap, tol):
    """Whether the bevels' lower ends lie at one depth (below their own plates, else along
    the V's bisector): within 3 tolerances or a quarter of the gap."""
    left, right = bevels.left, bevels.right
    lx, ly, rx, ry = ends
    if plate_l != NONE and abs(dot_dir(tb, plate_l, left)) > COS_LEVEL:
        plate_l = NONE  # a piece of the bevel, no plate
    if plate_r != NONE and abs(dot_dir(tb, plate_r, right)) > COS_LEVEL:
        plate_r = NONE
    plate_l, plate_r = (
        plate_l if plate_l != NONE else plate_r,
        plate_r if plate_r != NONE else plate_l,
    )
    if plate_l != NONE and plate_r != NONE:
        d_l, d_r = plate_depth(tb, plate_l, lx, ly), plate_depth(tb, plate_r, rx, ry)
    else:
        g = tb.geo
        uy, uz = -(g[left, UY] + g[right, UY]), -(g[left, UZ] + g[right, UZ])
        if uz > 0:
            uy, uz = -uy, -uz
        norm = max(math.hypot(uy, uz), 1e-300)
        uy, uz = uy / norm, uz / norm
        d_l, d_r = -(lx * uy + ly * uz), -(rx * uy + ry * uz)
    return abs(d_l - d_r) <= pmax(3.0 * tol, 0.25 * gap)


@numba.njit(**KERNEL)
def _inert(tb, k, left, right, plate, min_points):
    """A wall (steep on ``plate``) or a long straight piece off both bevels."""
    if _flat_dot(tb, k, plate) <= COS_WALL:
        return True
    return (
        tb.span[k, COUNT] >= 2 * min_points
        and abs(dot_dir(tb, k, left)) < COS_ARM
        and abs(dot_dir(tb, k, right)) < COS_ARM
    )


@numba.njit(**KERNEL)
def tip_filled(points, surface, tb, n, bevels, ends, plate, min_points, tol, spacing):
    """Whether surface points fill the V's tip below the bevels' lower ends: the triangle of
    the two lower ends and the apex (grown by a tolerance), away from the lower ends (root
    faces start there). Under a gap the tip is open air; there the bevels go on (cut up by
    spikes and dropouts) or a fill lies. Walls (root faces: steep on ``plate``) and straight
    pieces that are no part of a bevel (a reflection, a backing) do not count. Only read
    when the apex lies more than three tolerances below the lower ends (else noise fills
    any tip)."""
    left, right, ax, az = bevels
    lx, lz, rx, rz = ends
    cy, cz = rx - lx, rz - lz
    length = math.hypot(cy, cz)
    if length <= 0:
        return False
    ny, nz = -cz / length, cy / length
    if abs((ax - lx) * ny + (az - lz) * nz) <= 3.0 * tol:
        return False
    keep = np.empty(surface.shape[0], dtype=np.bool_)
    for i in range(keep.shape[0]):
        keep[i] = surface[i]
    span, pool = tb.span, tb.index
    for k in range(n):
        if _inert(tb, k, left, right, plate, min_points):
            for q in range(span[k, START], span[k, START] + span[k, COUNT]):
                keep[pool[q]] = False
    for r in (left, right):
        for q in range(span[r, START], span[r, START] + span[r, COUNT]):
            keep[pool[q]] = False
    ty, tz, my, mz = np.empty(3), np.empty(3), np.empty(3), np.empty(3)
    ty[0], ty[1], ty[2], tz[0], tz[1], tz[2] = lx, rx, ax, lz, rz, az
    ey_c, ez_c = ((lx + rx) + ax) / 3.0, ((lz + rz) + az) / 3.0
    for e in range(3):
        a, b = e, (e + 1) % 3
        dy, dz = ty[b] - ty[a], tz[b] - tz[a]
        norm = max(math.hypot(dy, dz), 1e-300)
        my[e], mz[e] = -dz / norm, dy / norm
        if (ey_c - ty[a]) * my[e] + (ez_c - tz[a]) * mz[e] < 0:
            my[e], mz[e] = -my[e], -mz[e]
    r0 = 2.0 * tol + 3.0 * spacing
    count = 0
    for i in range(points.shape[0]):
        if not keep[i]:
            continue
        qy, qz = points[i, 0], points[i, 1]
        inside = True
        for e in range(3):
            inside = inside and (qy - ty[e]) * my[e] + (qz - tz[e]) * mz[e] >= -tol
        if inside and math.hypot(qy - lx, qz - lz) > r0 and math.hypot(qy - rx, qz - rz) > r0:
            count += 1
    return count > min_points


@numba.njit(**KERNEL)
def covered_between(points, columns, runs, tb, n, left, right, plate, min_points):
    """Share of the columns between the bevels' lower ends that show a surface: points in no
    wall (steep on ``plate``: a root face), no long straight piece off both bevels and no
    piece cut off by jumps at both ends (a reflection, a backing), or, when more, the share
    not in the longest run of open columns. Over a gap the laser falls through (no points)."""
    lo, hi = last(tb, left), first(tb, right)
    if hi - lo < 2 or columns.shape[0] != points.shape[0]:
        return 0.0
    width = columns[hi] - columns[lo] - 1
    if width <= 0:
        return 0.0
    keep = np.ones(hi - lo - 1, dtype=np.bool_)
    span, pool = tb.span, tb.index
    starts = runs[:-1]
    for k in range(n):
        fst, lst = first(tb, k), last(tb, k)
        if lst <= lo or fst >= hi:
            continue
        j = -1  # np.searchsorted(starts, fst, side="right") - 1
        while j + 1 < starts.shape[0] and starts[j + 1] <= fst:
            j += 1
        cut_off = 0 <= j < starts.shape[0] and fst - starts[j] <= 3 and runs[j + 1] - 1 - lst <= 3
        if cut_off or _inert(tb, k, left, right, plate, min_points):
            for q in range(span[k, START], span[k, START] + span[k, COUNT]):
                if lo < pool[q] < hi:
                    keep[pool[q] - lo - 1] = False
    hit = np.zeros(width, dtype=np.bool_)
    kept = 0
    for j in range(hi - lo - 1):
        if keep[j]:
            kept += 1
            c = columns[lo + 1 + j] - columns[lo] - 1
            if 0 <= c < width:
                hit[c] = True
    longest, run = 0, 0
    for c in range(width):
        run = 0 if hit[c] else run + 1
        longest = max(longest, run)
    return pmax(kept / width, 1.0 - longest / width)


@numba.njit(**KERNEL)
def bridged(tb, n, bevels, ends, plate, min_points, tol, spacing):
    """Whether a piece between the bevels that is no wall (steep on ``plate``) runs from one
    root end to the other: the "gap" between them is a surface."""
    lx, lz, rx, rz = ends
    lo, hi = last(tb, bevels.left), first(tb, bevels.right)
    for k in range(n):
        if tb.span[k, COUNT] < min_points or first(tb, k) <= lo or last(tb, k) >= hi:
            continue
        if _flat_dot(tb, k, plate) <= COS_WALL:
            continue
        reach = 3.0 * pmax(pmax(spacing, step(tb, k, LAST_END)), step(tb, k, FIRST_END)) + tol
        y0, z0 = end(tb, k, FIRST_END)
        y1, z1 = end(tb, k, LAST_END)
        if math.hypot(y0 - lx, z0 - lz) <= reach and math.hypot(y1 - rx, z1 - rz) <= reach:
            return True
    return False


@numba.njit(**KERNEL)
def gap_seen(kept, surface, tb, n, bevels, root, plate_l, plate_r, gap, min_points, tol, spacing):
    """Whether the stretch between the bevels' lower ends is a root gap: the ends lie at one
    depth (not read where a stray line hides an end: its depth is then taken from the
    other), no detour lies between them (a surface continuing across spikes), the V's tip
    below them is empty and the columns between them are open (the laser falls through the
    gap). Otherwise the bevels end where spikes, dropouts or a fill take over. ``kept``: the
    profile's :class:`KeptPoints`; ``root``: the bevels' lower ends (a :class:`Root`), ``gap``
    apart."""
    points, stray, columns, runs = kept
    ends = root.ends
    if not root.covered and not level(tb, bevels, ends, plate_l, plate_r, gap, tol):
        return False
    lo, hi = last(tb, bevels.left), first(tb, bevels.right)
    m = points.shape[0]
    if stray.shape[0] == m:
        detour = 0
        for i in range(lo + 1, hi):
            detour += stray[i]
        if detour >= 3:
            return False  # a detour between them: a surface goes on across it, no gap
    if tip_filled(points, surface, tb, n, bevels, ends, plate_l, min_points, tol, spacing):
        return False
    left, right = bevels.left, bevels.right
    return covered_between(points, columns, runs, tb, n, left, right, plate_l, min_points) < 0.5
