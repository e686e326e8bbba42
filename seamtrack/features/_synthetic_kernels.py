"""The synthetic profiles' 2D sight-line test, compiled (:mod:`seamtrack.features.synthetic`).

The same arithmetic as the array expression it replaces, a hit and a segment at a time, with
the first blocking segment ending the hit's search: a filled groove's surface has hundreds of
segments and a profile two thousand hits, and the array form built (hits, segments) arrays of
each term (35 ms a profile of ~75-130)."""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray
from seamtrack.jit import KERNEL


class Crossings(NamedTuple):
    """The rays' first crossings (:func:`cast`): ``t`` (n,), inf where nothing is hit, and the
    segment hit (n,), -1 for none."""

    t: FloatArray
    segment: NDArray[np.int64]


@numba.njit(**KERNEL)
def occluded(hits: FloatArray, eye: FloatArray, segs: FloatArray) -> NDArray[np.bool_]:
    """(n,) True where the 2D sight line from a hit to ``eye`` crosses a segment (k, 2, 2);
    the hit's own surface (and a corner's neighbour), crossed at u ~ 0, is skipped."""
    n, k = hits.shape[0], segs.shape[0]
    out = np.zeros(n, dtype=np.bool_)
    for i in range(n):
        d0, d1 = eye[0] - hits[i, 0], eye[1] - hits[i, 1]
        for j in range(k):
            a0, a1 = segs[j, 0, 0], segs[j, 0, 1]
            e0, e1 = segs[j, 1, 0] - a0, segs[j, 1, 1] - a1
            det = d0 * -e1 + e0 * d1
            if not abs(det) > 1e-15:
                continue
            w0, w1 = a0 - hits[i, 0], a1 - hits[i, 1]
            u = (w0 * -e1 + e0 * w1) / det
            s = (d0 * w1 - d1 * w0) / det
            if u > 1e-7 and u <= 1 and s > 1e-9 and s < 1 - 1e-9:
                out[i] = True
                break
    return out


@numba.njit(**KERNEL)
def cast(origin: FloatArray, dirs: FloatArray, segs: FloatArray) -> Crossings:
    """First crossing of rays o + t d (t > 0) with segments (k, 2, 2) (the lowest index of
    equal t)."""
    n, k = dirs.shape[0], segs.shape[0]
    t_hit = np.full(n, np.inf)
    index = np.full(n, -1, dtype=np.int64)
    for j in range(k):
        a0, a1 = segs[j, 0, 0], segs[j, 0, 1]
        e0, e1 = segs[j, 1, 0] - a0, segs[j, 1, 1] - a1
        w0, w1 = a0 - origin[0], a1 - origin[1]
        for i in range(n):
            det = dirs[i, 0] * -e1 + e0 * dirs[i, 1]
            if not abs(det) > 1e-15:
                continue
            t = (w0 * -e1 + e0 * w1) / det
            s = (dirs[i, 0] * w1 - dirs[i, 1] * w0) / det
            if t > 1e-9 and s >= -1e-12 and s <= 1 + 1e-12 and t < t_hit[i]:
                t_hit[i] = t
                index[i] = j
    return Crossings(t_hit, index)
