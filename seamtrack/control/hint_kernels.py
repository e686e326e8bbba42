"""The trajectory tracker's hint to the extractor, compiled: where the robot program's seam
crosses the laser plane, shifted by how far the measured seam lies from the program (the
arithmetic of :func:`~seamtrack.sensing.profiles.hint_from_path`,
:func:`~seamtrack.sensing.scan.laser_plane_crossings` and the closest points of
:meth:`Seam.closest <seamtrack.geometry.seam.Seam.closest>`); the tracker calls it once a frame
through :func:`seamtrack.control.path_kernels.tracker_hint`."""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.jit import KERNEL

FloatArray = NDArray[np.float64]


@numba.njit(**KERNEL)
def column_medians(a: FloatArray) -> FloatArray:
    """``np.median(a, axis=0)`` of an (m, 3) array (m >= 1), compiled."""
    out = np.empty(a.shape[1])
    for c in range(a.shape[1]):
        out[c] = np.median(a[:, c])
    return out


@numba.njit(**KERNEL)
def plane_crossings(points: FloatArray, T_world_sensor: FloatArray) -> FloatArray:
    """:func:`~seamtrack.sensing.scan.laser_plane_crossings` compiled (the same half-open
    test and interpolation, equal to rounding): (k, 2) the (y_L, z_L) where the polyline
    ``points`` (world) crosses the laser plane x_L = 0, in order."""
    R = T_world_sensor[:3, :3]
    t = T_world_sensor[:3, 3]
    n = points.shape[0]
    # R^T (point - origin): its x_L for every point, its y_L, z_L only where the polyline
    # crosses (the same sums where they are needed).
    x = np.empty(n)
    for i in range(n):
        d0, d1, d2 = points[i, 0] - t[0], points[i, 1] - t[1], points[i, 2] - t[2]
        x[i] = R[0, 0] * d0 + R[1, 0] * d1 + R[2, 0] * d2
    out = np.empty((n, 2))
    k = 0
    for i in range(n - 1):
        x0, x1 = x[i], x[i + 1]
        if (x0 <= 0 and x1 > 0) or (x0 >= 0 and x1 < 0):
            y0, z0 = _in_plane(points[i], R, t)
            y1, z1 = _in_plane(points[i + 1], R, t)
            w = x0 / (x0 - x1)
            out[k, 0] = y0 + w * (y1 - y0)
            out[k, 1] = z0 + w * (z1 - z0)
            k += 1
    if n and x[n - 1] == 0:
        out[k, 0], out[k, 1] = _in_plane(points[n - 1], R, t)
        k += 1
    return out[:k].copy()


@numba.njit(**KERNEL, inline="always")
def _in_plane(point: FloatArray, R: FloatArray, t: FloatArray) -> tuple[float, float]:
    """(y_L, z_L) of a world point: rows 1 and 2 of R^T (point - origin)."""
    d0, d1, d2 = point[0] - t[0], point[1] - t[1], point[2] - t[2]
    return R[0, 1] * d0 + R[1, 1] * d1 + R[2, 1] * d2, R[0, 2] * d0 + R[1, 2] * d1 + R[2, 2] * d2


#: Segments per chunk of a polyline in :func:`polyline_chunks`.
CHUNK_SEGMENTS = 16
#: Margin (mm) of a chunk's lower bound: far above the rounding of a distance.
_CHUNK_MARGIN_MM = 1e-6


def polyline_chunks(a: FloatArray, d: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Bounding spheres of the segments ``a + t d`` in chunks of :data:`CHUNK_SEGMENTS`:
    centres (k, 3) and radii (k,), each sphere holding its segments' end points (so the whole
    segments), for :func:`closest_on_polyline`'s pruning."""
    n = len(a)
    k = (n + CHUNK_SEGMENTS - 1) // CHUNK_SEGMENTS
    centres, radii = np.empty((k, 3)), np.empty(k)
    for c in range(k):
        ends = np.concatenate([a[c * CHUNK_SEGMENTS : (c + 1) * CHUNK_SEGMENTS],
                               (a + d)[c * CHUNK_SEGMENTS : (c + 1) * CHUNK_SEGMENTS]])  # fmt: skip
        centres[c] = 0.5 * (ends.min(axis=0) + ends.max(axis=0))
        radii[c] = float(np.max(np.linalg.norm(ends - centres[c], axis=1))) * (1 + 1e-9)
    return centres, radii


