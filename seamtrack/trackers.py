"""Seam tracking algorithms: the user-replaceable part of the paper (Sec. 2.5, its DLL).

A tracker is any object with three methods (the :class:`Tracker` protocol):

* ``reset(context)`` once before the run, with the welding speed, periods and start pose;
* ``update(measurement)`` at every sensor frame, when the measurement *arrives* (capture time
  plus the sensor latency), with the seam point in the world frame (or a falsy measurement);
* ``command(t_s, tcp_world, tcp_velocity_world)`` at every control tick, returning the move the
  robot should execute (a :class:`Command`) or ``None`` to brake to rest and wait.

Built-ins: the paper's algorithm I (``point-to-point``), algorithm II (``convergence-radius``)
and a look-ahead ``trajectory`` tracker. A user's class is named in the scene as
``tracker.name = "package.module:Class"`` or registered under the entry-point group
``seamtrack.trackers``.
"""

from __future__ import annotations

import importlib
import inspect
from collections import deque
from dataclasses import dataclass, field
from importlib.metadata import entry_points
from typing import Any, Protocol, runtime_checkable

import numpy as np
from numpy.typing import NDArray

from .errors import PluginError
from .profiles import Feature

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
    """

    target_world: FloatArray
    speed_mm_s: float
    velocity_ff_world: FloatArray | None = None
    stop_at_target: bool = False


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


@dataclass(frozen=True)
class TrackerContext:
    """What a tracker may know about the run before it starts."""

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


@runtime_checkable
class Tracker(Protocol):
    """The protocol every tracker satisfies (see the module docstring)."""

    def reset(self, context: TrackerContext) -> None: ...

    def update(self, measurement: Measurement) -> None: ...

    def command(
        self, t_s: float, tcp_world: FloatArray, tcp_velocity_world: FloatArray
    ) -> Command | None: ...


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


class PointToPoint:
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
        tolerance_mm: float | None = None,
        decelerate: bool = False,
        min_spacing_mm: float = 0.05,
    ):
        self.tolerance_mm = tolerance_mm
        self.decelerate = decelerate
        self.min_spacing_mm = min_spacing_mm

    def reset(self, context: TrackerContext) -> None:
        self.speed = context.welding_speed_mm_s
        self.tol = (
            self.tolerance_mm if self.tolerance_mm is not None else (context.sensor_resolution_mm)
        )
        self.rest_speed = 0.01 * self.speed
        self.queue = _PointQueue(self.min_spacing_mm)
        self._command: Command | None = None

    def update(self, measurement: Measurement) -> None:
        if measurement:
            self.queue.push(measurement.point_world)

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


class ConvergenceRadius:
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

    def __init__(self, radius_mm: float = 1.0, min_spacing_mm: float = 0.05):
        if not radius_mm > 0:
            raise PluginError(
                f"radius must be > 0, got {radius_mm}",
                field="tracker.radius_mm",
                fix="give the radius of convergence in mm, e.g. 1.0",
            )
        self.radius_mm = radius_mm
        self.min_spacing_mm = min_spacing_mm

    def reset(self, context: TrackerContext) -> None:
        self.speed = context.welding_speed_mm_s
        self.queue = _PointQueue(self.min_spacing_mm)
        self._command: Command | None = None

    def update(self, measurement: Measurement) -> None:
        if measurement:
            self.queue.push(measurement.point_world)

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


# --------------------------------------------------------------------------- registry
def _builtin() -> dict[str, type]:
    from .trajectory import TrajectoryTracker

    return {
        "point-to-point": PointToPoint,
        "convergence-radius": ConvergenceRadius,
        "trajectory": TrajectoryTracker,
    }


#: Short names the CLI and the paper use.
ALIASES = {
    "I": "point-to-point",
    "II": "convergence-radius",
    "1": "point-to-point",
    "2": "convergence-radius",
}

_PROTOCOL_METHODS = ("reset", "update", "command")


def tracker_class(name: str) -> type:
    """The class behind a tracker name: a built-in, ``package.module:Class``, or an entry
    point in the group ``seamtrack.trackers``."""
    name = ALIASES.get(name, name)
    builtin = _builtin()
    if name in builtin:
        return builtin[name]
    if ":" in name:
        module_name, _, attr = name.partition(":")
        try:
            module = importlib.import_module(module_name)
        except Exception as exc:  # the user's module may fail in any way on import
            raise PluginError(
                f"cannot import {module_name!r}: {exc}",
                field="tracker.name",
                fix="check the module is on PYTHONPATH (or installed) and imports",
            ) from None
        cls = getattr(module, attr, None)
        if cls is None:
            raise PluginError(
                f"module {module_name!r} has no {attr!r}",
                field="tracker.name",
                fix="name the class as package.module:Class",
            )
    else:
        found = [ep for ep in entry_points(group="seamtrack.trackers") if ep.name == name]
        if not found:
            known = ", ".join(sorted(builtin) + sorted(ALIASES))
            raise PluginError(
                f"unknown tracker {name!r}",
                field="tracker.name",
                fix=f"use one of {known}, or package.module:Class",
            )
        try:
            cls = found[0].load()
        except Exception as exc:
            raise PluginError(
                f"entry point {name!r} failed to load: {exc}",
                field="tracker.name",
                fix="repair or uninstall that plugin",
            ) from None
    missing = [m for m in _PROTOCOL_METHODS if not callable(getattr(cls, m, None))]
    if missing:
        raise PluginError(
            f"{name!r} lacks the tracker method(s) {', '.join(missing)}",
            field="tracker.name",
            fix="implement reset(context), update(measurement) and "
            "command(t_s, tcp_world, tcp_velocity_world)",
        )
    return cls


def tracker_parameters(name: str) -> set[str]:
    """Keyword parameters a tracker class takes (all names when it takes ``**kwargs``)."""
    cls = tracker_class(name)
    try:
        parameters = inspect.signature(cls).parameters
    except (TypeError, ValueError):
        return set()
    if any(p.kind is p.VAR_KEYWORD for p in parameters.values()):
        return {"radius_mm", "tolerance_mm"}
    return {k for k in parameters if k != "self"}


def tracker(name: str, **params: Any) -> Tracker:
    """Build a tracker by name with its parameters (unknown parameters are an error)."""
    cls = tracker_class(name)
    try:
        signature = inspect.signature(cls)
    except (TypeError, ValueError):
        signature = None
    if signature is not None:
        accepts_any = any(p.kind is p.VAR_KEYWORD for p in signature.parameters.values())
        unknown = [k for k in params if k not in signature.parameters and not accepts_any]
        if unknown:
            allowed = ", ".join(k for k in signature.parameters if k != "self") or "none"
            raise PluginError(
                f"{name!r} takes no parameter {unknown[0]!r}",
                field=f"tracker.{unknown[0]}",
                fix=f"parameters of this tracker: {allowed}",
            )
    try:
        instance = cls(**params)
    except PluginError:
        raise
    except Exception as exc:
        raise PluginError(
            f"{name!r} could not be created: {exc}",
            field="tracker.name",
            fix="check the tracker's parameters",
        ) from None
    return instance
