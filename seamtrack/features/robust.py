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
from typing import NamedTuple, cast

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray, IndexArray
from seamtrack.features.line_geometry import fit_spans
from seamtrack.features.refusal import Refusal
from seamtrack.features.select import BUCKETS, kth_nonneg
from seamtrack.jit import KERNEL
from seamtrack.sensing.profiles import Profile, Reason

#: The front end's codes (:attr:`Front.code`): points kept; too few valid points; the valid
#: points do not spread out (a constant profile).
KEPT, TOO_FEW_POINTS, CONSTANT = 0, 1, 2


class FrontScalars(NamedTuple):
    """What :func:`robust_front` found besides the arrays it wrote: the front end's code, the
    points kept, the spikes and run bounds written, the noise (mm), the tolerance (mm), its
    floor (mm), the median spacing (mm), the range quantum (mm) and the resolution (mm)."""

    code: int
    kept: int
    n_spikes: int
    n_runs: int
    sigma: float
    tol: float
    floor: float
    spacing: float
    quantum: float
    resolution: float


class Front(NamedTuple):
    """The front end of one profile (:func:`front`): the code, the kept points (m, 2), their
    columns, the removed spikes' columns, the bounds of the runs between jumps, the points
    of detours (m,), and the noise, tolerance and the rest (:class:`FrontScalars`)."""

    code: int
    points: FloatArray
    columns: IndexArray
    spikes: IndexArray
    runs: IndexArray
    stray: NDArray[np.bool_]
    scalars: FrontScalars


#: Coordinates beyond this (mm) are not measurements: treated as invalid.
MAX_ABS_MM = 1e6
#: Range resolution assumed when neither the sensor's nor the profile's is known (mm): the
#: paper's sensor (Table 3).
DEFAULT_RESOLUTION_MM = 0.01
#: The split tolerance's floor, in range resolutions (quantization and pixel steps).
TOL_RESOLUTIONS = 3.0


_SIGMA_FROM_SECOND_DIFF = 1.4826 / math.sqrt(6.0)
_COS_15 = math.cos(math.radians(15.0))
#: Lag 1 as an int64: numba types a literal 1 as ``Literal[int](1)`` and compiles
#: :func:`_estimate` once more for it.
_LAG1 = cast(int, np.int64(1))


@numba.njit(**KERNEL)
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
    lo = z[0]
    hi = z[0]
    for i in range(1, n):
        lo = min(lo, z[i])
        hi = max(hi, z[i])
    tiny = 1e-12 * max(max(abs(lo), abs(hi)), 1.0)
    # The smallest step, branch-free over two running minima (taken in any order, a minimum
    # is the same).
    s0 = np.inf
    s1 = np.inf
    for i in range(0, n - 2, 2):
        d0 = abs(z[i + 1] - z[i])
        d1 = abs(z[i + 2] - z[i + 1])
        s0 = min(s0, d0 if d0 > tiny else np.inf)
        s1 = min(s1, d1 if d1 > tiny else np.inf)
    if n % 2 == 0:
        d0 = abs(z[n - 1] - z[n - 2])
        s0 = min(s0, d0 if d0 > tiny else np.inf)
    step = min(s0, s1)
    if not np.isfinite(step):
        return 0.0
    on, small, ones = 0, 0, 0
    slack = tiny / step
    for i in range(n - 1):
        k = abs(z[i + 1] - z[i]) / step
        r = np.rint(k)  # as round(): halves to even
        hit = abs(k - r) <= 1e-6 * max(r, 1.0) + slack
        on += hit
        small += hit & (r <= 1.0)
        ones += hit & (r == 1.0)
    if (
        on >= 0.98 * (n - 1)
        and small >= 0.2 * (n - 1)
        and ones >= max(3, 0.02 * (n - 1))
        and step <= 0.1 * (hi - lo)
    ):
        return step
    return 0.0


