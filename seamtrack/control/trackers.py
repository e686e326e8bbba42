"""The paper's seam tracking algorithms (Sec. 4.1-4.2), the user-replaceable part of the paper
(its DLL): algorithm I is ``point-to-point``, algorithm II ``convergence-radius``; both follow
the :class:`~seamtrack.control.tracking.Tracker` protocol.
"""

from __future__ import annotations

from collections import deque

import numpy as np
from numpy.typing import NDArray

from seamtrack.control.tracking import Command, Measurement, TrackerContext
from seamtrack.errors import PluginError
from seamtrack.params import NonNegative, Positive

FloatArray = NDArray[np.float64]


class _PointQueue:
    """Seam points waiting to be welded, in the order they were measured.

    A point closer than ``min_spacing_mm`` to the last one queued adds nothing: a sensor that
    looks at the same spot while the robot waits keeps reporting (nearly) the same point.
    """

    def __init__(self, min_spacing_mm: float):
        self.min_spacing_mm = min_spacing_mm
        self.points: deque[FloatArray] = deque()
        self._last: FloatArray | None = None

    def push(self, point: FloatArray) -> None:
        if self._last is not None and np.linalg.norm(point - self._last) < self.min_spacing_mm:
            return
        self.points.append(point)
        self._last = point

    def __len__(self) -> int:
        return len(self.points)


class _QueueTracker:
    """What the paper's two trackers share: the measured seam points, queued (at least
    ``min_spacing_mm`` apart), and the welding speed."""

    min_spacing_mm: float

    def reset(self, context: TrackerContext) -> None:
        self.speed = context.welding_speed_mm_s
        self.queue = _PointQueue(self.min_spacing_mm)
        self._command: Command | None = None

    def update(self, measurement: Measurement) -> None:
        if measurement:
            self.queue.push(measurement.point_world)


class PointToPoint(_QueueTracker):
    """The paper's seam tracking algorithm I (Sec. 4.1, Fig. 10).

    Go to each sensed seam point in turn, and take the next point only after converging on the
    current one: within ``tolerance_mm`` (default: the sensor's resolution, below which
    improving is meaningless, Sec. 4.3) and at rest ("it finishes performing the previous
    command", Sec. 4.2).

    The paper's robot "must keep the welding speed at 5 mm/sec", so by default each move is
    commanded at the welding speed with no deceleration: the torch reaches the point at speed,
    overshoots by about v^2 / (2 a) and swings about it, never at rest within the tolerance,
    and the tracker waits for ever (Sec. 4.2: "it could not converge near the desired
    position"). With ``decelerate=True`` the robot brakes onto each point instead (a modern
    controller's fine-positioning move): it converges, but stops at every point and cannot keep
    the welding speed either.

    Parameters
    ----------
    tolerance_mm : float, optional
        Convergence distance; default the sensor's lateral resolution.
    decelerate : bool
        Brake onto each point (True) or keep the welding speed (False, the paper's robot).
    min_spacing_mm : float
        Measured points closer than this to the previous one are ignored.
    """

    name = "point-to-point"

    def __init__(
        self,
        tolerance_mm: Positive | None = None,
        decelerate: bool = False,
        min_spacing_mm: NonNegative = 0.05,
    ):
        self.tolerance_mm = tolerance_mm
        self.decelerate = decelerate
        self.min_spacing_mm = min_spacing_mm

    def reset(self, context: TrackerContext) -> None:
        super().reset(context)
        self.tol = (
            self.tolerance_mm if self.tolerance_mm is not None else (context.sensor_resolution_mm)
        )
        self.rest_speed = 0.01 * self.speed

    def command(
        self, t_s: float, tcp_world: FloatArray, tcp_velocity_world: FloatArray
    ) -> Command | None:
        points = self.queue.points
        while points:
            target = points[0]
            converged = (
                np.linalg.norm(tcp_world - target) <= self.tol
                and np.linalg.norm(tcp_velocity_world) <= self.rest_speed
            )
            if not converged:
                break
            points.popleft()
            self._command = None
        if not points:
            return None
        if self._command is None:
            self._command = Command(points[0], self.speed, stop_at_target=self.decelerate)
        return self._command


class ConvergenceRadius(_QueueTracker):
    """The paper's seam tracking algorithm II (Sec. 4.3, Fig. 12-13).

    Move towards the current seam point at the welding speed without stopping, and switch to
    the next one as soon as the torch is within ``radius_mm`` of it (the radius of
    convergence). The last known point is approached with a finishing move, so that the torch
    waits there (instead of overshooting) when the sensor has nothing newer.

    Parameters
    ----------
    radius_mm : float
        Radius of convergence.
    min_spacing_mm : float
        Measured points closer than this to the previous one are ignored.
    """

    name = "convergence-radius"

    def __init__(self, radius_mm: Positive = 1.0, min_spacing_mm: NonNegative = 0.05):
        if not radius_mm > 0:
            raise PluginError(
                f"radius must be > 0, got {radius_mm}",
                field="tracker.radius_mm",
                fix="give the radius of convergence in mm, e.g. 1.0",
            )
        self.radius_mm = radius_mm
        self.min_spacing_mm = min_spacing_mm

    def command(
        self, t_s: float, tcp_world: FloatArray, tcp_velocity_world: FloatArray
    ) -> Command | None:
        points = self.queue.points
        while len(points) > 1 and np.linalg.norm(tcp_world - points[0]) <= self.radius_mm:
            points.popleft()
            self._command = None
        if not points:
            return None
        last = len(points) == 1
        if self._command is None or last != self._command.stop_at_target:
            self._command = Command(points[0], self.speed, stop_at_target=last)
        return self._command
