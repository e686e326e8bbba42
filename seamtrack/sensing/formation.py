"""Image formation on the chip: stripe pieces to pixels (blur or coherent speckle, pixel
integration), the chip's noise and quantization, and the per-column truth of a rendered image.

Coordinates are the image window's pixels, edge-based: pixel i spans [i, i + 1) in a row
coordinate u (along x_c) or a column coordinate w (along z_c). Work happens on s x s sub-pixels
("cells"), only in bands around the stripes: the image is cut into blocks of columns; in each,
the rows that hold light are grouped into runs, and each run is processed in a box with an apron
of cells around it (sources from the apron included, only the block's own columns kept:
overlap-save), so no light is lost or counted twice at block edges.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numba
import numpy as np
import scipy.fft
from numpy.typing import NDArray
from scipy import ndimage

FloatArray = NDArray[np.float64]

#: A stripe piece is laid out to this many standard deviations (its energy scaled back up).
REACH = 4.0


@dataclass(frozen=True)
class Optics:
    """What the image formation needs of the camera.

    Attributes
    ----------
    rows, columns : int
        Image size in pixels.
    supersample : int
        Cells per pixel and axis.
    cell_mm : (float, float)
        Cell size on the chip along rows and columns.
    blur_sigma_mm : float
        Gaussian fit of the Airy disc, used when ``speckle`` is off.
    speckle_size_mm : float
        lambda N on the chip; the pupil passes spatial frequencies up to 1 / (2 lambda N).
    speckle : bool
    speckle_contrast : float
        C of the surface (1: fully developed speckle).
    block_columns : int
        Pixel columns per block.
    """

    rows: int
    columns: int
    supersample: int
    cell_mm: tuple[float, float]
    blur_sigma_mm: float
    speckle_size_mm: float
    speckle: bool
    speckle_contrast: float = 1.0
    block_columns: int = 32

    def apron_cells(self) -> int:
        """Cells around a box: 4 blur sigmas, or 4 lambda N for the coherent field's tails;
        a whole number of pixels."""
        reach = 4.0 * (self.speckle_size_mm if self.speckle else self.blur_sigma_mm)
        cells = math.ceil(reach / min(self.cell_mm)) + 1
        s = self.supersample
        return s * math.ceil(cells / s)


@numba.njit(cache=True, nogil=True)
def _deposit_box(
    box: FloatArray, r0: int, c0: int, u: FloatArray, w: FloatArray, half_width: FloatArray,
    slope: FloatArray, sigma: FloatArray, electrons: FloatArray, reach: float,
) -> None:  # fmt: skip
    """Add stripe pieces (cell coordinates, edge-based) into a box whose corner is cell
    (r0, c0). A piece covers [w - half_width, w + half_width) along the columns, its energy
    shared by the length each cell column holds; there its centre row is u + slope * (dw), and
    across the rows it is a Gaussian integrated exactly over the cells within ``reach`` sigmas
    (and scaled back to its whole energy)."""
    n_r, n_c = box.shape
    inv_sqrt2 = 1.0 / math.sqrt(2.0)
    whole = 2.0 * math.erf(reach * inv_sqrt2)  # erf differences are twice the probability
    for i in range(u.shape[0]):
        sg = max(sigma[i], 0.05)
        hw = max(half_width[i], 1e-6)
        left, right = w[i] - hw, w[i] + hw
        for col in range(max(c0, int(math.floor(left))), min(c0 + n_c, int(math.floor(right)) + 1)):
            length = min(right, col + 1.0) - max(left, float(col))
            if length <= 0.0:
                continue
            centre = u[i] + slope[i] * (
                0.5 * (min(right, col + 1.0) + max(left, float(col))) - w[i]
            )
            lo = max(r0, int(math.floor(centre - reach * sg)))
            hi = min(r0 + n_r, int(math.ceil(centre + reach * sg)))
            scale = electrons[i] * length / (2.0 * hw) / whole
            cdf_lo = math.erf((lo - centre) / sg * inv_sqrt2)
            for k in range(lo, hi):
                cdf_hi = math.erf((k + 1 - centre) / sg * inv_sqrt2)
                box[k - r0, col - c0] += (cdf_hi - cdf_lo) * scale
                cdf_lo = cdf_hi


def _runs_of_rows(top: FloatArray, bottom: FloatArray, gap: int) -> list[tuple[int, int]]:
    """Merge row intervals [top, bottom) closer than ``gap`` into runs (sorted)."""
    order = np.argsort(top)
    runs: list[tuple[int, int]] = []
    for t, b in zip(top[order], bottom[order], strict=True):
        if runs and t <= runs[-1][1] + gap:
            runs[-1] = (runs[-1][0], max(runs[-1][1], int(b)))
        else:
            runs.append((int(t), int(b)))
    return runs


def form_image(
    u: FloatArray,
    w: FloatArray,
    half_width: FloatArray,
    slope: FloatArray,
    sigma: FloatArray,
    electrons: FloatArray,
    optics: Optics,
    rng: np.random.Generator,
) -> FloatArray:
    """Electrons per pixel, (rows, columns), of stripe pieces: laid on cells, blurred or
    imaged coherently (speckle), summed into pixels.

    Parameters
    ----------
    u, w : (n,) float
        Centres in pixels (edge-based): rows along x_c, columns along z_c.
    half_width : (n,) float
        Each piece covers w +- half_width along the columns (pixels): the stretch of the
        stripe its ray stands for.
    slope : (n,) float
        du/dw of the stripe there: the centre row moves along the piece.
    sigma : (n,) float
        Standard deviation across the stripe (along the rows), pixels; without speckle it
        is widened here by the blur.
    electrons : (n,) float
        Signal of each piece.
    """
    s = optics.supersample
    if not optics.speckle:
        sigma = np.hypot(sigma, optics.blur_sigma_mm / (optics.cell_mm[0] * s))
    n_rows, n_cols = optics.rows * s, optics.columns * s
    image = np.zeros((optics.rows, optics.columns))
    uf, wf, sf, hf = u * s, w * s, np.maximum(sigma * s, 0.05), np.maximum(half_width * s, 1e-6)
    extent = REACH * sf + np.abs(slope) * hf
    keep = (electrons > 0) & (wf + hf > 0) & (wf - hf < n_cols)
    keep &= (uf + extent > 0) & (uf - extent < n_rows)
    order = np.flatnonzero(keep)[np.argsort(wf[keep], kind="stable")]
    uf, wf, sf, hf, e = uf[order], wf[order], sf[order], hf[order], electrons[order]
    gf, extent = slope[order], extent[order]
    if len(e) == 0:
        return image
    apron = optics.apron_cells()
    block = optics.block_columns * s
    top = np.floor(uf - extent)
    bottom = np.ceil(uf + extent)
    reach_w = float(hf.max())
    for c0 in range(0, n_cols, block):
        c1 = min(n_cols, c0 + block)
        lo, hi = np.searchsorted(wf, [c0 - apron - reach_w, c1 + apron + reach_w])
        if lo == hi:
            continue
        box_c0, box_c1 = max(0, c0 - apron), min(n_cols, c1 + apron)
        for r_first, r_last in _runs_of_rows(top[lo:hi], bottom[lo:hi], 2 * apron + 1):
            r0 = max(0, s * ((r_first - apron) // s))
            r1 = min(n_rows, s * -(-(r_last + apron) // s))
            if r1 <= r0:
                continue
            cells = np.zeros((r1 - r0, box_c1 - box_c0))
            _deposit_box(cells, r0, box_c0, uf[lo:hi], wf[lo:hi], hf[lo:hi], gf[lo:hi],
                         sf[lo:hi], e[lo:hi], REACH)  # fmt: skip
            lit = _speckle(cells, optics, apron, rng) if optics.speckle else _blur(cells, optics)
            core = lit[:, c0 - box_c0 : c1 - box_c0]
            pixels = core.reshape((r1 - r0) // s, s, (c1 - c0) // s, s).sum(axis=(1, 3))
            image[r0 // s : r1 // s, c0 // s : c1 // s] += pixels
    return image


def _blur(cells: FloatArray, optics: Optics) -> FloatArray:
    """Diffraction blur (Gaussian fit of the Airy disc) along the columns, energy kept; across
    the stripe the caller has widened each piece's Gaussian by it (exact for Gaussians)."""
    sigma = optics.blur_sigma_mm / optics.cell_mm[1]
    return np.asarray(
        ndimage.gaussian_filter1d(cells, sigma, axis=1, mode="constant", truncate=4.0)
    )


