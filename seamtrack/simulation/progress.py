"""The loop's progress check: :meth:`~seamtrack.geometry.seam.Seam.closest_near` in one numba
kernel call instead of some twenty small numpy calls.

The kernel repeats the reference's arithmetic operation by operation (the window's end points
as ``np.interp`` computes them, the point-segment distance with its sums taken left to right,
the first smallest distance), so it returns the same arc length to the last bit; the one
BLAS-dependent step, the chosen segment's length (``np.linalg.norm``), is left to numpy. A test
compares the two on many points and seams.
"""

from __future__ import annotations

import bisect
import math
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]


@numba.njit(cache=True, nogil=True, inline="always")
def _interp(x: float, knots: FloatArray, values: FloatArray) -> float:
    """``np.interp(x, knots, values)`` for one x inside [knots[0], knots[-1]]."""
    n = len(knots)
    if x >= knots[n - 1]:
        return float(values[n - 1])
    j = max(int(np.searchsorted(knots, x, side="right")) - 1, 0)
    if knots[j] == x:
        return float(values[j])
    slope = (values[j + 1] - values[j]) / (knots[j + 1] - knots[j])
    result = slope * (x - knots[j]) + values[j]
    if math.isnan(result):
        result = slope * (x - knots[j + 1]) + values[j + 1]
        if math.isnan(result) and values[j] == values[j + 1]:
            result = values[j]
    return float(result)


@numba.njit(cache=True, nogil=True)
def _closest_in_window(
    points: FloatArray,
    knots: FloatArray,
    columns: FloatArray,
    q: FloatArray,
    s0: float,
    s1: float,
    i0: int,
    i1: int,
) -> tuple[float, float, float, float, float]:
    """The closest of segments i0..i1-1, cut to [s0, s1]: its start's arc length, the parameter
    t and the segment vector (three floats)."""
    best = np.inf
    best_s = 0.0
    best_t = 0.0
    bx = by = bz = 0.0
    qx, qy, qz = q[0], q[1], q[2]
    for k in range(i0, i1):
        if k == i0:
            ax = _interp(s0, knots, columns[0])
            ay = _interp(s0, knots, columns[1])
            az = _interp(s0, knots, columns[2])
            s_start = s0
        else:
            ax, ay, az = points[k, 0], points[k, 1], points[k, 2]
            s_start = knots[k]
        if k == i1 - 1:
            ex = _interp(s1, knots, columns[0])
            ey = _interp(s1, knots, columns[1])
            ez = _interp(s1, knots, columns[2])
        else:
            ex, ey, ez = points[k + 1, 0], points[k + 1, 1], points[k + 1, 2]
        dx, dy, dz = ex - ax, ey - ay, ez - az
        dd = max(dx * dx + dy * dy + dz * dz, 1e-300)
        t = ((qx - ax) * dx + (qy - ay) * dy + (qz - az) * dz) / dd
        t = min(max(t, 0.0), 1.0)
        rx = qx - (ax + t * dx)
        ry = qy - (ay + t * dy)
        rz = qz - (az + t * dz)
        dist = math.sqrt(rx * rx + ry * ry + rz * rz)
        if k == i0 or dist < best or (math.isnan(dist) and not math.isnan(best)):
            best, best_s, best_t, bx, by, bz = dist, s_start, t, dx, dy, dz
    return best_s, best_t, bx, by, bz


class ProgressTracker:
    """``closest_near`` of one seam, with the seam's arrays prepared once.

    Parameters
    ----------
    seam : Seam
    """

    def __init__(self, seam: Any):
        self.points = np.ascontiguousarray(seam.points, dtype=np.float64)
        self.knots = np.ascontiguousarray(seam.arc_length_mm, dtype=np.float64)
        self.knot_list = self.knots.tolist()  # bisect on a list: np.searchsorted, cheaper
        self.columns = np.ascontiguousarray(self.points.T)
        self.length_mm = float(seam.length_mm)
        self.n_seg = len(self.points) - 1

    def closest_near(self, point: Any, arc_length_hint_mm: float, window_mm: float = 5.0) -> float:
        """:meth:`Seam.closest_near <seamtrack.geometry.seam.Seam.closest_near>`, the same
        number."""
        knots = self.knots
        knot_list = self.knot_list
        length = self.length_mm
        n_seg = self.n_seg
        q = np.asarray(point, dtype=np.float64)
        while True:
            s0 = max(arc_length_hint_mm - window_mm, 0.0)
            s1 = min(arc_length_hint_mm + window_mm, length)
            i0 = min(max(bisect.bisect_right(knot_list, s0) - 1, 0), n_seg - 1)
            i1 = min(max(bisect.bisect_left(knot_list, s1), i0 + 1), n_seg)
            s_start, t, dx, dy, dz = _closest_in_window(
                self.points, knots, self.columns, q, s0, s1, i0, i1
            )
            d = np.array((dx, dy, dz))
            s = s_start + t * math.sqrt(d.dot(d))  # np.linalg.norm(d), the same BLAS dot
            cut_low = s0 > 0.0 and s <= s0 + 1e-12
            cut_high = s1 < length and s >= s1 - 1e-12
            if not (cut_low or cut_high) or window_mm >= length:
                return s
            window_mm *= 2.0
