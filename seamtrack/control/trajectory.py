"""A look-ahead trajectory tracker (trajectory-based control in the manner of de Graaf, Aarts,
Jonker and Meijer, "Real-time seam tracking for robotic laser welding using trajectory-based
control", Control Engineering Practice 18, 2010).

The sensor looks ahead of the torch, so every seam point is measured before the torch gets
there. Each measurement is stored in world coordinates, computed with the sensor pose *at
capture* (so a late-arriving frame is still placed right), and indexed by arc length along the
stored path. The path is smoothed locally, and the torch is driven along it at the constant
welding speed: the set-point moves along the path at that speed, its velocity is fed forward,
and a proportional term corrects the remaining error. A measured point that jumps more than
``max_jump_mm`` off the line through the last stored points (a tack weld, a reflection, a bogus
detection at a shadow's edge) is held back until points agreeing with it span
``reacquire_mm``. Frames without a usable seam point are bridged by extrapolating the stored
path along the chord of its last ``direction_fit_mm`` for ``bridge_mm``; beyond that the
set-point stops and the simulation reports the seam lost.

On a robot that turns its tool, the tracker also commands the tool's orientation from the robot
program (:class:`~seamtrack.control.orientation.ToolProgram`): the scene's work and travel
angles in the nominal seam frame at the set-point, and the heading that keeps the laser line
crossing the seam ``look_ahead_mm`` ahead. It is refreshed every ``orientation_period_s``, with
the program's rate of turning at the set-point's speed as a feed-forward (the arm turns its
goal on at that rate between refreshes).
"""

from __future__ import annotations

import bisect
import math

import numpy as np
from numpy.typing import NDArray

from seamtrack.control.path_kernels import PathBuffer, off_line, smooth_tail
from seamtrack.control.tracking import Command, Measurement, TrackerContext
from seamtrack.params import Fraction, NonNegative, Positive

FloatArray = NDArray[np.float64]


#: Residuals below this never mark a stored point as an outlier (the sensor's noise floor).
_MIN_INLIER_MM = 0.05


