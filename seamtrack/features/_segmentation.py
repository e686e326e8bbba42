"""Compiled inner loops of the family extractors' segmentation.

:func:`segment` is :func:`seamtrack.features.lines.segment_profile` in one call: the front end
(:func:`seamtrack.features.robust.front`), then the split-and-merge (:func:`_pieces`:
Douglas-Peucker, merge, best two-line corners, end kinks, trimmed total-least-squares
refits; the fits are :mod:`seamtrack.features.line_geometry`'s). Done as numpy calls on
~1,000 points they were some hundreds of small array operations per profile, whose per-call
overhead was most of an extractor's time. The arithmetic is that of the numpy
formulation (upper medians by sorting, the median-of-5 network, prefix-sum split costs,
total-least-squares directions from atan2 of the second moments); sums run in another order,
so results agree to rounding, not bit for bit.
"""

from __future__ import annotations

import math
from typing import NamedTuple, cast

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray, IntArray
from seamtrack.features.line_geometry import fit_points, fit_range
from seamtrack.features.robust import KEPT, FrontOut, FrontParams, robust_front
from seamtrack.jit import KERNEL


class PieceTable(NamedTuple):
    """A profile's straight pieces as segmentation leaves them (a numba-supported named
    tuple: compiled joint models take it whole).

    Piece ``j``'s inliers are ``index[bounds[j]:bounds[j + 1]]`` (their positions among the
    kept points, column order) and their coordinates along its line
    ``along[bounds[j]:bounds[j + 1]]``; ``fits[j]`` is its line, columns :data:`FIT_CY` ...
    :data:`FIT_LAST` (centroid y, z, direction y, z, rms, first and last coordinate along).
    """

    index: NDArray[np.intp]  # type: ignore[assignment]  # a field, over tuple.index
    along: FloatArray
    fits: FloatArray
    bounds: NDArray[np.intp]


#: numba types a literal (``0``) as its own type, ``Literal[int](0)``, and compiles the
#: kernel it reaches once more for it, a loop counter's start too; these type as int64.
_ZERO = cast(int, np.int64(0))
_THREE = cast(int, np.int64(3))

#: The columns of :attr:`PieceTable.fits`.
FIT_CY, FIT_CZ, FIT_UY, FIT_UZ, FIT_RMS, FIT_FIRST, FIT_LAST = range(7)

#: Segmentation's codes (:attr:`Segmentation.code`): pieces found (:data:`SEGMENTED`); the
#: front end's too few valid points and constant profile (:data:`~.robust.TOO_FEW_POINTS`,
#: :data:`~.robust.CONSTANT`); more pieces than allowed (too noisy or curved); no piece with
#: enough inliers.
SEGMENTED = KEPT
TOO_MANY_PIECES, NO_PIECE = 3, 4


class Split(NamedTuple):
    """The best split of a run into two lines: its position (from the run's start), the
    total-least-squares cost of the two lines and that of one line (sums of squared
    residuals, mm^2)."""

    at: int
    cost_two: float
    cost_one: float


class PieceCount(NamedTuple):
    """What :func:`_pieces` found: a code of :class:`Segmentation` and the pieces written."""

    code: int
    pieces: int


class BufferLayout(NamedTuple):
    """Where :func:`segment` writes in its two buffers, for a profile of n points and
    L = ``max_lines`` (:func:`buffer_layout`): in ``floats``, the kept points ((n, 2) from
    ``points``), the pieces' fits ((L, 7) from ``fits``: columns ``FIT_*``) and the inliers'
    coordinates along their pieces (n + L from ``along``), ``floats`` in all; in ``ints``,
    the kept points' columns (n from ``columns``), the run bounds (n + 1 from ``runs``), the
    pieces' bounds in the inliers (L + 1 from ``offsets``) and the inliers (n + L from
    ``inliers``), ``ints`` in all."""

    points: int
    fits: int
    along: int
    floats: int
    columns: int
    runs: int
    offsets: int
    inliers: int
    ints: int


