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

The end of the seam is not a gap in it. A tack or a clamp interrupts the seam with the part
going on beyond, and is bridged; at the part's end there is nothing to bridge to, and a torch
driven on for ``bridge_mm`` welds air. The sensor sees the end a look-ahead before the torch
gets there, so the stop is planned, as a welding engineer would, at the last seen seam point:
no bridge, the set-point brakes to a stop there, and later frames are ignored. The seam has
ended when it is lost with the last seen seam point within ``end_zone_mm`` of the robot
program's end of an open seam (the CAD seam's end, which the scene knows). An empty profile
alone (:attr:`~seamtrack.control.tracking.Measurement.stripe_points` 0: the stripe has left
the part) is not enough where the program's end is still ahead: a clamp over the seam hides
the whole stripe in just that way, and the part goes on beyond it; with no program end known
it ends the seam (``end_of_part``). Its ``stop_cause`` attribute names the end:
``"end_of_part"`` when the stripe left the part there, ``"seam_end"`` when the seam vanished
from a stripe still on the part (a wall at the seam's end hides its last millimetres: the
torch then finishes along the path to the program's end, as a robot program would); ``""``
while the tracker follows the seam.

On a robot that turns its tool, the tracker also commands the tool's orientation from the robot
program (:class:`~seamtrack.control.orientation.ToolProgram`): the scene's work and travel
angles in the nominal seam frame at the set-point, and the heading that keeps the laser line
crossing the seam ``look_ahead_mm`` ahead. It is refreshed every ``orientation_period_s``, with
the program's rate of turning at the set-point's speed as a feed-forward (the arm turns its
goal on at that rate between refreshes).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from seamtrack.control import path_kernels as pk
from seamtrack.control.hint_kernels import Polyline, polyline
from seamtrack.control.path_kernels import PathBuffer, off_line
from seamtrack.control.tracking import Command, Measurement, TrackerContext
from seamtrack.params import Fraction, NonNegative, Positive
from seamtrack.sensing.profiles import HINT_TOLERANCE_MM, SeamHint

FloatArray = NDArray[np.float64]


#: Residuals below this never mark a stored point as an outlier (the sensor's noise floor).
_MIN_INLIER_MM = 0.05


def _left(a: FloatArray, x: float) -> int:
    """``bisect.bisect_left`` on a sorted array."""
    return int(a.searchsorted(x))


def _length(v: FloatArray) -> float:
    """``np.linalg.norm`` of a vector, as it computes it (the same BLAS dot), without its
    checks."""
    return math.sqrt(v.dot(v))


def _right(a: FloatArray, x: float) -> int:
    """``bisect.bisect_right`` on a sorted array."""
    return int(a.searchsorted(x, side="right"))


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
    end_zone_mm : float
        The seam lost with the last seen seam point within this distance of the robot
        program's end of an open seam is the seam's end (a stop there, no bridge); 0 ignores
        the program's end. Wider than the part's placement error, narrower than the distance
        from the end to the last gap in the seam.
    end_of_part : bool
        With no program end known, take a frame whose profile has no valid point at all (the
        stripe has left the part) as the seam's end.
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
        end_zone_mm: NonNegative = 3.0,
        end_of_part: bool = True,
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
        self.end_zone_mm = end_zone_mm
        self.end_of_part = end_of_part

    # ----------------------------------------------------------------- protocol
    def reset(self, context: TrackerContext) -> None:
        self.speed = context.welding_speed_mm_s
        self.dt = context.control_period_s
        # The set-point accelerates no faster than the weakest axis can follow.
        self.accel = 0.9 * float(np.min(context.acceleration_max_world))
        # The set-point's state and parameters, in the array its compiled step works on.
        self._sp = sp = np.zeros(pk.SETPOINT_FIELDS)
        # The parameters of what follows each stored point (path_kernels.store_tail).
        self._tail = tail = np.zeros(pk.TAIL_FIELDS)
        tail[pk.T_SMOOTH], tail[pk.T_INLIER] = self.smoothing_mm, _MIN_INLIER_MM
        tail[pk.T_BUFFER], tail[pk.T_CORNER] = self.buffer_mm, self.corner_accel_fraction
        tail[pk.T_WINDOW] = self.curvature_window_mm
        tail[pk.T_A_LAT] = self.corner_accel_fraction * self.accel
        tail[pk.T_ACCEL], tail[pk.T_SPEED] = self.accel, self.speed
        sp[pk.SPEED], sp[pk.ACCEL], sp[pk.DT] = self.speed, self.accel, self.dt
        sp[pk.END_MARGIN], sp[pk.BRIDGE] = self.end_margin_mm, self.bridge_mm
        sp[pk.GAIN], sp[pk.DIRECTION_FIT] = self.gain_1_s, self.direction_fit_mm
        self._env_s = np.empty(0)  # arc lengths ahead of the set-point ...
        self._env_v = np.empty(0)  # ... and the speed allowed there (corners)
        start = np.asarray(context.tcp_start_world, dtype=float)
        # The stored points in arrays (the compiled smoothing and set-point work on them).
        self._buffer = PathBuffer(start)
        self._seen_seam = False
        self._held: list[FloatArray] = []
        # The hint's window of raw points and their closest points on the program seam.
        self._on_program: tuple[FloatArray, FloatArray] = (np.empty((0, 3)), np.empty((0, 3)))
        self._polyline: Polyline | None = None  # the program seam, chunked
        self.stop_cause = ""
        # The robot program's end of an open seam (the CAD seam's end), as floats; None: none.
        self._seam_end: tuple[float, float, float] | None = None
        nominal = context.tool_program
        if nominal is not None and self.end_zone_mm > 0 and not nominal.closed:
            x, y, z = np.asarray(nominal.seam.points[-1], dtype=float).tolist()
            self._seam_end = (x, y, z)
        sp[pk.TCP_X : pk.TCP_Z + 1] = start
        program = context.tool_program if context.turns_tool else None
        self._program = program
        self._rotation: FloatArray | None = None
        self._omega: FloatArray | None = None
        self._s_program = 0.0
        self._orient_every = max(1, round(self.orientation_period_s / self.dt))
        self._tick = 0
        if program is not None:
            self._rotation, self._s_program = program.rotation_near(start, 0.0)

    def set_speed(self, speed_mm_s: float) -> None:
        """Change the welding speed during the run (a multi-pass job's planner adapts it along
        the seam); the set-point reaches it within its acceleration limit."""
        self.speed = float(speed_mm_s)
        self._sp[pk.SPEED] = self._tail[pk.T_SPEED] = self.speed

    def update(self, measurement: Measurement) -> None:
        if self.stop_cause:  # the seam has ended: nothing more to follow
            if self.stop_cause == "seam_end" and measurement.stripe_points == 0:
                self.stop_cause = "end_of_part"  # the stripe then left the part
            return
        if not measurement:
            self._lost = self._seen_seam
            if self._seen_seam:
                self._check_end(measurement)
            return
        point = np.asarray(measurement.point_world, dtype=float)
        if not self.use_capture_pose:
            # Naive: pretend the frame was taken where the robot is now.
            point = point + (self._sp[pk.TCP_X : pk.TCP_Z + 1] - measurement.tcp_world)
        # The usual frame in one compiled call: the spacing, the outlier test, the point
        # stored and store_tail (see _store); the tracker decides the rest.
        env = self._env_s
        what, step, cut, envelope, i0, settled, v = self._buffer.take(
            point, self.min_spacing_mm, self.max_jump_mm, self.direction_fit_mm, self._sp,
            self._tail, float(env[-1]) if len(env) else math.nan,
        )  # fmt: skip
        if what == pk.STORED:
            self._held = []
            self._lost = False
            self._seen_seam = True
            self._stored(cut, envelope, i0, settled, v)
            return
        if what == pk.TOO_CLOSE:
            self._lost = False
            return
        if what == pk.OFF_PATH or self._off_path(point) > self.max_jump_mm:
            self._held.append(point)
            if not self._reacquired():
                self._lost = self._seen_seam  # bridge it, for now
                return
            held, self._held = self._held[:-1], []
            for p in held:  # the seam moved: store what was held back, then this point
                self._store(p)
            step = _length(point - self._path[-1])
        else:
            self._held = []
        self._lost = False
        self._seen_seam = True
        self._store(point, step)

    def compile_kernels(self) -> None:
        """Compile (or load from numba's cache) the kernel :meth:`update` calls, for the types
        it will be called with, without changing the tracker: the loop does it before the
        first frame (:func:`seamtrack.jit.compile_for`)."""
        self._buffer.compile_take(
            self.min_spacing_mm, self.max_jump_mm, self.direction_fit_mm, self._sp, self._tail
        )

    def hint(self, T_world_sensor: FloatArray) -> SeamHint | None:
        """Where this tracker expects the seam in the frame about to be taken at
        ``T_world_sensor`` (a :class:`~seamtrack.sensing.profiles.SeamHint` for the extractor).

        With a robot program (a robot that turns its tool), the program's seam where the laser
        plane crosses it, shifted by how far the measured seam lies from the program (the median
        over the last ``direction_fit_mm`` of measured points: a few false points do not move
        it); of several crossings, the one nearest the newest measured point carried straight
        on along the stored path (:func:`~seamtrack.sensing.profiles.hint_from_path`). The
        program knows a corner is coming; a path carried straight on does not, and misses a
        turning seam sideways, so without a program (a gantry) no hint (on `v-groove-corner`
        it made the max error 0.67 -> 0.74 mm). None before the seam is seen and after its
        end, or when the program's seam does not cross the laser plane; while frames are
        bridged (a tack, a clamp, refused frames) the program still says where the seam is."""
        if self._program is None:
            return None
        if not self._seen_seam or self.stop_cause:
            return None
        if self._polyline is None:  # the program's segments, once
            self._polyline = polyline(self._program.seam.points)
        buffer = self._buffer
        # The window of raw points, the direction, hint_from_path, laser_plane_crossings,
        # _closest_on_program and the choice, compiled in one call
        found, y, z, dx, dy, dz, near, window = pk.tracker_hint(
            np.asarray(T_world_sensor, dtype=np.float64), buffer.raw, buffer.path, buffer.s,
            self.direction_fit_mm, *self._on_program, *self._polyline,
        )  # fmt: skip
        self._on_program = (window, near)
        if not found:
            return None
        return SeamHint((y, z), (dx, dy, dz), HINT_TOLERANCE_MM)

    def _check_end(self, measurement: Measurement) -> None:
        """A frame without a seam point after the seam was seen: is it the seam's end?"""
        off_part = getattr(measurement, "stripe_points", -1) == 0
        if self._seam_end is None:
            if self.end_of_part and off_part:
                self._end("end_of_part")
            return
        x, y, z = self._buffer.raw[-1].tolist()
        ex, ey, ez = self._seam_end
        if math.sqrt((x - ex) ** 2 + (y - ey) ** 2 + (z - ez) ** 2) <= self.end_zone_mm:
            # Where the seam vanishes short of the program's end from a stripe still on the
            # part (a wall at the seam's end hides its last millimetres), the torch finishes
            # to the program's end along the path; where the stripe left the part, there.
            ahead = 0.0
            if not off_part:
                dx, dy, dz = pk.end_direction(self._path, self._s, self.direction_fit_mm)
                px, py, pz = self._path[-1].tolist()
                ahead = (ex - px) * dx + (ey - py) * dy + (ez - pz) * dz
            self._end("end_of_part" if off_part else "seam_end", ahead)

    def _end(self, cause: str, ahead_mm: float = 0.0) -> None:
        """Stop ``ahead_mm`` (at most ``end_zone_mm``) past the last seen seam point: no more
        bridge, points held back dropped, later frames ignored."""
        self.stop_cause = cause
        self._held = []
        self._sp[pk.BRIDGE] = min(max(ahead_mm, 0.0), self.end_zone_mm)
        self._lost = True

    def _store(self, point: FloatArray, step: float | None = None) -> None:
        if step is None:
            step = _length(point - self._path[-1])
        if step < self.min_spacing_mm:
            return
        buffer = self._buffer
        buffer.append(point, float(self._s[-1]) + step)
        # One compiled call (path_kernels.store_tail): refit the stored points whose window
        # the newest point entered (a robust line through the raw points within +-smoothing_mm
        # of arc length, evaluated at the point: a first least-squares fit gives residuals,
        # points farther than three times the window's median residual, at least
        # _MIN_INLIER_MM, are dropped and the line refitted, so a few bogus detections do not
        # bend the path while a real turn, which the majority of the window follows, does);
        # drop the points more than buffer_mm behind the set-point; refresh the corner
        # envelope, the speed the set-point may have at each stored point ahead: sqrt(a /
        # curvature) where the path turns, lowered so that braking at accel reaches every
        # later limit in time, over the settled path.
        env = self._env_s
        last = float(env[-1]) if len(env) else math.nan
        self._stored(*pk.store_tail(buffer.raw, buffer.path, buffer.s, self._sp, self._tail, last))

    def _stored(self, cut: int, what: int, i0: int, settled: int, v: FloatArray) -> None:
        """What follows :func:`~seamtrack.control.path_kernels.store_tail`: the points it
        found behind the buffer dropped, the corner envelope kept or replaced."""
        buffer = self._buffer
        if cut > 0:
            buffer.drop(cut)
        if what == 1:
            self._env_s, self._env_v = np.empty(0), np.empty(0)
        elif what == 2:
            # kept as the envelope: not a view of the buffer
            self._env_s, self._env_v = self._s[i0:settled].copy(), v

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
        """:meth:`command` on plain floats: one step of the set-point (compiled,
        :func:`~seamtrack.control.path_kernels.setpoint_step`, which the loop's compiled ticks
        call directly on the built-in tracker), then the tool's orientation when it turns.

        Returns the target (3 floats, world), the speed, the feed-forward (3 floats, world) and
        ``stop_at_target``, or None; the commanded rotation is :attr:`rotation_world`.
        """
        if not self._seen_seam:
            self._sp[pk.TCP_X : pk.TCP_Z + 1] = x, y, z
            return None
        buffer = self._buffer
        out = pk.setpoint_step(self._sp, buffer.path, buffer.s, self._env_s, self._env_v, x, y, z)
        if self._program is not None:
            self._tick += 1
            if self._tick % self._orient_every == 0:
                self._rotation, self._omega, self._s_program = self._program.turning_near(
                    np.array(out[:3]), self._s_program, self._v_set
                )
        return out

    @property
    def rotation_world(self) -> FloatArray | None:
        """The tool rotation the tracker commands (None: keep it)."""
        return self._rotation

    # ----------------------------------------------------------------- path
    def _end_direction(self) -> FloatArray:
        """Unit chord of the last ``direction_fit_mm`` of stored path (robust to the jitter of
        the last few points, which the last segment alone is not)."""
        buffer = self._buffer
        return np.array(pk.end_direction(buffer.path, buffer.s, self.direction_fit_mm))

    @property
    def _v_set(self) -> float:
        """Speed of the set-point along the path."""
        return float(self._sp[pk.V_SET])

    @property
    def _lost(self) -> bool:
        """The last frame gave no usable point: the set-point bridges."""
        return bool(self._sp[pk.LOST])

    @_lost.setter
    def _lost(self, lost: bool) -> None:
        self._sp[pk.LOST] = 1.0 if lost else 0.0

    @property
    def _s(self) -> FloatArray:
        """Arc lengths of the stored points, (n,)."""
        return self._buffer.s

    @property
    def _path(self) -> FloatArray:
        """The stored (smoothed) points, (n, 3), oldest first."""
        return self._buffer.path

    def _off_path(self, point: FloatArray) -> float:
        """Distance of a point from the line fitted (total least squares) to the raw stored
        points of the last ``direction_fit_mm``: a ramp of bogus points trips it on its second
        point, because the line they are measured against does not follow them."""
        knots = self._s
        i = max(_left(knots, knots[-1] - self.direction_fit_mm), 1)
        window = self._buffer.raw[i:]
        if len(window) < 3:
            d = self._end_direction()
            v = point - self._path[-1]
            return float(np.linalg.norm(v - (v @ d) * d))
        return float(off_line(window, point))

    def _at(self, s: float) -> tuple[FloatArray, FloatArray]:
        """Point and unit direction on the stored path at arc length s (extrapolated past
        the end along :meth:`_end_direction`)."""
        buffer = self._buffer
        at = pk.point_at(buffer.path, buffer.s, s, self.direction_fit_mm)
        return np.array(at[:3]), np.array(at[3:])
