"""The trajectory tracker's stored path in growable arrays, and its per-frame arithmetic compiled.

Each stored seam point costs the tracker a local smoothing of the path's tail (a robust line fit
per point whose window the new point entered) and, before it, an outlier test against the line
through the last few millimetres of raw points. On numpy these are a few dozen calls on arrays
of ~40 rows, which cost 0.1-0.2 ms per frame, more than the ray casting of the frame. Here they
are plain loops (:func:`smooth_tail`, :func:`off_line`), on the arrays of a :class:`PathBuffer`
that holds the points in place (no list of arrays to convert at every frame).
"""

from __future__ import annotations

import math
from typing import cast

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.control.hint_kernels import Polyline
from seamtrack.control.hint_kernels import closest_on_polyline as closest_on_polyline
from seamtrack.control.hint_kernels import column_medians as column_medians
from seamtrack.control.hint_kernels import plane_crossings as plane_crossings
from seamtrack.control.hint_kernels import program_hint as program_hint
from seamtrack.jit import KERNEL, compile_for

FloatArray = NDArray[np.float64]
#: An int64 0: numba types a literal 0 as ``Literal[int](0)`` and compiles the kernel it
#: reaches once more for it, a loop counter's start too.
_ZERO = cast(int, np.int64(0))


class PathBuffer:
    """Raw and smoothed points (n, 3) and their arc lengths (n,) in arrays that grow by doubling;
    dropping the oldest points moves a start index (``raw``, ``path``, ``s`` are views)."""

    def __init__(self, start: FloatArray, capacity: int = 1024) -> None:
        self._raw = np.empty((capacity, 3))
        self._path = np.empty((capacity, 3))
        self._s = np.empty(capacity)
        self._raw[0] = self._path[0] = start
        self._s[0] = 0.0
        self._lo, self._n = 0, 1

    def __len__(self) -> int:
        return self._n

    @property
    def raw(self) -> FloatArray:
        return self._raw[self._lo : self._lo + self._n]

    @property
    def path(self) -> FloatArray:
        return self._path[self._lo : self._lo + self._n]

    @property
    def s(self) -> FloatArray:
        return self._s[self._lo : self._lo + self._n]

    def append(self, point: FloatArray, s: float) -> None:
        self.make_room()
        end = self._lo + self._n
        self._raw[end] = self._path[end] = point
        self._s[end] = s
        self._n += 1

    def take(
        self, point: FloatArray, min_spacing: float, max_jump: float, fit_mm: float,
        sp: FloatArray, par: FloatArray, env_last: float,
    ) -> tuple[int, float, int, int, int, int, FloatArray]:  # fmt: skip
        """:func:`take_point` on these points (``point`` stored where it answers
        :data:`STORED`)."""
        self.make_room()
        out = take_point(
            self._raw, self._path, self._s, self._lo, self._n, point, min_spacing, max_jump,
            fit_mm, sp, par, env_last,
        )  # fmt: skip
        if out[0] == STORED:
            self._n += 1
        return out

    def compile_take(
        self, min_spacing: float, max_jump: float, fit_mm: float, sp: FloatArray, par: FloatArray
    ) -> None:
        """Compile :meth:`take`'s kernel for the types it will be called with, without calling
        it (:func:`seamtrack.jit.compile_for`)."""
        compile_for(
            take_point, self._raw, self._path, self._s, self._lo, self._n, np.zeros(3),
            min_spacing, max_jump, fit_mm, sp, par, math.nan,
        )  # fmt: skip

    def make_room(self) -> None:
        """Room for one more point after the newest: when full, the points move to the front
        of new arrays (twice as long when more than half full)."""
        end = self._lo + self._n
        if end == len(self._s):
            size = len(self._s) * (2 if 2 * self._n > len(self._s) else 1)
            for name in ("_raw", "_path", "_s"):
                old = getattr(self, name)
                new = np.empty((size, *old.shape[1:]))
                new[: self._n] = old[self._lo : end]
                setattr(self, name, new)
            self._lo = 0

    def drop(self, count: int) -> None:
        """Forget the ``count`` oldest points."""
        self._lo += count
        self._n -= count