def _speckle(cells: FloatArray, optics: Optics, apron: int, rng: np.random.Generator) -> FloatArray:
    """The rough surface's coherent field imaged through the circular pupil: intensity.

    Each cell's field is sqrt(I) times a phasor; a fully rough surface (C = 1) gives a circular
    Gaussian phasor of unit mean power, a smoother one a constant part besides (contrast C).
    The pupil passes frequencies up to f_c = 1 / (2 lambda N); the random part, white over the
    cells' band, keeps the pi f_c^2 d_r d_c share of its power, so it is scaled up by the
    inverse: the mean image keeps the energy (the incoherent image, blurred by the Airy PSF).
    """
    shape = cells.shape
    padded = (scipy.fft.next_fast_len(shape[0] + apron), scipy.fft.next_fast_len(shape[1] + apron))
    f_c = 1.0 / (2.0 * optics.speckle_size_mm)
    passed = min(1.0, math.pi * f_c**2 * optics.cell_mm[0] * optics.cell_mm[1])
    contrast = optics.speckle_contrast
    random_share = 1.0 - math.sqrt(max(0.0, 1.0 - contrast**2))
    noise = rng.standard_normal((2, *shape), dtype=np.float32)
    gain = np.float32(math.sqrt(0.5 * random_share / passed))
    amplitude = np.sqrt(cells.astype(np.float32))
    field = amplitude * (noise[0] * gain + np.float32(math.sqrt(1.0 - random_share)))
    field = field + 1j * (amplitude * noise[1] * gain)
    spectrum = scipy.fft.fft2(field.astype(np.complex64), s=padded)
    spectrum *= _pupil(padded, optics.cell_mm, f_c)
    image = scipy.fft.ifft2(spectrum)[: shape[0], : shape[1]]
    return np.asarray(image.real**2 + image.imag**2, dtype=np.float64)


