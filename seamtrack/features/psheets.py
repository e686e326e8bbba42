"""Compiled plate search of the two-plate extractors (:mod:`seamtrack.features.plates`).

:func:`two_plates` finds the plates (plate lines, runs, the square butt's test for an open
gap between pieces of one plate line), their neighbours and the extractors' choice of the
pair of runs in one call, on the profile's pieces held as flat arrays: as Python on ``Line``
objects it was some hundreds of small operations per profile, most of an extractor's time
once the segmentation is compiled. The plate lines' groups are
:func:`seamtrack.features.lines.collinear_members`' and the runs' refits
:func:`seamtrack.features.kernels.fit_line`'s, computed the same way.

The pieces: ``index`` and ``along`` concatenate their inliers' positions and coordinates
along them, ``counts`` are their numbers of inliers, ``geo`` their ``(cy, cz, dy, dz)``.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.kernels import fit_line
from seamtrack.features.pkernels import _corner, _median, hole, two_lines_share

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Kinds of run (:func:`two_plates`): one piece as it is, a refit of its pieces' inliers, or
#: its pieces' inliers measured on their plate's line.
PIECE, FIT, ON = 0, 1, 2


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _steps(t: FloatArray) -> tuple[float, float]:
    """Mean spacing of the first and of the last ten coordinates
    (:meth:`~seamtrack.features.lines.Line.step`)."""
    n = t.shape[0]
    k = min(10, n - 1)
    if k < 1:
        return 0.0, 0.0
    return abs(t[k] - t[0]) / k, abs(t[n - 1] - t[n - 1 - k]) / k


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _order(keys: IntArray) -> IntArray:
    """Stable ascending order of a few keys (an insertion sort: small code, where numba's
    sorts made the kernel slow to compile)."""
    n = keys.shape[0]
    o = np.arange(n)
    for i in range(1, n):
        x = o[i]
        j = i
        while j > 0 and keys[o[j - 1]] > keys[x]:
            o[j] = o[j - 1]
            j -= 1
        o[j] = x
    return o


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _span(
    rows: FloatArray, t_first: FloatArray, t_last: FloatArray, line: int, pieces: IntArray
) -> float:
    """Extent along piece ``line``'s line of ``pieces`` on it (from their ends)."""
    ly, lz, ldy, ldz = rows[line, 0], rows[line, 1], rows[line, 2], rows[line, 3]
    lo = math.inf
    hi = -math.inf
    for p in pieces:
        c = (rows[p, 0] - ly) * ldy + (rows[p, 1] - lz) * ldz
        d = rows[p, 2] * ldy + rows[p, 3] * ldz
        for x in (c + d * t_first[p], c + d * t_last[p]):
            lo = min(lo, x)
            hi = max(hi, x)
    return hi - lo


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _along(
    points: FloatArray, idx: IntArray, cy: float, cz: float, dy: float, dz: float
) -> FloatArray:
    """Coordinates of ``points[idx]`` along a line (:func:`seamtrack.features.lines._on`)."""
    t = np.empty(idx.shape[0])
    for i in range(idx.shape[0]):
        t[i] = (points[idx[i], 0] - cy) * dy + (points[idx[i], 1] - cz) * dz
    return t


@numba.njit(cache=True, nogil=True, error_model="numpy")
def _run_line(
    points: FloatArray,
    index: IntArray,
    along: FloatArray,
    offsets: IntArray,
    rows: FloatArray,
    t_first: FloatArray,
    t_last: FloatArray,
    pieces: IntArray,
    anchor: int,
    min_plate_mm: float,
) -> tuple[int, float, float, float, float, float, IntArray, FloatArray]:
    """A run's line from its ``pieces`` (of the plate line whose anchor is ``anchor``): a
    long piece as it is (:data:`PIECE`), else a refit of the pieces' inliers when they span
    ``min_plate_mm`` (:data:`FIT`), else those inliers measured on the anchor's line
    (:data:`ON`, a stub): (kind, cy, cz, dy, dz, rms (FIT only), inliers, their
    coordinates)."""
    p0 = pieces[0]
    if pieces.shape[0] == 1 and t_last[p0] - t_first[p0] >= min_plate_mm:
        a, b = offsets[p0], offsets[p0 + 1]
        cy, cz, dy, dz = rows[p0, 0], rows[p0, 1], rows[p0, 2], rows[p0, 3]
        return PIECE, cy, cz, dy, dz, 0.0, index[a:b].copy(), along[a:b].copy()
    total = 0
    for q in pieces:
        total += offsets[q + 1] - offsets[q]
    idx = np.empty(total, dtype=np.int64)
    c = 0
    for q in pieces:
        for k in range(offsets[q], offsets[q + 1]):
            idx[c] = index[k]
            c += 1
    if _span(rows, t_first, t_last, anchor, pieces) >= min_plate_mm:
        cy, cz, dy, dz, rms, t = fit_line(points, idx)
        return FIT, cy, cz, dy, dz, rms, idx, t
    cy, cz, dy, dz = rows[anchor, 0], rows[anchor, 1], rows[anchor, 2], rows[anchor, 3]
    return ON, cy, cz, dy, dz, 0.0, idx, _along(points, idx, cy, cz, dy, dz)


