"""The tracker protocol: what a tracker receives (:class:`Measurement`, :class:`TrackerContext`)
and what it returns (:class:`Command`).

A tracker is any object with three methods (the :class:`Tracker` protocol):

* ``reset(context)`` once before the run, with the welding speed, periods and start pose;
* ``update(measurement)`` at every sensor frame, when the measurement *arrives* (capture time
  plus the sensor latency), with the seam point in the world frame (or a falsy measurement);
* ``command(t_s, tcp_world, tcp_velocity_world)`` at every control tick, returning the move the
  robot should execute (a :class:`Command`) or ``None`` to brake to rest and wait.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from seamtrack.sensing.profiles import Feature

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Command:
    """A move in the world frame.

    Attributes
    ----------
    target_world : (3,) float
        Where the torch tip should go, mm.
    speed_mm_s : float
        Path speed towards it (the robot caps it at its axis limits).
    velocity_ff_world : (3,) float or None
        Velocity feed-forward added to the path velocity, mm/s.
    stop_at_target : bool
        Arrive at rest (a point-to-point move that "finishes") instead of passing through.
    rotation_world : (3, 3) float or None
        Tool orientation ``R_world_tcp`` to turn to (z along the torch away from the work, x
        the direction the sensor looks ahead in); None keeps the tool's orientation. A robot
        that cannot turn its tool (the paper's gantry) ignores it.
    angular_velocity_world : (3,) float or None
        The rate (rad/s, world axes) at which ``rotation_world`` itself turns: the arm turns
        its orientation goal on at this rate until the next command's rotation (feed-forward
        of the orientation). None: the goal holds still.
    """

    target_world: FloatArray
    speed_mm_s: float
    velocity_ff_world: FloatArray | None = None
    stop_at_target: bool = False
    rotation_world: FloatArray | None = None
    angular_velocity_world: FloatArray | None = None


@dataclass(frozen=True, eq=False)
class Measurement:
    """One sensor frame as the tracker receives it.

    Attributes
    ----------
    feature : Feature
        The seam point found in the frame (laser and world frame), or a falsy failure.
    t_capture_s, t_arrival_s : float
        When the frame was taken, and when it reached the tracker (latency later).
    T_world_sensor : (4, 4) float
        Pose of the sensor at capture, from the robot's measured axis positions.
    tcp_world : (3,) float
        Torch tip at capture.
    """

    feature: Feature
    t_capture_s: float
    t_arrival_s: float
    T_world_sensor: FloatArray
    tcp_world: FloatArray

    def __bool__(self) -> bool:
        return bool(self.feature)

    @property
    def point_world(self) -> FloatArray:
        """(3,) seam point in the world frame (empty when none was found)."""
        return self.feature.point_world

    @property
    def stripe_points(self) -> int:
        """Valid points in the profile of a frame without a seam point (0: the stripe is off
        the part, or hidden whole); -1 when not counted (seam mode, a found seam point)."""
        return int(getattr(self.feature, "stripe_points", -1))


@dataclass(frozen=True)
class TrackerContext:
    """What a tracker may know about the run before it starts.

    ``tool_program`` gives the tool orientations along the nominal seam (a
    :class:`~seamtrack.control.orientation.ToolProgram`: the robot program's torch angles and
    look-ahead heading); ``turns_tool`` is False for a robot that cannot turn its tool.
    """

    welding_speed_mm_s: float
    control_period_s: float
    frame_period_s: float
    latency_s: float
    look_ahead_mm: float
    sensor_resolution_mm: float
    tcp_start_world: FloatArray
    velocity_max_world: FloatArray
    acceleration_max_world: FloatArray
    rng: np.random.Generator = field(default_factory=lambda: np.random.default_rng(0))
    tool_program: Any = None
    turns_tool: bool = False


@runtime_checkable
class Tracker(Protocol):
    """The protocol every tracker satisfies (see the module docstring)."""

    def reset(self, context: TrackerContext) -> None: ...

    def update(self, measurement: Measurement) -> None: ...

    def command(
        self, t_s: float, tcp_world: FloatArray, tcp_velocity_world: FloatArray
    ) -> Command | None: ...
