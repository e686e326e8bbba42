"""The loop's progress check: :meth:`~seamtrack.geometry.seam.Seam.closest_near` in one numba
kernel call instead of some twenty small numpy calls.

The kernel repeats the reference's arithmetic operation by operation (the window's end points
as ``np.interp`` computes them, the point-segment distance with its sums taken left to right,
the first smallest distance), so it returns the same arc length to the last bit; the one
BLAS-dependent step, the chosen segment's length (``np.linalg.norm``), goes through ``np.dot``,
which numba hands to BLAS's ``ddot`` as numpy does. A test compares the two on many points and
seams.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple, cast

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack import constants
from seamtrack.jit import KERNEL

FloatArray = NDArray[np.float64]

_AT_REST = constants.AT_REST_SPEED_MM_S
_EPS = constants.PROGRESS_EPS_MM

#: :func:`progress_near`'s ``window`` (mm) and ``scalar_norm`` flags, passed by every caller
#: as typed values: a literal or an omitted argument would compile the kernel once more each.
NEAR_WINDOW_MM = 5.0
SCALAR_NORM = cast(bool, np.bool_(True))
DOT_NORM = cast(bool, np.bool_(False))


@numba.njit(**KERNEL, inline="always")
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


@numba.njit(**KERNEL)
def closest_in_window(
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
        self.columns = np.ascontiguousarray(self.points.T)
        self.length_mm = float(seam.length_mm)

    def closest_near(self, point: Any, arc_length_hint_mm: float, window_mm: float = 5.0) -> float:
        """:meth:`Seam.closest_near <seamtrack.geometry.seam.Seam.closest_near>`, the same
        number (:func:`progress_near`)."""
        q = np.asarray(point, dtype=np.float64)
        return progress_near(
            self.points, self.knots, self.columns, q, float(arc_length_hint_mm), self.length_mm,
            float(window_mm), DOT_NORM,
        )  # fmt: skip


@numba.njit(**KERNEL)
def progress_near(
    points: FloatArray, knots: FloatArray, columns: FloatArray, q: FloatArray, hint: float,
    length: float, window: float, scalar_norm: bool,
) -> float:  # fmt: skip
    """The arc length of the seam point closest to ``q`` near ``hint``: the search of
    :meth:`Seam.closest_near <seamtrack.geometry.seam.Seam.closest_near>` in a window of
    ``window`` mm either side of the hint, doubled while the closest point lies on a cut end.

    The same number as the seam's: the chosen segment's length through ``np.dot``, which
    numba hands to the same BLAS ``ddot`` as numpy (a test compares the two); ``length``: the
    seam's (``Seam.length_mm``, which may differ from ``knots[-1]`` in the last bit).
    ``scalar_norm``: that length by a scalar sqrt instead (within an ulp of it), as the
    compiled ticks' tool-orientation refresh has always taken it."""
    n_seg = len(points) - 1
    d = np.empty(3)
    while True:
        s0 = max(hint - window, 0.0)
        s1 = min(hint + window, length)
        i0 = min(max(int(np.searchsorted(knots, s0, side="right")) - 1, 0), n_seg - 1)
        i1 = min(max(int(np.searchsorted(knots, s1, side="left")), i0 + 1), n_seg)
        s_start, t, d[0], d[1], d[2] = closest_in_window(points, knots, columns, q, s0, s1, i0, i1)
        if scalar_norm:
            s = s_start + t * math.sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2])
        else:
            s = s_start + t * math.sqrt(np.dot(d, d))
        cut_low = s0 > 0.0 and s <= s0 + 1e-12
        cut_high = s1 < length and s >= s1 - 1e-12
        if not (cut_low or cut_high) or window >= length:
            return s
        window *= 2.0


#: The progress check's state and settings (:func:`progress_check`), one float array: the arc
#: length now, the best so far and when it was reached, since when the torch is at rest (NaN:
#: moving), whether the last frame showed the seam, a closed seam, the arc length that
#: completes it, the stall time, the rest window; the last tick checked by the compiled ticks.
S_NOW, S_BEST, T_PROGRESS, REST_SINCE, LAST_SEEN, CLOSED, S_DONE, STALL_S, REST_S = range(9)
CHECKED, FOUND = 9, 10  # the compiled ticks' last check: its tick, what it found
LENGTH = 11  # the seam's length
PROGRESS_FIELDS = 12
#: What a check found: go on; at rest with no seam in sight (``completed`` or ``lost_seam``);
#: a closed seam back where it began; no progress for the stall time.
GO_ON, AT_REST_END, CLOSED_END, NO_PROGRESS = 0, 1, 2, 3