class Polyline(NamedTuple):
    """A polyline as the hint's kernels read it: its ``points`` (m, 3), its segments
    ``a + t d`` (t in [0, 1]) and the bounding spheres of their chunks (``centres``,
    ``radii``: :func:`polyline_chunks`; none: every segment looked at, in order)."""

    points: FloatArray
    a: FloatArray
    d: FloatArray
    centres: FloatArray
    radii: FloatArray


def polyline(points: FloatArray, chunked: bool = True) -> Polyline:
    """The :class:`Polyline` through ``points`` (m, 3), with its chunks' bounding spheres
    (``chunked``) or none."""
    p = np.ascontiguousarray(points, dtype=np.float64)
    a = np.ascontiguousarray(p[:-1])
    d = np.ascontiguousarray(p[1:] - a)
    centres, radii = polyline_chunks(a, d) if chunked else (np.empty((0, 3)), np.empty(0))
    return Polyline(p, a, d, centres, radii)


@numba.njit(**KERNEL, inline="always")
def _nearer(
    q0: float, q1: float, q2: float, a: FloatArray, d: FloatArray, c: int, best: float,
    bt: float, bs: int,
) -> tuple[float, float, int]:  # fmt: skip
    """Segment ``c`` against the best so far (distance, t, segment): the nearer, the lower
    segment on a tie (:func:`~seamtrack.geometry.nearest.nearest_of`'s arithmetic)."""
    dd = max(d[c, 0] * d[c, 0] + d[c, 1] * d[c, 1] + d[c, 2] * d[c, 2], 1e-300)
    num = (q0 - a[c, 0]) * d[c, 0] + (q1 - a[c, 1]) * d[c, 1]
    num += (q2 - a[c, 2]) * d[c, 2]
    t = min(max(num / dd, 0.0), 1.0)
    e0 = q0 - (a[c, 0] + t * d[c, 0])
    e1 = q1 - (a[c, 1] + t * d[c, 1])
    e2 = q2 - (a[c, 2] + t * d[c, 2])
    dist = np.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
    if dist < best or (dist == best and c < bs):
        return dist, t, c
    return best, bt, bs


@numba.njit(**KERNEL)
def _reused_rows(
    points: FloatArray, last_points: FloatArray, last_near: FloatArray, near: FloatArray
) -> int:
    """Copy into ``near`` the answers ``last_near`` holds for the first rows of ``points``
    (where ``points`` starts inside ``last_points`` and goes on alike); how many rows."""
    m = points.shape[0]
    k = 0
    for j in range(last_points.shape[0]):
        if (last_points[j, 0] == points[0, 0] and last_points[j, 1] == points[0, 1]
                and last_points[j, 2] == points[0, 2]):  # fmt: skip
            k = min(last_points.shape[0] - j, m)
            for r in range(k):
                for c in range(3):
                    if last_points[j + r, c] != points[r, c]:
                        k = 0
            for r in range(k):
                near[r] = last_near[j + r]
            break
    return k


