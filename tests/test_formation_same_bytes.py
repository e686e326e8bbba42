"""The fast image formation makes the very images of the straightforward one (issue 41 item 5).

Oracles, both independent of the package's fast paths:
- NumPy itself for :mod:`seamtrack.sensing.gauss32` (the same float32 normals, the same
  generator state after, the ziggurat's rare tail included);
- the per-block formation as it stood before the speed work, copied here (with issue 41's
  later changes of the draws: normals only for lit cells; wide pieces' cells by the midpoint
  rule, itself pinned against ``erf`` below): one
  ``rng.standard_normal`` per box, ``scipy.fft.fft2`` / ``ifft2`` of the whole padded box, the
  pupil as a mask, numpy's reshape-sum into pixels, and the chip's readout in numpy. The images
  must agree to the byte for the same seed.
"""

from __future__ import annotations

import math

import numba
import numpy as np
import pytest
import scipy.fft
from scipy import ndimage

from seamtrack.sensing import formation, gauss32

# --------------------------------------------------------------------------- the oracle


@numba.njit(cache=False)
def _deposit_reference(box, r0, c0, u, w, half_width, slope, sigma, electrons, reach):  # type: ignore[no-untyped-def]
    n_r, n_c = box.shape
    inv_sqrt2 = 1.0 / math.sqrt(2.0)
    whole = 2.0 * math.erf(reach * inv_sqrt2)
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
            if sg >= 2.0:  # wide pieces: the midpoint rule and its corrections (issue 41)
                inv_var = 1.0 / (sg * sg)
                peak = 2.0 * scale / (sg * math.sqrt(2.0 * math.pi))
                x = lo + 0.5 - centre
                g = math.exp(-0.5 * x * x * inv_var)
                ratio = math.exp(-(x + 0.5) * inv_var)
                step = math.exp(-inv_var)
                for k in range(lo, hi):
                    u2 = x * x * inv_var
                    box[k - r0, col - c0] += peak * g * (
                        1.0 + inv_var / 24.0 * (u2 - 1.0)
                        + inv_var * inv_var / 1920.0 * (u2 * u2 - 6.0 * u2 + 3.0)
                    )  # fmt: skip
                    g *= ratio
                    ratio *= step
                    x += 1.0
                continue
            cdf_lo = math.erf((lo - centre) / sg * inv_sqrt2)
            for k in range(lo, hi):
                cdf_hi = math.erf((k + 1 - centre) / sg * inv_sqrt2)
                box[k - r0, col - c0] += (cdf_hi - cdf_lo) * scale
                cdf_lo = cdf_hi


def _runs(top, bottom, gap):  # type: ignore[no-untyped-def]
    order = np.argsort(top)
    runs: list[tuple[int, int]] = []
    for t, b in zip(top[order], bottom[order], strict=True):
        if runs and t <= runs[-1][1] + gap:
            runs[-1] = (runs[-1][0], max(runs[-1][1], int(b)))
        else:
            runs.append((int(t), int(b)))
    return runs


def _speckle_reference(cells, optics, apron, rng):  # type: ignore[no-untyped-def]
    shape = cells.shape
    padded = (scipy.fft.next_fast_len(shape[0] + apron), scipy.fft.next_fast_len(shape[1] + apron))
    f_c = 1.0 / (2.0 * optics.speckle_size_mm)
    passed = min(1.0, math.pi * f_c**2 * optics.cell_mm[0] * optics.cell_mm[1])
    random_share = 1.0 - math.sqrt(max(0.0, 1.0 - optics.speckle_contrast**2))
    gain = np.float32(math.sqrt(0.5 * random_share / passed))
    amplitude = np.sqrt(cells.astype(np.float32))
    lit = np.flatnonzero(amplitude > 0)  # only lit cells draw: elsewhere the field is 0
    draws = rng.standard_normal((2, len(lit)), dtype=np.float32)
    noise = np.zeros((2, *shape), dtype=np.float32)
    noise[0].flat[lit], noise[1].flat[lit] = draws[0], draws[1]
    field = amplitude * (noise[0] * gain + np.float32(math.sqrt(1.0 - random_share)))
    field = field + 1j * (amplitude * noise[1] * gain)
    spectrum = scipy.fft.fft2(field.astype(np.complex64), s=padded)
    fr = scipy.fft.fftfreq(padded[0], d=optics.cell_mm[0])
    fc = scipy.fft.fftfreq(padded[1], d=optics.cell_mm[1])
    spectrum *= (fr[:, None] ** 2 + fc[None, :] ** 2) <= f_c**2
    image = scipy.fft.ifft2(spectrum)[: shape[0], : shape[1]]
    return np.asarray(image.real**2 + image.imag**2, dtype=np.float64)


