"""Peak detectors: the sub-pixel row of the laser stripe in each image column, as a sensor's
firmware finds it.

A column's candidates are its runs of pixels above a threshold (a peak each). The default
threshold is each column's own (:func:`column_thresholds`): the background plus
max(NOISE_SIGMAS * the noise sigma, RELATIVE_THRESHOLD * the column's peak above it), so a dim
stripe (a matte plate at grazing incidence) is found as well as a bright one, and a column of
noise alone has none; an absolute threshold (a fraction of full scale) may be given instead.
One is chosen per column (the brightest, the first along the range, or the widest) and located
to a fraction of a pixel by

- ``centroid``: the centroid of (I - threshold) over the run;
- ``gaussian``: the 3-point Gaussian fit on the brightest pixel and its neighbours,
  delta = (ln I[-1] - ln I[+1]) / (2 (ln I[-1] - 2 ln I[0] + ln I[+1])) (falls back to the
  centroid on a saturated plateau or at the image edge);
- ``steger``: Steger's curvilinear line detector (IEEE PAMI 20(2), 1998): Gaussian-smoothed
  derivatives; at the run's brightest smoothed pixel, the Hessian's eigenvector of the most
  negative eigenvalue is the line's normal n (a line is there only where that eigenvalue is
  negative); the centre is the zero of the first derivative, taken *along the column* and
  averaged *along the line* (over columns c + s at rows shifted by the line's slope s, with
  Steger's Gaussian weights), located on the cubic through four rows. Along the column because
  the laser sheet's thickness images onto the chip's rows, so each column's profile is
  symmetric about the centre while the profile across n is not once the brightness changes
  along a slanted line; averaged along the line, not smoothed across the columns, because
  that smoothing shifts a slanted line's centre where the brightness changes (the two together
  put Steger's centre 0.03 px off at 30 deg of tilt and 0.14 px at 70 deg on the paper's
  chip, issue 43). A line within 17 deg of the column keeps Steger's point p + t n,
  t = -(g . n) / (n^T H n).

Rows are centre-based: row i's centre is i (as :attr:`StripeImage.truth_row`).

Blob and streak rejection (:class:`Rejection`, issue 38): before a column's peak is chosen, a
candidate run is dropped when it is not shaped like the laser stripe's cross-section, a narrow
near-Gaussian whose width the optics set. The frame measures its own stripe: the median, over
the columns, of the strongest run's *equivalent width* (its area above the background over its
height; sigma sqrt(2 pi) for a Gaussian, whatever the threshold cuts it at) and of its height.
A run wider than ``max_width`` times that (the arc's glow, a blob, a spatter streak running
along the column, a saturated plateau), brighter than ``max_peak`` times that (the arc seen
directly, a reflection of it) or dimmer than ``min_peak`` times that (a glow's fringe where the
stripe is hidden) is not the stripe. The stripe crosses nearly every column and spatter a few,
so both medians are the stripe's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import NDArray
from scipy import ndimage

from seamtrack.jit import KERNEL

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

METHODS = ("centroid", "gaussian", "steger")
CHOICES = ("strongest", "first", "widest")
#: The default threshold's share of each column's peak (above the background): half maximum.
RELATIVE_THRESHOLD = 0.5
#: ... and its floor in noise sigmas (the image's robust sigma): no false peak in a dark column.
NOISE_SIGMAS = 6.0


#: What :func:`detect` may reject: nothing, or runs not shaped like the stripe (:class:`Rejection`).
REJECTS = ("none", "blobs")


@dataclass(frozen=True)
class Rejection:
    """Bounds on a candidate run, relative to the frame's stripe (see the module docstring).

    Attributes
    ----------
    max_width : float
        Largest equivalent width, times the stripe's (> 1). 3: every stripe run of the
        v-groove-arc scene's images (18 frames, MAG spray and short-circuit at 250 and 350 A;
        speckled, on the walls and the plate) lies within 2.6 times the median; a Gaussian
        blob 3 times the stripe's sigma does not.
    max_peak : float
        Largest height, times the stripe's (> 1). 20: the speckled stripe's brightest run
        reaches 8.6 times the median on those images; twice that is the margin.
    min_peak : float
        Smallest height, times the stripe's (0: none).
    stripe_width_px : float, optional
        The stripe's equivalent width in pixels (from the optics: sigma sqrt(2 pi), sigma the
        line's image across the rows); default (None) the frame's own median.
    """

    max_width: float = 3.0
    max_peak: float = 20.0
    min_peak: float = 0.0
    stripe_width_px: float | None = None

    def __post_init__(self) -> None:
        checks = (("max_width", self.max_width, 1.0), ("max_peak", self.max_peak, 1.0))
        for name, value, low in checks:
            if not (math.isfinite(value) and value > low):
                raise ValueError(f"{name} must be > {low:g}, got {value}")
        if not (math.isfinite(self.min_peak) and 0 <= self.min_peak < 1):
            raise ValueError(f"min_peak must be in [0, 1), got {self.min_peak}")
        w = self.stripe_width_px
        if w is not None and not (math.isfinite(w) and w > 0):
            raise ValueError(f"stripe_width_px must be > 0, got {w}")


@dataclass(frozen=True, eq=False)
class Peaks:
    """Every run of pixels above the threshold, column by column (rows increasing).

    Attributes
    ----------
    column, start, stop : (k,) int
        The run covers rows [start, stop) of that column.
    peak : (k,) float
        Its largest pixel value.
    argmax : (k,) int
        The row of that pixel.
    centroid : (k,) float
        Centroid of (I - threshold) over the run.
    """

    column: IntArray
    start: IntArray
    stop: IntArray
    peak: FloatArray
    argmax: IntArray
    centroid: FloatArray

    def __len__(self) -> int:
        return len(self.column)

    @property
    def width(self) -> IntArray:
        return self.stop - self.start

    def subset(self, keep: NDArray[np.bool_]) -> Peaks:
        """The runs where ``keep`` (k,) is True, in the same order."""
        return Peaks(self.column[keep], self.start[keep], self.stop[keep], self.peak[keep],
                     self.argmax[keep], self.centroid[keep])  # fmt: skip


@numba.njit(**KERNEL)
def _runs(image_t: NDArray[np.float32], thresholds: FloatArray) -> tuple[
    IntArray, IntArray, IntArray, FloatArray, IntArray, FloatArray
]:  # fmt: skip
    """Runs above the threshold of a (columns, rows) image: two passes, count then fill."""
    n_cols, n_rows = image_t.shape
    count = 0
    for c in range(n_cols):
        inside = False
        threshold = thresholds[c]
        for r in range(n_rows):
            above = image_t[c, r] > threshold
            if above and not inside:
                count += 1
            inside = above
    column = np.empty(count, dtype=np.int64)
    start = np.empty(count, dtype=np.int64)
    stop = np.empty(count, dtype=np.int64)
    peak = np.empty(count)
    argmax = np.empty(count, dtype=np.int64)
    centroid = np.empty(count)
    k = -1
    for c in range(n_cols):
        inside = False
        total = 0.0
        moment = 0.0
        threshold = thresholds[c]
        for r in range(n_rows + 1):
            value = image_t[c, r] - threshold if r < n_rows else 0.0
            if value > 0:
                if not inside:
                    k += 1
                    column[k] = c
                    start[k] = r
                    peak[k] = -1.0
                    total = 0.0
                    moment = 0.0
                    inside = True
                total += value
                moment += value * r
                if value + threshold > peak[k]:
                    peak[k] = value + threshold
                    argmax[k] = r
            elif inside:
                stop[k] = r
                centroid[k] = moment / total
                inside = False
    return column, start, stop, peak, argmax, centroid


@numba.njit(**KERNEL)
def _run_sums(
    image: NDArray[np.float32], column: IntArray, start: IntArray, stop: IntArray
) -> FloatArray:
    """The sum of each run's pixels of a (rows, columns) image."""
    out = np.zeros(len(column))
    for k in range(len(column)):
        total = 0.0
        for r in range(start[k], stop[k]):
            total += image[r, column[k]]
        out[k] = total
    return out