@numba.njit(**KERNEL)
def _fit(
    raw: FloatArray, s: FloatArray, first: int, at: float, w: NDArray[np.bool_], out: FloatArray
) -> bool:
    """Least-squares line p = a + b ds through the window points ``w`` (ds = s - at): ``out``
    gets a (0:3) and b (3:6); True when well posed (at least 3 points, not all at one ds)."""
    n = sx = sxx = 0.0
    sy0 = sy1 = sy2 = sxy0 = sxy1 = sxy2 = 0.0  # the sums per coordinate, in scalars
    for j in range(first, s.shape[0]):
        if w[j - first]:
            ds = s[j] - at
            n += 1.0
            sx += ds
            sxx += ds * ds
            x, y, z = raw[j, 0], raw[j, 1], raw[j, 2]
            sy0 += x
            sxy0 += ds * x
            sy1 += y
            sxy1 += ds * y
            sy2 += z
            sxy2 += ds * z
    det = n * sxx - sx * sx
    ok = n >= 3 and det > 1e-12 * max(n * sxx, 1e-300)
    safe = det if ok else 1.0
    out[0], out[3] = (sxx * sy0 - sx * sxy0) / safe, (n * sxy0 - sx * sy0) / safe
    out[1], out[4] = (sxx * sy1 - sx * sxy1) / safe, (n * sxy1 - sx * sy1) / safe
    out[2], out[5] = (sxx * sy2 - sx * sxy2) / safe, (n * sxy2 - sx * sy2) / safe
    return ok