def _form_reference(u, w, half_width, slope, sigma, electrons, optics, rng):  # type: ignore[no-untyped-def]
    s = optics.supersample
    if not optics.speckle:
        sigma = np.hypot(sigma, optics.blur_sigma_mm / (optics.cell_mm[0] * s))
    n_rows, n_cols = optics.rows * s, optics.columns * s
    image = np.zeros((optics.rows, optics.columns))
    uf, wf, sf, hf = u * s, w * s, np.maximum(sigma * s, 0.05), np.maximum(half_width * s, 1e-6)
    extent = formation.REACH * sf + np.abs(slope) * hf
    keep = (electrons > 0) & (wf + hf > 0) & (wf - hf < n_cols)
    keep &= (uf + extent > 0) & (uf - extent < n_rows)
    order = np.flatnonzero(keep)[np.argsort(wf[keep], kind="stable")]
    uf, wf, sf, hf, e = uf[order], wf[order], sf[order], hf[order], electrons[order]
    gf, extent = slope[order], extent[order]
    apron = optics.apron_cells()
    block = optics.block_columns * s
    top, bottom = np.floor(uf - extent), np.ceil(uf + extent)
    reach_w = float(hf.max())
    for c0 in range(0, n_cols, block):
        c1 = min(n_cols, c0 + block)
        lo, hi = np.searchsorted(wf, [c0 - apron - reach_w, c1 + apron + reach_w])
        if lo == hi:
            continue
        box_c0, box_c1 = max(0, c0 - apron), min(n_cols, c1 + apron)
        for r_first, r_last in _runs(top[lo:hi], bottom[lo:hi], 2 * apron + 1):
            r0 = max(0, s * ((r_first - apron) // s))
            r1 = min(n_rows, s * -(-(r_last + apron) // s))
            if r1 <= r0:
                continue
            cells = np.zeros((r1 - r0, box_c1 - box_c0))
            _deposit_reference(cells, r0, box_c0, uf[lo:hi], wf[lo:hi], hf[lo:hi], gf[lo:hi],
                               sf[lo:hi], e[lo:hi], formation.REACH)  # fmt: skip
            if optics.speckle:
                lit = _speckle_reference(cells, optics, apron, rng)
            else:
                sigma_c = optics.blur_sigma_mm / optics.cell_mm[1]
                lit = ndimage.gaussian_filter1d(
                    cells, sigma_c, axis=1, mode="constant", truncate=4.0
                )
            core = lit[:, c0 - box_c0 : c1 - box_c0]
            pixels = core.reshape((r1 - r0) // s, s, (c1 - c0) // s, s).sum(axis=(1, 3))
            image[r0 // s : r1 // s, c0 // s : c1 // s] += pixels
    return image


def _readout_reference(
    electrons, rng, *, full_well_e, ambient, shot_noise, read_noise_e, bit_depth
):  # type: ignore[no-untyped-def]
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


# --------------------------------------------------------------------------- scenes


def _stripes(columns: int, seed: int):  # type: ignore[no-untyped-def]
    """A sloped stripe sampled 2.5 rays a column, a second stripe far below (another run of
    rows), a gap in the first, and a few broad pieces (a rough bounce)."""
    rng = np.random.default_rng(seed)
    w = np.arange(0.2, columns - 0.2, 0.4)
    w = w[(w < 0.3 * columns) | (w > 0.4 * columns)]
    u = 60.0 + 0.3 * w + 0.2 * np.sin(w / 7.0)
    w2 = np.arange(0.1, columns, 0.5)
    u2 = np.full_like(w2, 190.0)
    wb = rng.uniform(0, columns, 12)
    ub = rng.uniform(100, 150, 12)
    u_all = np.concatenate([u, u2, ub])
    w_all = np.concatenate([w, w2, wb])
    n = len(u_all)
    half = np.full(n, 0.2)
    slope = np.concatenate([np.full(len(u), 0.3), np.zeros(len(u2) + 12)])
    sigma = np.concatenate([np.full(len(u) + len(u2), 1.7), np.full(12, 8.0)])
    electrons = np.concatenate([rng.uniform(500, 3000, len(u) + len(u2)), np.full(12, 50.0)])
    return u_all, w_all, half, slope, sigma, electrons


def _optics(s: int, speckle: bool, contrast: float = 1.0) -> formation.Optics:
    return formation.Optics(
        rows=256, columns=192, supersample=s, cell_mm=(0.005 / s, 0.0038 / s),
        blur_sigma_mm=0.0022, speckle_size_mm=0.00528, speckle=speckle,
        speckle_contrast=contrast, block_columns=32,
    )  # fmt: skip


# --------------------------------------------------------------------------- tests


@pytest.mark.parametrize("n", [1, 2, 7, 1000, 250_001])
@pytest.mark.parametrize("odd_start", [False, True])
def test_gauss32_draws_numpys_float32_normals_and_leaves_its_state(n, odd_start) -> None:
    ours, theirs = np.random.default_rng(n), np.random.default_rng(n)
    if odd_start:  # a kept half-word at the start
        ours.standard_normal(3, dtype=np.float32)
        theirs.standard_normal(3, dtype=np.float32)
    a = gauss32.standard_normal_f32(ours, (n,))
    b = theirs.standard_normal(n, dtype=np.float32)
    assert a.tobytes() == b.tobytes()
    assert ours.bit_generator.state == theirs.bit_generator.state
    assert np.array_equal(ours.poisson(7.0, 5), theirs.poisson(7.0, 5))


def test_gauss32_ziggurat_tail_and_wedges_match_numpy() -> None:
    ours, theirs = np.random.default_rng(41), np.random.default_rng(41)
    a = gauss32.standard_normal_f32(ours, (2_000_000,))
    b = theirs.standard_normal(2_000_000, dtype=np.float32)
    assert (np.abs(b) > gauss32.ZIGGURAT_R).sum() > 100  # the tail beyond r was drawn
    assert a.tobytes() == b.tobytes()


def test_gauss32_falls_back_to_numpy_for_another_bit_generator() -> None:
    ours = np.random.Generator(np.random.MT19937(5))
    theirs = np.random.Generator(np.random.MT19937(5))
    assert np.array_equal(
        gauss32.standard_normal_f32(ours, (4, 5)), theirs.standard_normal((4, 5), dtype=np.float32)
    )


@pytest.mark.parametrize(
    ("s", "speckle", "contrast"), [(2, True, 1.0), (3, True, 1.0), (2, True, 0.6), (2, False, 1.0)]
)
def test_form_image_is_the_per_block_reference_to_the_byte(s, speckle, contrast) -> None:
    optics = _optics(s, speckle, contrast)
    pieces = _stripes(optics.columns, seed=s)
    ours, theirs = np.random.default_rng(3), np.random.default_rng(3)
    a = formation.form_image(*pieces, optics, ours)
    b = _form_reference(*pieces, optics, theirs)
    assert a.sum() > 0
    assert a.tobytes() == b.tobytes()
    assert ours.bit_generator.state == theirs.bit_generator.state


@pytest.mark.parametrize(
    "change",
    [{}, {"ambient": 0.01}, {"bit_depth": None}, {"read_noise_e": 0.0}, {"shot_noise": False}],
)
def test_chip_readout_is_the_numpy_reference_to_the_byte(change) -> None:
    optics = _optics(2, True)
    electrons = formation.form_image(*_stripes(optics.columns, 1), optics, np.random.default_rng(1))
    chip = {"full_well_e": 10_000.0, "ambient": 0.0, "shot_noise": True, "read_noise_e": 5.0,
            "bit_depth": 10, **change}  # fmt: skip
    ours, theirs = np.random.default_rng(9), np.random.default_rng(9)
    a = formation.chip_readout(electrons * 4.0, ours, **chip)
    b = _readout_reference(electrons * 4.0, theirs, **chip)
    assert a.dtype == b.dtype == np.float32
    assert a.tobytes() == b.tobytes()
    assert ours.bit_generator.state == theirs.bit_generator.state


def test_poisson_by_inversion_draws_poisson_counts() -> None:
    """The arc frames' shot-noise sampler against the Poisson law (scipy.stats.poisson): at
    means from 0.05 to just under INVERSION_MAX_MEAN the counts' frequencies are the pmf within
    5 standard errors, mean and variance the mean; a mean at the bound is left to NumPy."""
    from scipy import stats

    from seamtrack.sensing.formation import INVERSION_MAX_MEAN, poisson_by_inversion

    rng = np.random.default_rng(7)
    n = 200_000
    for lam in (0.05, 1.0, 3.3, 12.0, INVERSION_MAX_MEAN - 0.5):
        counts = poisson_by_inversion(np.full(n, lam, dtype=np.float32), rng.random(n))
        k = np.arange(int(lam + 8 * np.sqrt(lam) + 10))
        freq = np.bincount(counts.astype(np.int64), minlength=len(k))[: len(k)] / n
        pmf = stats.poisson.pmf(k, np.float32(lam))
        assert np.all(np.abs(freq - pmf) <= 5 * np.sqrt(pmf * (1 - pmf) / n) + 1e-12), lam
        assert abs(counts.mean() - lam) < 5 * np.sqrt(lam / n)
        assert abs(counts.var() - lam) < 0.05 * lam + 0.01
    left = poisson_by_inversion(np.array([INVERSION_MAX_MEAN], dtype=np.float32), np.array([0.5]))
    assert left[0] == np.float32(INVERSION_MAX_MEAN)


def _sequential_inversion(mean: np.ndarray, u: np.ndarray) -> np.ndarray:
    """The inversion one pixel after another, as the kernel was first written (the reference;
    numba's ``float`` keeps a float32 a float32, so exp(-mean) is taken in float32)."""
    import math

    import numba

    from seamtrack.sensing.formation import INVERSION_MAX_MEAN

    reciprocals = 1.0 / np.arange(1.0, 201.0)

    @numba.njit
    def kernel(mean: np.ndarray, u: np.ndarray) -> np.ndarray:
        out = np.empty(mean.shape[0], dtype=np.float32)
        for i in range(mean.shape[0]):
            m = float(mean[i])
            if m >= INVERSION_MAX_MEAN:
                out[i] = mean[i]
                continue
            p = math.exp(-m)
            cdf = p
            k = 0
            while cdf <= u[i] and k < 200:
                p *= m * reciprocals[k]
                cdf += p
                k += 1
            out[i] = k
        return out

    return kernel(mean, u)


def test_poisson_by_inversion_in_blocks_is_the_sequential_inversion_to_the_bit() -> None:
    """The blocked kernel (pixels side by side) gives the counts of the sequential inversion:
    means over the whole range, ragged blocks, bright and NaN pixels among dim ones."""
    from seamtrack.sensing.formation import INVERSION_MAX_MEAN, poisson_by_inversion

    rng = np.random.default_rng(3)
    for n in (1, 31, 33, 1000):
        mean = (rng.random(n) ** 2 * 1.2 * INVERSION_MAX_MEAN).astype(np.float32)
        mean[::7] = INVERSION_MAX_MEAN
        if n > 5:
            mean[5] = np.nan
        u = rng.random(n)
        u[::11] = 0.0
        got = poisson_by_inversion(mean, u)
        want = _sequential_inversion(mean, u)
        assert got.tobytes() == want.tobytes(), n
    # a pixel of v-groove-arc whose uniform falls 1e-9 below P(X <= 10): float32's exp(-mean)
    # puts it above (11), float64's would not (10); the kernels agree on 11
    mean, u = np.array([12.725028], dtype=np.float32), np.array([0.2760405056599191])
    assert poisson_by_inversion(mean, u)[0] == _sequential_inversion(mean, u)[0] == 11.0


@pytest.mark.parametrize("sigma", [2.0, 2.5, 3.4, 8.0, 40.0])
@pytest.mark.parametrize("centre", [180.0, 180.37, 181.81])
def test_wide_pieces_cells_are_the_erf_integral_within_1e_6_of_the_peak(sigma, centre) -> None:
    """A piece of sigma >= SERIES_MIN_SIGMA cells is laid by the midpoint rule with two
    Euler-Maclaurin terms: each cell within 1e-6 of the peak cell (and 1e-4 of itself) of the
    exact Gaussian integral by erf differences, the total within 1e-8. One piece covering one
    column, one cell a pixel, no blur: the image is the cells."""
    assert sigma >= formation.SERIES_MIN_SIGMA
    optics = formation.Optics(
        rows=400, columns=3, supersample=1, cell_mm=(0.005, 0.005), blur_sigma_mm=1e-12,
        speckle_size_mm=0.005, speckle=False,
    )  # fmt: skip
    one = np.ones(1)
    rng = np.random.default_rng(0)
    image = formation.form_image(np.array([centre]), 1.5 * one, 0.5 * one, 0.0 * one,
                                 sigma * one, 1000.0 * one, optics, rng)  # fmt: skip
    ours = image[:, 1]
    exact = np.zeros(optics.rows)
    whole = math.erf(formation.REACH / math.sqrt(2.0))
    reach = formation.REACH * sigma
    for k in range(math.floor(centre - reach), math.ceil(centre + reach)):
        lower, upper = (k - centre) / sigma, (k + 1 - centre) / sigma
        p = 0.5 * (math.erf(upper / math.sqrt(2.0)) - math.erf(lower / math.sqrt(2.0)))
        exact[k] = 1000.0 * p / whole
    lit = exact > 0
    assert np.array_equal(ours > 0, lit)
    assert np.max(np.abs(ours - exact)) <= 1e-6 * exact.max()
    assert np.max(np.abs(ours[lit] - exact[lit]) / exact[lit]) <= 1e-4
    assert ours.sum() == pytest.approx(exact.sum(), rel=1e-8)