def find_peaks(pixels: NDArray[np.floating], threshold: float | FloatArray) -> Peaks:
    """All candidate peaks of an image (rows, columns); ``threshold`` in pixel units, one for
    the image or one per column."""
    image_t = np.ascontiguousarray(np.asarray(pixels, dtype=np.float32).T)
    levels = np.broadcast_to(np.asarray(threshold, dtype=np.float64), image_t.shape[:1])
    return Peaks(*_runs(image_t, np.ascontiguousarray(levels)))


def column_thresholds(
    pixels: NDArray[np.floating],
    relative: float = RELATIVE_THRESHOLD,
    noise_sigmas: float = NOISE_SIGMAS,
) -> FloatArray:
    """Each column's threshold: background + max(noise_sigmas * sigma, relative * (column peak
    - background)). The background is the image's median and sigma its robust spread (1.4826
    times the median absolute deviation): the stripe covers a few rows of each column, so both
    are the dark pixels'. A column whose peak is within the noise floor gets none above it."""
    image = np.asarray(pixels, dtype=np.float32)
    if image.size == 0:
        return np.zeros(image.shape[1] if image.ndim == 2 else 0)
    background = float(np.median(image))
    sigma = 1.4826 * float(np.median(np.abs(image - np.float32(background))))
    peak = image.max(axis=0).astype(np.float64) - background
    return np.asarray(background + np.maximum(noise_sigmas * sigma, relative * peak))