def buffer_layout(n: int, max_lines: int) -> BufferLayout:
    """The :class:`BufferLayout` of a profile of ``n`` points (pieces of fewer than 6 points
    may share an end point, Douglas-Peucker's, so there may be up to ``max_lines`` more
    inliers than points)."""
    fits = 2 * n
    along = fits + 7 * max_lines
    runs = n
    offsets = runs + n + 1
    inliers = offsets + max_lines + 1
    return BufferLayout(
        0, fits, along, along + n + max_lines, 0, runs, offsets, inliers, inliers + n + max_lines
    )


_buffer_layout = numba.njit(**KERNEL)(buffer_layout)


class Segmentation(NamedTuple):
    """What :func:`segment` found besides the arrays it wrote: the code (:data:`SEGMENTED`,
    :data:`TOO_FEW_POINTS`, :data:`CONSTANT`, :data:`TOO_MANY_PIECES`, :data:`NO_PIECE`),
    the kept points, the run bounds, the pieces, the noise, tolerance, spacing, range
    quantum and resolution (mm)."""

    code: int
    kept: int
    n_runs: int
    n_pieces: int
    sigma: float
    tol: float
    spacing: float
    quantum: float
    resolution: float


# ----------------------------------------------------------------------- split and merge
@numba.njit(**KERNEL)
def _cost(n: float, s1: float, s2: float, s3: float, s4: float, s5: float) -> float:
    n = max(n, 1.0)
    cyy = s3 - s1 * s1 / n
    czz = s4 - s2 * s2 / n
    cyz = s5 - s1 * s2 / n
    h = 0.5 * (cyy - czz)
    # sqrt, not hypot: hypot's care for overflow costs ~20 ns, and this runs for every split
    return max(0.5 * (cyy + czz) - math.sqrt(h * h + cyz * cyz), 0.0)


@numba.njit(**KERNEL)
def _best_split(
    p: FloatArray, lo: int, hi: int, min_size: int, pre: FloatArray, cost: FloatArray
) -> Split:
    """:func:`best_split` with scratch space: ``pre`` (6, >= hi - lo), ``cost`` (>= hi - lo).

    The prefix sums are kept by column and the split costs computed for every b before the
    minimum is sought, so that the divisions and square roots run in SIMD lanes (the
    arithmetic of each cost is unchanged)."""
    k = hi - lo
    my = 0.0
    mz = 0.0
    for i in range(lo, hi):
        my += p[i, 0]
        mz += p[i, 1]
    my /= k
    mz /= k
    a0 = a1 = a2 = a3 = a4 = a5 = 0.0
    for i in range(k):
        y, z = p[lo + i, 0] - my, p[lo + i, 1] - mz
        a0 += 1.0
        a1 += y
        a2 += z
        a3 += y * y
        a4 += z * z
        a5 += y * z
        pre[0, i], pre[1, i], pre[2, i] = a0, a1, a2
        pre[3, i], pre[4, i], pre[5, i] = a3, a4, a5
    single = _cost(a0, a1, a2, a3, a4, a5)
    if k - min_size + 1 <= min_size:
        return Split(k, single, single)
    # cost[t]: the split at b = min_size + t (left: the first b points, prefix row b - 1)
    m = k - 2 * min_size + 1
    first = min_size - 1
    p0, p1, p2 = pre[0, first:], pre[1, first:], pre[2, first:]
    p3, p4, p5 = pre[3, first:], pre[4, first:], pre[5, first:]
    for t in range(m):
        cost[t] = _cost(p0[t], p1[t], p2[t], p3[t], p4[t], p5[t]) + _cost(
            a0 - p0[t], a1 - p1[t], a2 - p2[t], a3 - p3[t], a4 - p4[t], a5 - p5[t]
        )
    best = cost[0]
    best_b = min_size
    for t in range(1, m):
        if cost[t] < best:
            best, best_b = cost[t], min_size + t
    return Split(best_b, best, single)


@numba.njit(**KERNEL)
def best_split(p: FloatArray, lo: int, hi: int, min_size: int) -> Split:
    """Best split of ``p[lo:hi]`` into two lines (:class:`Split`), total-least-squares sums
    of squared residuals for every split from prefix sums (O(n)); ``at`` counts from ``lo``."""
    k = max(hi - lo, 1)
    return _best_split(p, lo, hi, min_size, np.empty((6, k)), np.empty(k))


