"""A look-ahead trajectory tracker (trajectory-based control in the manner of de Graaf, Aarts,
Jonker and Meijer, "Real-time seam tracking for robotic laser welding using trajectory-based
control", Control Engineering Practice 18, 2010).

The sensor looks ahead of the torch, so every seam point is measured before the torch gets
there. Each measurement is stored in world coordinates, computed with the sensor pose *at
capture* (so a late-arriving frame is still placed right), and indexed by arc length along the
stored path. The path is smoothed locally, and the torch is driven along it at the constant
welding speed: the set-point moves along the path at that speed, its velocity is fed forward,
and a proportional term corrects the remaining error. Frames without a seam point are bridged by
extrapolating the stored path along its last direction for ``bridge_mm``; beyond that the
set-point stops and the simulation reports the seam lost.
"""

from __future__ import annotations

import bisect
import math

import numpy as np
from numpy.typing import NDArray

from .trackers import Command, Measurement, TrackerContext

FloatArray = NDArray[np.float64]


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
    """

    name = "trajectory"

    def __init__(
        self,
        buffer_mm: float = 100.0,
        smoothing_mm: float = 1.0,
        min_spacing_mm: float = 0.05,
        gain_1_s: float = 20.0,
        bridge_mm: float = 10.0,
        end_margin_mm: float = 0.0,
        use_capture_pose: bool = True,
    ):
        self.buffer_mm = buffer_mm
        self.smoothing_mm = smoothing_mm
        self.min_spacing_mm = min_spacing_mm
        self.gain_1_s = gain_1_s
        self.bridge_mm = bridge_mm
        self.end_margin_mm = end_margin_mm
        self.use_capture_pose = use_capture_pose

    # ----------------------------------------------------------------- protocol
    def reset(self, context: TrackerContext) -> None:
        self.speed = context.welding_speed_mm_s
        self.dt = context.control_period_s
        # The set-point accelerates no faster than the weakest axis can follow.
        self.accel = 0.9 * float(np.min(context.acceleration_max_world))
        self._v_set = 0.0
        start = np.asarray(context.tcp_start_world, dtype=float)
        self._raw: list[FloatArray] = [start]
        self._path: list[FloatArray] = [start]
        self._s: list[float] = [0.0]
        self._s_set = 0.0
        self._seen_seam = False
        self._lost = False
        self._tcp_now = start

    def update(self, measurement: Measurement) -> None:
        if not measurement:
            self._lost = self._seen_seam
            return
        point = np.asarray(measurement.point_world, dtype=float)
        if not self.use_capture_pose:
            # Naive: pretend the frame was taken where the robot is now.
            point = point + (self._tcp_now - measurement.tcp_world)
        self._lost = False
        step = float(np.linalg.norm(point - self._path[-1]))
        if step < self.min_spacing_mm:
            return
        if not self._seen_seam:
            self._seen_seam = True
        self._raw.append(point)
        self._path.append(point)
        self._s.append(self._s[-1] + step)
        self._smooth_tail()
        self._trim()

    def command(
        self, t_s: float, tcp_world: FloatArray, tcp_velocity_world: FloatArray
    ) -> Command | None:
        self._tcp_now = tcp_world
        if not self._seen_seam:
            return None
        # The set-point may run up to bridge_mm past the newest stored point: while the seam is
        # in view the path grows ahead of it, and when it is lost this is the bridge. Braking
        # room to that limit is what lets it keep speed with a short look-ahead.
        s_limit = self._s[-1] - (0.0 if self._lost else self.end_margin_mm) + self.bridge_mm
        # Set-point speed: ramp up at the acceleration limit, brake to stop at s_limit.
        room = max(s_limit - self._s_set, 0.0)
        self._v_set = min(
            self._v_set + self.accel * self.dt, self.speed, math.sqrt(2.0 * self.accel * room)
        )
        step = min(self._v_set * self.dt, room)
        moving = step > 0.0
        self._s_set += step
        target, tangent = self._at(self._s_set)
        ff = tangent * (step / self.dt)
        error = float(np.linalg.norm(target - tcp_world))
        return Command(
            target, self.gain_1_s * error, velocity_ff_world=ff, stop_at_target=not moving
        )

    # ----------------------------------------------------------------- path
    def _at(self, s: float) -> tuple[FloatArray, FloatArray]:
        """Point and unit direction on the stored path at arc length s (extrapolated past
        the end along the last segment)."""
        knots = self._s
        if len(knots) < 2:
            return self._path[0], np.zeros(3)
        i = min(max(bisect.bisect_right(knots, s) - 1, 0), len(knots) - 2)
        a, b = self._path[i], self._path[i + 1]
        length = knots[i + 1] - knots[i]
        direction = (b - a) / length if length > 0 else np.zeros(3)
        return a + (s - knots[i]) * direction, direction

    def _smooth_tail(self) -> None:
        """Refit the stored points whose window the newest point entered: a least-squares line
        through the raw points within +-smoothing_mm (arc length), evaluated at the point."""
        h = self.smoothing_mm
        if h <= 0 or len(self._raw) < 3:
            return
        s_last = self._s[-1]
        first = max(bisect.bisect_left(self._s, s_last - 2 * h), 1)  # index 0 is the start pose
        s = np.asarray(self._s[first:])
        raw = np.asarray(self._raw[first:])
        targets = np.flatnonzero(s >= s_last - h)
        ds = s[None, :] - s[targets, None]  # (m, n): offsets of the window points
        w = (np.abs(ds) <= h).astype(float)
        n = w.sum(axis=1)
        sx = (w * ds).sum(axis=1)
        sxx = (w * ds * ds).sum(axis=1)
        sy = w @ raw
        sxy = (w * ds) @ raw
        det = n * sxx - sx * sx
        ok = (n >= 3) & (det > 1e-12 * np.maximum(n * sxx, 1e-300))
        # The fitted line's value at ds = 0 (its intercept).
        fitted = (sxx[:, None] * sy - sx[:, None] * sxy) / np.where(ok, det, 1.0)[:, None]
        for k, i in enumerate(targets):
            if ok[k]:
                self._path[first + i] = fitted[k]

    def _trim(self) -> None:
        """Drop stored points more than ``buffer_mm`` behind the set-point."""
        cut = bisect.bisect_left(self._s, self._s_set - self.buffer_mm) - 1
        if cut > 0:
            del self._raw[:cut], self._path[:cut], self._s[:cut]

    @property
    def lost(self) -> bool:
        """True while frames come without a seam point (the bridge is in use)."""
        return self._lost and not math.isnan(self._s_set)
