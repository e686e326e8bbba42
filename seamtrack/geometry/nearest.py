"""The nearest of candidate segments, compiled (the closest-point search of
:meth:`seamtrack.geometry.seam.Seam.closest`; a module of its own so that importing the seam
model does not load numba)."""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.jit import KERNEL

FloatArray = NDArray[np.float64]


@numba.njit(**KERNEL, inline="always")
def _to_segment(q: FloatArray, i: int, a: FloatArray, d: FloatArray, c: int) -> tuple[float, float]:
    """Distance from query point ``q[i]`` to segment ``c`` (from ``a[c]`` along ``d[c]``), and
    the segment's parameter t in [0, 1] at the nearest point."""
    dd = max(d[c, 0] * d[c, 0] + d[c, 1] * d[c, 1] + d[c, 2] * d[c, 2], 1e-300)
    num = (q[i, 0] - a[c, 0]) * d[c, 0] + (q[i, 1] - a[c, 1]) * d[c, 1]
    num += (q[i, 2] - a[c, 2]) * d[c, 2]
    t = min(max(num / dd, 0.0), 1.0)
    e0 = q[i, 0] - (a[c, 0] + t * d[c, 0])
    e1 = q[i, 1] - (a[c, 1] + t * d[c, 1])
    e2 = q[i, 2] - (a[c, 2] + t * d[c, 2])
    return np.sqrt(e0 * e0 + e1 * e1 + e2 * e2), t


@numba.njit(**KERNEL)
def nearest_of(
    q: FloatArray, a: FloatArray, d: FloatArray, cand: NDArray[np.int64]
) -> tuple[NDArray[np.int64], FloatArray, FloatArray]:
    """For each query point, the nearest of its candidate segments (the first on a tie):
    (segment, distance, t); the arithmetic of :func:`seamtrack.geometry.seam._point_segment`
    in loops, without its (m, k, 3) temporaries (a run's scoring asks this for every tick)."""
    m, k = cand.shape
    seg = np.empty(m, dtype=np.int64)
    best_dist = np.empty(m)
    best_t = np.empty(m)
    for i in range(m):
        best, bt, bs = np.inf, 0.0, cand[i, 0]
        for j in range(k):
            c = cand[i, j]
            dist, t = _to_segment(q, i, a, d, c)
            if dist < best:
                best, bt, bs = dist, t, c
        seg[i], best_dist[i], best_t[i] = bs, best, bt
    return seg, best_dist, best_t


@numba.njit(**KERNEL)
def nearest_all(
    q: FloatArray, a: FloatArray, d: FloatArray
) -> tuple[NDArray[np.int64], FloatArray, FloatArray]:
    """:func:`nearest_of` with every segment a candidate, in their order (a few query points
    on a short seam: no tree to ask)."""
    m = len(q)
    n = len(a)
    seg = np.empty(m, dtype=np.int64)
    best_dist = np.empty(m)
    best_t = np.empty(m)
    for i in range(m):
        best, bt, bs = np.inf, 0.0, 0
        for c in range(n):
            dist, t = _to_segment(q, i, a, d, c)
            if dist < best:
                best, bt, bs = dist, t, c
        seg[i], best_dist[i], best_t[i] = bs, best, bt
    return seg, best_dist, best_t