@numba.njit(**KERNEL)
def _split(
    p: FloatArray, lo: int, hi: int, tol: float, limit: int, out_lo: IntArray, out_hi: IntArray
) -> int:
    """Douglas-Peucker over ``p[lo:hi + 1]``: inclusive index ranges within ``tol`` of their
    chord, in column order, written to ``out_lo``/``out_hi``; their count, or -1 past
    ``limit`` (pieces and pending ranges)."""
    stack_a = np.empty(limit + 2, dtype=np.int64)
    stack_b = np.empty(limit + 2, dtype=np.int64)
    dist = np.empty(hi - lo + 1)  # the distances of the points inside a range
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
            ay, az = p[a, 0], p[a, 1]
            cy, cz = p[b, 0] - ay, p[b, 1] - az
            norm = math.hypot(cy, cz)
            # All distances first (divisions in SIMD lanes: loops from 0 over views), then
            # the first farthest point.
            q = p[a + 1 : b]
            if norm == 0.0:
                for t in range(b - a - 1):
                    dist[t] = math.hypot(q[t, 0] - ay, q[t, 1] - az)
            else:
                for t in range(b - a - 1):
                    dist[t] = abs((q[t, 0] - ay) * cz - (q[t, 1] - az) * cy) / norm
            kmax = 0
            dmax = -1.0
            for t in range(b - a - 1):
                if dist[t] > dmax:
                    dmax, kmax = dist[t], a + 1 + t
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


@numba.njit(**KERNEL)
def _merge(p: FloatArray, lo: IntArray, hi: IntArray, n: int, tol: float) -> int:
    """Join neighbouring pieces whose union fits one line within ``tol`` (in place); the
    number of pieces left."""
    k = 0
    for j in range(1, n):
        a, b = lo[k], hi[j]
        cy, cz, uy, uz = fit_range(p, a, b + 1)
        fits = True  # the largest residual within tol: no residual beyond it (stop at one)
        for i in range(a, b + 1):
            if abs(-(p[i, 0] - cy) * uz + (p[i, 1] - cz) * uy) > tol:
                fits = False
                break
        if fits:
            hi[k] = b
        else:
            k += 1
            lo[k], hi[k] = lo[j], hi[j]
    return k + 1


@numba.njit(**KERNEL)
def _refit(
    p: FloatArray,
    a: int,
    b: int,
    trim: float,
    min_points: int,
    index: IntArray,
    along: FloatArray,
    fit: FloatArray,
) -> int:
    """The trimmed refit of the piece ``p[a:b + 1]``: its inliers (within ``trim`` of its
    first fit) written to ``index`` and their count returned; when there are ``min_points``,
    their total-least-squares line written to ``fit`` (centroid, direction, rms, first and
    last coordinate along it) and their coordinates along it to ``along``.

    The arithmetic of :func:`~seamtrack.features.line_geometry.fit_range` and then
    :func:`~seamtrack.features.line_geometry.fit_points` on the inliers."""
    cy, cz, uy, uz = fit_range(p, a, b + 1)
    n = _ZERO
    for i in range(a, b + 1):
        if abs(-(p[i, 0] - cy) * uz + (p[i, 1] - cz) * uy) <= trim:
            index[n] = i
            n += 1
    if n < min_points:
        return n
    cy, cz, uy, uz, rms = fit_points(p, index, n)
    for k in range(n):
        along[k] = (p[index[k], 0] - cy) * uy + (p[index[k], 1] - cz) * uz
    fit[0], fit[1], fit[2], fit[3] = cy, cz, uy, uz
    fit[4], fit[5], fit[6] = rms, along[0], along[n - 1]
    return n


@numba.njit(**KERNEL)
def _corner_cuts(
    p: FloatArray, run_lo: IntArray, run_hi: IntArray, n: int, pre: FloatArray, cost: FloatArray
) -> None:
    """Moves the bounds between the ``n`` pieces of a run to the best two-line split of each
    neighbouring pair (in order: each moves the next's start)."""
    for j in range(n - 1):
        a, b = run_lo[j], run_hi[j + 1] + 1
        if b - a >= 6:
            cut = a + _best_split(p, a, b, _THREE, pre, cost).at
            run_hi[j], run_lo[j + 1] = cut - 1, cut