def stripe_like(
    image: NDArray[np.floating], peaks: Peaks, rejection: Rejection
) -> NDArray[np.bool_]:
    """Which runs are shaped like the stripe, (k,) bool (see :class:`Rejection`).

    Each run's height is its peak above the background (the image's median, as
    :func:`column_thresholds`) and its equivalent width its area above the background over its
    height; the stripe's are the medians over the columns of their strongest runs."""
    keep = np.ones(len(peaks), dtype=bool)
    if len(peaks) == 0:
        return keep
    pixels = np.asarray(image, dtype=np.float32)
    # The dark pixels' level from every 4th row and column (the stripe covers a few rows of a
    # column, so the median is theirs; 1/16 of the pixels keeps it cheap).
    background = float(np.median(pixels[::4, ::4]))
    area = _run_sums(pixels, peaks.column, peaks.start, peaks.stop)
    area -= background * peaks.width
    height = np.maximum(peaks.peak - background, 1e-12)
    width = area / height
    strongest = choose_peaks(peaks, pixels.shape[1], "strongest")
    strongest = strongest[strongest >= 0]
    stripe_width = rejection.stripe_width_px or float(np.median(width[strongest]))
    stripe_height = float(np.median(height[strongest]))
    keep &= width <= rejection.max_width * stripe_width
    keep &= height <= rejection.max_peak * stripe_height
    keep &= height >= rejection.min_peak * stripe_height
    return keep


def choose_peaks(peaks: Peaks, columns: int, choose: str) -> IntArray:
    """Index of the chosen peak per column, (columns,), -1 where a column has none."""
    if choose not in CHOICES:
        raise ValueError(f"choose must be one of {CHOICES}, got {choose!r}")
    out = np.full(columns, -1, dtype=np.int64)
    if len(peaks) == 0:
        return out
    # "first" along the range is the nearest to the sensor: the largest row (x_c = +H/2 is
    # the near end); runs come in row order, so the key is the index itself.
    key = {"strongest": peaks.peak, "first": np.arange(len(peaks), dtype=float),
           "widest": peaks.width + 1e-9 * peaks.peak}[choose]  # fmt: skip
    order = np.lexsort((key, peaks.column))
    out[peaks.column[order]] = order  # the last per column (largest key) wins
    return out


