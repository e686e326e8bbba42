"""Exact order statistics of the extractors' front end, compiled: the k-th smallest of
non-negative values (absolute differences: the spacing and noise medians of
:func:`seamtrack.features.robust.front`).

The value is that of ``np.sort(x)[k]``, found without sorting. Non-negative doubles order as
their bit patterns read as integers, so the values are counted into buckets of a sixteenth
of a binade around the median of a small sample (one branch-free pass), the few values of the
bucket that holds the k-th are gathered (a second pass), and that bucket is narrowed by
counting on the bits again until a handful of values are left to sort. Quickselect on ~1,000
values is mostly mispredicted branches, and quantized ranges (values repeating in runs) make
its partitions uneven.
"""

from __future__ import annotations

from typing import Any, cast

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray, IntArray
from seamtrack.jit import KERNEL

#: Buckets of the counting passes (of ``hist``: twice as many, two counts interleaved).
BUCKETS = 128
#: The first pass's buckets: the top 4 mantissa bits (a sixteenth of a binade each).
_SHIFT = 48
#: Values sorted directly when this few are left.
_FEW = 24
#: numba types a literal (``0``) as its own type, ``Literal[int](0)``, and compiles the
#: kernel it reaches once more for it, a loop counter's start too; these type as int64.
_ZERO = cast(int, np.int64(0))
#: The strided sample that places the first buckets (an int64, as above).
_SAMPLE = cast(int, np.int64(31))


@numba.njit(**KERNEL)
def sort_small(x: NDArray[Any]) -> NDArray[Any]:
    """Sort ``x`` in place by insertion (stable; few values, or runs already in order: the
    generic sorts cost seconds of compile time for nothing here); ``x``."""
    for i in range(1, x.shape[0]):
        v = x[i]
        j = i - 1
        while j >= 0 and x[j] > v:
            x[j + 1] = x[j]
            j -= 1
        x[j + 1] = v
    return x


@numba.njit(**KERNEL)
def _sorted_kth(w: IntArray, c: int, k: int) -> int:
    """The k-th smallest of ``w[:c]`` by insertion sort (few values)."""
    return sort_small(w[:c])[k]


@numba.njit(**KERNEL)
def _kth_bits(w: IntArray, c: int, k: int, hist: IntArray) -> int:
    """The k-th smallest of the non-negative integers ``w[:c]`` (reordered): bucketed by
    their spread into :data:`BUCKETS` counts, keeping the bucket that holds it, until a
    few are left or all are equal."""
    while c > _FEW:
        lo = w[0]
        hi = w[0]
        for i in range(1, c):
            lo = min(lo, w[i])
            hi = max(hi, w[i])
        if lo == hi:
            return lo
        shift = 0
        while ((hi - lo) >> shift) >= BUCKETS:
            shift += 1
        hist[:BUCKETS] = 0
        for i in range(c):
            hist[(w[i] - lo) >> shift] += 1
        below = 0
        kb = 0
        while below + hist[kb] <= k:
            below += hist[kb]
            kb += 1
        j = 0
        for i in range(c):
            v = w[i]
            w[j] = v
            j += ((v - lo) >> shift) == kb
        c = j
        k -= below
    return _sorted_kth(w, c, k)


@numba.njit(**KERNEL)
def kth_nonneg(x: FloatArray, n: int, k: int, work: IntArray, hist: IntArray) -> float:
    """The k-th smallest of ``x[:n]`` (``np.sort(x[:n])[k]``, ``0 <= k < n``), for values
    that are all ``+0.0`` or positive and finite (absolute values; not -0.0, not NaN).

    Parameters
    ----------
    x : (>= n,) float, contiguous; unchanged
    n, k : int
    work : (>= n,) int scratch
    hist : (>= 2 BUCKETS,) int scratch
    """
    bits = x.view(np.int64)
    if n <= 4 * _FEW:
        work[:n] = bits[:n]
        work[0] = _kth_bits(work, n, k, hist)
        return work[:1].view(np.float64)[0]
    # The median of a strided sample of 31 places the buckets (an estimate suffices: a value
    # outside the buckets is counted in the first or the last).
    s = _SAMPLE
    for i in range(s):
        work[i] = bits[((2 * i + 1) * n) // (2 * s)]
    base = (_sorted_kth(work, s, (k * s) // n) >> _SHIFT) - BUCKETS // 2
    top = BUCKETS - 1
    hist[: 2 * BUCKETS] = 0
    # Two interleaved counts: a run of equal values does not wait on its own increments.
    for i in range(0, n - 1, 2):
        a = min(max((bits[i] >> _SHIFT) - base, 0), top)
        b = min(max((bits[i + 1] >> _SHIFT) - base, 0), top)
        hist[a] += 1
        hist[BUCKETS + b] += 1
    if n % 2:
        hist[min(max((bits[n - 1] >> _SHIFT) - base, 0), top)] += 1
    below = 0
    kb = 0
    while below + hist[kb] + hist[BUCKETS + kb] <= k:
        below += hist[kb] + hist[BUCKETS + kb]
        kb += 1
    c = _ZERO
    for i in range(n):
        v = bits[i]
        work[c] = v
        c += min(max((v >> _SHIFT) - base, 0), top) == kb
    work[0] = _kth_bits(work, c, k - below, hist)
    return work[:1].view(np.float64)[0]
