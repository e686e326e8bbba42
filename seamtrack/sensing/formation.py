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
from typing import Any

import numba
import numpy as np
import scipy.fft
from numpy.typing import NDArray
from scipy import ndimage

from seamtrack.jit import KERNEL
from seamtrack.sensing import gauss32

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


@numba.njit(**KERNEL)
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
            if sg >= SERIES_MIN_SIGMA:
                _add_gaussian_cells(box[:, col - c0], lo - r0, hi - r0, lo + 0.5 - centre, sg,
                                    2.0 * scale)  # fmt: skip
                continue
            cdf_lo = math.erf((lo - centre) / sg * inv_sqrt2)
            for k in range(lo, hi):
                cdf_hi = math.erf((k + 1 - centre) / sg * inv_sqrt2)
                box[k - r0, col - c0] += (cdf_hi - cdf_lo) * scale
                cdf_lo = cdf_hi


#: A piece at least this many cells wide (standard deviation) is integrated over its cells by
#: :func:`_add_gaussian_cells` (the midpoint rule and its corrections: within 1e-6 of the peak
#: cell's share, 1e-4 of a tail cell's own), a narrower one by ``erf`` differences.
SERIES_MIN_SIGMA = 2.0


@numba.njit(**KERNEL)
def _add_gaussian_cells(
    column: FloatArray, first: int, last: int, x0: float, sigma: float, mass: float
) -> None:
    """Add ``mass`` times the standard normal's probability of each unit cell, x in
    [x_k - 1/2, x_k + 1/2) with x_k = x0 + (k - first) in units of ``sigma`` times sigma, to
    ``column[first:last]``.

    The cell's probability is phi(u) / sigma (1 + (u^2 - 1) / (24 sigma^2) + (u^4 - 6 u^2 + 3)
    / (1920 sigma^4)), u = x_k / sigma: the midpoint rule and the first two terms of its
    Euler-Maclaurin expansion (what is left is under 1e-6 of the peak cell for sigma >= 2). The
    Gaussian steps from cell to cell by a ratio that itself steps by exp(-1 / sigma^2): three
    exponentials a column, where ``erf`` differences took one ``erf`` a cell."""
    inv_var = 1.0 / (sigma * sigma)
    a = inv_var / 24.0
    b = inv_var * inv_var / 1920.0
    peak = mass / (sigma * math.sqrt(2.0 * math.pi))
    x = x0
    g = math.exp(-0.5 * x * x * inv_var)
    ratio = math.exp(-(x + 0.5) * inv_var)  # g(x + 1) / g(x)
    step = math.exp(-inv_var)
    for k in range(first, last):
        u2 = x * x * inv_var
        column[k] += peak * g * (1.0 + a * (u2 - 1.0) + b * (u2 * u2 - 6.0 * u2 + 3.0))
        g *= ratio
        ratio *= step
        x += 1.0


