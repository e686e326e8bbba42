"""Compiled inner loops of the two-plate extractors (:mod:`seamtrack.features.plates`).

:func:`hole` reads what lies between two plate runs in one call: done as numpy calls on the
few dozen points of a hole, its masks, medians and stretches were some hundred small array
operations per profile, whose per-call overhead was most of the extractor's time, and more on
the profiles with reflections or outliers (one pass per piece and per run of loose points).
:func:`_corner` is :func:`seamtrack.features.lines.corner_or_end` and
:func:`two_lines_share` :func:`seamtrack.features.base.explained` of a two-line model, on
floats. The arithmetic is that of the numpy formulation (the same formulas, medians as numpy
takes them), so results agree to rounding. Booleans are passed to callees at run time: a
literal True or False compiles a copy of the callee per value.

Lines are passed as floats: centroid (y, z) and unit direction (y, z); ``lines`` holds the
profile's pieces as rows ``(cy, cz, dy, dz)``.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.counts import explained_share
from seamtrack.features.kernels import _fit as _fit_tls

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: As :data:`seamtrack.features.lines._WALL_DEG`, ``_BOTTOM_DEG`` and ``_PLATE_DEG` (rad).
_WALL = math.radians(65.0)
_BOTTOM = math.radians(10.0)
_PLATE = math.radians(20.0)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _towards(cy: float, cz: float, dy: float, dz: float, y: float, z: float) -> float:
    """Signed distance of (y, z) from the line, positive on the sensor's side (the origin)."""
    h = (y - cy) * -dz + (z - cz) * dy
    return h if cy * -dz + cz * dy < 0 else -h


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _angle(ady: float, adz: float, bdy: float, bdz: float) -> float:
    """Unsigned angle between two directions (rad, in [0, pi/2])."""
    return math.acos(min(1.0, abs(ady * bdy + adz * bdz)))


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _median(v: FloatArray) -> float:
    """numpy's median (mean of the two middle values of an even count; NaN propagates). A
    Shell sort of a copy: small code (numba's sort made the kernels slow to compile) and
    fast enough on the few hundred values of a hole."""
    n = v.shape[0]
    for x in v:
        if math.isnan(x):
            return math.nan
    s = v.copy()
    gap = 1
    while gap < n // 3:
        gap = 3 * gap + 1
    while gap > 0:
        for i in range(gap, n):
            x = s[i]
            j = i
            while j >= gap and s[j - gap] > x:
                s[j] = s[j - gap]
                j -= gap
            s[j] = x
        gap //= 3
    if n % 2:
        return s[n // 2]
    return (s[n // 2 - 1] + s[n // 2]) / 2.0


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _kept(keep: NDArray[np.bool_]) -> IntArray:
    """Positions of the True flags (``np.flatnonzero``)."""
    n = 0
    for x in keep:
        if x:
            n += 1
    k = np.empty(n, dtype=np.int64)
    n = 0
    for i in range(keep.shape[0]):
        if keep[i]:
            k[n] = i
            n += 1
    return k


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _stretch_ends(
    keep: NDArray[np.bool_], t: FloatArray, spacing: float, first: bool
) -> tuple[float, float, IntArray]:
    """Of the stretches of consecutive kept points (broken by another point or a jump of
    three spacings along the line): the first one's start, the last one's end, and the
    positions of the points of the first (``first``) or of the last stretch."""
    k = _kept(keep)
    n = k.shape[0]
    hi_first = n
    for i in range(1, n):
        if k[i] - k[i - 1] > 1 or abs(t[k[i]] - t[k[i - 1]]) > 3.0 * spacing:
            hi_first = i
            break
    lo_last = 0
    for i in range(n - 1, 0, -1):
        if k[i] - k[i - 1] > 1 or abs(t[k[i]] - t[k[i - 1]]) > 3.0 * spacing:
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
    return t0 - 0.5 * spacing, t1 + 0.5 * spacing, part


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _covered(keep: NDArray[np.bool_], t: FloatArray, spacing: float, ta: float, tb: float) -> float:
    """Summed length along the line of the stretches of consecutive kept points, clipped to
    ``[ta, tb]`` (NaN propagates, as numpy's reductions do)."""
    k = _kept(keep)
    n = k.shape[0]
    total = 0.0
    i = 0
    while i < n:
        j = i + 1
        while j < n and not (k[j] - k[j - 1] > 1 or abs(t[k[j]] - t[k[j - 1]]) > 3.0 * spacing):
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


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _hidden_edge(
    part: IntArray,
    t: FloatArray,
    on_line: NDArray[np.bool_],
    stray: NDArray[np.bool_],
    t_end: float,
    spacing: float,
    at_end: bool,
) -> tuple[bool, float]:
    """Where a run's edge lies when the covered stretch next to it (``part``, from the run's
    end outwards) holds a stray line: the middle of the stray line's stretch along the run's
    line (the edge may lie anywhere under it), or, when the plate shows again beyond it, the
    last plate point seen (half a spacing on); up to the first point of anything else (the
    other plate, a surface). (found, coordinate along the run's line); not found when no
    stray line touches the run's end."""
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
        return False, 0.0
    sign = 1.0 if at_end else -1.0
    if p_last >= 0 and p_last > s_last:
        return True, t[part[p_last]] + sign * 0.5 * spacing
    return True, 0.5 * (t_end + t[part[s_last]] + sign * 0.5 * spacing)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def hole(
    points: FloatArray,
    owner: IntArray,
    lines: FloatArray,
    acy: float,
    acz: float,
    ady: float,
    adz: float,
    a_t: float,
    a_step: float,
    bcy: float,
    bcz: float,
    bdy: float,
    bdz: float,
    b_t: float,
    b_step: float,
    lo: int,
    hi: int,
    tol: float,
    spacing: float,
    sigma: float,
    min_bottom_mm: float,
    butt: bool,
) -> tuple[float, bool, float, float, bool, float, float]:
    """What lies between run ``a``'s last inlier (kept point ``lo``) and run ``b``'s first
    (``hi``): (open_mm, left hidden?, left edge y, z, right hidden?, right edge y, z).

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

    Run ``a``: centroid, direction, its last inlier's coordinate along it and its step
    there (:meth:`~seamtrack.features.lines.Line.step`); run ``b``: the same at its first
    inlier. ``owner``: each kept point's piece (row of ``lines``), -1 for none.
    """
    sp_a = max(a_step, spacing)
    sp_b = max(b_step, spacing)
    ta = a_t + 0.5 * a_step
    tb_b = b_t - 0.5 * b_step
    tb = (bcy + tb_b * bdy - acy) * ady + (bcz + tb_b * bdz - acz) * adz
    width = tb - ta
    if hi - lo < 2:
        return width, False, 0.0, 0.0, False, 0.0, 0.0
    n = hi - lo - 1
    q = points[lo + 1 : hi]
    own = owner[lo + 1 : hi]
    towards_a = np.empty(n)
    towards_b = np.empty(n)
    off_a = np.empty(n)
    off_b = np.empty(n)
    off = np.empty(n)
    plate = np.empty(n, dtype=np.bool_)
    for i in range(n):
        towards_a[i] = _towards(acy, acz, ady, adz, q[i, 0], q[i, 1])
        towards_b[i] = _towards(bcy, bcz, bdy, bdz, q[i, 0], q[i, 1])
        off_a[i] = abs(towards_a[i])
        off_b[i] = abs(towards_b[i])
        x, y = off_a[i], off_b[i]
        off[i] = math.nan if math.isnan(x) or math.isnan(y) else min(x, y)
        plate[i] = off[i] <= tol
    cover = np.zeros(n, dtype=np.bool_)
    nlines = lines.shape[0]
    present = np.zeros(nlines, dtype=np.bool_)
    for i in range(n):
        if own[i] >= 0:
            present[own[i]] = True
    for j in range(nlines):
        if not present[j]:
            continue
        rel = _angle(lines[j, 2], lines[j, 3], ady, adz)
        if rel >= _WALL:
            top = -math.inf
            cnt = 0
            for i in range(n):
                if own[i] == j:
                    cnt += 1
                    if off[i] > top or math.isnan(off[i]):
                        top = off[i] if not math.isnan(top) else top
            if top >= 2 * tol:
                drop = True
                if butt:
                    v = np.empty(cnt)
                    c = 0
                    for i in range(n):
                        if own[i] == j:
                            v[c] = towards_a[i]
                            c += 1
                    drop = _median(v) < 0.0
                if drop:
                    continue  # a wall going down into a gap
        if rel <= _BOTTOM:
            cy, cz = lines[j, 0], lines[j, 1]
            x = _towards(acy, acz, ady, adz, cy, cz)
            y = _towards(bcy, bcz, bdy, bdz, cy, cz)
            depth = -(y if y > x else x)
            if depth >= min_bottom_mm:
                continue
        unplate = rel > _PLATE
        for i in range(n):
            if own[i] == j:
                if unplate:
                    plate[i] = False
                cover[i] = True
    if butt:
        for i in range(n):
            if own[i] < 0 and off[i] <= 3.0 * tol:
                plate[i] = True
    nloose = 0
    for i in range(n):
        if own[i] < 0 and not plate[i]:
            nloose += 1
    if nloose >= 3:
        loose = np.empty(nloose, dtype=np.int64)
        c = 0
        for i in range(n):
            if own[i] < 0 and not plate[i]:
                loose[c] = i
                c += 1
        s = 0
        while s < nloose:
            e = s + 1
            while e < nloose and loose[e] - loose[e - 1] <= 1:
                e += 1
            part = loose[s:e]
            behind = np.empty(e - s)
            for r in range(e - s):
                x, y = towards_a[part[r]], towards_b[part[r]]
                behind[r] = -(math.nan if math.isnan(x) or math.isnan(y) else max(x, y))
            if not _median(behind) >= min_bottom_mm:
                if e - s >= 3:
                    _, _, uy, uz, _ = _fit_tls(q, part, part.shape[0])
                    yes = _angle(uy, uz, ady, adz) < _WALL
                    if not yes:
                        top = -math.inf
                        for r in range(e - s):
                            x = off[part[r]]
                            if x > top or math.isnan(x):
                                top = x if not math.isnan(top) else top
                        yes = top < 2 * tol
                    if not yes and butt:
                        v = np.empty(e - s)
                        for r in range(e - s):
                            v[r] = towards_a[part[r]]
                        yes = _median(v) > 0.0
                    if yes:
                        for r in range(e - s):
                            cover[part[r]] = True
            s = e
    anything = False
    for i in range(n):
        cover[i] = cover[i] or plate[i]
        anything = anything or cover[i]
    if not anything:
        return width, False, 0.0, 0.0, False, 0.0, 0.0
    # Jumps between consecutive points of the hole, its plates' ends included.
    m = n + 1
    cut = np.empty(m, dtype=np.bool_)
    big = max(6 * spacing, 2 * tol, 0.1)
    held = max(6 * spacing, 4 * sigma, 0.1)
    for i in range(m):
        dy = points[lo + i + 1, 0] - points[lo + i, 0]
        dz = points[lo + i + 1, 1] - points[lo + i, 1]
        d = math.hypot(dy, dz)
        cut[i] = d > (held if i == 0 or i == m - 1 else big)
    stray = np.empty(n, dtype=np.bool_)
    any_stray = False
    k0 = -1
    k1 = -1
    for i in range(m):
        if cut[i]:
            if k0 < 0:
                k0 = i
            k1 = i
    for i in range(n):
        st = cover[i] and not plate[i]
        if k0 < 0:
            st = False
        else:
            if not cut[0] and i < k0:
                st = False
            if not cut[m - 1] and i >= k1:
                st = False
        stray[i] = st
        any_stray = any_stray or st
    qa = np.empty(n)
    na = acy * -adz + acz * ady
    for i in range(n):
        s_ = na / (q[i, 0] * -adz + q[i, 1] * ady)
        qa[i] = (q[i, 0] * s_ - acy) * ady + (q[i, 1] * s_ - acz) * adz
    covered = _covered(cover, qa, sp_a, ta, tb)
    left = right = False
    ly = lz = ry = rz = 0.0
    if any_stray:
        on_a = np.empty(n, dtype=np.bool_)
        on_b = np.empty(n, dtype=np.bool_)
        for i in range(n):
            on_a[i] = plate[i] and off_a[i] <= tol
            on_b[i] = plate[i] and off_b[i] <= tol
        # Runtime flags: a literal True or False would compile a copy of the callee each.
        at_end, at_start = butt | True, butt & False
        t0, _, first = _stretch_ends(cover, qa, sp_a, at_end)
        if t0 <= ta + 2.0 * sp_a:
            left, t = _hidden_edge(first, qa, on_a, stray, ta, sp_a, at_end)
            ly, lz = acy + t * ady, acz + t * adz
        qb = np.empty(n)
        nb = bcy * -bdz + bcz * bdy
        for i in range(n):
            s_ = nb / (q[i, 0] * -bdz + q[i, 1] * bdy)
            qb[i] = (q[i, 0] * s_ - bcy) * bdy + (q[i, 1] * s_ - bcz) * bdz
        _, t1, last = _stretch_ends(cover, qb, sp_b, at_start)
        if t1 >= tb_b - 2.0 * sp_b:
            back = np.empty_like(last)
            for i in range(last.shape[0]):
                back[i] = last[last.shape[0] - 1 - i]
            right, t = _hidden_edge(back, qb, on_b, stray, tb_b, sp_b, at_start)
            ry, rz = bcy + t * bdy, bcz + t * bdz
    rest = width - covered
    return (rest if rest > 0.0 else 0.0), left, ly, lz, right, ry, rz


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _corner(
    run: FloatArray,
    ends: FloatArray,
    at_end: bool,
    skip: int,
    rows: FloatArray,
    count: IntArray,
    t_first: FloatArray,
    t_last: FloatArray,
    steps: FloatArray,
    min_points: int,
    spacing: float,
    tol: float,
) -> tuple[float, float]:
    """Where a run's line ends (:func:`seamtrack.features.lines.corner_or_end` with the
    pieces of ``min_points`` as the others, ``skip`` the run's own piece or -1): its crossing
    with a piece meeting it there (a visible corner), else half a step beyond its last
    inlier. ``run``: (cy, cz, dy, dz); ``ends``: (first t, last t, first step, last step);
    ``steps``: each piece's first and last step."""
    cy, cz, dy, dz = run[0], run[1], run[2], run[3]
    t_tip = ends[1] if at_end else ends[0]
    tip_y, tip_z = cy + t_tip * dy, cz + t_tip * dz
    reach = ends[3] if at_end else ends[2]
    reach = 3.0 * (spacing if spacing > reach else reach) + tol
    cos_min = math.cos(math.radians(20))
    found = False
    best_y = best_z = 0.0
    best_d = math.inf
    for j in range(rows.shape[0]):
        if count[j] < min_points or j == skip:
            continue
        ocy, ocz, ody, odz = rows[j, 0], rows[j, 1], rows[j, 2], rows[j, 3]
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
        near = math.hypot(ocy + t_first[j] * ody - xy, ocz + t_first[j] * odz - xz)
        far = math.hypot(ocy + t_last[j] * ody - xy, ocz + t_last[j] * odz - xz)
        near = far if far < near else near
        wide = steps[j, 1]
        wide = steps[j, 0] if steps[j, 0] > wide else wide
        wide = spacing if spacing > wide else wide
        if near <= 3.0 * wide + tol:
            found, best_y, best_z, best_d = True, xy, xz, d
    if found:
        return best_y, best_z
    t = ends[1] + 0.5 * ends[3] if at_end else ends[0] - 0.5 * ends[2]
    return cy + t * dy, cz + t * dz


@numba.njit(cache=True, nogil=True, error_model="numpy")
def two_lines_share(
    points: FloatArray,
    stray: NDArray[np.bool_],
    lo: int,
    hi: int,
    acy: float,
    acz: float,
    ady: float,
    adz: float,
    bcy: float,
    bcz: float,
    bdy: float,
    bdz: float,
    band: float,
) -> float:
    """Share of the surface points (``stray`` left out when it flags each point) within
    ``band`` of their line when line ``a`` (centroid, unit direction) runs from the profile's
    start to kept point ``lo`` and line ``b`` from ``hi`` to its end, what lies between
    them left out: :func:`seamtrack.features.base.explained` of a two-plate or two-face
    model (:func:`seamtrack.features.counts.explained_share`)."""
    m = points.shape[0]
    zones = np.empty((3, 3), dtype=np.int64)
    zones[0, 0], zones[0, 1], zones[0, 2] = 0, lo, 1
    zones[1, 0], zones[1, 1], zones[1, 2] = lo, hi, 0
    zones[2, 0], zones[2, 1], zones[2, 2] = max(hi, lo), m, 1
    fits = np.zeros((3, 1, 4))
    fits[0, 0, 0], fits[0, 0, 1], fits[0, 0, 2], fits[0, 0, 3] = acy, acz, -adz, ady
    fits[2, 0, 0], fits[2, 0, 1], fits[2, 0, 2], fits[2, 0, 3] = bcy, bcz, -bdz, bdy
    surface = ~stray if stray.shape[0] == m else np.ones(m, dtype=np.bool_)
    return explained_share(points, surface, zones, fits, band)