@numba.njit(**KERNEL)
def _kink_cuts(
    p: FloatArray, a: int, b: int, first: bool, last: bool, min_points: int, significant: float,
    min_kink_rad: float, pre: FloatArray, cost: FloatArray, cuts: IntArray,
) -> int:  # fmt: skip
    """The cuts of the piece ``p[a:b + 1]`` at a small kink, written to ``cuts`` in order: a
    run's end piece (``first``: its left half; ``last``: its right half) splits where two
    lines explain it ``significant``-ly better than one and meet at more than
    ``min_kink_rad``; returns how many."""
    nc = 0
    if b - a + 1 < 4 * min_points:
        return nc
    mid = (a + b) // 2
    for h in range(2):
        if (h == 0 and not first) or (h == 1 and not last):
            continue
        h_lo, h_hi = (a, mid + 1) if h == 0 else (mid, b + 1)
        best = _best_split(p, h_lo, h_hi, min_points, pre, cost)
        if best.cost_one - best.cost_two > significant:
            cut = h_lo + best.at
            _, _, uy1, uz1 = fit_range(p, a, cut)
            _, _, uy2, uz2 = fit_range(p, cut, b + 1)
            kink = math.acos(min(1.0, abs(uy1 * uy2 + uz1 * uz2)))
            if kink > min_kink_rad:
                cuts[nc] = cut
                nc += 1
    if nc == 2 and cuts[1] < cuts[0]:
        cuts[0], cuts[1] = cuts[1], cuts[0]
    return nc


@numba.njit(**KERNEL)
def _add_cut_piece(
    a: int, b: int, cuts: IntArray, nc: int, all_lo: IntArray, all_hi: IntArray, total: int
) -> int:
    """Appends the piece ``[a, b]`` cut at ``cuts[:nc]`` (empty parts left out) to
    ``all_lo``/``all_hi`` after their ``total`` pieces; returns the new total."""
    prev = a
    for c in range(nc + 1):
        nxt = cuts[c] if c < nc else b + 1
        if nxt > prev:
            all_lo[total], all_hi[total] = prev, nxt - 1
            total += 1
        prev = nxt
    return total


@numba.njit(**KERNEL)
def _trimmed_refits(
    p: FloatArray, all_lo: IntArray, all_hi: IntArray, total: int, trim: float, min_points: int,
    out: PieceTable,
) -> int:  # fmt: skip
    """Refits each of the ``total`` pieces to its inliers within ``trim`` of its first fit,
    written to ``out`` as :func:`_pieces` says (a piece left with fewer than ``min_points`` is
    dropped); returns how many pieces are kept."""
    out.bounds[0] = 0
    k = 0
    used = 0
    for j in range(total):
        n = _refit(
            p, all_lo[j], all_hi[j], trim, min_points, out.index[used:], out.along[used:],
            out.fits[k],
        )  # fmt: skip
        if n >= min_points:
            used += n
            k += 1
            out.bounds[k] = used
    return k


