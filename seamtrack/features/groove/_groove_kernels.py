"""The groove extractor's inner loops, compiled (:mod:`seamtrack.features.groove.extractor`): the
fill surface's local and robust line fits and its running median. The same arithmetic as the numpy
they replace, without numpy's per-call overhead on a few dozen points (the extractor runs on
every frame of every pass of a multi-pass job); the least-squares lines are solved in closed
form (centred sums) where numpy's ``lstsq`` used an SVD: the same line to a few ulps.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray
from seamtrack.jit import KERNEL


@numba.njit(**KERNEL)
def _median_of(x: FloatArray) -> float:
    """``np.median`` of a 1-d array (the middle element, or the two middle ones' mean)."""
    n = len(x)
    s = np.sort(x)
    h = n // 2
    if n % 2:
        return float(s[h])
    return float((s[h - 1] + s[h]) / 2)


@numba.njit(**KERNEL)
def _line_fit(a: FloatArray, b: FloatArray, keep: NDArray[np.bool_]) -> tuple[float, float]:
    """b = c0 + c1 a, least squares on the kept points (at least 3), in closed form; all at
    one a: numpy's ``lstsq``'s minimum-norm answer."""
    n = 0
    sa = 0.0
    sb = 0.0
    for m in range(len(a)):
        if keep[m]:
            n += 1
            sa += a[m]
            sb += b[m]
    ma = sa / n
    mb = sb / n
    saa = 0.0
    sab = 0.0
    for m in range(len(a)):
        if keep[m]:
            da = a[m] - ma
            saa += da * da
            sab += da * (b[m] - mb)
    # All at one a (to lstsq's rank cut, eps times the size): the minimum-norm solution.
    if saa <= (2.220446049250313e-16 * n) ** 2 * n * (1.0 + ma * ma) ** 2:
        return mb / (1.0 + ma * ma), mb * ma / (1.0 + ma * ma)
    c1 = sab / saa
    return mb - c1 * ma, c1


@numba.njit(**KERNEL)
def local_v(qu: FloatArray, qv: FloatArray, ut: float, h: float, tol: float) -> float:
    """:func:`seamtrack.features.groove.surface_v_at` (NaN for its None)."""
    count = 0
    for m in range(len(qu)):
        if abs(qu[m] - ut) <= h:
            count += 1
    if count < 3:
        return np.nan
    a = np.empty(count)
    b = np.empty(count)
    k = 0
    left = False
    right = False
    for m in range(len(qu)):
        if abs(qu[m] - ut) <= h:
            a[k] = qu[m] - ut
            b[k] = qv[m]
            left |= a[k] <= 0
            right |= a[k] >= 0
            k += 1
    if not (left and right):
        return np.nan
    mid = _median_of(b)
    spread = _median_of(np.abs(b - mid))
    keep = np.abs(b - mid) <= max(5.0 * tol, 4.0 * spread)
    c0 = np.nan
    for _ in range(2):
        if np.count_nonzero(keep) < 3:
            return np.nan
        c0, c1 = _line_fit(a, b, keep)
        for m in range(count):
            keep[m] = abs(b[m] - (c0 + c1 * a[m])) <= 3.0 * tol
    return c0


@numba.njit(**KERNEL)
def robust_uv_line(
    qu: FloatArray,
    qv: FloatArray,
    tol: float,
    i: NDArray[np.intp],
    j: NDArray[np.intp],
) -> tuple[float, float, bool]:
    """:func:`seamtrack.features.groove.robust_uv_fit` for the pairs of points ``(i, j)``
    (in their order): (a, b, found)."""
    best = -1
    best_a = 0.0
    best_b = 0.0
    n = len(qu)
    for p in range(len(i)):
        ii, jj = i[p], j[p]
        if not abs(qu[jj] - qu[ii]) > 1e-9:
            continue
        b = (qv[jj] - qv[ii]) / (qu[jj] - qu[ii])
        a = qv[ii] - b * qu[ii]
        count = 0
        for m in range(n):
            if abs(qv[m] - (a + b * qu[m])) <= 2.0 * tol:
                count += 1
        if count > best:  # the first of the most
            best, best_a, best_b = count, a, b
    if best < 0:
        return 0.0, 0.0, False
    keep = np.abs(qv - (best_a + best_b * qu)) <= 2.0 * tol
    if np.count_nonzero(keep) < 3:
        return 0.0, 0.0, False
    c0, c1 = _line_fit(qu, qv, keep)
    return c0, c1, True


@numba.njit(**KERNEL)
def running_median(v: FloatArray, k: int) -> FloatArray:
    """The median of every window of ``k`` (odd) points, the ends padded with their whole
    window's (``np.pad(..., mode="edge")`` of the windows' medians); ``len(v) >= k``."""
    n = len(v)
    half = k // 2
    out = np.empty(n)
    for c in range(n - k + 1):
        out[c + half] = np.sort(v[c : c + k])[half]
    for c in range(half):
        out[c] = out[half]
        out[n - 1 - c] = out[n - 1 - half]
    return out


@numba.njit(**KERNEL)
def running_median_cut(v: FloatArray, k: int) -> FloatArray:
    """The median over the ``k`` (odd) points about each point, the windows at the ends cut
    short to the points there are (``np.median(v[max(0, i - k // 2) : i + k // 2 + 1])``);
    ``len(v) >= k``."""
    n = len(v)
    half = k // 2
    out = np.empty(n)
    for c in range(n):
        out[c] = _median_of(v[max(0, c - half) : min(n, c + half + 1)])
    return out