@functools.lru_cache(maxsize=64)
def _pupil(shape: tuple[int, int], cell_mm: tuple[float, float], f_c: float) -> NDArray[np.bool_]:
    """The circular pupil's transfer function on an FFT grid: frequencies up to f_c pass."""
    fr = scipy.fft.fftfreq(shape[0], d=cell_mm[0])
    fc = scipy.fft.fftfreq(shape[1], d=cell_mm[1])
    mask = (fr[:, None] ** 2 + fc[None, :] ** 2) <= f_c**2
    mask.flags.writeable = False
    return mask


def chip_readout(
    electrons: FloatArray,
    rng: np.random.Generator,
    *,
    full_well_e: float,
    ambient: float,
    shot_noise: bool,
    read_noise_e: float,
    bit_depth: int | None,
) -> NDArray[np.float32]:
    """Electrons to the digital image, as a fraction of full scale: ambient light, shot
    noise, read noise, saturation, quantization (in this order)."""
    e = (electrons + ambient * full_well_e).astype(np.float32)
    if shot_noise:
        if ambient > 0:
            e = rng.poisson(e).astype(np.float32)
        else:
            lit = np.flatnonzero(e)
            e.flat[lit] = rng.poisson(e.flat[lit])
    if read_noise_e > 0:
        e += np.float32(read_noise_e) * rng.standard_normal(e.shape, dtype=np.float32)
    fraction = np.clip(e * np.float32(1.0 / full_well_e), 0.0, 1.0)
    if bit_depth is not None:
        levels = np.float32(2**bit_depth - 1)
        fraction = np.round(fraction * levels) / levels
    return fraction.astype(np.float32, copy=False)