def detect(
    pixels: NDArray[np.floating],
    *,
    method: str = "centroid",
    threshold: float | None = None,
    choose: str = "strongest",
    sigma_px: float | None = None,
    relative: float = RELATIVE_THRESHOLD,
    noise_sigmas: float = NOISE_SIGMAS,
    reject: Rejection | None = None,
) -> FloatArray:
    """Sub-pixel stripe row per column (see the module docstring); NaN where none.

    Parameters
    ----------
    pixels : (rows, columns) float
    method : {"centroid", "gaussian", "steger"}
    threshold : float, optional
        An absolute threshold in pixel units (a fraction of full scale for a
        :class:`StripeImage`); default (None) each column's own, :func:`column_thresholds`.
    choose : {"strongest", "first", "widest"}
        "first" is the first along the range: the peak nearest the sensor (largest row).
    sigma_px : float, optional
        Steger's smoothing scale (along the column, and the weights' scale along the line);
        default the median run width / (2 sqrt 3) (Steger's bound for a bar-shaped line), at
        least 0.8.
    relative, noise_sigmas : float
        The default threshold's share of each column's peak (0-1) and its floor in noise
        sigmas (>= 0).
    reject : Rejection, optional
        Drop the runs not shaped like the stripe before choosing (None: keep every run).

    Returns
    -------
    (columns,) float
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}, got {method!r}")
    if threshold is not None and not (math.isfinite(threshold) and threshold >= 0):
        raise ValueError(f"threshold must be >= 0, got {threshold}")
    if not (math.isfinite(relative) and 0 <= relative < 1):
        raise ValueError(f"relative must be in [0, 1), got {relative}")
    if not (math.isfinite(noise_sigmas) and noise_sigmas >= 0):
        raise ValueError(f"noise_sigmas must be >= 0, got {noise_sigmas}")
    image = np.asarray(pixels, dtype=np.float32)
    n_cols = image.shape[1]
    level = column_thresholds(image, relative, noise_sigmas) if threshold is None else threshold
    peaks = find_peaks(image, level)
    if reject is not None:
        peaks = peaks.subset(stripe_like(image, peaks, reject))
    chosen = choose_peaks(peaks, n_cols, choose)
    rows = np.full(n_cols, np.nan)
    cols = np.flatnonzero(chosen >= 0)
    k = chosen[cols]
    if method == "centroid":
        rows[cols] = peaks.centroid[k]
    elif method == "gaussian":
        rows[cols] = _gaussian(image, peaks, k, cols)
    else:
        rows[cols] = _steger(image, peaks, k, cols, sigma_px)
    return rows


def _gaussian(image: NDArray[np.float32], peaks: Peaks, k: IntArray, cols: IntArray) -> FloatArray:
    m = peaks.argmax[k]
    n_rows = image.shape[0]
    inner = (m > 0) & (m < n_rows - 1)
    below = image[np.clip(m - 1, 0, n_rows - 1), cols].astype(np.float64)
    centre = image[m, cols].astype(np.float64)
    above = image[np.clip(m + 1, 0, n_rows - 1), cols].astype(np.float64)
    tiny = 1e-6
    la, lb, lc = (np.log(np.maximum(v, tiny)) for v in (below, centre, above))
    curvature = la - 2.0 * lb + lc
    ok = inner & (curvature < 0) & (centre > below) & (centre > above)
    with np.errstate(invalid="ignore", divide="ignore"):
        delta = 0.5 * (la - lc) / np.where(ok, curvature, -1.0)
    return np.where(ok, m + delta, peaks.centroid[k])


def _steger(
    image: NDArray[np.float32], peaks: Peaks, k: IntArray, cols: IntArray, sigma_px: float | None
) -> FloatArray:
    if len(k) == 0:
        return np.empty(0)
    width = peaks.width[k]
    sigma = sigma_px if sigma_px is not None else max(0.8, float(np.median(width)) / (2 * 3**0.5))
    reach = int(math.ceil(4 * sigma)) + 1
    r0 = max(0, int(peaks.start[k].min()) - reach)
    r1 = min(image.shape[0], int(peaks.stop[k].max()) + reach)
    crop = image[r0:r1].astype(np.float64)

    def derivative(order: tuple[int, int]) -> FloatArray:
        return np.asarray(ndimage.gaussian_filter(crop, sigma, order=order, mode="nearest"))

    smooth, g_r, g_c = derivative((0, 0)), derivative((1, 0)), derivative((0, 1))
    h_rr, h_cc, h_rc = derivative((2, 0)), derivative((0, 2)), derivative((1, 1))
    # Every pixel of every chosen run, with the run it belongs to.
    run_of = np.repeat(np.arange(len(k)), width)
    first = np.repeat(peaks.start[k], width)
    offset = np.arange(len(run_of)) - np.repeat(np.cumsum(width) - width, width)
    rr = first + offset - r0
    cc = np.repeat(cols, width)
    # The line's pixel in each run: the brightest of the smoothed image (a plateau's middle).
    response = smooth[rr, cc]
    best = np.full(len(k), -np.inf)
    np.maximum.at(best, run_of, response)
    winners = np.flatnonzero(response == best[run_of])
    pick = np.full(len(k), -1, dtype=np.int64)
    pick[run_of[winners]] = winners
    p = np.maximum(pick, 0)
    pr, pc = rr[p], cc[p]
    a, b, d = h_rr[pr, pc], h_rc[pr, pc], h_cc[pr, pc]
    # Most negative eigenvalue of the Hessian [[a, b], [b, d]] and its eigenvector: the line's
    # normal n; a line is there only where the curvature across it is negative.
    half_trace, root = 0.5 * (a + d), np.sqrt(0.25 * (a - d) ** 2 + b**2)
    eig = half_trace - root
    n_r, n_c = b, eig - a  # (H - eig I) v = 0 -> v = (b, eig - a), or (eig - d, b)
    alt = np.hypot(n_r, n_c) < 1e-12 * (np.abs(a) + np.abs(d) + 1e-30)
    n_r, n_c = np.where(alt, eig - d, n_r), np.where(alt, b, n_c)
    norm = np.hypot(n_r, n_c)
    norm = np.where(norm > 0, norm, 1.0)
    n_r, n_c = n_r / norm, n_c / norm
    # A line nearly along the column (|n_r| < 0.3: within 17 deg of it) crosses the column at a
    # grazing angle: there the centre is Steger's own point p + t n, t = -(g . n) / (n^T H n).
    steep = np.abs(n_r) < 0.3
    slope = np.where(steep, 0.0, -n_c / np.where(steep, 1.0, n_r))  # rows per column
    along = np.asarray(ndimage.gaussian_filter1d(crop, sigma, axis=0, order=1, mode="nearest"))
    # The columns the line runs through whole: a run cut by the image's top or bottom edge is
    # not the line's full profile.
    whole = np.zeros(image.shape[1], dtype=bool)
    whole[cols] = (peaks.start[k] > 0) & (peaks.stop[k] < image.shape[0])
    row = _centre_in_column(along, pr, pc, slope, sigma, whole)
    curvature = n_r * n_r * a + 2 * n_r * n_c * b + n_c * n_c * d
    with np.errstate(invalid="ignore", divide="ignore"):
        t = -(n_r * g_r[pr, pc] + n_c * g_c[pr, pc]) / curvature
    row = np.where(steep, pr + t * n_r, row) + r0
    good = (pick >= 0) & (eig < 0) & np.isfinite(row) & (~steep | (np.abs(t) <= 1.0))
    return np.where(good, row, peaks.centroid[k])


#: The column's rows where the derivative is sampled, about the line's pixel.
_TAPS = np.arange(-3, 4)


def _centre_in_column(
    d_row: FloatArray,
    pr: IntArray,
    pc: IntArray,
    slope: FloatArray,
    sigma_px: float,
    whole: NDArray[np.bool_],
) -> FloatArray:
    """The row, in each pixel (pr, pc)'s own column, where the derivative along the column
    falls through zero (the ridge's top), the derivative averaged along the line.

    ``d_row`` is the image's derivative along the columns (rows smoothed at the line's
    scale, the columns not mixed). Each column's profile is symmetric about the stripe's
    centre (the laser sheet's thickness, along x_L as the camera's baseline, images onto the
    chip's rows), and a straight line's centre moves by ``slope`` rows a column; so the
    derivative sampled at ``row + slope * s`` in column ``pc + s`` and averaged over s with
    Gaussian weights (scale ``sigma_px``, as Steger's smoothing; linear interpolation along
    the rows) keeps that symmetry, whatever the brightness does along the line, and averages
    speckle as Steger's smoothing does. The zero is bracketed between two rows next to the
    pixel and located on the cubic through four rows. NaN where no bracket lies within 2
    rows."""
    n_rows, n_cols = d_row.shape
    reach = int(math.ceil(3.0 * sigma_px))
    s = np.arange(-reach, reach + 1)
    weight = np.exp(-0.5 * (s / sigma_px) ** 2)
    columns = pc[:, None] + s[None, :]  # (k, S)
    # Only over columns the line crosses whole (``whole``: not past its end, the image's side
    # or a column where it leaves the chip), as far on both sides: an error in the slope
    # then cancels.
    gaps = np.concatenate(([-1], np.flatnonzero(~whole), [n_cols]))
    at = np.searchsorted(gaps, pc)
    half = np.maximum(np.minimum(pc - gaps[at - 1], gaps[at] - pc) - 1, 0)
    inside = np.abs(s)[None, :] <= half[:, None]
    columns = np.clip(columns, 0, n_cols - 1)[:, None, :]
    rows = pr[:, None, None] + _TAPS[None, :, None] + slope[:, None, None] * s[None, None, :]
    low = np.floor(rows)
    frac = rows - low
    low_i = np.clip(low.astype(np.int64), 0, n_rows - 1)
    high_i = np.clip(low_i + 1, 0, n_rows - 1)
    values = (1.0 - frac) * d_row[low_i, columns] + frac * d_row[high_i, columns]  # (k, 7, S)
    w = (weight[None, :] * inside)[:, None, :]
    f = (values * w).sum(axis=2) / w.sum(axis=2)  # (k, 7)
    out = np.full(len(pr), np.nan)
    # Brackets [i, i + 1] with i = -2..1 (a cubic needs i - 1..i + 2), nearest the pixel first.
    for i in (0, -1, 1, -2):
        j = i + 3  # the tap's column in f
        todo = np.isnan(out) & (f[:, j] >= 0) & (f[:, j + 1] <= 0) & (f[:, j] != f[:, j + 1])
        if not todo.any():
            continue
        y = f[todo][:, j - 1 : j + 3]  # values at x = -1, 0, 1, 2 (x = 0 is row pr + i)
        # The cubic through the four values, in powers of x.
        c0 = y[:, 1]
        c1 = -y[:, 0] / 3.0 - y[:, 1] / 2.0 + y[:, 2] - y[:, 3] / 6.0
        c2 = y[:, 0] / 2.0 - y[:, 1] + y[:, 2] / 2.0
        c3 = -y[:, 0] / 6.0 + y[:, 1] / 2.0 - y[:, 2] / 2.0 + y[:, 3] / 6.0
        linear = y[:, 1] / (y[:, 1] - y[:, 2])
        x = linear  # then Newton on the cubic, kept in the bracket
        for _ in range(4):
            value = c0 + x * (c1 + x * (c2 + x * c3))
            slope_x = c1 + x * (2.0 * c2 + 3.0 * x * c3)
            with np.errstate(invalid="ignore", divide="ignore"):
                x = np.clip(x - value / slope_x, 0.0, 1.0)
        out[todo] = pr[todo] + i + np.where(np.isfinite(x), x, linear)
    return out
