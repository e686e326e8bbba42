"""Robust front end of the extractors: the scale of a profile, spikes and reflections, robust fits.

Real triangulation sensors give integer range units (0.01-0.05 mm steps), lose points in
clustered runs, and see specular spikes and multipath streaks millimetres off the surface, most
of them inside grooves. The extractors' front end (:func:`seamtrack.features.lines.segment_profile`)
reads a profile's scale from the data so that its tolerances hold at any pitch and unit:

* :func:`range_quantum`: the range step when the ranges sit on a grid (integer units), else 0;
* the noise (:func:`seamtrack.features.lines.noise_sigma`): 1.4826 / sqrt(6) times the median
  absolute second difference of the range, at lags of 1, 2, 4 and 8 points (a sensor that
  smooths, and quantized ranges, hide their scatter from neighbours), never below the rounding
  noise of the quantum (q / sqrt(12)): on a quantized plate most second differences are 0;
* :func:`detours`: runs of points cut off by jumps on both sides, off the line on which the
  surface continues across them (the surface before and after them fits one line): a specular
  spike or a reflection, not part of the part (:attr:`Reason.REFLECTION`); isolated points off
  a running median of 5 are :attr:`Reason.SPIKE`;

:func:`reject` returns the profile with those points invalid and their reasons set, the same
points the extractors leave out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.sensing.profiles import Profile, Reason

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

#: Coordinates beyond this (mm) are not measurements: treated as invalid.
_MAX_ABS_MM = 1e6
#: Range resolution assumed when neither the sensor's nor the profile's is known (mm): the
#: paper's sensor (Table 3).
DEFAULT_RESOLUTION_MM = 0.01
#: The split tolerance's floor, in range resolutions (quantization and pixel steps).
TOL_RESOLUTIONS = 3.0


_SIGMA_FROM_SECOND_DIFF = 1.4826 / math.sqrt(6.0)
_COS_15 = math.cos(math.radians(15.0))


@numba.njit(cache=True, nogil=True)
def range_quantum(z: FloatArray) -> float:
    """The range step (mm) when consecutive ranges differ by whole multiples of one step (an
    integer range unit), else 0.

    The step is the smallest non-zero difference; it counts when at least 98 % of the
    differences are multiples of it (within 1e-6 relative: ranges stored as unit x count in
    floating point), at least a fifth of them are zero or one step, at least 2 % (and three)
    are one step, and the step is at most a tenth of the ranges' spread (one step between two
    flat plates is no unit).
    """
    n = z.shape[0]
    if n < 8:
        return 0.0
    scale = 0.0
    for i in range(n):
        scale = max(scale, abs(z[i]))
    tiny = 1e-12 * max(scale, 1.0)
    step = np.inf
    for i in range(n - 1):
        d = abs(z[i + 1] - z[i])
        if tiny < d < step:
            step = d
    if not np.isfinite(step):
        return 0.0
    on, small, ones = 0, 0, 0
    for i in range(n - 1):
        k = abs(z[i + 1] - z[i]) / step
        r = round(k)
        if abs(k - r) <= 1e-6 * max(r, 1.0) + tiny / step:
            on += 1
            if r <= 1:
                small += 1
            if r == 1:
                ones += 1
    if (
        on >= 0.98 * (n - 1)
        and small >= 0.2 * (n - 1)
        and ones >= max(3, 0.02 * (n - 1))
        and step <= 0.1 * (np.max(z) - np.min(z))
    ):
        return step
    return 0.0


@numba.njit(cache=True, nogil=True)
def _tls(p: FloatArray, lo: int, hi: int, lo2: int, hi2: int) -> tuple[float, float, float, float]:
    """Total-least-squares line through p[lo:hi] and p[lo2:hi2]: centroid, unit direction."""
    n = (hi - lo) + (hi2 - lo2)
    cy = 0.0
    cz = 0.0
    for r in ((lo, hi), (lo2, hi2)):
        for i in range(r[0], r[1]):
            cy += p[i, 0]
            cz += p[i, 1]
    cy /= n
    cz /= n
    syy = 0.0
    szz = 0.0
    syz = 0.0
    for r in ((lo, hi), (lo2, hi2)):
        for i in range(r[0], r[1]):
            dy, dz = p[i, 0] - cy, p[i, 1] - cz
            syy += dy * dy
            szz += dz * dz
            syz += dy * dz
    theta = 0.5 * math.atan2(2.0 * syz, syy - szz)
    return cy, cz, math.cos(theta), math.sin(theta)


@numba.njit(cache=True, nogil=True)
def detours(
    p: FloatArray,
    starts: IntArray,
    ends: IntArray,
    tol: float,
    min_run: int,
    reach_mm: float,
) -> NDArray[np.bool_]:
    """Which runs (``p[starts[k]:ends[k]]``, cut off each other by jumps) are detours: off the
    line on which the surface continues across them.

    For each run A of at least ``min_run`` points, the following runs within ``reach_mm``
    (laterally, from A's last point) are searched for the first run B of at least
    ``min_run`` points such that A's last and B's first ``w`` points (``w`` = 2 ``min_run``,
    fewer when a run is shorter) run the same way as the line through both (within 15 deg)
    and fit it within ``1.5 tol``: the surface goes on from A to B. Every run between them
    with a point more than ``2 tol`` off that line (and none of them as long as A or B) is a
    detour. A run that lies on the line (a fragment of the surface) is kept.
    """
    k = starts.shape[0]
    out = np.zeros(k, dtype=np.bool_)
    for a in range(k):
        na = ends[a] - starts[a]
        if na < min_run:
            continue
        ya = p[ends[a] - 1, 0]
        longest = 0
        for b in range(a + 1, k):
            if abs(p[starts[b], 0] - ya) > reach_mm:
                break
            nb = ends[b] - starts[b]
            if nb >= min_run and b > a + 1 and longest < min(na, nb):
                w = 2 * min_run
                lo, hi = max(starts[a], ends[a] - w), ends[a]
                lo2, hi2 = starts[b], min(ends[b], starts[b] + w)
                # Both ends run the same way (within 15 deg) and fit one line.
                _, _, ay, az = _tls(p, lo, hi, lo, lo)
                _, _, by, bz = _tls(p, lo2, hi2, lo2, lo2)
                cy, cz, uy, uz = _tls(p, lo, hi, lo2, hi2)
                same = min(abs(ay * by + az * bz), abs(ay * uy + az * uz), abs(by * uy + bz * uz))
                worst = 0.0 if same >= _COS_15 else np.inf
                for r in ((lo, hi), (lo2, hi2)):
                    for i in range(r[0], r[1]):
                        worst = max(worst, abs((p[i, 0] - cy) * -uz + (p[i, 1] - cz) * uy))
                if worst <= 1.5 * tol:
                    for c in range(a + 1, b):
                        for i in range(starts[c], ends[c]):
                            if abs((p[i, 0] - cy) * -uz + (p[i, 1] - cz) * uy) > 2.0 * tol:
                                out[c] = True
                                break
                    break
            longest = max(longest, nb)
    return out


def _median5(z: FloatArray) -> FloatArray:
    """Running median of 5 (edges: the nearest full window), by a min/max network."""
    if len(z) < 5:
        return np.full_like(z, np.median(z))
    a, b, c, d, e = z[:-4], z[1:-3], z[2:-2], z[3:-1], z[4:]
    f = np.maximum(np.minimum(a, b), np.minimum(c, d))
    g = np.minimum(np.maximum(a, b), np.maximum(c, d))
    med = np.maximum(np.minimum(e, f), np.minimum(np.maximum(e, f), g))
    return np.concatenate([np.full(2, med[0]), med, np.full(2, med[-1])])


def kept_points(profile: Profile) -> FloatArray:
    """(m, 2) valid, finite, bounded points of a profile, in column order."""
    return _kept(profile)[0]


def _kept(profile: Profile) -> tuple[FloatArray, NDArray[np.intp]]:
    pts = np.asarray(profile.points_laser, dtype=np.float64).reshape(-1, 2)
    valid = np.asarray(profile.valid, dtype=bool).reshape(-1)
    if valid.shape != (len(pts),):
        return np.empty((0, 2)), np.empty(0, dtype=np.intp)
    a = np.abs(pts)
    columns = np.flatnonzero(valid & (a[:, 0] < _MAX_ABS_MM) & (a[:, 1] < _MAX_ABS_MM))
    return pts[columns], columns  # NaN fails the bounds too


def _median(x: FloatArray) -> float:
    """Upper median, without ``np.median``'s overhead (0 for an empty array).

    A full sort, not ``np.partition``: on quantized profiles most values repeat (second
    differences are mostly 0 or one pixel step), and introselect then takes ~70 us for 1000
    values where the sort takes 7 us.
    """
    n = len(x)
    return float(np.sort(x)[n // 2]) if n else 0.0


def _spacing(points: FloatArray) -> float:
    """Typical distance between neighbouring columns (mm): the median lateral step, which
    range noise does not inflate (the median absolute step when the profile is vertical)."""
    d = np.abs(np.diff(points, axis=0))
    lateral = _median(d[:, 0])
    return lateral if lateral > 0 else _median(np.hypot(d[:, 0], d[:, 1]))


def noise_sigma(points: FloatArray, lags: tuple[int, ...] = (1,)) -> float:
    """Robust noise estimate (mm) in range z_L, where a triangulation sensor's noise lies:
    1.4826 median |second difference of z_L| / sqrt(6). On lines sampled at even spacing the
    second differences are noise only; corners and jumps are few.

    With several ``lags`` (second differences of points ``lag`` apart; the first is the
    estimate of white noise), the largest estimate when it exceeds the first one by half: a
    sensor that smooths its profile (or a rippled surface) hides its scatter from
    neighbouring points, and quantized ranges show none between neighbours that round alike.
    """
    z = points[:, 1]
    estimates = [
        _SIGMA_FROM_SECOND_DIFF * _median(np.abs(z[2 * k :] - 2.0 * z[k:-k] + z[: -2 * k]))
        for k in lags
        if len(z) > 2 * k
    ]
    if not estimates:
        return 0.0
    return estimates[0] if max(estimates) <= 1.5 * estimates[0] else max(estimates)


#: Lags of the noise estimate (:func:`noise_sigma`).
NOISE_LAGS = (1, 2, 4, 8)


@dataclass
class FrontEnd:
    """The scale and the clean-up of a profile, before any line is fitted (:func:`front_end`).

    ``points`` are the kept points (valid, bounded, isolated spikes removed) in column order,
    ``columns`` their columns in the profile, ``spike_columns`` the columns of the removed
    spikes; ``runs`` are the bounds of the runs between jumps (``points[runs[k]:runs[k + 1]]``)
    and ``stray`` marks the points of detours (:func:`seamtrack.features.robust.detours`).
    """

    points: FloatArray
    columns: NDArray[np.intp]
    spike_columns: NDArray[np.intp]
    runs: NDArray[np.intp]
    stray: NDArray[np.bool_]
    sigma: float
    tol: float
    floor: float
    spacing: float
    quantum: float
    resolution: float


@numba.njit(cache=True, nogil=True)
def _select(x: FloatArray, k: int) -> float:
    """The k-th smallest of ``x`` (``np.sort(x)[k]``) by quickselect with a three-way
    partition, in place: O(n) also when most values repeat (quantized ranges)."""
    lo, hi = 0, x.shape[0] - 1
    while lo < hi:
        a, b, c = x[lo], x[(lo + hi) // 2], x[hi]
        pivot = max(min(a, b), min(max(a, b), c))
        lt, i, gt = lo, lo, hi
        while i <= gt:
            v = x[i]
            if v < pivot:
                x[i], x[lt] = x[lt], v
                lt += 1
                i += 1
            elif v > pivot:
                x[i], x[gt] = x[gt], v
                gt -= 1
            else:
                i += 1
        if k < lt:
            hi = lt - 1
        elif k > gt:
            lo = gt + 1
        else:
            return pivot
    return x[lo]


@numba.njit(cache=True, nogil=True)
def _upper_median(x: FloatArray) -> float:
    """``np.sort(x)[len(x) // 2]`` (0 for an empty array); ``x`` is reordered.

    A sample of ~100 values brackets the median (Floyd and Rivest's idea); one branch-free
    pass counts the values below the bracket and copies those inside, and the median is
    selected among those few (else, rarely, among all). Quickselect alone on ~1,000 fresh
    values is mostly mispredicted branches."""
    n = x.shape[0]
    if n == 0:
        return 0.0
    k = n // 2
    if n < 256:
        return _select(x, k)
    s = 99
    sample = np.empty(s)
    for i in range(s):
        sample[i] = x[((2 * i + 1) * n) // (2 * s)]
    sample.sort()
    r = (k * s) // n
    lo_v = sample[max(r - 12, 0)]
    hi_v = sample[min(r + 12, s - 1)]
    band = np.empty(n)
    below = 0
    j = 0
    for i in range(n):
        v = x[i]
        below += v < lo_v
        band[j] = v
        j += (v >= lo_v) & (v <= hi_v)
    if below <= k < below + j:
        return _select(band[:j], k - below)
    return _select(x, k)


@numba.njit(cache=True, nogil=True)
def _noise(z: FloatArray, lags: IntArray) -> float:
    """1.4826 / sqrt(6) median |second difference| at each lag that fits; the first lag's
    estimate unless a later one exceeds it by half (then the largest)."""
    n = z.shape[0]
    first = -1.0
    best = -1.0
    for j in range(lags.shape[0]):
        k = lags[j]
        if n <= 2 * k:
            continue
        d = np.empty(n - 2 * k)
        for i in range(n - 2 * k):
            d[i] = abs(z[i + 2 * k] - 2.0 * z[i + k] + z[i])
        e = _SIGMA_FROM_SECOND_DIFF * _upper_median(d)
        if first < 0.0:
            first = e
        best = max(best, e)
    if first < 0.0:
        return 0.0
    return first if best <= 1.5 * first else best


@numba.njit(cache=True, nogil=True)
def front(
    points: FloatArray,
    valid: NDArray[np.bool_],
    max_abs: float,
    min_points: int,
    resolution_mm: float,
    min_tol_mm: float,
    sigma_factor: float,
    max_detour_mm: float,
    default_resolution: float,
    tol_resolutions: float,
) -> tuple[
    int,
    FloatArray,
    IntArray,
    IntArray,
    IntArray,
    NDArray[np.bool_],
    FloatArray,
]:
    """The front end of :func:`seamtrack.features.robust.front_end` in one pass.

    ``resolution_mm`` 0: not given (read from the data); ``min_tol_mm`` NaN: not given.

    Returns
    -------
    code : int
        0 ok; 1 too few valid points (``len(p)`` of the kept points); 2 constant profile.
    p : (m, 2) kept points (spikes removed)
    columns, spike_columns : their columns, the removed spikes' columns
    runs : bounds of the runs between jumps
    stray : (m,) points of detours
    scalars : (sigma, tol, floor, spacing, quantum, resolution)
    """
    n = points.shape[0]
    m = 0
    for i in range(n):
        if valid[i] and abs(points[i, 0]) < max_abs and abs(points[i, 1]) < max_abs:
            m += 1
    p = np.empty((m, 2))
    cols = np.empty(m, dtype=np.int64)
    j = 0
    for i in range(n):
        if valid[i] and abs(points[i, 0]) < max_abs and abs(points[i, 1]) < max_abs:
            p[j, 0] = points[i, 0]
            p[j, 1] = points[i, 1]
            cols[j] = i
            j += 1
    empty_i = np.empty(0, dtype=np.int64)
    scalars = np.zeros(6)
    if m < 2 * min_points:
        return 1, p, cols, empty_i, empty_i, np.zeros(m, dtype=np.bool_), scalars
    if m < 2:
        return 2, p, cols, empty_i, empty_i, np.zeros(m, dtype=np.bool_), scalars
    d = np.empty(m - 1)
    for i in range(m - 1):
        d[i] = abs(p[i + 1, 0] - p[i, 0])
    spacing = _upper_median(d)
    if not spacing > 0.0:
        for i in range(m - 1):
            d[i] = math.hypot(p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1])
        spacing = _upper_median(d)
    if not spacing > 0.0:
        return 2, p, cols, empty_i, empty_i, np.zeros(m, dtype=np.bool_), scalars
    z = np.ascontiguousarray(p[:, 1])
    q = range_quantum(z)
    if resolution_mm != 0.0:
        resolution = resolution_mm
    elif q > 0.0:
        resolution = q
    else:
        resolution = default_resolution
    floor = tol_resolutions * resolution if math.isnan(min_tol_mm) else min_tol_mm
    rounding = q / math.sqrt(12.0)
    one = np.ones(1, dtype=np.int64)
    sigma = max(_noise(z, one), rounding)
    # Isolated outliers against a running median of 5 (edges: the nearest full window).
    med = np.empty(m)
    if m < 5:
        med[:] = np.median(z)
    else:
        for i in range(m - 4):
            a, b, c, dd, e = z[i], z[i + 1], z[i + 2], z[i + 3], z[i + 4]
            f = max(min(a, b), min(c, dd))
            g = min(max(a, b), max(c, dd))
            med[i + 2] = max(min(e, f), min(max(e, f), g))
        med[0] = med[1] = med[2]
        med[m - 1] = med[m - 2] = med[m - 3]
    limit = max(6.0 * sigma, 4.0 * floor, 4.0 * spacing)
    keep = np.empty(m, dtype=np.bool_)
    kept = 0
    for i in range(m):
        keep[i] = abs(z[i] - med[i]) <= limit
        if keep[i]:
            kept += 1
    p2 = np.empty((kept, 2))
    cols2 = np.empty(kept, dtype=np.int64)
    spikes = np.empty(m - kept, dtype=np.int64)
    j = 0
    s = 0
    for i in range(m):
        if keep[i]:
            p2[j, 0] = p[i, 0]
            p2[j, 1] = p[i, 1]
            cols2[j] = cols[i]
            j += 1
        else:
            spikes[s] = cols[i]
            s += 1
    lags = np.array([1, 2, 4, 8], dtype=np.int64)
    sigma = max(_noise(np.ascontiguousarray(p2[:, 1]), lags), rounding)
    tol = max(floor, sigma_factor * sigma)
    jump = max(6.0 * spacing, 2.0 * tol, 0.1)
    jump2 = jump * jump
    cut = np.empty(max(kept - 1, 0), dtype=np.bool_)
    ncut = 0
    for i in range(kept - 1):
        dy, dz = p2[i + 1, 0] - p2[i, 0], p2[i + 1, 1] - p2[i, 1]
        cut[i] = dy * dy + dz * dz > jump2
        if cut[i]:
            ncut += 1
    runs = np.empty(ncut + 2, dtype=np.int64)
    runs[0] = 0
    r = 1
    for i in range(kept - 1):
        if cut[i]:
            runs[r] = i + 1
            r += 1
    runs[r] = kept
    off = detours(p2, runs[:-1], runs[1:], tol, min_points, max_detour_mm)
    stray = np.zeros(kept, dtype=np.bool_)
    for k in range(runs.shape[0] - 1):
        if off[k]:
            stray[runs[k] : runs[k + 1]] = True
    scalars[0] = sigma
    scalars[1] = tol
    scalars[2] = floor
    scalars[3] = spacing
    scalars[4] = q
    scalars[5] = resolution
    return 0, p2, cols2, spikes, runs, stray, scalars


def front_end(
    profile: Profile,
    *,
    min_tol_mm: float | None = None,
    resolution_mm: float | None = None,
    sigma_factor: float = 5.0,
    min_points: int = 8,
    max_detour_mm: float = 3.0,
) -> FrontEnd | str:
    """Kept points, noise, tolerance, runs between jumps and detours of a profile, or why
    there are none (a ``str``); the parameters as for :func:`segment_profile`.

    One compiled pass (:func:`front`): the valid bounded points,
    their spacing (:func:`_spacing`) and range quantum (:func:`range_quantum`), the noise at
    lag 1 (:func:`noise_sigma`), isolated spikes off a running median of 5 (:func:`_median5`)
    dropped, the noise again over :data:`NOISE_LAGS`, the runs between jumps and their
    detours (:func:`detours`).
    """
    pts = np.ascontiguousarray(profile.points_laser, dtype=np.float64).reshape(-1, 2)
    valid = np.ascontiguousarray(profile.valid, dtype=np.bool_).reshape(-1)
    if valid.shape != (len(pts),):
        return "too few valid points (0)"
    code, p, columns, spikes, runs, stray, s = front(
        pts,
        valid,
        _MAX_ABS_MM,
        int(min_points),
        float(resolution_mm) if resolution_mm else 0.0,
        math.nan if min_tol_mm is None else float(min_tol_mm),
        float(sigma_factor),
        float(max_detour_mm),
        DEFAULT_RESOLUTION_MM,
        TOL_RESOLUTIONS,
    )
    if code == 1:
        return f"too few valid points ({len(p)})"
    if code == 2:
        return "the valid points do not spread out (constant profile)"
    sigma, tol, floor, spacing, q, resolution = (float(v) for v in s)
    return FrontEnd(p, columns, spikes, runs, stray, sigma, tol, floor, spacing, q, resolution)


def reject(
    profile: Profile,
    *,
    min_tol_mm: float | None = None,
    resolution_mm: float | None = None,
    min_points: int = 8,
    max_detour_mm: float = 3.0,
) -> Profile:
    """The profile with the points the extractors' front end leaves out made invalid, with their
    reason: :attr:`Reason.SPIKE` (isolated, off a running median of 5) or
    :attr:`Reason.REFLECTION` (a run off the line on which the surface continues across it).
    Other points and reasons are unchanged; the parameters as for :func:`front_end`."""
    assert profile.reason is not None
    reason = profile.reason.copy()
    fe = front_end(
        profile,
        min_tol_mm=min_tol_mm,
        resolution_mm=resolution_mm,
        min_points=min_points,
        max_detour_mm=max_detour_mm,
    )
    if not isinstance(fe, str):
        reason[fe.spike_columns] = Reason.SPIKE
        reason[fe.columns[fe.stray]] = Reason.REFLECTION
    points = profile.points_laser.copy()
    points[reason != Reason.VALID] = np.nan
    return Profile(
        points,
        valid=reason == Reason.VALID,
        reason=reason,
        T_world_sensor=profile.T_world_sensor,
        t_s=profile.t_s,
    )