@numba.njit(**KERNEL)
def closest_on_polyline(
    points: FloatArray, last_points: FloatArray, last_near: FloatArray, line: Polyline
) -> FloatArray:
    """(m, 3) the closest points to ``points`` on the segments of ``line`` (the nearest of
    all, the first on a tie: :func:`~seamtrack.geometry.nearest.nearest_of`'s arithmetic),
    reusing ``last_near`` for the rows ``points`` shares with ``last_points`` (a window sliding
    along the same stored points: ``points`` starts inside ``last_points``). With the
    segments' bounding spheres of :func:`polyline_chunks`, the chunk nearest a point first,
    then only the chunks whose sphere comes nearer than the best found (a lower bound, with a
    margin far above rounding); without, every segment in order. The same points: the
    nearest segment, the first on a tie, whatever the order the segments are looked at in."""
    a, d, centres, radii = line.a, line.d, line.centres, line.radii
    m = points.shape[0]
    near = np.empty((m, 3))
    k = _reused_rows(points, last_points, last_near, near)
    n_seg, n_chunk = a.shape[0], radii.shape[0]
    lower = np.empty(n_chunk)
    for r in range(k, m):
        best, bt, bs = np.inf, 0.0, 0
        q0, q1, q2 = points[r, 0], points[r, 1], points[r, 2]
        if n_chunk == 0:
            for c in range(n_seg):
                best, bt, bs = _nearer(q0, q1, q2, a, d, c, best, bt, bs)
        else:
            first = 0
            for h in range(n_chunk):
                e0, e1, e2 = q0 - centres[h, 0], q1 - centres[h, 1], q2 - centres[h, 2]
                lower[h] = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2) - radii[h]
                if lower[h] < lower[first]:
                    first = h
            for o in range(n_chunk):
                h = first if o == 0 else (o - 1 if o <= first else o)
                if o > 0 and lower[h] > best + _CHUNK_MARGIN_MM:
                    continue
                for c in range(h * CHUNK_SEGMENTS, min((h + 1) * CHUNK_SEGMENTS, n_seg)):
                    best, bt, bs = _nearer(q0, q1, q2, a, d, c, best, bt, bs)
        for c in range(3):
            near[r, c] = a[bs, c] + bt * d[bs, c]
    return near


@numba.njit(**KERNEL)
def program_hint(
    T: FloatArray, last: FloatArray, direction: FloatArray, program: Polyline,
    window: FloatArray, last_window: FloatArray, last_near: FloatArray,
) -> tuple[bool, float, float, float, float, float, FloatArray]:  # fmt: skip
    """The trajectory tracker's hint in one call (:meth:`TrajectoryTracker.hint
    <seamtrack.control.trajectory.TrajectoryTracker.hint>`, its arithmetic): the straight
    path's crossing of the laser plane (``hint_from_path``: through ``last`` heading
    ``direction``, world), the ``program`` seam's crossings (:func:`plane_crossings`), shifted
    by the median offset of the measured ``window`` from the program (its closest points by
    :func:`closest_on_polyline`, reusing ``last_near``), the crossing nearest the straight
    one.

    Returns (found, y_L, z_L, the direction in the sensor frame (3), the window's closest
    points on the program, for the next call).
    """
    near = closest_on_polyline(window, last_window, last_near, program)
    R = T[:3, :3]
    p = np.empty(3)
    v = np.empty(3)
    for c in range(3):  # R^T (last - origin), R^T direction
        p[c] = (R[0, c] * (last[0] - T[0, 3]) + R[1, c] * (last[1] - T[1, 3])
                + R[2, c] * (last[2] - T[2, 3]))  # fmt: skip
        v[c] = R[0, c] * direction[0] + R[1, c] * direction[1] + R[2, c] * direction[2]
    norm = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    if not norm > 1e-12 or abs(v[0]) < 1e-6 * norm:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, near
    v /= norm
    k = p[0] / v[0]
    sy, sz = p[1] - k * v[1], p[2] - k * v[2]
    if not (math.isfinite(p[0] - k * v[0]) and math.isfinite(sy) and math.isfinite(sz)):
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, near
    sign = 1.0 if v[0] > 0 else -1.0
    crossings = plane_crossings(program.points, T)
    if crossings.shape[0] == 0:
        return False, 0.0, 0.0, 0.0, 0.0, 0.0, near
    offset = column_medians(window - near)
    shift1 = R[0, 1] * offset[0] + R[1, 1] * offset[1] + R[2, 1] * offset[2]
    shift2 = R[0, 2] * offset[0] + R[1, 2] * offset[1] + R[2, 2] * offset[2]
    best, y, z = np.inf, 0.0, 0.0
    for i in range(crossings.shape[0]):
        ey, ez = crossings[i, 0] + shift1, crossings[i, 1] + shift2
        dist = math.hypot(ey - sy, ez - sz)
        if dist < best:
            best, y, z = dist, ey, ez
    return True, y, z, sign * v[0], sign * v[1], sign * v[2], near
