"""Compiled inner loops of the family extractors' segmentation.

:func:`pieces` is the split-and-merge of :func:`seamtrack.features.lines.segment_profile`
(Douglas-Peucker, merge, best two-line corners, end kinks, trimmed total-least-squares
refits) and :func:`fit_line` its line fit; the front end before it is
:func:`seamtrack.features.robust.front` (compiled too). Done as numpy calls on ~1,000 points
they were some hundreds of small array operations per profile, whose per-call overhead was
most of an extractor's time. The arithmetic is that of the numpy
formulation (upper medians by sorting, the median-of-5 network, prefix-sum split costs,
total-least-squares directions from atan2 of the second moments); sums run in another order,
so results agree to rounding, not bit for bit.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


# ----------------------------------------------------------------------- split and merge
@numba.njit(cache=True, nogil=True)
def _fit(p: FloatArray, idx: IntArray, n: int) -> tuple[float, float, float, float, float]:
    """Total-least-squares line through ``p[idx[:n]]``: centroid, unit direction (from the
    first point towards the last), rms residual; as ``seamtrack.features.lines._fit``."""
    cy = 0.0
    cz = 0.0
    for k in range(n):
        cy += p[idx[k], 0]
        cz += p[idx[k], 1]
    cy /= n
    cz /= n
    syy = 0.0
    szz = 0.0
    syz = 0.0
    for k in range(n):
        dy, dz = p[idx[k], 0] - cy, p[idx[k], 1] - cz
        syy += dy * dy
        szz += dz * dz
        syz += dy * dz
    theta = 0.5 * math.atan2(2.0 * syz, syy - szz)
    uy, uz = math.cos(theta), math.sin(theta)
    a, b = idx[0], idx[n - 1]
    if uy * (p[b, 0] - p[a, 0]) + uz * (p[b, 1] - p[a, 1]) < 0.0:
        uy, uz = -uy, -uz
    rr = 0.0
    for k in range(n):
        r = -(p[idx[k], 0] - cy) * uz + (p[idx[k], 1] - cz) * uy
        rr += r * r
    return cy, cz, uy, uz, math.sqrt(rr / n)


@numba.njit(cache=True, nogil=True)
def fit_range(p: FloatArray, lo: int, hi: int) -> tuple[float, float, float, float]:
    """Total-least-squares line through ``p[lo:hi]``: centroid and unit direction."""
    n = hi - lo
    cy = 0.0
    cz = 0.0
    for i in range(lo, hi):
        cy += p[i, 0]
        cz += p[i, 1]
    cy /= n
    cz /= n
    syy = 0.0
    szz = 0.0
    syz = 0.0
    for i in range(lo, hi):
        dy, dz = p[i, 0] - cy, p[i, 1] - cz
        syy += dy * dy
        szz += dz * dz
        syz += dy * dz
    theta = 0.5 * math.atan2(2.0 * syz, syy - szz)
    uy, uz = math.cos(theta), math.sin(theta)
    if uy * (p[hi - 1, 0] - p[lo, 0]) + uz * (p[hi - 1, 1] - p[lo, 1]) < 0.0:
        uy, uz = -uy, -uz
    return cy, cz, uy, uz


@numba.njit(cache=True, nogil=True)
def _cost(n: float, s1: float, s2: float, s3: float, s4: float, s5: float) -> float:
    n = max(n, 1.0)
    cyy = s3 - s1 * s1 / n
    czz = s4 - s2 * s2 / n
    cyz = s5 - s1 * s2 / n
    h = 0.5 * (cyy - czz)
    # sqrt, not hypot: hypot's care for overflow costs ~20 ns, and this runs for every split
    return max(0.5 * (cyy + czz) - math.sqrt(h * h + cyz * cyz), 0.0)


@numba.njit(cache=True, nogil=True)
def best_split(p: FloatArray, lo: int, hi: int, min_size: int) -> tuple[int, float, float]:
    """Best split of ``p[lo:hi]`` into two lines: (b, cost of the two, cost of one line),
    total-least-squares sums of squared residuals for every b from prefix sums (O(n));
    ``b`` counts from ``lo``."""
    k = hi - lo
    my = 0.0
    mz = 0.0
    for i in range(lo, hi):
        my += p[i, 0]
        mz += p[i, 1]
    my /= k
    mz /= k
    pre = np.empty((k, 6))
    a0 = a1 = a2 = a3 = a4 = a5 = 0.0
    for i in range(k):
        y, z = p[lo + i, 0] - my, p[lo + i, 1] - mz
        a0 += 1.0
        a1 += y
        a2 += z
        a3 += y * y
        a4 += z * z
        a5 += y * z
        pre[i, 0], pre[i, 1], pre[i, 2] = a0, a1, a2
        pre[i, 3], pre[i, 4], pre[i, 5] = a3, a4, a5
    single = _cost(a0, a1, a2, a3, a4, a5)
    if k - min_size + 1 <= min_size:
        return k, single, single
    best_b = min_size
    best = np.inf
    for b in range(min_size, k - min_size + 1):
        j = b - 1
        c = _cost(pre[j, 0], pre[j, 1], pre[j, 2], pre[j, 3], pre[j, 4], pre[j, 5]) + _cost(
            a0 - pre[j, 0],
            a1 - pre[j, 1],
            a2 - pre[j, 2],
            a3 - pre[j, 3],
            a4 - pre[j, 4],
            a5 - pre[j, 5],
        )
        if c < best or (b == min_size):
            best, best_b = c, b
    return best_b, best, single


@numba.njit(cache=True, nogil=True)
def _split(
    p: FloatArray, lo: int, hi: int, tol: float, limit: int, out_lo: IntArray, out_hi: IntArray
) -> int:
    """Douglas-Peucker over ``p[lo:hi + 1]``: inclusive index ranges within ``tol`` of their
    chord, in column order, written to ``out_lo``/``out_hi``; their count, or -1 past
    ``limit`` (pieces and pending ranges)."""
    stack_a = np.empty(limit + 2, dtype=np.int64)
    stack_b = np.empty(limit + 2, dtype=np.int64)
    stack_a[0], stack_b[0] = lo, hi
    ns = 1
    no = 0
    while ns > 0:
        ns -= 1
        a, b = stack_a[ns], stack_b[ns]
        if b - a < 2:
            out_lo[no], out_hi[no] = a, b
            no += 1
        else:
            cy, cz = p[b, 0] - p[a, 0], p[b, 1] - p[a, 1]
            norm = math.hypot(cy, cz)
            kmax = 0
            dmax = -1.0
            for i in range(a + 1, b):
                qy, qz = p[i, 0] - p[a, 0], p[i, 1] - p[a, 1]
                if norm == 0.0:
                    d = math.hypot(qy, qz)
                else:
                    d = abs(qy * cz - qz * cy) / norm
                if d > dmax:
                    dmax, kmax = d, i
            if dmax > tol:
                stack_a[ns], stack_b[ns] = kmax, b
                stack_a[ns + 1], stack_b[ns + 1] = a, kmax
                ns += 2
            else:
                out_lo[no], out_hi[no] = a, b
                no += 1
        if no + ns > limit:
            return -1
    return no


@numba.njit(cache=True, nogil=True)
def _merge(p: FloatArray, lo: IntArray, hi: IntArray, n: int, tol: float) -> int:
    """Join neighbouring pieces whose union fits one line within ``tol`` (in place); the
    number of pieces left."""
    k = 0
    for j in range(1, n):
        a, b = lo[k], hi[j]
        cy, cz, uy, uz = fit_range(p, a, b + 1)
        worst = 0.0
        for i in range(a, b + 1):
            worst = max(worst, abs(-(p[i, 0] - cy) * uz + (p[i, 1] - cz) * uy))
        if worst <= tol:
            hi[k] = b
        else:
            k += 1
            lo[k], hi[k] = lo[j], hi[j]
    return k + 1


@numba.njit(cache=True, nogil=True)
def pieces(
    p: FloatArray,
    runs: IntArray,
    stray: NDArray[np.bool_],
    tol: float,
    sigma: float,
    floor: float,
    min_points: int,
    max_lines: int,
    min_kink_rad: float,
) -> tuple[int, IntArray, IntArray, FloatArray, FloatArray]:
    """The straight pieces of :func:`seamtrack.features.lines.segment_profile`.

    Returns
    -------
    code : int
        0 ok; 1 too noisy or curved (more than ``max_lines`` pieces); 2 no piece keeps
        ``min_points`` inliers.
    offsets : (k + 1,) the pieces' inliers are ``index[offsets[j]:offsets[j + 1]]``
    index : inlier positions in ``p``, column order within each piece
    fits : (k, 5) centroid y, z, direction y, z, rms
    along : the inliers' coordinates along their piece's line (from its centroid)
    """
    cap = 2 * max_lines + 8
    all_lo = np.empty(cap, dtype=np.int64)
    all_hi = np.empty(cap, dtype=np.int64)
    total = 0
    run_lo = np.empty(max_lines + 2, dtype=np.int64)
    run_hi = np.empty(max_lines + 2, dtype=np.int64)
    significant = 30.0 * max(sigma, floor / 5.0) ** 2
    cuts = np.empty(2, dtype=np.int64)
    scratch = np.empty(p.shape[0], dtype=np.int64)
    for r in range(runs.shape[0] - 1):
        lo, hi = runs[r], runs[r + 1]
        if hi - lo >= min_points and not stray[lo]:
            n = _split(p, lo, hi - 1, tol, max_lines, run_lo, run_hi)
            if n < 0:
                return 1, np.zeros(1, np.int64), scratch[:0], np.empty((0, 5)), np.empty(0)
            n = _merge(p, run_lo, run_hi, n, tol)
            # Corners at the best two-line split (in order: each moves the next's start).
            for j in range(n - 1):
                a, b = run_lo[j], run_hi[j + 1] + 1
                if b - a >= 6:
                    cut = a + best_split(p, a, b, 3)[0]
                    run_hi[j], run_lo[j + 1] = cut - 1, cut
            # A run's end pieces split at a small kink.
            for j in range(n):
                a, b = run_lo[j], run_hi[j]
                nc = 0
                if b - a + 1 >= 4 * min_points:
                    mid = (a + b) // 2
                    for h in range(2):
                        if h == 0 and j != 0:
                            continue
                        if h == 1 and j != n - 1:
                            continue
                        h_lo, h_hi = (a, mid + 1) if h == 0 else (mid, b + 1)
                        bb, split, single = best_split(p, h_lo, h_hi, min_points)
                        if single - split > significant:
                            cut = h_lo + bb
                            _, _, uy1, uz1 = fit_range(p, a, cut)
                            _, _, uy2, uz2 = fit_range(p, cut, b + 1)
                            kink = math.acos(min(1.0, abs(uy1 * uy2 + uz1 * uz2)))
                            if kink > min_kink_rad:
                                cuts[nc] = cut
                                nc += 1
                if nc == 2 and cuts[1] < cuts[0]:
                    cuts[0], cuts[1] = cuts[1], cuts[0]
                prev = a
                for c in range(nc + 1):
                    nxt = cuts[c] if c < nc else b + 1
                    if nxt > prev:
                        all_lo[total], all_hi[total] = prev, nxt - 1
                        total += 1
                    prev = nxt
        if total > max_lines:
            return 1, np.zeros(1, np.int64), scratch[:0], np.empty((0, 5)), np.empty(0)
    # Trimmed refits: inliers within max(3 sigma, floor / 2) of each piece's first fit.
    trim = max(3.0 * sigma, 0.5 * floor)
    offsets = np.zeros(total + 1, dtype=np.int64)
    index = np.empty(p.shape[0], dtype=np.int64)
    along = np.empty(p.shape[0])
    fits = np.empty((total, 5))
    k = 0
    used = 0
    for j in range(total):
        a, b = all_lo[j], all_hi[j]
        cy, cz, uy, uz = fit_range(p, a, b + 1)
        n = 0
        for i in range(a, b + 1):
            if abs(-(p[i, 0] - cy) * uz + (p[i, 1] - cz) * uy) <= trim:
                index[used + n] = i
                n += 1
        if n >= min_points:
            fy, fz, fuy, fuz, rms = _fit(p, index[used:], n)
            fits[k, 0], fits[k, 1], fits[k, 2], fits[k, 3], fits[k, 4] = fy, fz, fuy, fuz, rms
            for i in range(used, used + n):
                along[i] = (p[index[i], 0] - fy) * fuy + (p[index[i], 1] - fz) * fuz
            used += n
            k += 1
            offsets[k] = used
    if k == 0:
        return 2, offsets[:1], index[:0], fits[:0], along[:0]
    return 0, offsets[: k + 1], index[:used], fits[:k], along[:used]


@numba.njit(cache=True, nogil=True)
def fit_line(p: FloatArray, idx: IntArray) -> tuple[float, float, float, float, float, FloatArray]:
    """Total-least-squares line through ``p[idx]`` (at least one point): centroid, unit
    direction (from the first point towards the last), rms residual, and the points'
    coordinates along it; :func:`seamtrack.features.lines._fit` in one call."""
    n = idx.shape[0]
    cy, cz, uy, uz, rms = _fit(p, idx, n)
    t = np.empty(n)
    for k in range(n):
        t[k] = (p[idx[k], 0] - cy) * uy + (p[idx[k], 1] - cz) * uz
    return cy, cz, uy, uz, rms, t
