"""The trajectory tracker's compiled path arithmetic against an independent numpy statement of
it (the tracker's former vectorized code), and its path buffer against plain lists."""

from __future__ import annotations

import numpy as np
import pytest

from seamtrack.control.hint_kernels import polyline
from seamtrack.control.path_kernels import (
    PathBuffer,
    closest_on_polyline,
    corner_envelope,
    kth_smallest,
    off_line,
    program_hint,
    smooth_tail,
    store_tail,
)


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


@pytest.mark.parametrize("seed", range(4))
def test_kth_smallest_is_the_sorted_arrays_kth(seed: int) -> None:
    """Quickselect (the smoothing's median residual) against a full sort: the same value for
    every k, with ties (values drawn from a few levels) and without."""
    rng = np.random.default_rng(seed)
    for n in (1, 2, 3, 7, 20, 41):
        for values in (rng.random(n), rng.integers(0, 3, n).astype(float)):
            for k in range(n):
                scratch = np.concatenate([values, rng.random(5)])  # rows past n untouched
                tail = scratch[n:].copy()
                assert kth_smallest(scratch, n, k) == np.sort(values)[k]
                assert np.array_equal(np.sort(scratch[:n]), np.sort(values))
                assert np.array_equal(scratch[n:], tail)


@pytest.mark.parametrize("seed", range(3))
def test_chunked_closest_points_are_the_full_scans(seed: int) -> None:
    """The hint's closest points with the chunks' bounding spheres (most segments never looked
    at) against every segment looked at in order: the same points to the last bit, for
    points near a winding polyline, far from it, and on its vertices (ties of two segments)."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 200))
    turn = np.cumsum(rng.normal(0.0, 0.3, n))
    steps = np.column_stack([np.cos(turn), np.sin(turn), rng.normal(0.0, 0.2, n)])
    program = np.cumsum(steps * rng.uniform(0.2, 2.0, (n, 1)), axis=0) + 100.0
    chunked_line = polyline(program)
    a, d, centres, radii = chunked_line.a, chunked_line.d, chunked_line.centres, chunked_line.radii
    near = program[rng.integers(0, n, 40)] + rng.normal(0.0, 0.05, (40, 3))
    far = rng.uniform(-50.0, 250.0, (20, 3))
    points = np.concatenate([near, far, program[rng.integers(0, n, 10)]])
    empty = np.empty((0, 3))
    full = closest_on_polyline(points, empty, empty, polyline(program, chunked=False))
    chunked = closest_on_polyline(points, empty, empty, chunked_line)
    assert np.array_equal(chunked, full)
    # Each sphere holds its segments.
    for c, (centre, radius) in enumerate(zip(centres, radii, strict=True)):
        ends = np.concatenate([a[16 * c : 16 * c + 16], (a + d)[16 * c : 16 * c + 16]])
        assert np.linalg.norm(ends - centre, axis=1).max() <= radius


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


def _envelope_numpy(
    p: np.ndarray, s: np.ndarray, w: float, a_lat: float, accel: float, speed: float
) -> np.ndarray:
    """The tracker's former vectorized corner envelope."""
    back = np.searchsorted(s, s - w)
    fwd = np.minimum(np.searchsorted(s, s + w), len(s) - 1)
    d1, d2 = p - p[back], p[fwd] - p
    n1, n2 = np.linalg.norm(d1, axis=1), np.linalg.norm(d2, axis=1)
    ok = (n1 > 0.5 * w) & (n2 > 0.5 * w)
    cos = np.sum(d1 * d2, axis=1) / np.where(ok, n1 * n2, 1.0)
    turn = np.where(ok, np.arccos(np.clip(cos, -1.0, 1.0)), 0.0)
    curvature = turn / np.where(ok, 0.5 * (n1 + n2), 1.0)
    v_allow = np.sqrt(a_lat / np.maximum(curvature, 1e-12))
    reach = np.minimum(v_allow, speed) ** 2 + 2.0 * accel * s
    suffix = np.minimum.accumulate(reach[::-1])[::-1]
    return np.sqrt(np.maximum(suffix - 2.0 * accel * s, 0.0))


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_corner_envelope_is_the_braking_suffix_minimum(seed: int) -> None:
    """A path with a 90 deg corner and jitter: the compiled envelope equals the numpy one (to
    an ulp of the arccos), slows at the corner and never exceeds the welding speed."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 20.0, 0.2)
    corner = np.column_stack([np.minimum(t, 10.0), np.maximum(t - 10.0, 0.0), 0 * t])
    p = corner + rng.normal(0.0, 0.01, corner.shape)
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    got = corner_envelope(p, s, 3.0, 20.0, 500.0, 10.0)
    want = _envelope_numpy(p, s, 3.0, 20.0, 500.0, 10.0)
    np.testing.assert_allclose(got, want, rtol=1e-12, atol=0.0)
    at_corner = int(np.argmin(np.abs(s - s[50])))
    assert got[at_corner] < 0.7 * 10.0 and got.max() <= 10.0 * (1 + 1e-12)


def test_program_hint_is_the_straight_crossing_and_the_programs() -> None:
    """The compiled hint against its parts in numpy: the straight path's crossing of the laser
    plane (hint_from_path), the program's crossings (laser_plane_crossings) shifted by the
    median offset of the measured window from the program (Seam.closest), the nearest."""
    from seamtrack.geometry.seam import Seam
    from seamtrack.sensing.profiles import hint_from_path
    from seamtrack.sensing.scan import laser_plane_crossings

    rng = np.random.default_rng(5)
    # A program seam with a corner, and measured points 0.3 mm beside it with noise.
    program = np.array([[0.0, 0.0, 0.0], [50.0, 0.0, 0.0], [50.0, 40.0, 0.0]])
    seam = Seam.from_points(program)
    x = np.arange(30.0, 45.0, 0.25)
    window = np.column_stack([x, 0.3 + rng.normal(0, 0.02, len(x)), 0.1 + 0 * x])
    direction = np.array([1.0, 0.0, 0.0])
    # A sensor ahead, looking down, its laser plane x - y = 46 across both legs of the corner.
    r = np.sqrt(0.5)
    T = np.eye(4)
    T[:3, :3] = np.column_stack([(r, -r, 0.0), (-r, -r, 0.0), (0.0, 0.0, -1.0)])
    T[:3, 3] = (46.0, 0.0, 90.0)
    line = polyline(program, chunked=False)
    found, y, z, dx, dy, dz, near = program_hint(
        T, window[-1], direction, line, window, np.empty((0, 3)), np.empty((0, 3))
    )
    straight = hint_from_path(T, window[-1], direction)
    assert straight is not None and found
    offset = np.median(window - seam.closest(window).points, axis=0)
    expected = laser_plane_crossings(seam, T) + (T[:3, :3].T @ offset)[1:]
    k = int(np.argmin(np.hypot(*(expected - straight.point_laser).T)))
    np.testing.assert_allclose((y, z), expected[k], atol=1e-12)
    np.testing.assert_allclose((dx, dy, dz), straight.direction, atol=1e-15)
    np.testing.assert_allclose(near, seam.closest(window).points, atol=1e-12)
    assert len(expected) == 2  # both legs cross: the choice is real
    # Reusing the window's closest points gives the same answer.
    again = program_hint(T, window[-1], direction, line, window, window[:-3], near)
    assert again[:6] == (found, y, z, dx, dy, dz)
    # A path along the laser plane crosses it nowhere: no hint.
    along = program_hint(T, window[-1], np.array([r, r, 0.0]), line, window, window, near)
    assert not along[0]


@pytest.mark.parametrize("seed", range(4))
def test_store_tail_is_smoothing_trim_and_envelope(seed: int) -> None:
    """The tracker's step after storing a point, in one call, against its three parts: the
    numpy smoothing, the buffer's cut behind the set-point and the numpy envelope over the
    settled path (rows the call names, after the cut)."""
    from seamtrack.control import path_kernels as pk

    rng = np.random.default_rng(seed)
    n = int(rng.integers(30, 120))
    s = np.concatenate([[0.0], np.cumsum(rng.uniform(0.05, 0.3, n - 1))])
    turn = np.clip(s - s[n // 2], 0.0, None)
    raw = np.column_stack([s - turn, turn, 0 * s]) + rng.normal(0, 0.01, (n, 3))
    path = raw.copy()
    sp = np.zeros(pk.SETPOINT_FIELDS)
    sp[pk.S_SET] = float(rng.uniform(0.0, s[-1]))
    par = np.zeros(pk.TAIL_FIELDS)
    par[[pk.T_SMOOTH, pk.T_INLIER, pk.T_BUFFER, pk.T_CORNER, pk.T_WINDOW]] = (
        1.0,
        0.05,
        3.0,
        0.5,
        2.0,
    )
    par[[pk.T_A_LAT, pk.T_ACCEL, pk.T_SPEED]] = 5.0, 10.0, 8.0
    cut, what, i0, settled, v = store_tail(raw, path, s, sp, par, np.nan)
    first = max(int(np.searchsorted(s, s[-1] - 2.0)), 1)
    np.testing.assert_allclose(path, _smooth_numpy(raw, s, first, 1.0, 0.05), rtol=0, atol=1e-12)
    assert cut == max(int(np.searchsorted(s, sp[pk.S_SET] - 3.0)) - 1, 0)
    kept, points = s[cut:], path[cut:]
    want_settled = int(np.searchsorted(kept, kept[-1] - 2.0, side="right"))
    want_i0 = max(int(np.searchsorted(kept, sp[pk.S_SET] - 2.0)), 1)
    if want_settled - want_i0 < 3:
        assert what == 1
        return
    assert (what, i0, settled) == (2, want_i0, want_settled)
    rows = slice(i0, settled)
    want = _envelope_numpy(points[rows], kept[rows], 2.0, 5.0, 10.0, 8.0)
    np.testing.assert_allclose(v, want, rtol=1e-12, atol=0.0)
    # An envelope refreshed less than half a window ago is kept.
    again = store_tail(raw, path.copy(), s, sp, par, float(kept[settled - 1]))
    assert again[1] == 0


def test_a_spot_measured_again_behind_the_newest_point_is_not_stored() -> None:
    """While the robot starts, the sensor sees about one spot and its points scatter: one
    0.18 mm behind the newest along the path (multipass-varying-gap's last cap bead) was
    stored, the path doubled back, the set-point stepped back 0.27 mm and the torch slowed
    to half speed, laying a bead 60 % fat. A point more than min_spacing behind, within
    max_jump, is now too close; one beside the newest at the same x (a lateral step the
    seam really makes), or ahead, is stored as before."""
    from seamtrack.control import path_kernels as pk

    def take(buf, point):
        sp, par = np.zeros(pk.SETPOINT_FIELDS), np.zeros(pk.TAIL_FIELDS)
        par[[pk.T_SMOOTH, pk.T_INLIER, pk.T_BUFFER, pk.T_WINDOW]] = 1.0, 0.05, 100.0, 3.0
        par[[pk.T_ACCEL, pk.T_SPEED]] = 10.0, 8.0
        return buf.take(np.asarray(point, float), 0.05, 0.5, 5.0, sp, par, np.nan)[0]

    buf = PathBuffer(np.array([4.5, 11.81, 20.0]))
    for x in np.arange(5.0, 10.0, 0.5):
        buf.append(np.array([x, 11.81, 20.0]), float(buf.s[-1]) + 0.5)
    assert take(buf, [10.231, 11.81, 20.0]) == pk.STORED
    assert take(buf, [10.051, 11.811, 20.0]) == pk.TOO_CLOSE  # 0.18 mm behind
    assert take(buf, [10.231, 12.11, 20.0]) == pk.STORED  # beside it: the seam steps
    assert take(buf, [10.75, 11.81, 20.0]) == pk.STORED  # ahead
    assert len(buf) == 14  # the start, 10 points, then 3 of the 4 offered
