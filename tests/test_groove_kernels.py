"""The groove extractor's compiled inner loops and the fast paths of a multi-pass job's frame
against the numpy they replace (an independent reference implementation in this file):
np.median, sliding-window medians, np.linalg.lstsq line fits, the KD-tree search of
Seam.closest."""

from __future__ import annotations

import numpy as np
import pytest

from seamtrack.features.groove import _groove_kernels as kern
from seamtrack.features.groove import extractor as groove
from seamtrack.geometry import seam as seam_module
from seamtrack.geometry.seam import Seam


def _local_v_numpy(qu, qv, ut, h, tol):  # the extractor's former numpy version
    sel = np.abs(qu - ut) <= h
    if np.count_nonzero(sel) < 3:
        return None
    a, b = qu[sel] - ut, qv[sel]
    if not (np.any(a <= 0) and np.any(a >= 0)):
        return None
    keep = np.abs(b - np.median(b)) <= max(
        5.0 * tol, 4.0 * float(np.median(np.abs(b - np.median(b))))
    )
    for _ in range(2):
        if np.count_nonzero(keep) < 3:
            return None
        A = np.column_stack([np.ones(np.count_nonzero(keep)), a[keep]])
        coef = np.linalg.lstsq(A, b[keep], rcond=None)[0]
        r = b - (coef[0] + coef[1] * a)
        keep = np.abs(r) <= 3.0 * tol
    return float(coef[0])


