"""The extractors' compiled kernels (seamtrack.features._segmentation, robust.front) against
independent references: numpy's SVD for line fits, brute-force two-line splits, sorting for
medians, and the numpy formulation of the robust front end (seamtrack.features.robust's
helpers)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from seamtrack.features import _segmentation as kernels
from seamtrack.features.line_geometry import fit_line
from seamtrack.features.lines import segment_profile
from seamtrack.features.refusal import Refusal
from seamtrack.features.robust import (
    DEFAULT_RESOLUTION_MM,
    NOISE_LAGS,
    TOL_RESOLUTIONS,
    _kept,
    _median5,
    _spacing,
    detours,
    front_end,
    noise_sigma,
    range_quantum,
)
from seamtrack.features.select import BUCKETS, kth_nonneg
from seamtrack.features.synthetic import Imperfections, synthetic_profile
from seamtrack.sensing.sensor import preset


def _svd_line(q: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
    """Centroid, unit direction (sign: first point to last), rms residual by SVD."""
    c = q.mean(axis=0)
    _, s, vt = np.linalg.svd(q - c, full_matrices=False)
    u = vt[0] if vt[0] @ (q[-1] - q[0]) >= 0 else -vt[0]
    rms = s[-1] / math.sqrt(len(q)) if len(s) > 1 else 0.0
    return c, u, rms


@pytest.mark.parametrize("seed", range(5))
def test_fit_line_equals_svd(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 400))
    angle = rng.uniform(-np.pi, np.pi)
    t = np.sort(rng.uniform(-20, 20, n))
    p = np.column_stack([t * np.cos(angle), t * np.sin(angle)]) + rng.normal(0, 0.05, (n, 2))
    p += rng.uniform(-50, 50, 2)
    idx = np.sort(rng.choice(n, size=max(2, n // 2), replace=False)).astype(np.int64)
    cy, cz, uy, uz, rms, along = fit_line(p, idx)
    c, u, r = _svd_line(p[idx])
    np.testing.assert_allclose([cy, cz], c, atol=1e-9)
    np.testing.assert_allclose([uy, uz], u, atol=1e-9)
    assert rms == pytest.approx(r, abs=1e-9)
    np.testing.assert_allclose(along, (p[idx] - c) @ u, atol=1e-8)


@pytest.mark.parametrize("n", [1, 2, 3, 4, 7, 24, 25, 96, 97, 100, 255, 256, 1001, 2048])
def test_kth_nonneg_equals_sort(n: int) -> None:
    """Counted on the bits, bucketed around a sample's median: the sorted array's k-th, bit
    for bit (sorted, reversed, clustered, repeating, zero, subnormal and huge values
    included, where a sample can mislead)."""
    rng = np.random.default_rng(n)
    normal = np.abs(rng.normal(size=n))
    cases = (
        normal,
        np.sort(normal),
        np.sort(normal)[::-1],
        np.abs(np.where(np.arange(n) % 2 == 0, 0.0, 1e6) + rng.normal(size=n)),
        rng.integers(0, 3, n).astype(float),
        np.round(normal * 5.0) * 0.02,
        np.zeros(n),
        np.where(rng.random(n) < 0.5, 0.0, normal * 1e-300),
        np.abs(rng.standard_cauchy(n)) * 1e-3,
        normal * 1e300,
    )
    work = np.empty(n, dtype=np.int64)
    hist = np.empty(2 * BUCKETS, dtype=np.int64)
    for x in cases:
        x = np.ascontiguousarray(x)
        for k in sorted({0, n // 3, n // 2, n - 1}):
            assert kth_nonneg(x, n, k, work, hist).hex() == np.sort(x)[k].hex()


@pytest.mark.parametrize("seed", range(4))
def test_best_split_equals_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    k = int(rng.integers(12, 80))
    corner = int(rng.integers(4, k - 4))
    y = np.arange(k, dtype=float) * 0.1
    z = np.where(np.arange(k) < corner, 0.3 * y, 0.3 * y[corner] - 1.2 * (y - y[corner]))
    p = np.column_stack([y, z + rng.normal(0, 0.01, k)])

    def cost(q: np.ndarray) -> float:
        return float(np.linalg.svd(q - q.mean(axis=0), compute_uv=False)[-1] ** 2)

    both = {b: cost(p[:b]) + cost(p[b:]) for b in range(3, k - 2)}
    b, split, single = kernels.best_split(p, 0, k, 3)
    assert split == pytest.approx(min(both.values()), rel=1e-9, abs=1e-12)
    assert both[b] == pytest.approx(min(both.values()), rel=1e-9, abs=1e-12)
    assert single == pytest.approx(cost(p), rel=1e-9, abs=1e-12)


def _profiles(level: Imperfections, joint: str, n: int, seed: int) -> list:
    rng = np.random.default_rng(seed)
    sensor = preset("paper")
    return [
        synthetic_profile(
            joint,
            sensor,
            rng=rng,
            rays=1024,
            imperfections=level,
            pitch_deg=rng.uniform(-15, 15),
            roll_deg=rng.uniform(-15, 15),
        )[0]
        for _ in range(n)
    ]


LEVELS = [
    Imperfections(),
    Imperfections(noise_mm=0.05),
    Imperfections(noise_mm=0.05, outlier_fraction=0.05, reflection_probability=1.0),
    Imperfections(noise_mm=0.05, dropout_runs=5, dropout_max_columns=10),
]


@pytest.mark.parametrize("level", LEVELS)
def test_front_end_equals_numpy_formulation(level: Imperfections) -> None:
    """The compiled front end gives the points, spikes, noise, tolerance, runs and detours
    of the numpy formulation (robust's helpers, composed as documented)."""
    for profile in _profiles(level, "v-groove", 4, 7):
        fe = front_end(profile)
        assert not isinstance(fe, Refusal)
        p, columns = _kept(profile)
        spacing = _spacing(p)
        q = range_quantum(np.ascontiguousarray(p[:, 1]))
        resolution = q if q > 0 else DEFAULT_RESOLUTION_MM
        floor = TOL_RESOLUTIONS * resolution
        rounding = q / math.sqrt(12.0)
        sigma = max(noise_sigma(p), rounding)
        keep = np.abs(p[:, 1] - _median5(p[:, 1])) <= max(6 * sigma, 4 * floor, 4 * spacing)
        np.testing.assert_array_equal(fe.spike_columns, columns[~keep])
        p, columns = p[keep], columns[keep]
        np.testing.assert_array_equal(fe.points, p)
        np.testing.assert_array_equal(fe.columns, columns)
        sigma = max(noise_sigma(p, NOISE_LAGS), rounding)
        tol = max(floor, 5.0 * sigma)
        assert fe.sigma == sigma and fe.tol == tol and fe.spacing == spacing
        assert fe.quantum == q and fe.floor == floor
        gaps = np.hypot(*np.diff(p, axis=0).T)
        runs = np.concatenate([[0], np.flatnonzero(gaps > max(6 * spacing, 2 * tol, 0.1)) + 1])
        np.testing.assert_array_equal(fe.runs, np.append(runs, len(p)))
        off = detours(p, fe.runs[:-1], fe.runs[1:], tol, 8, 3.0)
        np.testing.assert_array_equal(fe.stray, np.repeat(off, np.diff(fe.runs)))


@pytest.mark.parametrize("level", LEVELS)
@pytest.mark.parametrize("joint", ["v-groove", "square-butt", "lap"])
def test_pieces_are_trimmed_tls_lines(level: Imperfections, joint: str) -> None:
    """Every piece: in column order, disjoint from the others, inside one run and off the
    detours, its inliers within the trim of their own SVD line, whose centroid, direction
    and rms the piece carries; together they cover most of the surface."""
    for profile in _profiles(level, joint, 3, 11):
        seg = segment_profile(profile)
        assert not isinstance(seg, Refusal)
        trim = max(3.0 * seg.sigma, 0.5 * (TOL_RESOLUTIONS * seg.resolution))
        last = -1
        covered = 0
        for line in seg.lines:
            idx = line.index
            assert len(idx) >= 8 and idx[0] > last and np.all(np.diff(idx) > 0)
            last = int(idx[-1])
            run = np.searchsorted(seg.runs, idx[0], side="right")
            assert idx[-1] < seg.runs[run] and not seg.stray[idx].any()
            c, u, rms = _svd_line(seg.points[idx])
            np.testing.assert_allclose(line.centroid, c, atol=1e-9)
            np.testing.assert_allclose(line.direction, u, atol=1e-9)
            assert line.rms == pytest.approx(rms, abs=1e-9)
            # trimmed around the first fit over the piece's span: the inliers lie within
            # the trim of a line through them (a loose bound, as the refit moves the line)
            assert np.abs((seg.points[idx] - c) @ np.array([-u[1], u[0]])).max() <= 2 * trim
            covered += len(idx)
        assert covered >= 0.6 * np.count_nonzero(~seg.stray)


def test_split_pieces_lie_within_tolerance_of_their_chord() -> None:
    """Douglas-Peucker: each piece's points lie within the tolerance of its chord, the
    pieces tile the run, and a run needing more pieces than the limit gives up."""
    rng = np.random.default_rng(3)
    y = np.linspace(0, 30, 600)
    p = np.column_stack([y, 2.0 * np.sin(y / 3.0) + rng.normal(0, 0.005, y.size)])
    lo = np.empty(66, dtype=np.int64)
    hi = np.empty(66, dtype=np.int64)
    n = kernels._split(p, 0, len(p) - 1, 0.05, 64, lo, hi)
    assert 2 < n <= 64
    assert lo[0] == 0 and hi[n - 1] == len(p) - 1
    np.testing.assert_array_equal(lo[1:n], hi[: n - 1])  # neighbours share their split point
    for a, b in zip(lo[:n], hi[:n], strict=True):
        chord = p[b] - p[a]
        q = p[a : b + 1] - p[a]
        d = np.abs(q[:, 0] * chord[1] - q[:, 1] * chord[0]) / np.hypot(*chord)
        assert d.max() <= 0.05
    assert kernels._split(p, 0, len(p) - 1, 1e-4, 8, lo, hi) == -1