@numba.njit(**KERNEL)
def _plan_boxes(
    wf: FloatArray, top: FloatArray, bottom: FloatArray, n_rows: int, n_cols: int, s: int,
    block: int, apron: int, reach_w: float,
) -> NDArray[np.int64]:  # fmt: skip
    """The boxes, in the order they are drawn: per block of columns (left to right), the runs
    of its pieces' rows (row intervals closer than 2 aprons + 1 merged, top to bottom), each
    widened by the apron to whole pixels. Rows of (c0, c1, box_c0, box_c1, r0, r1, lo, hi):
    the block's columns, the box's columns and rows (cells), and the pieces [lo, hi) that
    may reach it (sorted by ``wf``)."""
    boxes = np.empty((0, 8), dtype=np.int64)
    found = []
    gap = 2 * apron + 1
    for c0 in range(0, n_cols, block):
        c1 = min(n_cols, c0 + block)
        lo = np.searchsorted(wf, c0 - apron - reach_w)
        hi = np.searchsorted(wf, c1 + apron + reach_w)
        if lo == hi:
            continue
        box_c0, box_c1 = max(0, c0 - apron), min(n_cols, c1 + apron)
        order = np.argsort(top[lo:hi])
        t_run = -1
        b_run = -1
        for j in range(order.shape[0] + 1):
            if j < order.shape[0]:
                t = int(top[lo + order[j]])
                b = int(bottom[lo + order[j]])
                if j > 0 and t <= b_run + gap:
                    b_run = max(b_run, b)
                    continue
            if j > 0:  # close the run [t_run, b_run)
                r0 = max(0, s * ((t_run - apron) // s))
                r1 = min(n_rows, s * -(-(b_run + apron) // s))
                if r1 > r0:
                    found.append((c0, c1, box_c0, box_c1, r0, r1, lo, hi))
            if j < order.shape[0]:
                t_run, b_run = t, b
    if found:
        boxes = np.array(found, dtype=np.int64)
    return boxes


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

    Notes
    -----
    With speckle, every box's Gaussian draws are made at once, in the boxes' order (the same
    numbers, in the same order, as one draw per box), two for each lit cell (a cell without
    light has no field, whatever its draw: it draws nothing); the field, the pupil and the squared
    modulus summed into pixels run in numba, the transforms in :func:`scipy.fft.fft2` box by
    box on the same zero-padded grids: the image is the same to the bit as one box after
    another would make it. A piece at least :data:`SERIES_MIN_SIGMA` cells wide is laid on
    its cells by the midpoint rule (:func:`_add_gaussian_cells`, within 1e-6 of the peak
    cell of the ``erf`` integral), a narrower one by ``erf`` differences.
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
    boxes = _plan_boxes(wf, np.floor(uf - extent), np.ceil(uf + extent), n_rows, n_cols, s,
                        optics.block_columns * s, apron, float(hf.max()))  # fmt: skip
    if optics.speckle:
        _speckle_boxes(image, boxes, uf, wf, hf, gf, sf, e, optics, apron, rng)
        return image
    for c0, c1, box_c0, box_c1, r0, r1, lo, hi in boxes.tolist():
        cells = np.zeros((r1 - r0, box_c1 - box_c0))
        _deposit_box(cells, r0, box_c0, uf[lo:hi], wf[lo:hi], hf[lo:hi], gf[lo:hi],
                     sf[lo:hi], e[lo:hi], REACH)  # fmt: skip
        core = _blur(cells, optics)[:, c0 - box_c0 : c1 - box_c0]
        pixels = core.reshape((r1 - r0) // s, s, (c1 - c0) // s, s).sum(axis=(1, 3))
        image[r0 // s : r1 // s, c0 // s : c1 // s] += pixels
    return image


def _speckle_boxes(
    image: FloatArray, boxes: NDArray[np.int64], uf: FloatArray, wf: FloatArray,
    hf: FloatArray, gf: FloatArray, sf: FloatArray, e: FloatArray, optics: Optics, apron: int,
    rng: np.random.Generator,
) -> None:  # fmt: skip
    """Add the speckle image of every box into ``image`` (see :class:`_SpeckleConstants`).

    The Gaussian draws of all boxes are made at once, in the boxes' order, two for each lit
    cell (:func:`_fields`); the cells are laid first (:func:`_deposit_boxes`). Boxes whose padded
    grids agree are transformed together, and only where the pupil lets light through: the
    forward transform's second pass only on the frequency rows the pupil meets, the inverse's
    first pass only on its frequency columns, its second only on the box's rows (the rest is
    zeros in, zeros out, or cropped away). Each 1-D transform is pocketfft's, on the same
    numbers as the whole 2-D one (its scaling after the first inverse pass, as pocketfft
    scales), so the image is the same to the bit as a full ``ifft2(pupil * fft2(field))``.
    """
    s = optics.supersample
    constants = _SpeckleConstants(optics)
    areas = (boxes[:, 5] - boxes[:, 4]) * (boxes[:, 3] - boxes[:, 2])
    cell_starts = np.concatenate([[0], np.cumsum(areas)])
    amplitude = np.empty(int(cell_starts[-1]), dtype=np.float32)
    lit = _deposit_boxes(amplitude, cell_starts, boxes, uf, wf, hf, gf, sf, e)
    noise = gauss32.standard_normal_f32(rng, 2 * int(lit.sum()))
    noise_starts = np.concatenate([[0], np.cumsum(2 * lit)])
    groups: dict[tuple[int, int], list[int]] = {}
    shapes = []
    for k, (_, _, box_c0, box_c1, r0, r1, _, _) in enumerate(boxes.tolist()):
        shapes.append((r1 - r0, box_c1 - box_c0))
        groups.setdefault(constants.padded(shapes[-1], apron), []).append(k)
    intensity: list[tuple[NDArray[np.complex64], int]] = [None] * len(boxes)  # type: ignore[list-item]
    for padded, members in groups.items():
        n_r = max(shapes[k][0] for k in members)
        n_c = max(shapes[k][1] for k in members)
        field = np.zeros((len(members), padded[0], n_c), dtype=np.complex64)
        _fields(field, boxes[members], amplitude, cell_starts[members], noise,
                noise_starts[members], lit[members], constants.gain, constants.steady)  # fmt: skip
        pupil = _pupil(padded, optics.cell_mm, constants.f_c)
        rows = np.flatnonzero(pupil.any(axis=1))
        columns = np.flatnonzero(pupil.any(axis=0))
        half = scipy.fft.fft(field, axis=1, overwrite_x=True)
        spectrum = scipy.fft.fft(half[:, rows, :], n=padded[1], axis=2, overwrite_x=True)
        band = np.zeros((len(members), padded[0], len(columns)), dtype=np.complex64)
        _pass_band(spectrum, pupil, rows, columns, band)
        back = scipy.fft.ifft(band, axis=1, norm="forward", overwrite_x=True)
        rows_back = np.zeros((len(members), n_r, padded[1]), dtype=np.complex64)
        _spread_scaled(back, columns, np.float32(1.0 / (padded[0] * padded[1])), rows_back)
        out = scipy.fft.ifft(rows_back, axis=2, norm="forward", overwrite_x=True)
        for m, k in enumerate(members):
            intensity[k] = (out, m)
    for k, (c0, c1, box_c0, _, r0, r1, _, _) in enumerate(boxes.tolist()):
        out, m = intensity[k]
        _add_intensity(image, out[m], r0, r1, c0 - box_c0, c0, c1, s)


def _blur(cells: FloatArray, optics: Optics) -> FloatArray:
    """Diffraction blur (Gaussian fit of the Airy disc) along the columns, energy kept; across
    the stripe the caller has widened each piece's Gaussian by it (exact for Gaussians)."""
    sigma = optics.blur_sigma_mm / optics.cell_mm[1]
    return np.asarray(
        ndimage.gaussian_filter1d(cells, sigma, axis=1, mode="constant", truncate=4.0)
    )


class _SpeckleConstants:
    """The rough surface's coherent field imaged through the circular pupil.

    Each cell's field is sqrt(I) times a phasor; a fully rough surface (C = 1) gives a circular
    Gaussian phasor of unit mean power, a smoother one a constant part besides (contrast C).
    The pupil passes frequencies up to f_c = 1 / (2 lambda N); the random part, white over the
    cells' band, keeps the pi f_c^2 d_r d_c share of its power, so it is scaled up by the
    inverse: the mean image keeps the energy (the incoherent image, blurred by the Airy PSF).
    A box of cells is padded by the apron (to a fast FFT length) against wrap-around.
    """

    def __init__(self, optics: Optics) -> None:
        self.f_c = 1.0 / (2.0 * optics.speckle_size_mm)
        passed = min(1.0, math.pi * self.f_c**2 * optics.cell_mm[0] * optics.cell_mm[1])
        contrast = optics.speckle_contrast
        random_share = 1.0 - math.sqrt(max(0.0, 1.0 - contrast**2))
        self.gain = np.float32(math.sqrt(0.5 * random_share / passed))
        self.steady = np.float32(math.sqrt(1.0 - random_share))

    @staticmethod
    def padded(shape: tuple[int, ...], apron: int) -> tuple[int, int]:
        return (
            scipy.fft.next_fast_len(shape[0] + apron),
            scipy.fft.next_fast_len(shape[1] + apron),
        )


@numba.njit(**KERNEL)
def _pass_band(
    spectrum: NDArray[np.complex64], pupil: NDArray[np.bool_], rows: NDArray[np.int64],
    columns: NDArray[np.int64], band: NDArray[np.complex64],
) -> None:  # fmt: skip
    """band[:, rows[i], j] = spectrum[:, i, columns[j]] where the pupil passes it, else 0."""
    for m in range(spectrum.shape[0]):
        for i in range(rows.shape[0]):
            for j in range(columns.shape[0]):
                if pupil[rows[i], columns[j]]:
                    band[m, rows[i], j] = spectrum[m, i, columns[j]]


@numba.njit(**KERNEL)
def _spread_scaled(
    back: NDArray[np.complex64], columns: NDArray[np.int64], scale: np.float32,
    out: NDArray[np.complex64],
) -> None:  # fmt: skip
    """out[:, r, columns[j]] = back[:, r, j] * scale (real and imaginary parts, float32), for
    the rows of ``out``."""
    for m in range(out.shape[0]):
        for r in range(out.shape[1]):
            for j in range(columns.shape[0]):
                z = back[m, r, j]
                out[m, r, columns[j]] = complex(z.real * scale, z.imag * scale)


@numba.njit(**KERNEL)
def _deposit_boxes(
    amplitude: NDArray[np.float32], starts: NDArray[np.int64], boxes: NDArray[np.int64],
    uf: FloatArray, wf: FloatArray, hf: FloatArray, gf: FloatArray, sf: FloatArray,
    e: FloatArray,
) -> NDArray[np.int64]:  # fmt: skip
    """Each box's cells (:func:`_deposit_box`) as the field's amplitude sqrt(float32(I)), box m
    row by row in ``amplitude[starts[m]:starts[m + 1]]``; returns the number of its lit cells
    (amplitude above zero) per box."""
    lit = np.zeros(boxes.shape[0], dtype=np.int64)
    largest = 0
    for m in range(boxes.shape[0]):
        largest = max(largest, starts[m + 1] - starts[m])
    scratch = np.empty(largest)
    for m in range(boxes.shape[0]):
        _, _, box_c0, box_c1, r0, r1, lo, hi = boxes[m]
        n = starts[m + 1] - starts[m]
        cells = scratch[:n]
        cells[:] = 0.0
        _deposit_box(cells.reshape((r1 - r0, box_c1 - box_c0)), r0, box_c0, uf[lo:hi],
                     wf[lo:hi], hf[lo:hi], gf[lo:hi], sf[lo:hi], e[lo:hi], REACH)  # fmt: skip
        for q in range(n):
            a = np.sqrt(np.float32(cells[q]))
            amplitude[starts[m] + q] = a
            if a > 0:
                lit[m] += 1
    return lit


@numba.njit(**KERNEL)
def _fields(
    field: NDArray[np.complex64], boxes: NDArray[np.int64], amplitude: NDArray[np.float32],
    cell_starts: NDArray[np.int64], noise: NDArray[np.float32], noise_starts: NDArray[np.int64],
    lit: NDArray[np.int64], gain: np.float32, steady: np.float32,
) -> None:  # fmt: skip
    """Per box m (rows of :func:`_plan_boxes`): the surface's field on its cells (amplitudes
    sqrt(I) from ``cell_starts[m]``, row by row) in the top left corner of the zeroed
    ``field[m]``: sqrt(I) (noise_0 gain + steady) + i sqrt(I) noise_1 gain, in float32. Only
    its ``lit[m]`` lit cells (sqrt(I) > 0; elsewhere the field is 0 whatever the draw) take
    normals: from ``noise_starts[m]``, first the real parts of its lit cells, then the
    imaginary."""
    for m in range(boxes.shape[0]):
        _, _, box_c0, box_c1, r0, r1, _, _ = boxes[m]
        n_r, n_c = r1 - r0, box_c1 - box_c0
        re = noise[noise_starts[m] : noise_starts[m] + lit[m]]
        im = noise[noise_starts[m] + lit[m] : noise_starts[m] + 2 * lit[m]]
        q = 0
        for i in range(n_r):
            for j in range(n_c):
                a = amplitude[cell_starts[m] + i * n_c + j]
                if a > 0:
                    field[m, i, j] = complex(a * (re[q] * gain + steady), a * im[q] * gain)
                    q += 1


@numba.njit(**KERNEL)
def _add_intensity(
    image: FloatArray, field: NDArray[np.complex64], r0: int, r1: int, first: int, c0: int,
    c1: int, s: int,
) -> None:  # fmt: skip
    """Add |field|^2 (float32, then float64) of the cells [r0, r1) x [c0, c1) (the field's
    columns from ``first``) into the image's pixels, each pixel's s x s cells summed row by
    row (as numpy sums them)."""
    for pr in range(r0 // s, r1 // s):
        for pc in range(c0 // s, c1 // s):
            total = 0.0
            for i in range(s):
                for j in range(s):
                    z = field[pr * s - r0 + i, pc * s - c0 + first + j]
                    total += np.float64(z.real * z.real + z.imag * z.imag)
            image[pr, pc] += total


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
    dim_by_inversion: bool = False,
) -> NDArray[np.float32]:
    """Electrons to the digital image, as a fraction of full scale: ambient light, shot
    noise, read noise, saturation, quantization (in this order).

    The draws: Poisson counts of every lit pixel (every pixel with ambient light), in raster
    order, then a float32 normal per pixel (:mod:`seamtrack.sensing.gauss32`, NumPy's numbers);
    the arithmetic is float32 throughout.

    ``dim_by_inversion`` (a frame with the welding arc, whose fume and glow light most of the
    chip with a few electrons a pixel): the counts are drawn by inverting the Poisson CDF with
    one uniform a pixel (:func:`poisson_by_inversion`; exactly Poisson, about 4x faster than
    NumPy's generator at such means), NumPy's Poisson only where the mean reaches
    :data:`INVERSION_MAX_MEAN`. Other frames draw as before, to the byte."""
    e = np.empty(electrons.shape, dtype=np.float32)
    lit = _to_float32(electrons, ambient * full_well_e, e)
    flat = e.reshape(-1)
    if shot_noise:
        counts = _shot_counts(flat if ambient > 0 else flat[lit], rng, dim_by_inversion)
        if ambient > 0:
            flat[:] = counts
        elif len(lit):
            flat[lit] = counts
    noise = (
        gauss32.standard_normal_f32(rng, flat.shape)
        if read_noise_e > 0
        else np.empty(0, dtype=np.float32)
    )
    levels = -1.0 if bit_depth is None else float(2**bit_depth - 1)
    _digitize(flat, noise, np.float32(read_noise_e), np.float32(1.0 / full_well_e),
              np.float32(levels))  # fmt: skip
    return e


def _shot_counts(
    means: NDArray[np.float32], rng: np.random.Generator, dim_by_inversion: bool
) -> NDArray[Any]:
    """Poisson counts of ``means``: NumPy's, or (``dim_by_inversion``) by inversion below
    :data:`INVERSION_MAX_MEAN` and NumPy's above (one uniform a pixel first, in raster order,
    then NumPy's counts of the bright pixels)."""
    if not dim_by_inversion or not len(means):
        return rng.poisson(means)
    counts = poisson_by_inversion(means, rng.random(len(means)))
    bright = np.flatnonzero(means >= INVERSION_MAX_MEAN)
    counts[bright] = rng.poisson(means[bright])
    return counts


#: :func:`chip_readout`'s inversion draws pixels of a mean below this; brighter ones (the
#: stripe, the arc's core) go to NumPy's Poisson (its transformed rejection is fast there).
INVERSION_MAX_MEAN = 30.0
#: The terms summed at most (P(X > 200) is below 1e-100 for a mean under 30).
_INVERSION_TERMS = 200
_RECIPROCALS = 1.0 / np.arange(1.0, _INVERSION_TERMS + 1.0)


#: :func:`poisson_by_inversion` inverts this many pixels side by side (a block of neighbours,
#: whose means are alike): the same arithmetic per pixel, in SIMD lanes and without a
#: mispredicted branch at each pixel's end (3-4x faster than one pixel after another).
_INVERSION_LANES = 32


@numba.njit(**KERNEL)
def poisson_by_inversion(mean: NDArray[np.float32], u: FloatArray) -> NDArray[np.float32]:
    """A Poisson count of each ``mean`` (float32) by inverting its CDF at the uniform ``u``
    (float64 in [0, 1)): the smallest k with P(X <= k) > u, the terms p_k = p_(k-1) mean / k
    summed from p_0 = exp(-mean) (exp taken in float32: p_0 and the sums are good to about 1e-7
    of themselves, the counts Poisson to that). Its cost grows with the mean, so the caller
    takes means of :data:`INVERSION_MAX_MEAN` and more elsewhere (there the result is left as
    the mean, to be replaced).

    The pixels go in blocks of :data:`_INVERSION_LANES`: each one's partial sums are the
    sequential ones (the same operations in the same order), and k counts the sums that stay
    at or below u (the sums never fall), so the counts are those of one pixel after another,
    to the bit (tests/test_formation_same_bytes.py)."""
    n = mean.shape[0]
    out = np.empty(n, dtype=np.float32)
    lanes = _INVERSION_LANES
    m = np.zeros(lanes)
    target = np.zeros(lanes)
    p = np.zeros(lanes)
    cdf = np.zeros(lanes)
    k = np.zeros(lanes, dtype=np.int64)
    for first in range(0, n, lanes):
        width = min(lanes, n - first)
        for j in range(lanes):
            dim = j < width and not float(mean[first + j]) >= INVERSION_MAX_MEAN
            x = mean[first + j] if dim else np.float32(0.0)
            m[j] = x
            target[j] = u[first + j] if dim else -1.0  # a bright or absent lane: done at once
            p[j] = math.exp(-x)  # in float32 (expf), as the pixel-by-pixel kernel took it
            cdf[j] = p[j]
            k[j] = 0
        for term in range(_INVERSION_TERMS):
            below = 0
            for j in range(lanes):
                step = cdf[j] <= target[j]
                k[j] += step
                below += step
            if below == 0:
                break
            for j in range(lanes):
                p[j] *= m[j] * _RECIPROCALS[term]  # p_(k+1) = p_k mean / (k + 1)
                cdf[j] += p[j]
        for j in range(width):
            out[first + j] = k[j] if target[j] >= 0.0 else mean[first + j]
    return out


@numba.njit(**KERNEL)
def _to_float32(
    electrons: FloatArray, offset: float, out: NDArray[np.float32]
) -> NDArray[np.int64]:
    """out = float32(electrons + offset); return the flat indices of its nonzero pixels."""
    src = electrons.reshape(-1)
    dst = out.reshape(-1)
    lit = np.empty(src.shape[0], dtype=np.int64)
    n = 0
    for i in range(src.shape[0]):
        v = np.float32(src[i] + offset)
        dst[i] = v
        if v != 0:
            lit[n] = i
            n += 1
    return lit[:n]


@numba.njit(**KERNEL)
def _digitize(
    e: NDArray[np.float32], noise: NDArray[np.float32], read_noise: np.float32,
    per_electron: np.float32, levels: np.float32,
) -> None:  # fmt: skip
    """In place: e + read_noise * noise (when drawn), times per_electron, clipped to [0, 1],
    rounded (half to even) to ``levels`` steps when levels > 0."""
    zero = np.float32(0.0)
    one = np.float32(1.0)
    for i in range(e.shape[0]):
        v = e[i]
        if noise.shape[0]:
            v = v + read_noise * noise[i]
        v = v * per_electron
        if v < zero:
            v = zero
        elif v > one:
            v = one
        if levels > zero:
            v = np.rint(v * levels) / levels
        e[i] = v


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