@numba.njit(**KERNEL)
def progress_check(
    P: FloatArray, t: float, x: float, y: float, z: float, speed: float, points: FloatArray,
    knots: FloatArray, columns: FloatArray,
) -> int:  # fmt: skip
    """One progress check of the loop at time ``t`` with the torch tip at (x, y, z) moving at
    ``speed`` (``P``: its state, updated): the arc length along the seam followed from the
    last, the best so far, the rest; returns what it found (``GO_ON`` or why the run ends)."""
    if speed <= _AT_REST:
        if math.isnan(P[REST_SINCE]):
            P[REST_SINCE] = t
    else:
        P[REST_SINCE] = math.nan
    q = np.empty(3)
    q[0], q[1], q[2] = x, y, z
    s_now = progress_near(points, knots, columns, q, P[S_NOW], P[LENGTH], NEAR_WINDOW_MM, DOT_NORM)
    P[S_NOW] = s_now
    if s_now > P[S_BEST] + _EPS:
        P[S_BEST], P[T_PROGRESS] = s_now, t
    rest_since = P[REST_SINCE]
    if not math.isnan(rest_since) and t - rest_since >= P[REST_S] and P[LAST_SEEN] == 0.0:
        return AT_REST_END
    if P[CLOSED] != 0.0 and P[S_BEST] >= P[S_DONE]:
        return CLOSED_END
    if t - P[T_PROGRESS] >= P[STALL_S]:
        return NO_PROGRESS
    return GO_ON


class CheckArrays(NamedTuple):
    """The arrays a progress check reads and writes, as the compiled ticks take them: its
    state (:func:`progress_check`'s, fields ``S_BEST``...), the seam's points, arc lengths and
    columns, and the log of (t, s) at every check (the count in its last row's first
    column)."""

    state: FloatArray
    points: FloatArray
    knots: FloatArray
    columns: FloatArray
    log: FloatArray


class ProgressCheck:
    """The loop's progress checks of one run: their state (:func:`progress_check`'s array),
    the seam's arrays and the log of (t, s) at every check, whether the loop checks
    (:meth:`check`) or its compiled ticks do (``args``, then :meth:`take` their log).

    ``done_mm``: the arc length that completes the seam; ``rest_s``: how long the torch rests
    with no seam in sight before the run ends."""

    def __init__(
        self, seam: Any, closed: bool, done_mm: float, stall_s: float, rest_s: float
    ) -> None:
        near = ProgressTracker(seam)
        self.P = P = np.zeros(PROGRESS_FIELDS)
        P[S_BEST], P[REST_SINCE], P[CHECKED] = -math.inf, math.nan, -1.0
        P[CLOSED], P[S_DONE], P[STALL_S], P[REST_S] = float(closed), done_mm, stall_s, rest_s
        P[LENGTH] = near.length_mm
        # The log of every check, (t, s) rows, the loop's and its compiled ticks' in the order
        # made; the count in the last row's first column; grown by doubling (:meth:`room`).
        self.checks = np.zeros((1025, 2))
        self._seam = (near.points, near.knots, near.columns)
        self.args = CheckArrays(P, *self._seam, self.checks)

    def room(self, rows: int) -> bool:
        """At least ``rows`` free rows in the log; True when it was replaced by a larger one
        (and :attr:`args` with it)."""
        checks = self.checks
        m = int(checks[-1, 0])
        size = len(checks) - 1
        if m + rows <= size:
            return False
        while m + rows > size:
            size *= 2
        self.checks = np.zeros((size + 1, 2))
        self.checks[:m] = checks[:m]
        self.checks[-1, 0] = m
        self.args = CheckArrays(self.P, *self._seam, self.checks)
        return True

    @property
    def t_log(self) -> FloatArray:
        """The times of the checks made, (m,)."""
        return np.ascontiguousarray(self.checks[: int(self.checks[-1, 0]), 0])

    @property
    def s_log(self) -> FloatArray:
        """The arc length at each check, (m,)."""
        return np.ascontiguousarray(self.checks[: int(self.checks[-1, 0]), 1])

    def check(self, t: float, tcp: list[float], v: list[float]) -> int:
        """The check at time ``t``, the torch tip at ``tcp`` moving at ``v``: what it found."""
        P, points, knots, columns, _ = self.args
        x, y, z = tcp
        speed = math.sqrt(sum(c * c for c in v))
        found = int(progress_check(P, t, x, y, z, speed, points, knots, columns))
        self.room(1)
        checks = self.checks
        m = int(checks[-1, 0])
        checks[m, 0], checks[m, 1] = t, P[S_NOW]
        checks[-1, 0] = m + 1
        return found

    def ended(self, found: int) -> tuple[str, str]:
        """The status and stop reason of a check that found the run's end."""
        P = self.P
        if found == AT_REST_END:  # at rest, and nothing new can come
            return ("completed" if P[S_BEST] >= P[S_DONE] else "lost_seam"), ""
        if found == CLOSED_END:  # a girth seam ends where it began: the program stops
            return "completed", ""
        return "stalled", f"no progress for {P[STALL_S]:g} s"