@numba.njit(cache=True, nogil=True, error_model="numpy")
def two_plates(
    points: FloatArray,
    index: IntArray,
    along: FloatArray,
    counts: IntArray,
    geo: FloatArray,
    stray: NDArray[np.bool_],
    min_points: int,
    min_plate_mm: float,
    max_tilt_deg: float,
    max_gap_mm: float,
    tol: float,
    spacing: float,
    sigma: float,
    butt: bool,
    min_opening: float,
    min_open_mm: float,
    min_bottom_mm: float,
    min_step_mm: float,
) -> tuple[IntArray, FloatArray]:
    """The two plates of a square butt (``butt``) or a lap, as the extractors choose them.

    ``counts``: each piece's number of inliers; ``geo``: the pieces' ``(cy, cz, dy, dz)``,
    concatenated; ``stray``: the segmentation's detour points (left out of the explained
    share). Returns ``(ints, floats)``: ``ints`` = (left run, right run (-1: no pair
    qualifies), their kinds (:data:`PIECE`, :data:`FIT`, :data:`ON`), their first pieces,
    their plate lines' anchor pieces, their inlier counts, open gap?, left edge hidden?,
    right edge hidden?); ``floats`` = (open width, left hidden edge y, z, right hidden edge
    y, z, the lap's step, the left run's cy, cz, dy, dz, rms (FIT only), the right run's,
    the left run's end y, z (:func:`_corner`), the right run's start y, z, the share of the
    surface points the two-plate model explains (each plate running on to the profile's
    end, what lies between them left out; :func:`seamtrack.features.base.explained`)).
    """
    rows = geo.reshape(-1, 4)
    nl = rows.shape[0]
    offsets = np.zeros(nl + 1, dtype=np.int64)
    for j in range(nl):
        offsets[j + 1] = offsets[j] + counts[j]
    m = points.shape[0]
    owner = np.full(m, -1, dtype=np.int64)
    count = np.empty(nl, dtype=np.int64)
    t_first = np.empty(nl)
    t_last = np.empty(nl)
    first = np.empty(nl, dtype=np.int64)
    for j in range(nl):
        a, b = offsets[j], offsets[j + 1]
        count[j] = b - a
        t_first[j], t_last[j] = along[a], along[b - 1]
        first[j] = index[a]
        for k in range(a, b):
            owner[index[k]] = j
    # Flat pieces, grouped by the line they lie on (collinear_members: best supported first,
    # each joins the earliest group whose anchor holds both its ends).
    tilt = math.radians(max_tilt_deg)
    flat = np.empty(nl, dtype=np.int64)
    nf = 0
    for j in range(nl):
        if count[j] >= min_points and abs(math.atan2(rows[j, 3], rows[j, 2])) <= tilt:
            flat[nf] = j
            nf += 1
    flat = flat[:nf]
    minus = np.empty(nf, dtype=np.int64)
    for o in range(nf):
        minus[o] = -count[flat[o]]
    order = _order(minus)
    cos_max = math.cos(math.radians(30.0))
    group = np.empty(nf, dtype=np.int64)  # each flat piece's group (position in flat)
    anchors = np.empty(nf, dtype=np.int64)  # each group's anchor (a piece)
    ng = 0
    for o in order:
        i = flat[o]
        cy, cz, dy, dz = rows[i, 0], rows[i, 1], rows[i, 2], rows[i, 3]
        e0y, e0z = cy + t_first[i] * dy, cz + t_first[i] * dz
        e1y, e1z = cy + t_last[i] * dy, cz + t_last[i] * dz
        joined = -1
        for k in range(ng):
            r = anchors[k]
            ay, az, ady, adz = rows[r, 0], rows[r, 1], rows[r, 2], rows[r, 3]
            if (
                abs(ady * dy + adz * dz) >= cos_max
                and abs((e0y - ay) * -adz + (e0z - az) * ady) <= tol
                and abs((e1y - ay) * -adz + (e1z - az) * ady) <= tol
            ):
                joined = k
                break
        if joined < 0:
            anchors[ng] = i
            joined = ng
            ng += 1
        group[o] = joined
    # Plate lines span min_plate_mm; their pieces in column order.
    plate_of = np.full(ng, -1, dtype=np.int64)  # collinear group -> plate line
    plate_anchor = np.empty(ng, dtype=np.int64)
    npl = 0
    for k in range(ng):
        pieces = np.empty(nf, dtype=np.int64)
        c = 0
        for o in range(nf):
            if group[o] == k:
                pieces[c] = flat[o]
                c += 1
        pieces = pieces[:c]
        if _span(rows, t_first, t_last, anchors[k], pieces) >= min_plate_mm:
            plate_of[k] = npl
            plate_anchor[npl] = anchors[k]
            npl += 1
    pg = np.empty(nf, dtype=np.int64)
    pl = np.empty(nf, dtype=np.int64)
    n = 0
    for o in range(nf):
        if plate_of[group[o]] >= 0:
            pg[n], pl[n] = plate_of[group[o]], flat[o]
            n += 1
    starts = np.empty(n, dtype=np.int64)
    for o in range(n):
        starts[o] = first[pl[o]]
    srt = _order(starts)
    pg0, pl0 = pg.copy(), pl.copy()
    for o in range(n):
        pg[o], pl[o] = pg0[srt[o]], pl0[srt[o]]
    # A plate line showing briefly between two stretches of another, tilted to it, far
    # behind it or too short, is no plate there; of competing blocks the smallest goes.
    ten = math.radians(10.0)
    while True:
        best_c, bi, bj = 0, -1, -1
        i = 1
        while i < n - 1:
            j = i
            while j < n and pg[j] == pg[i]:
                j += 1
            if j < n and pg[i - 1] == pg[j]:
                host = plate_anchor[pg[j]]
                b0 = pl[i]
                c = abs(rows[b0, 2] * rows[host, 2] + rows[b0, 3] * rows[host, 3])
                tilted = math.acos(min(1.0, c)) > ten
                hy, hz, hdy, hdz = rows[host, 0], rows[host, 1], rows[host, 2], rows[host, 3]
                flip = not hy * -hdz + hz * hdy < 0
                heights = np.empty(j - i)
                for r in range(i, j):
                    h = (rows[pl[r], 0] - hy) * -hdz + (rows[pl[r], 1] - hz) * hdy
                    heights[r - i] = -h if flip else h
                behind = -_median(heights) >= min_bottom_mm if butt else False
                short = _span(rows, t_first, t_last, plate_anchor[pg[i]], pl[i:j]) < min_plate_mm
                if tilted or behind or short:
                    cnt = 0
                    for r in range(i, j):
                        cnt += count[pl[r]]
                    if bi < 0 or cnt < best_c:
                        best_c, bi, bj = cnt, i, j
            i = j
        if bi < 0:
            break
        for o in range(bj, n):
            pg[o - (bj - bi)], pl[o - (bj - bi)] = pg[o], pl[o]
        n -= bj - bi
    # Runs: consecutive pieces of one plate line, unless (square butt) an open gap lies
    # between them. Holes found on the way are kept for the pair chosen below.
    run_lo = np.empty(n + 1, dtype=np.int64)
    run_hi = np.empty(n + 1, dtype=np.int64)
    nr = 0
    cache_key = np.empty((n + 1, 2), dtype=np.int64)
    cache_val = np.empty((n + 1, 7))
    nc = 0
    for p in range(n):
        if nr > 0 and pg[run_lo[nr - 1]] == pg[p]:
            join = True
            if butt:
                g = plate_anchor[pg[p]]
                cy, cz, dy, dz = rows[g, 0], rows[g, 1], rows[g, 2], rows[g, 3]
                left = pl[p - 1]
                right = pl[p]
                li = index[max(offsets[left], offsets[left + 1] - 11) : offsets[left + 1]]
                ri = index[offsets[right] : min(offsets[right + 1], offsets[right] + 11)]
                tl = _along(points, li, cy, cz, dy, dz)
                tr = _along(points, ri, cy, cz, dy, dz)
                step_l = _steps(tl)[1]
                step_r = _steps(tr)[0]
                t_l, t_r = tl[-1], tr[0]
                el, er = t_l + 0.5 * step_l, t_r - 0.5 * step_r
                gap = (cy + er * dy - (cy + el * dy)) * dy + (cz + er * dz - (cz + el * dz)) * dz
                if not gap < min_opening:
                    lo, hi = li[-1], ri[0]
                    res = hole(
                        points,
                        owner,
                        rows,
                        cy,
                        cz,
                        dy,
                        dz,
                        t_l,
                        step_l,
                        cy,
                        cz,
                        dy,
                        dz,
                        t_r,
                        step_r,
                        lo,
                        hi,
                        tol,
                        spacing,
                        sigma,
                        min_bottom_mm,
                        butt,
                    )
                    cache_key[nc, 0], cache_key[nc, 1] = lo, hi
                    cache_val[nc, 0] = res[0]
                    cache_val[nc, 1] = 1.0 if res[1] else 0.0
                    cache_val[nc, 2], cache_val[nc, 3] = res[2], res[3]
                    cache_val[nc, 4] = 1.0 if res[4] else 0.0
                    cache_val[nc, 5], cache_val[nc, 6] = res[5], res[6]
                    nc += 1
                    join = not res[0] >= min_open_mm
            if join:
                run_hi[nr - 1] = p + 1
                continue
        run_lo[nr], run_hi[nr] = p, p + 1
        nr += 1
    # Each run's line: a long piece as it is, else a refit of its pieces (long enough) or
    # its pieces measured on their plate's line.
    kind = np.empty(nr, dtype=np.int64)
    rms = np.empty(nr)  # the refits' (FIT only)
    line = np.empty((nr, 4))
    ends = np.empty((nr, 4))  # first t, last t, step at the start, step at the end
    lims = np.empty((nr, 3), dtype=np.int64)  # first inlier, last inlier, count
    for r in range(nr):
        lo, hi = run_lo[r], run_hi[r]
        g = plate_anchor[pg[lo]]
        kind[r], cy, cz, dy, dz, rms[r], idx, t = _run_line(
            points, index, along, offsets, rows, t_first, t_last, pl[lo:hi], g, min_plate_mm
        )
        line[r, 0], line[r, 1], line[r, 2], line[r, 3] = cy, cz, dy, dz
        s0, s1 = _steps(t)
        ends[r, 0], ends[r, 1], ends[r, 2], ends[r, 3] = t[0], t[-1], s0, s1
        lims[r, 0], lims[r, 1], lims[r, 2] = idx[0], idx[-1], idx.shape[0]
    # Neighbouring runs near parallel, their facing ends near; the best pair.
    ints = np.full(13, -1, dtype=np.int64)
    out = np.zeros(21)
    best_open = False
    best_key = 0.0
    for a in range(nr - 1):
        b = a + 1
        acy, acz, ady, adz = line[a, 0], line[a, 1], line[a, 2], line[a, 3]
        bcy, bcz, bdy, bdz = line[b, 0], line[b, 1], line[b, 2], line[b, 3]
        if not math.acos(min(1.0, abs(ady * bdy + adz * bdz))) <= ten:
            continue
        ta, tb = ends[a, 1], ends[b, 0]
        if (
            not math.hypot(bcy + tb * bdy - (acy + ta * ady), bcz + tb * bdz - (acz + ta * adz))
            <= max_gap_mm
        ):
            continue
        if butt:
            ea, eb = ta + 0.5 * ends[a, 3], tb - 0.5 * ends[b, 2]
            opening = math.hypot(
                bcy + eb * bdy - (acy + ea * ady), bcz + eb * bdz - (acz + ea * adz)
            )
            if opening < min_opening:
                continue
            lo, hi = lims[a, 1], lims[b, 0]
            res = (0.0, False, 0.0, 0.0, False, 0.0, 0.0)
            hit = -1
            for k in range(nc):
                if cache_key[k, 0] == lo and cache_key[k, 1] == hi:
                    hit = k
            if hit >= 0:
                v = cache_val[hit]
                res = (v[0], v[1] > 0.5, v[2], v[3], v[4] > 0.5, v[5], v[6])
            else:
                res = hole(
                    points,
                    owner,
                    rows,
                    acy,
                    acz,
                    ady,
                    adz,
                    ta,
                    ends[a, 3],
                    bcy,
                    bcz,
                    bdy,
                    bdz,
                    tb,
                    ends[b, 2],
                    lo,
                    hi,
                    tol,
                    spacing,
                    sigma,
                    min_bottom_mm,
                    butt,
                )
            is_open = res[0] >= min_open_mm
            if not is_open and not res[1] and not res[4]:
                continue
            if (is_open and not best_open) or (is_open == best_open and opening > best_key):
                best_open, best_key = is_open, opening
                ints[0], ints[1] = a, b
                ints[10] = 1 if is_open else 0
                ints[11] = 1 if res[1] else 0
                ints[12] = 1 if res[4] else 0
                out[0], out[1], out[2], out[3], out[4] = res[0], res[2], res[3], res[5], res[6]
        else:
            step = (bcy - acy) * -adz + (bcz - acz) * ady  # > 0: b is deeper
            if pg[run_lo[a]] == pg[run_lo[b]] or abs(step) < max(min_step_mm, 3 * tol):
                continue
            score = float(lims[a, 2] + lims[b, 2])
            if score > best_key:
                best_key = score
                ints[0], ints[1] = a, b
                out[5] = step
    if ints[0] < 0:
        return ints, out
    a, b = ints[0], ints[1]
    if not butt:
        res = hole(
            points,
            owner,
            rows,
            line[a, 0],
            line[a, 1],
            line[a, 2],
            line[a, 3],
            ends[a, 1],
            ends[a, 3],
            line[b, 0],
            line[b, 1],
            line[b, 2],
            line[b, 3],
            ends[b, 0],
            ends[b, 2],
            lims[a, 1],
            lims[b, 0],
            tol,
            spacing,
            sigma,
            math.inf,
            butt,
        )
        ints[11] = 1 if res[1] else 0
        ints[12] = 1 if res[4] else 0
        out[0], out[1], out[2], out[3], out[4] = res[0], res[2], res[3], res[5], res[6]
    # The runs' ends (a visible corner or half a step beyond the last inlier), the share of
    # the profile the model (each plate running on to the profile's end) explains.
    # Runtime flags: a literal True or False would compile a copy of the callee each.
    at_end, at_start = butt | True, butt & False
    piece_a = pl[run_lo[a]] if kind[a] == PIECE else -1
    piece_b = pl[run_lo[b]] if kind[b] == PIECE else -1
    steps = np.empty((nl, 2))
    for j in range(nl):
        steps[j, 0], steps[j, 1] = _steps(along[offsets[j] : offsets[j + 1]])
    out[16], out[17] = _corner(
        line[a],
        ends[a],
        at_end,
        piece_a,
        rows,
        count,
        t_first,
        t_last,
        steps,
        min_points,
        spacing,
        tol,
    )
    out[18], out[19] = _corner(
        line[b],
        ends[b],
        at_start,
        piece_b,
        rows,
        count,
        t_first,
        t_last,
        steps,
        min_points,
        spacing,
        tol,
    )
    ay, az, ady, adz = line[a, 0], line[a, 1], line[a, 2], line[a, 3]
    by, bz, bdy, bdz = line[b, 0], line[b, 1], line[b, 2], line[b, 3]
    lo, hi = lims[a, 1] + 1, lims[b, 0]
    out[20] = two_lines_share(points, stray, lo, hi, ay, az, ady, adz, by, bz, bdy, bdz, 3.0 * tol)

    out[6], out[7], out[8], out[9], out[10] = line[a, 0], line[a, 1], line[a, 2], line[a, 3], rms[a]
    out[11], out[12], out[13], out[14], out[15] = (
        line[b, 0],
        line[b, 1],
        line[b, 2],
        line[b, 3],
        rms[b],
    )
    ints[2], ints[3] = kind[a], kind[b]
    ints[4], ints[5] = pl[run_lo[a]], pl[run_lo[b]]
    ints[6], ints[7] = plate_anchor[pg[run_lo[a]]], plate_anchor[pg[run_lo[b]]]
    ints[8], ints[9] = lims[a, 2], lims[b, 2]
    return ints, out
