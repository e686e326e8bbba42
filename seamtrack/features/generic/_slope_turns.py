"""Slopes and turns of a profile, compiled: the inner loops of the generic (slope/curvature)
extractor (:mod:`seamtrack.features.generic.extractor`).

The generic extractor is the fastest built-in: its work is a handful of passes over the profile
(valid points, spacing, noise, a running median, window sums, turning angles), which numpy does
as some forty small array operations. Fused into two loops here they cost a fraction of that.
Medians are selections (``np.partition``), not sorts: sorting ~1,000 fresh values is mostly
branch mispredictions (a benchmark repeating one profile hides that, the CPU learns it).
The arithmetic is the same as the numpy formulation in :mod:`seamtrack.features.lines` (upper
medians,
the median-of-5 network, total-least-squares window directions).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray
from seamtrack.features.line_geometry import Point, fit_range, principal_angle
from seamtrack.features.robust import median5_of
from seamtrack.jit import KERNEL

_SIGMA_FROM_SECOND_DIFF = 1.4826 / math.sqrt(6.0)

#: What :func:`clean_points` found (:attr:`Cleaned.status`): enough points that spread out,
#: too few valid points, or valid points that do not spread out.
OK, TOO_FEW, NO_SPREAD = 0, 1, 2


class Cleaned(NamedTuple):
    """The profile's points cleaned up (:func:`clean_points`): ``status`` (:data:`OK`,
    :data:`TOO_FEW`, :data:`NO_SPREAD`), the points kept (the valid bounded points when
    not OK), their ``spacing`` (median lateral step, else median step) and noise ``sigma``
    (1.4826 / sqrt(6) median |second difference of z|, as in :mod:`seamtrack.features.lines`);
    0 when not OK."""

    status: int
    kept: FloatArray
    spacing: float
    sigma: float


class Turns(NamedTuple):
    """Gaps between neighbours (m - 1) and the turn (rad, in (-pi, pi]) between the
    directions of the k-point windows ending at i + k - 1 and i + 2k - 1 (m - 2k + 1; 0
    where a window pair spans a jump; the corner is at i + k)."""

    gaps: FloatArray
    turn: FloatArray


@numba.njit(**KERNEL)
def _near(p: FloatArray, med: FloatArray, limit: float) -> FloatArray:
    """The points of ``p`` whose range lies within ``limit`` of ``med``, in order."""
    m = p.shape[0]
    count = 0
    for i in range(m):
        if abs(p[i, 1] - med[i]) <= limit:
            count += 1
    kept = np.empty((count, 2))
    j = 0
    for i in range(m):
        if abs(p[i, 1] - med[i]) <= limit:
            kept[j, 0] = p[i, 0]
            kept[j, 1] = p[i, 1]
            j += 1
    return kept


@numba.njit(**KERNEL)
def clean_points(
    points: FloatArray, valid: NDArray[np.bool_], max_abs: float, min_kept: int
) -> Cleaned:
    """Valid bounded points, their spacing and noise, and the points left after dropping
    isolated outliers against a running median of 5 (too few: fewer than ``min_kept`` or 5
    valid points within ``max_abs`` of the origin)."""
    n = points.shape[0]
    m = 0
    for i in range(n):
        if valid[i] and abs(points[i, 0]) < max_abs and abs(points[i, 1]) < max_abs:
            m += 1
    p = np.empty((m, 2))
    j = 0
    for i in range(n):
        if valid[i] and abs(points[i, 0]) < max_abs and abs(points[i, 1]) < max_abs:
            p[j, 0] = points[i, 0]
            p[j, 1] = points[i, 1]
            j += 1
    if m < max(min_kept, 5):
        return Cleaned(TOO_FEW, p, 0.0, 0.0)
    steps = np.empty(m - 1)
    for i in range(m - 1):
        steps[i] = abs(p[i + 1, 0] - p[i, 0])
    spacing = np.partition(steps, (m - 1) // 2)[(m - 1) // 2]
    if not spacing > 0.0:
        for i in range(m - 1):
            steps[i] = math.hypot(p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1])
        spacing = np.partition(steps, (m - 1) // 2)[(m - 1) // 2]
    if not spacing > 0.0:
        return Cleaned(NO_SPREAD, p, 0.0, 0.0)
    second = np.empty(m - 2)
    for i in range(m - 2):
        second[i] = abs(p[i + 2, 1] - 2.0 * p[i + 1, 1] + p[i, 1])
    sigma = _SIGMA_FROM_SECOND_DIFF * np.partition(second, (m - 2) // 2)[(m - 2) // 2]
    # Running median of 5 by the min/max network; the two points at each end take the
    # nearest full window's median.
    med = median5_of(p[:, 1], m)
    kept = _near(p, med, max(6.0 * sigma, 0.12, 4.0 * spacing))
    return Cleaned(OK, kept, spacing, sigma)


@numba.njit(**KERNEL)
def window_turns(p: FloatArray, k: int, jump_mm: float) -> Turns:
    """Gaps between neighbours, and the turn between the total-least-squares directions of
    the k-point windows ending at i + k - 1 and i + 2k - 1 (0 where a window pair spans a
    jump of more than ``jump_mm``; the corner is at i + k)."""
    m = p.shape[0]
    gaps = np.empty(m - 1)
    jumps = np.zeros(m, dtype=np.int64)  # jumps[i]: gaps > jump_mm among the first i gaps
    for i in range(m - 1):
        gaps[i] = math.hypot(p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1])
        jumps[i + 1] = jumps[i] + (1 if gaps[i] > jump_mm else 0)
    cy, cz = p[m // 2, 0], p[m // 2, 1]
    # Prefix sums of y, z, y^2, z^2 and yz (about the middle point): window sums by
    # subtraction.
    sum_y = np.zeros(m + 1)
    sum_z = np.zeros(m + 1)
    sum_yy = np.zeros(m + 1)
    sum_zz = np.zeros(m + 1)
    sum_yz = np.zeros(m + 1)
    for i in range(m):
        y, z = p[i, 0] - cy, p[i, 1] - cz
        sum_y[i + 1] = sum_y[i] + y
        sum_z[i + 1] = sum_z[i] + z
        sum_yy[i + 1] = sum_yy[i] + y * y
        sum_zz[i + 1] = sum_zz[i] + z * z
        sum_yz[i + 1] = sum_yz[i] + y * z
    n_win = m - k + 1
    theta = np.empty(n_win)
    for i in range(n_win):
        sy = sum_y[i + k] - sum_y[i]
        sz = sum_z[i + k] - sum_z[i]
        cyy = sum_yy[i + k] - sum_yy[i] - sy * sy / k
        czz = sum_zz[i + k] - sum_zz[i] - sz * sz / k
        cyz = sum_yz[i + k] - sum_yz[i] - sy * sz / k
        t = principal_angle(cyy, czz, cyz)
        chord_y = p[i + k - 1, 0] - p[i, 0]
        chord_z = p[i + k - 1, 1] - p[i, 1]
        if math.cos(t) * chord_y + math.sin(t) * chord_z < 0.0:
            t += math.pi
        theta[i] = t
    n_turn = n_win - k
    turn = np.empty(n_turn)
    for i in range(n_turn):
        if jumps[i + 2 * k - 1] == jumps[i]:
            turn[i] = (theta[i + k] - theta[i] + math.pi) % (2.0 * math.pi) - math.pi
        else:
            turn[i] = 0.0
    return Turns(gaps, turn)


@numba.njit(**KERNEL)
def corner_point(p: FloatArray, c: int, k: int) -> Point:
    """The corner at point c: the crossing of the lines fitted 2k points to each side (a guard
    of k/2 points left out), or point c itself when the crossing is implausibly far; NaN
    (too near an end) when a side has fewer than 3 points."""
    m = p.shape[0]
    guard = max(1, k // 2)
    llo, lhi = max(0, c - guard - 2 * k), max(1, c - guard)
    rlo, rhi = c + guard, min(c + guard + 2 * k, m)
    if lhi - llo < 3 or rhi - rlo < 3:
        return Point(math.nan, math.nan)
    ay, az, ady, adz = fit_range(p, llo, lhi)
    by, bz, bdy, bdz = fit_range(p, rlo, rhi)
    # Spacing along the left line over its last ten points, as Line.step(True).
    kk = min(10, lhi - llo - 1)
    t_last = (p[lhi - 1, 0] - ay) * ady + (p[lhi - 1, 1] - az) * adz
    t_prev = (p[lhi - 1 - kk, 0] - ay) * ady + (p[lhi - 1 - kk, 1] - az) * adz
    step = abs(t_last - t_prev) / kk
    d = ady * bdz - adz * bdy
    if abs(d) >= 1e-9:
        wy, wz = by - ay, bz - az
        s = (wy * bdz - wz * bdy) / d
        y, z = ay + s * ady, az + s * adz
        if math.hypot(y - p[c, 0], z - p[c, 1]) <= 2 * k * (step + 1e-9) + 1.0:
            return Point(y, z)
    return Point(p[c, 0], p[c, 1])