@numba.njit(**KERNEL)
def kth_smallest(a: FloatArray, n: int, k: int) -> float:
    """The ``k``-th smallest (from 0) of ``a[:n]`` (no NaN), by quickselect in place (``a[:n]``
    reordered): the value ``np.partition(a[:n], k)[k]`` gives, without its copy."""
    lo, hi = 0, n - 1
    while lo < hi:
        pivot = a[(lo + hi) // 2]
        i, j = lo, hi
        while i <= j:
            while a[i] < pivot:
                i += 1
            while a[j] > pivot:
                j -= 1
            if i <= j:
                a[i], a[j] = a[j], a[i]
                i += 1
                j -= 1
        if k <= j:
            hi = j
        elif k >= i:
            lo = i
        else:
            return a[k]
    return a[k]


@numba.njit(**KERNEL)
def smooth_tail(
    raw: FloatArray, path: FloatArray, s: FloatArray, first: int, h: float, min_inlier: float
) -> None:
    """Refit, in ``path``, every point whose window the newest point entered (arc length within
    ``h`` of the last): a least-squares line through the raw points ``first:`` within +-h of
    it, refitted without those farther than three times the window's median residual (at least
    ``min_inlier``), evaluated at the point (kept as it is when the refit is ill posed)."""
    n = s.shape[0]
    m = n - first
    w = np.empty(m, dtype=np.bool_)
    residual = np.empty(m)
    ordered = np.empty(m)
    line = np.empty(6)
    s_last = s[n - 1]
    for t in range(first, n):
        at = s[t]
        if at < s_last - h:
            continue
        count = 0
        for j in range(m):
            w[j] = abs(s[first + j] - at) <= h
            count += w[j]
        _fit(raw, s, first, at, w, line)
        k = _ZERO
        for j in range(m):
            ds = s[first + j] - at
            r2 = 0.0
            for c in range(3):
                e = raw[first + j, c] - (line[c] + ds * line[3 + c])
                r2 += e * e
            residual[j] = math.sqrt(r2)
            if w[j]:
                ordered[k] = residual[j]
                k += 1
        # The window's median residual: its (count // 2)-th smallest, found by quickselect
        # (the same value a full sort puts there).
        median = kth_smallest(ordered, k, count // 2) if k else np.inf
        limit = max(3.0 * (median if math.isfinite(median) else 0.0), min_inlier)
        for j in range(m):
            w[j] = w[j] and residual[j] <= limit
        if _fit(raw, s, first, at, w, line):
            for c in range(3):
                path[t, c] = line[c]


@numba.njit(**KERNEL)
def off_line(window: FloatArray, point: FloatArray) -> float:
    """Distance of ``point`` from the total-least-squares line through the rows of ``window``
    (its centroid and principal direction)."""
    n = window.shape[0]
    centre = np.zeros(3)
    for i in range(n):
        for c in range(3):
            centre[c] += window[i, c]
    centre /= n
    scatter = np.zeros((3, 3))
    for i in range(n):
        for a in range(3):
            da = window[i, a] - centre[a]
            for b in range(3):
                scatter[a, b] += da * (window[i, b] - centre[b])
    direction = np.linalg.eigh(scatter)[1][:, 2]  # eigenvalues ascending: the largest
    v = point - centre
    along = v[0] * direction[0] + v[1] * direction[1] + v[2] * direction[2]
    off = 0.0
    for c in range(3):
        e = v[c] - along * direction[c]
        off += e * e
    return math.sqrt(off)


# ----------------------------------------------------------------------------- the set-point
#: Layout of the set-point's float array (:func:`setpoint_step`): its state, then the tracker's
#: parameters.
S_SET, V_SET, TCP_X, TCP_Y, TCP_Z, LOST = 0, 1, 2, 3, 4, 5
SPEED, ACCEL, DT, END_MARGIN, BRIDGE, GAIN, DIRECTION_FIT = 6, 7, 8, 9, 10, 11, 12
SETPOINT_FIELDS = 13


@numba.njit(**KERNEL)
def end_direction(path: FloatArray, s: FloatArray, fit_mm: float) -> tuple[float, float, float]:
    """Unit chord of the last ``fit_mm`` of stored path (zero when it has no length)."""
    n = s.shape[0]
    i = max(np.searchsorted(s, s[n - 1] - fit_mm) - 1, 0)
    if n > 2:
        i = max(i, 1)  # the start pose is not a seam point
    cx = path[n - 1, 0] - path[i, 0]
    cy = path[n - 1, 1] - path[i, 1]
    cz = path[n - 1, 2] - path[i, 2]
    length = math.sqrt(cx * cx + cy * cy + cz * cz)
    if length > 0.0:
        return cx / length, cy / length, cz / length
    return 0.0, 0.0, 0.0


@numba.njit(**KERNEL)
def point_at(
    path: FloatArray, s: FloatArray, at: float, fit_mm: float
) -> tuple[float, float, float, float, float, float]:
    """Point and unit direction on the stored path at arc length ``at``, extrapolated past the
    end along :func:`end_direction`."""
    n = s.shape[0]
    if n < 2:
        return path[0, 0], path[0, 1], path[0, 2], 0.0, 0.0, 0.0
    if at > s[n - 1]:
        dx, dy, dz = end_direction(path, s, fit_mm)
        k = at - s[n - 1]
        return path[n - 1, 0] + k * dx, path[n - 1, 1] + k * dy, path[n - 1, 2] + k * dz, dx, dy, dz
    i = min(max(np.searchsorted(s, at, side="right") - 1, 0), n - 2)
    length = s[i + 1] - s[i]
    dx = dy = dz = 0.0
    if length > 0.0:
        dx = (path[i + 1, 0] - path[i, 0]) / length
        dy = (path[i + 1, 1] - path[i, 1]) / length
        dz = (path[i + 1, 2] - path[i, 2]) / length
    k = at - s[i]
    return path[i, 0] + k * dx, path[i, 1] + k * dy, path[i, 2] + k * dz, dx, dy, dz


@numba.njit(**KERNEL)
def corner_speed(env_s: FloatArray, env_v: FloatArray, at: float) -> float:
    """The corner envelope at arc length ``at`` (no limit beyond its last point)."""
    n = env_s.shape[0]
    if n == 0 or at > env_s[n - 1]:
        return math.inf
    i = np.searchsorted(env_s, at, side="right") - 1
    if i < 0:
        return env_v[0]
    if i >= n - 1:
        return env_v[n - 1]
    f = (at - env_s[i]) / (env_s[i + 1] - env_s[i])
    return env_v[i] + f * (env_v[i + 1] - env_v[i])


@numba.njit(**KERNEL)
def setpoint_step(
    sp: FloatArray,
    path: FloatArray,
    s: FloatArray,
    env_s: FloatArray,
    env_v: FloatArray,
    x: float,
    y: float,
    z: float,
) -> tuple[float, float, float, float, float, float, float, bool]:
    """One control tick of the set-point (``sp``: state and parameters, updated in place) with
    the torch at (x, y, z): it runs along the stored path at the welding speed, ramping at the
    acceleration limit, braking for corners and to stop where the path (or its bridge) ends.

    Returns the target (x, y, z), the speed of the proportional correction, the feed-forward
    velocity (x, y, z) and whether the set-point has stopped.
    """
    sp[TCP_X], sp[TCP_Y], sp[TCP_Z] = x, y, z
    # The set-point may run up to bridge_mm past the newest stored point: while the seam is
    # in view the path grows ahead of it, and when it is lost this is the bridge. Braking
    # room to that limit is what lets it keep speed with a short look-ahead.
    s_limit = s[s.shape[0] - 1] - (0.0 if sp[LOST] else sp[END_MARGIN]) + sp[BRIDGE]
    s_set, dt, accel = sp[S_SET], sp[DT], sp[ACCEL]
    room = max(s_limit - s_set, 0.0)
    corner = corner_speed(env_s, env_v, s_set)
    wanted = min(sp[SPEED], math.sqrt(2.0 * accel * room), corner)
    # Speed up or brake at most at the acceleration limit: a limit that appears late (a
    # corner just measured) is met as soon as braking allows, never by a jump in speed.
    dv = accel * dt
    v_set = min(max(wanted, sp[V_SET] - dv), sp[V_SET] + dv)
    step = min(v_set * dt, room)
    s_set += step
    sp[V_SET], sp[S_SET] = v_set, s_set
    tx, ty, tz, dx, dy, dz = point_at(path, s, s_set, sp[DIRECTION_FIT])
    rate = step / dt
    ex, ey, ez = tx - x, ty - y, tz - z
    error = math.sqrt(ex * ex + ey * ey + ez * ez)
    return tx, ty, tz, sp[GAIN] * error, dx * rate, dy * rate, dz * rate, not step > 0.0


@numba.njit(**KERNEL)
def tracker_hint(
    T: FloatArray, raw: FloatArray, path: FloatArray, s: FloatArray, fit_mm: float,
    last_window: FloatArray, last_near: FloatArray, points: FloatArray, a: FloatArray,
    d: FloatArray, centres: FloatArray, radii: FloatArray,
) -> tuple[bool, float, float, float, float, float, FloatArray, FloatArray]:  # fmt: skip
    """:func:`~seamtrack.control.hint_kernels.program_hint` on the tracker's stored path
    (``raw``, ``path``, ``s``): the window of raw points of the last ``fit_mm`` (at least the
    newest) and the direction of :func:`end_direction`, in the one call the tracker makes at
    each frame. ``points`` .. ``radii``: the fields of the program seam's
    :class:`~seamtrack.control.hint_kernels.Polyline` (its segments in the chunks of
    :func:`~seamtrack.control.hint_kernels.polyline_chunks`), passed loose (``*polyline``):
    numba reads a named tuple from Python in about 1 us, its arrays alone in a tenth of that.

    Returns :func:`program_hint`'s answer and the window (a copy, for the next call)."""
    n = s.shape[0]
    i = max(np.searchsorted(s, s[n - 1] - fit_mm), 1)
    window = raw[i:].copy() if n > i else raw[n - 1 :].copy()
    direction = np.empty(3)
    direction[0], direction[1], direction[2] = end_direction(path, s, fit_mm)
    program = Polyline(points, a, d, centres, radii)
    found, y, z, dx, dy, dz, near = program_hint(
        T, raw[n - 1], direction, program, window, last_window, last_near
    )
    return found, y, z, dx, dy, dz, near, window


@numba.njit(**KERNEL)
def corner_envelope(
    path: FloatArray, s: FloatArray, w: float, a_lat: float, accel: float, speed: float
) -> FloatArray:
    """The speed allowed at each point of ``path`` (arc lengths ``s``, at least 3 points):
    sqrt(a_lat / curvature), the curvature the turn between the chords to the points ``w``
    behind and ahead over their mean length (0 where either chord is shorter than w / 2),
    lowered so that braking at ``accel`` reaches every later limit in time (a suffix minimum
    of v^2 + 2 accel s). The arithmetic of :meth:`TrajectoryTracker._corner_envelope
    <seamtrack.control.trajectory.TrajectoryTracker._corner_envelope>`' numpy form, compiled."""
    n = s.shape[0]
    reach = np.empty(n)
    for i in range(n):
        back = np.searchsorted(s, s[i] - w)
        fwd = min(np.searchsorted(s, s[i] + w), n - 1)
        a0 = path[i, 0] - path[back, 0]
        a1 = path[i, 1] - path[back, 1]
        a2 = path[i, 2] - path[back, 2]
        b0 = path[fwd, 0] - path[i, 0]
        b1 = path[fwd, 1] - path[i, 1]
        b2 = path[fwd, 2] - path[i, 2]
        n1 = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
        n2 = math.sqrt(b0 * b0 + b1 * b1 + b2 * b2)
        curvature = 0.0
        if n1 > 0.5 * w and n2 > 0.5 * w:
            cos = (a0 * b0 + a1 * b1 + a2 * b2) / (n1 * n2)
            curvature = math.acos(min(max(cos, -1.0), 1.0)) / (0.5 * (n1 + n2))
        v_allow = math.sqrt(a_lat / max(curvature, 1e-12))
        reach[i] = min(v_allow, speed) ** 2 + 2.0 * accel * s[i]
    v = np.empty(n)
    low = np.inf
    for i in range(n - 1, -1, -1):
        low = min(low, reach[i])
        v[i] = math.sqrt(max(low - 2.0 * accel * s[i], 0.0))
    return v


#: What :func:`take_point` did with a measured point: nothing (closer than the minimum spacing
#: to the newest stored point), nothing (off the line of the last stored points, or too few of
#: them there to fit one: the tracker's to decide), stored it.
TOO_CLOSE, OFF_PATH, FEW, STORED = 0, 1, 2, 3


@numba.njit(**KERNEL)
def take_point(
    raw_all: FloatArray, path_all: FloatArray, s_all: FloatArray, lo: int, n: int,
    point: FloatArray, min_spacing: float, max_jump: float, fit_mm: float, sp: FloatArray,
    par: FloatArray, env_last: float,
) -> tuple[int, float, int, int, int, int, FloatArray]:  # fmt: skip
    """The trajectory tracker's update with a measured ``point``, in one call: its distance
    from the newest of the ``n`` stored points (rows ``lo:`` of a :class:`PathBuffer`'s
    arrays, with room for one more: ``np.linalg.norm``'s arithmetic, the same BLAS dot); where
    it is not too close (nor, within ``max_jump``, more than ``min_spacing`` behind the newest
    along the path's last step: a spot measured again, as while the robot starts, whose point
    stored would double the path back and step the set-point back with it), its distance
    from the line through the raw points of the last ``fit_mm`` (:func:`off_line`); where
    that is within ``max_jump``, the point stored after the newest and :func:`store_tail` on
    the stored points.

    Returns (what it did: :data:`TOO_CLOSE`, :data:`OFF_PATH`, :data:`FEW` or
    :data:`STORED`, the distance, then :func:`store_tail`'s answer where stored).
    """
    none = np.empty(0)
    d = point - path_all[lo + n - 1]
    step = math.sqrt(np.dot(d, d))
    if step < min_spacing:
        return TOO_CLOSE, step, 0, 0, 0, 0, none
    if n >= 2 and step < max_jump:  # behind the newest by more than min_spacing: re-measured
        e = path_all[lo + n - 1] - path_all[lo + n - 2]
        if np.dot(d, e) < -min_spacing * math.sqrt(np.dot(e, e)):
            return TOO_CLOSE, step, 0, 0, 0, 0, none
    if n >= 3:
        s = s_all[lo : lo + n]
        i = max(np.searchsorted(s, s[n - 1] - fit_mm), 1)
        if n - i < 3:
            return FEW, step, 0, 0, 0, 0, none
        if off_line(raw_all[lo + i : lo + n], point) > max_jump:
            return OFF_PATH, step, 0, 0, 0, 0, none
    end = lo + n
    raw_all[end], path_all[end] = point, point
    s_all[end] = s_all[end - 1] + step
    cut, what, i0, settled, v = store_tail(
        raw_all[lo : end + 1], path_all[lo : end + 1], s_all[lo : end + 1], sp, par, env_last
    )
    return STORED, step, cut, what, i0, settled, v


#: Layout of :func:`store_tail`'s parameters: the smoothing half-width, the inlier floor, the
#: stored length kept behind the set-point, the corner fraction, the curvature window, the
#: lateral acceleration, the set-point's acceleration and the welding speed.
T_SMOOTH, T_INLIER, T_BUFFER, T_CORNER, T_WINDOW, T_A_LAT, T_ACCEL, T_SPEED = range(8)
TAIL_FIELDS = 8


@numba.njit(**KERNEL)
def store_tail(
    raw: FloatArray, path: FloatArray, s: FloatArray, sp: FloatArray, par: FloatArray,
    env_last: float,
) -> tuple[int, int, int, int, FloatArray]:  # fmt: skip
    """What the trajectory tracker does after storing a point, in one call: refit the tail
    (:func:`smooth_tail` from the first point within two half-widths of the newest), the
    count of points more than ``par[T_BUFFER]`` behind the set-point (``sp``) to drop, and the
    corner envelope (:func:`corner_envelope`) over the points from the curvature window behind
    the set-point to the *settled* path (the last two smoothing windows are still refitted as
    points arrive: curvature read there would be transient; that tail lies a look-ahead ahead
    of the torch, beyond any braking distance), refreshed once the settled path has grown by
    half the curvature window past the envelope's last arc length ``env_last`` (NaN: none).

    Returns (points to drop, what became of the envelope: 0 kept, 1 emptied, 2 new, and the
    new one's rows [i0, settled) of the buffer after the drop, its speeds).
    """
    n = s.shape[0]
    h = par[T_SMOOTH]
    if h > 0 and n >= 3:
        first = max(np.searchsorted(s, s[n - 1] - 2 * h), 1)  # 0: the start pose
        smooth_tail(raw, path, s, first, h, par[T_INLIER])
    cut = max(np.searchsorted(s, sp[S_SET] - par[T_BUFFER]) - 1, 0)
    kept, points = s[cut:], path[cut:]
    m = kept.shape[0]
    none = np.empty(0)
    if par[T_CORNER] <= 0 or m < 4:
        return cut, 0, 0, 0, none
    w = par[T_WINDOW]
    settled = np.searchsorted(kept, kept[m - 1] - 2.0 * max(par[T_SMOOTH], 0.0), side="right")
    if not math.isnan(env_last) and kept[settled - 1] - env_last < 0.5 * w:
        return cut, 0, 0, 0, none
    i0 = max(np.searchsorted(kept, sp[S_SET] - w), 1)
    if settled - i0 < 3:
        return cut, 1, 0, 0, none
    v = corner_envelope(points[i0:settled], kept[i0:settled], w, par[T_A_LAT], par[T_ACCEL],
                        par[T_SPEED])  # fmt: skip
    return cut, 2, i0, settled, v
