"""The trajectory tracker's compiled path arithmetic against an independent numpy statement of
it (the tracker's former vectorized code), and its path buffer against plain lists."""

from __future__ import annotations

import numpy as np
import pytest

from seamtrack.control.path_kernels import PathBuffer, off_line, smooth_tail


def _fit_rows(w: np.ndarray, ds: np.ndarray, raw: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = w.sum(axis=1)
    sx, sxx = (w * ds).sum(axis=1), (w * ds * ds).sum(axis=1)
    sy, sxy = w @ raw, (w * ds) @ raw
    det = n * sxx - sx * sx
    ok = (n >= 3) & (det > 1e-12 * np.maximum(n * sxx, 1e-300))
    safe = np.where(ok, det, 1.0)[:, None]
    return (
        (sxx[:, None] * sy - sx[:, None] * sxy) / safe,
        (n[:, None] * sxy - sx[:, None] * sy) / (safe),
        ok,
    )


def _smooth_numpy(raw: np.ndarray, s: np.ndarray, first: int, h: float, floor: float) -> np.ndarray:
    path = raw.copy()
    s_w, raw_w = s[first:], raw[first:]
    targets = np.flatnonzero(s_w >= s[-1] - h)
    ds = s_w[None, :] - s_w[targets, None]
    w = (np.abs(ds) <= h).astype(float)
    a, b, _ = _fit_rows(w, ds, raw_w)
    residual = np.linalg.norm(raw_w[None] - (a[:, None] + ds[..., None] * b[:, None]), axis=2)
    count = w.sum(axis=1).astype(int)
    ordered = np.sort(np.where(w > 0, residual, np.inf), axis=1)
    median = ordered[np.arange(len(ordered)), count // 2]
    limit = np.maximum(3.0 * np.where(np.isfinite(median), median, 0.0), floor)
    a, _, ok = _fit_rows(w * (residual <= limit[:, None]), ds, raw_w)
    for k, i in enumerate(targets):
        if ok[k]:
            path[first + i] = a[k]
    return path


@pytest.mark.parametrize("seed", range(6))
def test_smooth_tail_is_the_robust_local_line_fit(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 80))
    s = np.cumsum(rng.uniform(0.02, 0.1, n))
    raw = np.column_stack([s, 0.3 * np.sin(s), 0.01 * s**2]) + rng.normal(0, 0.01, (n, 3))
    bogus = rng.random(n) < 0.1
    raw[bogus] += rng.normal(0, 0.5, (int(bogus.sum()), 3))  # detections off the seam
    h = float(rng.uniform(0.2, 1.5))
    first = max(int(np.searchsorted(s, s[-1] - 2 * h)), 1)
    path = raw.copy()
    smooth_tail(raw, path, s, first, h, 0.05)
    np.testing.assert_allclose(path, _smooth_numpy(raw, s, first, h, 0.05), rtol=0, atol=1e-9)
    assert np.array_equal(
        path[: np.searchsorted(s, s[-1] - h)], raw[: np.searchsorted(s, s[-1] - h)]
    )


def test_off_line_is_the_distance_from_the_principal_axis() -> None:
    rng = np.random.default_rng(3)
    for _ in range(50):
        window = rng.normal(size=(int(rng.integers(3, 40)), 3)) * [5.0, 0.1, 0.05]
        point = rng.normal(size=3) * 3.0
        centre = window.mean(axis=0)
        direction = np.linalg.svd(window - centre, full_matrices=False)[2][0]
        v = point - centre
        expected = np.linalg.norm(v - (v @ direction) * direction)
        assert off_line(window, point) == pytest.approx(expected, abs=1e-9)


def test_path_buffer_keeps_the_points_a_list_would() -> None:
    rng = np.random.default_rng(1)
    start = np.zeros(3)
    buffer, points, arcs = PathBuffer(start, capacity=4), [start], [0.0]
    for k in range(300):
        p = rng.normal(size=3)
        buffer.append(p, float(k + 1))
        points.append(p)
        arcs.append(float(k + 1))
        if k % 7 == 6:  # trim the oldest, as the tracker does behind the set-point
            buffer.drop(3)
            del points[:3], arcs[:3]
        assert len(buffer) == len(points)
    np.testing.assert_array_equal(buffer.raw, np.array(points))
    np.testing.assert_array_equal(buffer.path, np.array(points))
    np.testing.assert_array_equal(buffer.s, np.array(arcs))