@numba.njit(**KERNEL)
def _pieces(
    p: FloatArray,
    runs: IntArray,
    stray: NDArray[np.bool_],
    tol: float,
    sigma: float,
    floor: float,
    min_points: int,
    max_lines: int,
    min_kink_rad: float,
    offsets: IntArray,
    index: IntArray,
    fits: FloatArray,
    along: FloatArray,
) -> PieceCount:
    """The straight pieces of :func:`seamtrack.features.lines.segment_profile`, written to
    ``offsets`` (>= max_lines + 1,), ``index``, ``along`` (>= len(p) + max_lines,: pieces of
    fewer than 6 points may share an end point) and ``fits`` (>= max_lines, 7).

    Returns a :class:`PieceCount`: ``code`` :data:`SEGMENTED`, :data:`TOO_MANY_PIECES` (too
    noisy or curved: more than ``max_lines`` pieces) or :data:`NO_PIECE` (none keeps
    ``min_points`` inliers); ``pieces`` written: the inliers of piece j are
    ``index[offsets[j]:offsets[j + 1]]`` (their positions in ``p``, column order), their
    coordinates along its line ``along[offsets[j]:offsets[j + 1]]``; ``fits[j]`` holds its
    centroid y, z, direction y, z, rms, and the first and last inliers' coordinates along it
    (columns ``FIT_*``).
    """
    cap = 2 * max_lines + 8
    all_lo = np.empty(cap, dtype=np.int64)
    all_hi = np.empty(cap, dtype=np.int64)
    total = _ZERO
    run_lo = np.empty(max_lines + 2, dtype=np.int64)
    run_hi = np.empty(max_lines + 2, dtype=np.int64)
    significant = 30.0 * max(sigma, floor / 5.0) ** 2
    cuts = np.empty(2, dtype=np.int64)
    pre = np.empty((6, p.shape[0]))
    cost = np.empty(p.shape[0])
    for r in range(runs.shape[0] - 1):
        lo, hi = runs[r], runs[r + 1]
        if hi - lo >= min_points and not stray[lo]:
            n = _split(p, lo, hi - 1, tol, max_lines, run_lo, run_hi)
            if n < 0:
                return PieceCount(TOO_MANY_PIECES, 0)
            n = _merge(p, run_lo, run_hi, n, tol)
            _corner_cuts(p, run_lo, run_hi, n, pre, cost)
            for j in range(n):
                a, b = run_lo[j], run_hi[j]
                nc = _kink_cuts(
                    p, a, b, j == 0, j == n - 1, min_points, significant, min_kink_rad,
                    pre, cost, cuts,
                )  # fmt: skip
                total = _add_cut_piece(a, b, cuts, nc, all_lo, all_hi, total)
        if total > max_lines:
            return PieceCount(TOO_MANY_PIECES, 0)
    # Trimmed refits: inliers within max(3 sigma, floor / 2) of each piece's first fit.
    trim = max(3.0 * sigma, 0.5 * floor)
    out = PieceTable(index, along, fits, offsets)
    k = _trimmed_refits(p, all_lo, all_hi, total, trim, min_points, out)
    return PieceCount(SEGMENTED if k else NO_PIECE, k)


# numba's on-disk cache keys a kernel on its own file only: when the front end
# (seamtrack.features.robust) changes, this file must change too, or a checkout's cached
# ``segment`` keeps the old front end compiled in (the same numbers, the old speed).
@numba.njit(**KERNEL)
def segment(
    points: FloatArray,
    valid: NDArray[np.bool_],
    params: FrontParams,
    max_lines: int,
    min_kink_rad: float,
    floats: FloatArray,
    ints: IntArray,
    stray: NDArray[np.bool_],
) -> Segmentation:
    """:func:`seamtrack.features.lines.segment_profile` in one compiled call: the front end
    (:func:`seamtrack.features.robust.front`) and the straight pieces (:func:`_pieces`),
    written to three given arrays (each array passed to or returned from a compiled call
    costs a fraction of a microsecond): ``floats`` and ``ints``, laid out as
    :func:`buffer_layout` says, and ``stray`` (n,), the points of detours; the front end's
    settings ``params`` (:class:`seamtrack.features.robust.FrontParams`).

    Returns a :class:`Segmentation` (with :data:`TOO_FEW_POINTS`, ``kept`` counts the valid
    points).
    """
    n = points.shape[0]
    at = _buffer_layout(n, max_lines)
    p = floats[at.points : at.fits].reshape((n, 2))
    runs = ints[at.runs : at.offsets]
    inliers = ints[at.inliers :]
    # The spikes' columns go where the inliers will: they are not returned.
    out = FrontOut(p, ints[at.columns : at.runs], inliers, runs, stray)
    front = robust_front(points, valid, params, out)
    found = PieceCount(front.code, 0)
    if front.code == KEPT:
        found = _pieces(
            p[: front.kept],
            runs[: front.n_runs],
            stray,
            front.tol,
            front.sigma,
            front.floor,
            params.min_points,
            max_lines,
            min_kink_rad,
            ints[at.offsets : at.inliers],
            inliers,
            floats[at.fits : at.along].reshape((max_lines, 7)),
            floats[at.along :],
        )
    return Segmentation(
        found.code,
        front.kept,
        front.n_runs,
        found.pieces,
        front.sigma,
        front.tol,
        front.spacing,
        front.quantum,
        front.resolution,
    )