class TrajectoryTracker:
    """Drive the torch along the stored, smoothed seam path at constant speed.

    Parameters
    ----------
    buffer_mm : float
        Length of stored path kept behind the torch (older points are dropped).
    smoothing_mm : float
        Half-width of the moving least-squares line fit that smooths each stored point
        (0 = raw points).
    min_spacing_mm : float
        Measured points closer than this (along the path) to the last stored one are ignored.
    gain_1_s : float
        Proportional gain of the position correction, 1/s.
    bridge_mm : float
        How far the set-point may run past the last measured point (along the last direction)
        while frames come without a seam point.
    end_margin_mm : float
        The set-point stays this far behind the newest stored point while the sensor still
        sees the seam (room for smoothing to settle).
    use_capture_pose : bool
        Place each point with the sensor pose at capture (True) or, naively, at arrival.
    max_jump_mm : float
        A new point farther than this from the extrapolated stored path is held back (and the
        frame bridged): bogus detections at the edge of a shadow, reflections, tack welds.
    reacquire_mm : float
        Held-back points that agree with each other (within ``max_jump_mm`` of their own line)
        over this length are accepted: the seam really turned or stepped.
    direction_fit_mm : float
        Length of stored path whose chord gives the direction for extrapolation.
    orientation_period_s : float
        How often the commanded tool orientation is refreshed (robots that turn their tool).
    corner_accel_fraction : float
        Where the stored path turns, the set-point slows to sqrt(a / curvature), a being this
        fraction of the set-point's acceleration limit, braking ahead of the turn in time; the
        axes then turn the torch without cutting the corner. 0 switches it off.
    curvature_window_mm : float
        Arc length over which the turning of the stored path is measured.
    """

    name = "trajectory"

    def __init__(
        self,
        buffer_mm: Positive = 100.0,
        smoothing_mm: NonNegative = 1.0,
        min_spacing_mm: NonNegative = 0.05,
        gain_1_s: Positive = 20.0,
        bridge_mm: NonNegative = 10.0,
        end_margin_mm: NonNegative = 0.0,
        use_capture_pose: bool = True,
        max_jump_mm: Positive = 0.5,
        reacquire_mm: NonNegative = 2.0,
        corner_accel_fraction: Fraction = 0.5,
        curvature_window_mm: Positive = 3.0,
        direction_fit_mm: Positive = 5.0,
        orientation_period_s: Positive = 0.01,
    ):
        self.buffer_mm = buffer_mm
        self.smoothing_mm = smoothing_mm
        self.min_spacing_mm = min_spacing_mm
        self.gain_1_s = gain_1_s
        self.bridge_mm = bridge_mm
        self.end_margin_mm = end_margin_mm
        self.use_capture_pose = use_capture_pose
        self.max_jump_mm = max_jump_mm
        self.reacquire_mm = reacquire_mm
        self.corner_accel_fraction = corner_accel_fraction
        self.curvature_window_mm = curvature_window_mm
        self.direction_fit_mm = direction_fit_mm
        self.orientation_period_s = orientation_period_s

    # ----------------------------------------------------------------- protocol
    def reset(self, context: TrackerContext) -> None:
        self.speed = context.welding_speed_mm_s
        self.dt = context.control_period_s
        # The set-point accelerates no faster than the weakest axis can follow.
        self.accel = 0.9 * float(np.min(context.acceleration_max_world))
        self._v_set = 0.0
        self._env_s: list[float] = []  # arc lengths ahead of the set-point ...
        self._env_v: list[float] = []  # ... and the speed allowed there (corners)
        start = np.asarray(context.tcp_start_world, dtype=float)
        # The stored points in arrays (compiled smoothing works on them in place); their arc
        # lengths also as a list, which the per-tick bisection reads fastest.
        self._buffer = PathBuffer(start)
        self._s: list[float] = [0.0]
        self._s_set = 0.0
        self._segments: dict[int, tuple[float, ...]] = {}  # _at_floats' cache, by segment
        self._seen_seam = False
        self._lost = False
        self._held: list[FloatArray] = []
        self._tcp_now: tuple[float, ...] = tuple(start.tolist())
        program = context.tool_program if context.turns_tool else None
        self._program = program
        self._rotation: FloatArray | None = None
        self._omega: FloatArray | None = None
        self._s_program = 0.0
        self._orient_every = max(1, round(self.orientation_period_s / self.dt))
        self._tick = 0
        if program is not None:
            self._rotation, self._s_program = program.rotation_near(start, 0.0)

    def update(self, measurement: Measurement) -> None:
        if not measurement:
            self._lost = self._seen_seam
            return
        point = np.asarray(measurement.point_world, dtype=float)
        if not self.use_capture_pose:
            # Naive: pretend the frame was taken where the robot is now.
            point = point + (np.asarray(self._tcp_now) - measurement.tcp_world)
        step = float(np.linalg.norm(point - self._path[-1]))
        if step < self.min_spacing_mm:
            self._lost = False
            return
        if len(self._path) >= 3 and self._off_path(point) > self.max_jump_mm:
            self._held.append(point)
            if not self._reacquired():
                self._lost = self._seen_seam  # bridge it, for now
                return
            held, self._held = self._held[:-1], []
            for p in held:  # the seam moved: store what was held back, then this point
                self._store(p)
            step = float(np.linalg.norm(point - self._path[-1]))
        else:
            self._held = []
        self._lost = False
        self._seen_seam = True
        self._store(point, step)

    def _store(self, point: FloatArray, step: float | None = None) -> None:
        if step is None:
            step = float(np.linalg.norm(point - self._path[-1]))
        if step < self.min_spacing_mm:
            return
        s = self._s[-1] + step
        self._buffer.append(point, s)
        self._s.append(s)
        self._segments.clear()  # the path changes (smoothing, trimming): index by index
        self._smooth_tail()
        self._trim()
        self._corner_envelope()

    def _corner_envelope(self) -> None:
        """The speed the set-point may have at each stored point ahead: sqrt(a / curvature)
        where the path turns, lowered so that braking at ``accel`` reaches every later limit
        in time (a backward pass over the points ahead, once per stored point)."""
        if self.corner_accel_fraction <= 0 or len(self._s) < 4:
            return
        w = self.curvature_window_mm
        # Only the settled path: the last two smoothing windows are still re-fitted as points
        # arrive, and curvature read there would be transient. (That tail lies a look-ahead
        # ahead of the torch, beyond any braking distance.) Refreshing each time the settled
        # path has grown by half the curvature window keeps the envelope current cheaply.
        settled = bisect.bisect_right(self._s, self._s[-1] - 2.0 * max(self.smoothing_mm, 0.0))
        if self._env_s and self._s[settled - 1] - self._env_s[-1] < 0.5 * w:
            return
        i0 = max(bisect.bisect_left(self._s, self._s_set - w), 1)
        s = np.asarray(self._s[i0:settled])
        if len(s) < 3:
            self._env_s, self._env_v = [], []
            return
        p = np.asarray(self._path[i0:settled])
        back = np.searchsorted(s, s - w)
        fwd = np.minimum(np.searchsorted(s, s + w), len(s) - 1)
        d1 = p - p[back]
        d2 = p[fwd] - p
        n1 = np.linalg.norm(d1, axis=1)
        n2 = np.linalg.norm(d2, axis=1)
        ok = (n1 > 0.5 * w) & (n2 > 0.5 * w)
        cos = np.sum(d1 * d2, axis=1) / np.where(ok, n1 * n2, 1.0)
        turn = np.where(ok, np.arccos(np.clip(cos, -1.0, 1.0)), 0.0)
        curvature = turn / np.where(ok, 0.5 * (n1 + n2), 1.0)
        a_lat = self.corner_accel_fraction * self.accel
        v_allow = np.sqrt(a_lat / np.maximum(curvature, 1e-12))
        # Braking backwards from every later limit: v(s_j)^2 = min over i >= j of
        # v_allow_i^2 + 2 a (s_i - s_j), a suffix minimum.
        reach = np.minimum(v_allow, self.speed) ** 2 + 2.0 * self.accel * s
        suffix = np.minimum.accumulate(reach[::-1])[::-1]
        v = np.sqrt(np.maximum(suffix - 2.0 * self.accel * s, 0.0))
        self._env_s, self._env_v = s.tolist(), v.tolist()

    def _corner_speed(self, s: float) -> float:
        """The corner envelope at arc length s (no limit beyond the stored points)."""
        knots = self._env_s
        if not knots or s > knots[-1]:
            return math.inf
        i = bisect.bisect_right(knots, s) - 1
        if i < 0:
            return self._env_v[0]
        if i >= len(knots) - 1:
            return self._env_v[-1]
        f = (s - knots[i]) / (knots[i + 1] - knots[i])
        return self._env_v[i] + f * (self._env_v[i + 1] - self._env_v[i])

    def _reacquired(self) -> bool:
        """True when the newest held-back points span ``reacquire_mm`` and lie on one line;
        older held points (bogus ones before the seam's new course) are dropped."""
        held = np.asarray(self._held)
        reach = np.linalg.norm(held - held[-1], axis=1)
        spanning = np.flatnonzero(reach >= self.reacquire_mm)
        if len(spanning) == 0:
            return False
        self._held = self._held[int(spanning[-1]) :]
        held = held[int(spanning[-1]) :]
        if len(held) < 3:
            # Sparse frames (1 frame/s: points 5 mm apart): two points that span the length
            # are the evidence there is.
            return len(held) == 2
        centred = held - held.mean(axis=0)
        direction = np.linalg.svd(centred, full_matrices=False)[2][0]
        off = centred - np.outer(centred @ direction, direction)
        return bool(np.max(np.linalg.norm(off, axis=1)) <= self.max_jump_mm)

    def command(
        self, t_s: float, tcp_world: FloatArray, tcp_velocity_world: FloatArray
    ) -> Command | None:
        x, y, z = np.asarray(tcp_world, dtype=float).tolist()
        move = self.command_floats(x, y, z)
        if move is None:
            return None
        tx, ty, tz, speed, fx, fy, fz, stop = move
        return Command(
            np.array((tx, ty, tz)),
            speed,
            velocity_ff_world=np.array((fx, fy, fz)),
            stop_at_target=stop,
            rotation_world=self._rotation,
            angular_velocity_world=self._omega,
        )

    def command_floats(
        self, x: float, y: float, z: float
    ) -> tuple[float, float, float, float, float, float, float, bool] | None:
        """:meth:`command` on plain floats, for the loop's fast path (no objects per tick).

        Returns the target (3 floats, world), the speed, the feed-forward (3 floats, world) and
        ``stop_at_target``, or None; the commanded rotation is :attr:`rotation_world`.
        """
        self._tcp_now = (x, y, z)
        if not self._seen_seam:
            return None
        # The set-point may run up to bridge_mm past the newest stored point: while the seam is
        # in view the path grows ahead of it, and when it is lost this is the bridge. Braking
        # room to that limit is what lets it keep speed with a short look-ahead.
        s_limit = self._s[-1] - (0.0 if self._lost else self.end_margin_mm) + self.bridge_mm
        # Set-point speed: ramp up at the acceleration limit, brake to stop at s_limit.
        s_set, dt = self._s_set, self.dt
        room = max(s_limit - s_set, 0.0)
        env = self._env_s
        corner = math.inf if not env or s_set > env[-1] else self._corner_speed(s_set)
        wanted = min(self.speed, math.sqrt(2.0 * self.accel * room), corner)
        # Speed up or brake at most at the acceleration limit: a limit that appears late (a
        # corner just measured) is met as soon as braking allows, never by a jump in speed.
        dv = self.accel * dt
        v_set = self._v_set
        self._v_set = v_set = min(max(wanted, v_set - dv), v_set + dv)
        step = min(v_set * dt, room)
        moving = step > 0.0
        self._s_set = s_set = s_set + step
        tx, ty, tz, dx, dy, dz = self._at_floats(s_set)
        rate = step / dt
        error = math.dist((tx, ty, tz), (x, y, z))
        if self._program is not None:
            self._tick += 1
            if self._tick % self._orient_every == 0:
                self._rotation, self._omega, self._s_program = self._program.turning_near(
                    np.array((tx, ty, tz)), self._s_program, self._v_set
                )
        return (tx, ty, tz, self.gain_1_s * error, dx * rate, dy * rate, dz * rate, not moving)

    @property
    def rotation_world(self) -> FloatArray | None:
        """The tool rotation the tracker commands (None: keep it)."""
        return self._rotation

    # ----------------------------------------------------------------- path
    def _end_direction(self) -> FloatArray:
        """Unit chord of the last ``direction_fit_mm`` of stored path (robust to the jitter of
        the last few points, which the last segment alone is not)."""
        knots = self._s
        i = max(bisect.bisect_left(knots, knots[-1] - self.direction_fit_mm) - 1, 0)
        if len(knots) > 2:
            i = max(i, 1)  # the start pose is not a seam point
        chord = self._path[-1] - self._path[i]
        length = float(np.linalg.norm(chord))
        return chord / length if length > 0 else np.zeros(3)

    @property
    def _path(self) -> FloatArray:
        """The stored (smoothed) points, (n, 3), oldest first."""
        return self._buffer.path

    def _off_path(self, point: FloatArray) -> float:
        """Distance of a point from the line fitted (total least squares) to the raw stored
        points of the last ``direction_fit_mm``: a ramp of bogus points trips it on its second
        point, because the line they are measured against does not follow them."""
        knots = self._s
        i = max(bisect.bisect_left(knots, knots[-1] - self.direction_fit_mm), 1)
        window = self._buffer.raw[i:]
        if len(window) < 3:
            d = self._end_direction()
            v = point - self._path[-1]
            return float(np.linalg.norm(v - (v @ d) * d))
        return float(off_line(window, point))

    def _at_floats(self, s: float) -> tuple[float, float, float, float, float, float]:
        """:meth:`_at` as six floats (the same arithmetic, element by element), with the
        segments and the end direction cached until the stored path changes."""
        knots = self._s
        if len(knots) < 2:
            px, py, pz = self._path[0].tolist()
            return px, py, pz, 0.0, 0.0, 0.0
        cache = self._segments
        if s > knots[-1]:
            end = cache.get(-1)
            if end is None:
                end = (*self._path[-1].tolist(), *self._end_direction().tolist())
                cache[-1] = end
            ax, ay, az, dx, dy, dz = end
            k = s - knots[-1]
            return ax + k * dx, ay + k * dy, az + k * dz, dx, dy, dz
        i = min(max(bisect.bisect_right(knots, s) - 1, 0), len(knots) - 2)
        seg = cache.get(i)
        if seg is None:
            a, b = self._path[i], self._path[i + 1]
            length = knots[i + 1] - knots[i]
            direction = (b - a) / length if length > 0 else np.zeros(3)
            seg = (*a.tolist(), *direction.tolist())
            cache[i] = seg
        ax, ay, az, dx, dy, dz = seg
        k = s - knots[i]
        return ax + k * dx, ay + k * dy, az + k * dz, dx, dy, dz

    def _at(self, s: float) -> tuple[FloatArray, FloatArray]:
        """Point and unit direction on the stored path at arc length s (extrapolated past
        the end along :meth:`_end_direction`)."""
        knots = self._s
        if len(knots) < 2:
            return self._path[0], np.zeros(3)
        if s > knots[-1]:
            d = self._end_direction()
            return self._path[-1] + (s - knots[-1]) * d, d
        i = min(max(bisect.bisect_right(knots, s) - 1, 0), len(knots) - 2)
        a, b = self._path[i], self._path[i + 1]
        length = knots[i + 1] - knots[i]
        direction = (b - a) / length if length > 0 else np.zeros(3)
        return a + (s - knots[i]) * direction, direction

    def _smooth_tail(self) -> None:
        """Refit the stored points whose window the newest point entered: a robust line through
        the raw points within +-smoothing_mm (arc length), evaluated at the point.

        A first least-squares fit gives residuals; points farther than three times the window's
        median residual (at least ``_MIN_INLIER_MM``) are dropped and the line is refitted, so a
        few bogus detections (an extractor fooled at the edge of a shadow) do not bend the path,
        while a real turn, which the majority of the window follows, does.
        """
        h = self.smoothing_mm
        buffer = self._buffer
        if h <= 0 or len(buffer) < 3:
            return
        first = max(bisect.bisect_left(self._s, self._s[-1] - 2 * h), 1)  # 0: the start pose
        smooth_tail(buffer.raw, buffer.path, buffer.s, first, h, _MIN_INLIER_MM)

    def _trim(self) -> None:
        """Drop stored points more than ``buffer_mm`` behind the set-point."""
        cut = bisect.bisect_left(self._s, self._s_set - self.buffer_mm) - 1
        if cut > 0:
            self._buffer.drop(cut)
            del self._s[:cut]