def _robust_uv_line_numpy(qu, qv, tol):  # the extractor's former numpy version
    n = len(qu)
    if n < 3:
        return None
    pick = np.unique(np.linspace(0, n - 1, min(n, 40)).round().astype(np.intp))
    i, j = np.triu_indices(len(pick), k=max(1, len(pick) // 3))
    i, j = pick[i], pick[j]
    ok = np.abs(qu[j] - qu[i]) > 1e-9
    if not np.any(ok):
        return None
    i, j = i[ok], j[ok]
    b = (qv[j] - qv[i]) / (qu[j] - qu[i])
    a = qv[i] - b * qu[i]
    count = (np.abs(qv[None, :] - (a[:, None] + b[:, None] * qu[None, :])) <= 2.0 * tol).sum(1)
    k = int(np.argmax(count))
    keep = np.abs(qv - (a[k] + b[k] * qu)) <= 2.0 * tol
    if np.count_nonzero(keep) < 3:
        return None
    A = np.column_stack([np.ones(np.count_nonzero(keep)), qu[keep]])
    coef = np.linalg.lstsq(A, qv[keep], rcond=None)[0]
    return float(coef[0]), float(coef[1])


def _surface(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A bumpy fill surface with noise and a few spikes, sorted along u."""
    qu = np.sort(rng.uniform(-6.0, 6.0, n))
    qv = 0.4 * np.cos(qu) + 0.05 * qu + rng.normal(0.0, 0.01, n)
    spikes = rng.choice(n, size=max(1, n // 20), replace=False)
    qv[spikes] += rng.uniform(-1.0, 1.0, len(spikes))
    return qu, qv


@pytest.mark.parametrize("n", [1, 2, 3, 4, 7, 8, 51, 200])
def test_median_is_numpys(n: int) -> None:
    rng = np.random.default_rng(n)
    x = rng.normal(size=n)
    assert groove.median_of(x) == np.median(x)
    x[rng.integers(n)] = np.nan
    assert np.isnan(groove.median_of(x))


@pytest.mark.parametrize("k", [5, 11, 101])
def test_running_median_is_numpys_sliding_median(k: int) -> None:
    rng = np.random.default_rng(k)
    v = rng.normal(size=300)
    want = np.pad(np.median(np.lib.stride_tricks.sliding_window_view(v, k), axis=1), k // 2,
                  mode="edge")  # fmt: skip
    assert np.array_equal(kern.running_median(v, k), want)


def test_line_fit_is_lstsq() -> None:
    rng = np.random.default_rng(3)
    for _ in range(50):
        a = rng.uniform(-3, 3, 20)
        b = 0.7 - 0.3 * a + rng.normal(0, 0.05, 20)
        keep = rng.uniform(size=20) < 0.7
        keep[:3] = True
        A = np.column_stack([np.ones(keep.sum()), a[keep]])
        want = np.linalg.lstsq(A, b[keep], rcond=None)[0]
        assert np.allclose(kern._line_fit(a, b, keep), want, rtol=0, atol=1e-12)
    # all at one a: lstsq's minimum-norm answer
    a, b = np.full(5, 2.0), np.array([1.0, 1.2, 0.8, 1.1, 0.9])
    want = np.linalg.lstsq(np.column_stack([np.ones(5), a]), b, rcond=None)[0]
    assert np.allclose(kern._line_fit(a, b, np.ones(5, dtype=bool)), want, atol=1e-12)


def test_local_v_and_robust_line_are_the_numpy_fits() -> None:
    rng = np.random.default_rng(7)
    compared = 0
    for trial in range(200):
        qu, qv = _surface(rng, int(rng.integers(2, 120)))
        tol = float(rng.uniform(0.005, 0.05))
        ut, h = float(rng.uniform(-6, 6)), float(rng.uniform(0.1, 2.0))
        want, got = _local_v_numpy(qu, qv, ut, h, tol), groove.surface_v_at(qu, qv, ut, h, tol)
        assert (want is None) == (got is None), trial
        if want is not None:
            assert got == pytest.approx(want, abs=1e-9)
            compared += 1
        want2, got2 = _robust_uv_line_numpy(qu, qv, tol), groove.robust_uv_fit(qu, qv, tol)
        assert (want2 is None) == (got2 is None), trial
        if want2 is not None:
            assert np.allclose(got2, want2, rtol=0, atol=1e-9)
    assert compared > 50


@pytest.mark.parametrize("n_points", [2, 7, 301])
def test_closest_without_the_tree_is_the_trees(
    n_points: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    t = np.linspace(0.0, 1.0, n_points)
    seam = Seam.from_points(np.column_stack([300 * t, 8 * np.sin(4 * t), 3 * np.cos(3 * t)]))
    rng = np.random.default_rng(n_points)
    queries = rng.normal(size=(60, 3)) * [120, 20, 20] + [150, 0, 0]
    direct = [seam.closest(q) for q in queries[:, None, :]]  # 1 point: every segment
    monkeypatch.setattr(seam_module, "_ALL_PAIRS", 0)  # the KD-tree's candidates
    for q, got in zip(queries[:, None, :], direct, strict=True):
        want = seam.closest(q)
        assert np.array_equal(got.segment, want.segment)
        assert np.array_equal(got.arc_length_mm, want.arc_length_mm)
        assert np.array_equal(got.points, want.points)
        assert np.array_equal(got.distance_mm, want.distance_mm)


def test_a_bottom_along_one_laser_ray_is_a_spike_streak_not_a_surface() -> None:
    """Points on one ray from the laser's origin over several mm of range are a reflection's
    streak; a fill surface across the rays, an empty V's root (one point) and a narrow gap's
    bottom 12 mm wide are not."""
    ray = np.array([0.037, 1.0]) / np.hypot(0.037, 1.0)
    streak = np.outer([104.0, 148.0, 192.0, 236.0, 280.0], ray)
    assert groove.along_a_ray(streak)
    assert not groove.along_a_ray(np.tile([[0.5, 98.0]], (5, 1)))  # a V's root
    fill = np.column_stack([np.linspace(-6.0, 6.0, 5), np.full(5, 110.0)])
    assert not groove.along_a_ray(fill)
    tilted = streak + np.column_stack([np.linspace(0.0, 2.0, 5), np.zeros(5)])
    assert not groove.along_a_ray(tilted)  # 2 mm across the rays: a surface


@pytest.mark.parametrize("k", [3, 5, 11, 51])
def test_running_median_cut_is_numpys_median_of_each_cut_window(k: int) -> None:
    """Each point's median over the window about it, cut short at the ends (the fits' level
    of a surface near a wall): the same numbers as ``np.median`` of each slice."""
    rng = np.random.default_rng(k)
    for n in (k, k + 1, 200):
        v = np.round(rng.normal(size=n), 2)  # ties, as on a quantized profile
        h = k // 2
        want = np.array([np.median(v[max(0, i - h) : i + h + 1]) for i in range(n)])
        assert np.array_equal(kern.running_median_cut(v, k), want)