@numba.njit(**KERNEL)
def detours(
    p: FloatArray,
    starts: IndexArray,
    ends: IndexArray,
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
                _, _, ay, az = fit_spans(p, lo, hi, lo, lo)
                _, _, by, bz = fit_spans(p, lo2, hi2, lo2, lo2)
                cy, cz, uy, uz = fit_spans(p, lo, hi, lo2, hi2)
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
    columns = np.flatnonzero(valid & (a[:, 0] < MAX_ABS_MM) & (a[:, 1] < MAX_ABS_MM))
    return pts[columns], columns  # NaN fails the bounds too


def median_of(x: FloatArray) -> float:
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
    lateral = median_of(d[:, 0])
    return lateral if lateral > 0 else median_of(np.hypot(d[:, 0], d[:, 1]))


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
        _SIGMA_FROM_SECOND_DIFF * median_of(np.abs(z[2 * k :] - 2.0 * z[k:-k] + z[: -2 * k]))
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


@numba.njit(**KERNEL)
def _estimate(
    z: FloatArray, n: int, lag: int, d: FloatArray, work: IndexArray, hist: IndexArray
) -> float:
    """1.4826 / sqrt(6) times the upper median |second difference| of ``z[:n]`` at ``lag``
    (``n > 2 lag``)."""
    m = n - 2 * lag
    for i in range(m):
        d[i] = abs(z[i + 2 * lag] - 2.0 * z[i + lag] + z[i])
    return _SIGMA_FROM_SECOND_DIFF * kth_nonneg(d, m, m // 2, work, hist)


@numba.njit(**KERNEL)
def _noise(
    z: FloatArray, n: int, first: float, d: FloatArray, work: IndexArray, hist: IndexArray
) -> float:
    """:func:`noise_sigma` of ``z[:n]`` over :data:`NOISE_LAGS` (1, 2, 4, 8), given the
    estimate at lag 1 (``first``; ``n > 2``).

    The first estimate stands unless a later one exceeds it by half, and whether one does is
    a count: the upper median ``d[m // 2]`` of ``m`` values is at most ``x`` when at least
    ``m // 2 + 1`` of them are (the scaling is monotone), so only an estimate that exceeds it
    is taken exactly (the largest of those is the result). The lags are taken from the
    largest down, each tested against the largest estimate so far as well: on a smooth
    surface the estimates grow with the lag (curvature), so one exact median serves where
    three were taken (the same result: a maximum)."""
    limit = 1.5 * first
    best = -1.0
    for lag in (8, 4, 2):
        m = n - 2 * lag
        if m <= 0:
            continue
        bar = max(limit, best)
        within = 0
        for i in range(m):
            v = _SIGMA_FROM_SECOND_DIFF * abs(z[i + 2 * lag] - 2.0 * z[i + lag] + z[i])
            within += v <= bar
        if within < m // 2 + 1:
            best = _estimate(z, n, lag, d, work, hist)  # above bar: the largest so far
    return first if best < 0.0 else best


class FrontParams(NamedTuple):
    """The front end's settings (a numba-supported named tuple: the compiled calls take it
    whole): the bound on coordinates (mm), the fewest points of a piece, the range resolution
    (mm; 0: not given, read from the data), the tolerance's floor (mm; NaN: not given), the
    tolerance in noise sigmas, the longest detour (mm), the resolution when none is known (mm)
    and the floor in resolutions."""

    max_abs: float
    min_points: int
    resolution_mm: float
    min_tol_mm: float
    sigma_factor: float
    max_detour_mm: float
    default_resolution: float
    tol_resolutions: float


def front_params(
    min_points: int,
    resolution_mm: float | None,
    min_tol_mm: float | None,
    sigma_factor: float,
    max_detour_mm: float,
) -> FrontParams:
    """The :class:`FrontParams` of the extractors' keyword arguments (``None``: not given),
    with :data:`MAX_ABS_MM`, :data:`DEFAULT_RESOLUTION_MM` and :data:`TOL_RESOLUTIONS`."""
    return FrontParams(
        MAX_ABS_MM,
        int(min_points),
        float(resolution_mm) if resolution_mm else 0.0,
        math.nan if min_tol_mm is None else float(min_tol_mm),
        float(sigma_factor),
        float(max_detour_mm),
        DEFAULT_RESOLUTION_MM,
        TOL_RESOLUTIONS,
    )


@numba.njit(**KERNEL)
def _bounded_points(
    points: FloatArray, valid: NDArray[np.bool_], max_abs: float, p: FloatArray, z: FloatArray,
    cols: IndexArray,
) -> int:  # fmt: skip
    """Writes the valid points within ``max_abs`` to the front of ``p``, their ranges to ``z``
    and their columns to ``cols``; returns how many there are."""
    m = 0
    for i in range(points.shape[0]):
        y0, z0 = points[i, 0], points[i, 1]
        p[m, 0], p[m, 1], z[m], cols[m] = y0, z0, z0, i
        m += valid[i] & (abs(y0) < max_abs) & (abs(z0) < max_abs)
    return m


@numba.njit(**KERNEL)
def _column_spacing(
    p: FloatArray, m: int, d: FloatArray, work: IndexArray, hist: IndexArray
) -> float:
    """:func:`_spacing` of ``p[:m]`` (``m >= 2``): the median lateral step, else the median
    step length (0: the points do not spread out)."""
    for i in range(m - 1):
        d[i] = abs(p[i + 1, 0] - p[i, 0])
    spacing = kth_nonneg(d, m - 1, (m - 1) // 2, work, hist)
    if not spacing > 0.0:
        for i in range(m - 1):
            d[i] = math.hypot(p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1])
        spacing = kth_nonneg(d, m - 1, (m - 1) // 2, work, hist)
    return spacing


@numba.njit(**KERNEL)
def _resolution(params: FrontParams, quantum: float) -> float:
    """The range resolution: the given one, else the range quantum, else the default."""
    if params.resolution_mm != 0.0:
        return params.resolution_mm
    if quantum > 0.0:
        return quantum
    return params.default_resolution


@numba.njit(**KERNEL)
def median5_of(z: FloatArray, m: int) -> FloatArray:
    """:func:`_median5` of ``z[:m]``: the running median of 5 (edges: the nearest full
    window) by a min/max network."""
    med = np.empty(m)
    if m < 5:
        med[:] = np.median(z[:m])
        return med
    for i in range(m - 4):
        a, b, c, dd, e = z[i], z[i + 1], z[i + 2], z[i + 3], z[i + 4]
        f = max(min(a, b), min(c, dd))
        g = min(max(a, b), max(c, dd))
        med[i + 2] = max(min(e, f), min(max(e, f), g))
    for k in range(2):  # the edges: the nearest full window's
        med[k] = med[2]
        med[m - 1 - k] = med[m - 3]
    return med


class SpikeSplit(NamedTuple):
    """:func:`_drop_spikes`' counts: the points kept at the front, the spikes' columns."""

    kept: int
    spikes: int


@numba.njit(**KERNEL)
def _drop_spikes(
    p: FloatArray, z: FloatArray, cols: IndexArray, m: int, limit: float, spikes: IndexArray
) -> SpikeSplit:
    """Moves the points of ``p[:m]`` (and ``z``, ``cols``) within ``limit`` of their running
    median of 5 to the front, the others' columns to ``spikes``; returns (kept, spikes)."""
    med = median5_of(z, m)
    kept = 0
    ns = 0
    for i in range(m):
        if abs(z[i] - med[i]) <= limit:
            p[kept, 0], p[kept, 1], z[kept], cols[kept] = p[i, 0], p[i, 1], z[i], cols[i]
            kept += 1
        else:
            spikes[ns] = cols[i]
            ns += 1
    return SpikeSplit(kept, ns)


@numba.njit(**KERNEL)
def _jump_runs(p: FloatArray, kept: int, jump: float, runs: IndexArray) -> int:
    """Writes the bounds of the runs of ``p[:kept]`` between steps longer than ``jump`` to
    ``runs`` (0 first, ``kept`` last); returns the number of runs."""
    jump2 = jump * jump
    runs[0] = 0
    r = 1
    for i in range(kept - 1):
        dy, dz = p[i + 1, 0] - p[i, 0], p[i + 1, 1] - p[i, 1]
        if dy * dy + dz * dz > jump2:
            runs[r] = i + 1
            r += 1
    runs[r] = kept
    return r


class FrontOut(NamedTuple):
    """Where :func:`robust_front` writes, for n profile points: the kept points ``p``
    (n, 2), their columns ``cols`` (n,), the removed spikes' columns ``spikes`` (n,), the
    bounds of the runs between jumps ``runs`` (n + 1,) and the points of detours ``stray``
    (n,)."""

    p: FloatArray
    cols: IndexArray
    spikes: IndexArray
    runs: IndexArray
    stray: NDArray[np.bool_]


@numba.njit(**KERNEL)
def robust_front(
    points: FloatArray, valid: NDArray[np.bool_], params: FrontParams, out: FrontOut
) -> FrontScalars:
    """:func:`front` into the given arrays ``out``.

    Returns a :class:`FrontScalars`: ``kept`` points (before spikes are removed when
    ``code`` is not :data:`KEPT`), the counts of spikes and run bounds written, and the
    noise, tolerance, its floor, the spacing, the range quantum and the resolution."""
    p, cols, spikes, runs, stray = out
    z = np.empty(points.shape[0])
    m = _bounded_points(points, valid, params.max_abs, p, z, cols)
    if m < 2 * params.min_points:
        return FrontScalars(TOO_FEW_POINTS, m, 0, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    if m < 2:
        return FrontScalars(CONSTANT, m, 0, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    d = np.empty(m)
    work = np.empty(m, dtype=np.int64)
    hist = np.empty(2 * BUCKETS, dtype=np.int64)
    spacing = _column_spacing(p, m, d, work, hist)
    if not spacing > 0.0:
        return FrontScalars(CONSTANT, m, 0, 0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    q = range_quantum(z[:m])
    resolution = _resolution(params, q)
    floor = (
        params.tol_resolutions * resolution if math.isnan(params.min_tol_mm) else params.min_tol_mm
    )
    rounding = q / math.sqrt(12.0)
    first = _estimate(z, m, _LAG1, d, work, hist) if m > 2 else 0.0
    # Isolated outliers against a running median of 5 (edges: the nearest full window).
    limit = max(6.0 * max(first, rounding), 4.0 * floor, 4.0 * spacing)
    kept, ns = _drop_spikes(p, z, cols, m, limit, spikes)
    # Without spikes the lag-1 differences are those already counted.
    sigma = 0.0
    if kept > 2:
        if ns > 0:
            first = _estimate(z, kept, _LAG1, d, work, hist)
        sigma = _noise(z, kept, first, d, work, hist)
    sigma = max(sigma, rounding)
    tol = max(floor, params.sigma_factor * sigma)
    r = _jump_runs(p, kept, max(6.0 * spacing, 2.0 * tol, 0.1), runs)
    off = detours(p[:kept], runs[:r], runs[1 : r + 1], tol, params.min_points, params.max_detour_mm)
    stray[:kept] = False
    for k in range(r):
        if off[k]:
            stray[runs[k] : runs[k + 1]] = True
    return FrontScalars(KEPT, kept, ns, r + 1, sigma, tol, floor, spacing, q, resolution)


@numba.njit(**KERNEL)
def front(points: FloatArray, valid: NDArray[np.bool_], params: FrontParams) -> Front:
    """The front end of :func:`seamtrack.features.robust.front_end` in one pass, with the
    settings ``params`` (:class:`FrontParams`).

    Returns a :class:`Front`: ``code`` :data:`KEPT`, :data:`TOO_FEW_POINTS` (``len(points)``
    of them) or :data:`CONSTANT`; the kept points (spikes removed), their columns, the removed
    spikes' columns, the bounds of the runs between jumps, the points of detours, and
    ``scalars``: noise, tolerance, its floor, spacing, range quantum and resolution.
    """
    n = points.shape[0]
    p = np.empty((n, 2))
    cols = np.empty(n, dtype=np.int64)
    spikes = np.empty(n, dtype=np.int64)
    runs = np.empty(n + 1, dtype=np.int64)
    stray = np.zeros(n, dtype=np.bool_)
    f = robust_front(points, valid, params, FrontOut(p, cols, spikes, runs, stray))
    m = f.kept
    return Front(f.code, p[:m], cols[:m], spikes[: f.n_spikes], runs[: f.n_runs], stray[:m], f)


def profile_arrays(profile: Profile) -> tuple[FloatArray, NDArray[np.bool_]] | Refusal:
    """A profile's points (n, 2) and valid flags (n,) as the compiled front end takes them
    (contiguous), or a refusal when the flags do not match the points."""
    pts = np.ascontiguousarray(profile.points_laser, dtype=np.float64).reshape(-1, 2)
    valid = np.ascontiguousarray(profile.valid, dtype=np.bool_).reshape(-1)
    if valid.shape != (len(pts),):
        return Refusal("too few valid points (0)")
    return pts, valid


def front_end(
    profile: Profile,
    *,
    min_tol_mm: float | None = None,
    resolution_mm: float | None = None,
    sigma_factor: float = 5.0,
    min_points: int = 8,
    max_detour_mm: float = 3.0,
) -> FrontEnd | Refusal:
    """Kept points, noise, tolerance, runs between jumps and detours of a profile, or why
    there are none (a :class:`~seamtrack.features.refusal.Refusal`); the parameters as for
    :func:`segment_profile`.

    One compiled pass (:func:`front`): the valid bounded points,
    their spacing (:func:`_spacing`; medians by :func:`seamtrack.features.select.kth_nonneg`)
    and range quantum (:func:`range_quantum`), the noise at
    lag 1 (:func:`noise_sigma`), isolated spikes off a running median of 5 (:func:`_median5`)
    dropped, the noise again over :data:`NOISE_LAGS`, the runs between jumps and their
    detours (:func:`detours`).
    """
    arrays = profile_arrays(profile)
    if isinstance(arrays, Refusal):
        return arrays
    pts, valid = arrays
    params = front_params(min_points, resolution_mm, min_tol_mm, sigma_factor, max_detour_mm)
    fr = front(pts, valid, params)
    if fr.code == TOO_FEW_POINTS:
        return Refusal(f"too few valid points ({len(fr.points)})")
    if fr.code == CONSTANT:
        return Refusal("the valid points do not spread out (constant profile)")
    s = fr.scalars
    return FrontEnd(
        *(fr.points, fr.columns, fr.spikes, fr.runs, fr.stray),
        *(float(v) for v in (s.sigma, s.tol, s.floor, s.spacing, s.quantum, s.resolution)),
    )


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
    if not isinstance(fe, Refusal):
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