# --------------------------------------------------------------------------- truth
def stripe_rows(
    u: FloatArray,
    w: FloatArray,
    ray: NDArray[np.int64],
    points: FloatArray,
    spacing_mm: FloatArray,
    columns: int,
) -> FloatArray:
    """Per column, the row where a stripe sampled by consecutive fan rays crosses the column
    centre, by linear interpolation between neighbouring rays (exact on a plane: a line in the
    laser plane images to a line). Two rays are neighbours when consecutive in the fan and no
    farther apart than 20 ray spacings and one column (a step or an occlusion breaks the
    stripe). Where a column is crossed twice, the larger row (the nearer range) is kept.

    Parameters
    ----------
    u, w : (n,) float
        Pixel coordinates (edge-based) of the stripe's rays.
    ray : (n,) int
        Their index in the fan, increasing.
    points : (n, 3) float
        The lit points (for the gap test).
    spacing_mm : (n,) float
        Expected distance to the next ray's point on a surface facing the laser.
    columns : int

    Returns
    -------
    (columns,) float
        Sub-pixel row (pixel i centred on i); NaN where no stripe crosses.
    """
    if len(u) < 2:
        return np.full(columns, np.nan)
    a, b = np.arange(len(u) - 1), np.arange(1, len(u))
    gap = np.linalg.norm(points[b] - points[a], axis=1)
    centre_a, centre_b = w[a] - 0.5, w[b] - 0.5
    linked = (
        (ray[b] == ray[a] + 1)
        & (gap <= 20.0 * np.maximum(spacing_mm[a], 1e-9))
        & (np.abs(centre_b - centre_a) < 1.0)
    )
    lo, hi = np.minimum(centre_a, centre_b), np.maximum(centre_a, centre_b)
    col = np.ceil(lo)
    hit = linked & (col <= hi) & (col >= 0) & (col < columns)
    if not hit.any():
        return np.full(columns, np.nan)
    a, b, col = a[hit], b[hit], col[hit].astype(np.int64)
    span = centre_b[hit] - centre_a[hit]
    t = np.where(span != 0, (col - centre_a[hit]) / np.where(span != 0, span, 1.0), 0.0)
    row = u[a] + t * (u[b] - u[a]) - 0.5
    nearest = np.full(columns, -np.inf)
    np.maximum.at(nearest, col, row)
    return np.where(np.isfinite(nearest), nearest, np.nan)


def column_mean_rows(
    u: FloatArray, w: FloatArray, half_width: FloatArray, electrons: FloatArray, columns: int
) -> tuple[FloatArray, FloatArray]:
    """Electrons per column and their mean row, pieces shared between the columns they cover
    (as :func:`form_image` lays them; the slope along a piece is left out)."""
    total = np.zeros(columns)
    moment = np.zeros(columns)
    hw = np.maximum(half_width, 1e-6)
    left, right = w - hw, w + hw
    first = np.floor(left).astype(np.int64)
    for step in range(int(np.ceil(2 * hw.max())) + 2 if len(w) else 0):
        col = first + step
        length = np.minimum(right, col + 1.0) - np.maximum(left, col)
        ok = (length > 0) & (col >= 0) & (col < columns)
        share = np.where(ok, length / (2 * hw), 0.0) * electrons
        total += np.bincount(col[ok], weights=share[ok], minlength=columns)
        moment += np.bincount(col[ok], weights=(share * (u - 0.5))[ok], minlength=columns)
    with np.errstate(invalid="ignore", divide="ignore"):
        return total, np.where(total > 0, moment / total, np.nan)
