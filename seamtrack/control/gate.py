"""The seam-point gate in time, between the extractor and the tracker (issue 38): what an
industrial seam tracker does with each frame's seam point before the robot gets it.

Each frame's seam point is checked against a *search window* around the point predicted from
the last accepted ones (the line through them, crossed with this frame's laser plane): a point
farther than ``window_mm`` from the prediction is a false detection (a spatter streak, a
reflection of the arc, the edge of a tack) and the frame is *invalid*, as is a frame with no
seam point at all. After ``reacquire_frames`` invalid frames in a row the gate re-acquires: the
next point found is taken whatever its distance, and the prediction starts again from it (the
seam really moved, or the gate had locked onto a wrong track). The Riftek RF627Weld tracker does
this with a "search distance" of 15 mm from the previous point and an "invalid sequence" of 20
points, after which a new point is taken as valid (RF627Weld series manual, revision 1.1.1,
03.08.2020, p. 30, search parameters).

What a refused frame (a point outside the window) hands the tracker (``on_invalid``):

- ``"hold"``: no seam point (a falsy feature): the tracker keeps what it had, its last target
  (the point trackers) or its own bridge (``trajectory``);
- ``"predict"``: the predicted point instead of the false one, as long as the invalid frames
  have not outrun ``reacquire_frames`` and the prediction lies within the window of the last
  accepted point (a chord nearly in the laser plane predicts nothing sensible).

A frame without a seam point reaches the tracker without one in both modes: the tracker's own
rule bridges it or ends the seam there, and a tracker's end detection needs that frame (a
prediction past the seam's end would weld on beyond it).

The gate works in the world frame on :class:`~seamtrack.sensing.profiles.Feature` s, and holds
the state of one run: the loop makes a new one per run.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seamtrack.sensing.profiles import Feature

FloatArray = NDArray[np.float64]

#: What an invalid frame hands the tracker.
ON_INVALID = ("hold", "predict")
#: The Riftek RF627Weld's factory search distance (mm) and invalid sequence (points), manual
#: revision 1.1.1 (03.08.2020), p. 30.
RF627WELD_SEARCH_DISTANCE_MM = 15.0
RF627WELD_INVALID_SEQUENCE = 20
#: Accepted points the prediction's line is drawn through (the oldest to the newest): at 25 Hz
#: and 10 mm/s they span 1.6 mm of seam, enough to average the point's noise along it.
HISTORY_POINTS = 5
#: Why a frame the gate refused reaches the tracker without its seam point.
OUTSIDE = "outside the search window"


@dataclass(frozen=True)
class GateSettings:
    """The gate's settings (see the module docstring).

    Attributes
    ----------
    window_mm : float or None
        The search window's radius about the predicted point; None: no window (every point
        found is valid, the gate hands every frame on as it is).
    reacquire_frames : int
        Invalid frames in a row after which the next point found is taken (>= 1).
    on_invalid : {"hold", "predict"}
    history : int
        Accepted points the prediction is drawn through (>= 2).
    """

    window_mm: float | None = RF627WELD_SEARCH_DISTANCE_MM
    reacquire_frames: int = RF627WELD_INVALID_SEQUENCE
    on_invalid: str = "hold"
    history: int = HISTORY_POINTS

    def __post_init__(self) -> None:
        if self.window_mm is not None and not self.window_mm > 0:
            raise ValueError(f"window_mm must be > 0, got {self.window_mm}")
        if self.reacquire_frames < 1:
            raise ValueError(f"reacquire_frames must be >= 1, got {self.reacquire_frames}")
        if self.on_invalid not in ON_INVALID:
            raise ValueError(f"on_invalid must be one of {ON_INVALID}, got {self.on_invalid!r}")
        if self.history < 2:
            raise ValueError(f"history must be >= 2, got {self.history}")


def predict_point(history: FloatArray, T_world_sensor: FloatArray) -> FloatArray:
    """Where the line through the accepted points crosses a frame's laser plane.

    Parameters
    ----------
    history : (k, 3) float
        Accepted seam points, world frame, oldest first (k >= 1).
    T_world_sensor : (4, 4) float
        The frame's sensor pose; its laser plane is x_L = 0.

    Returns
    -------
    (3,) float
        The crossing of the chord from the oldest to the newest point with the plane; the
        newest point itself when there is one point, or the chord is (nearly) in the plane.
    """
    newest = history[-1]
    direction = newest - history[0]
    normal, origin = T_world_sensor[:3, 0], T_world_sensor[:3, 3]
    along = float(normal @ direction)
    if len(history) < 2 or abs(along) <= 1e-9 * (float(np.linalg.norm(direction)) + 1e-12):
        return np.array(newest, dtype=float)
    s = float(normal @ (origin - newest)) / along
    return np.asarray(newest + s * direction, dtype=float)


class SeamGate:
    """The gate of one run: call it on each frame's feature, in capture order.

    ``gate(feature, T_world_sensor)`` returns the feature the tracker gets: the frame's own
    (valid, or without a seam point), a falsy one (refused, ``hold``) or the predicted point
    (refused, ``predict``).
    Counters ``accepted``, ``refused`` (found but outside the window), ``predicted`` and
    ``reacquired`` say what it did.
    """

    def __init__(self, settings: GateSettings) -> None:
        self.settings = settings
        self.history: deque[FloatArray] = deque(maxlen=settings.history)
        self.invalid_run = 0
        self.accepted = self.refused = self.predicted = self.reacquired = 0

    def __call__(self, feature: Feature, T_world_sensor: FloatArray) -> Feature:
        T = np.asarray(T_world_sensor, dtype=float)
        found = bool(feature)
        if found and feature.point_world.shape != (3,):
            return feature  # no world point (a profile without a pose): nothing to gate
        prediction = predict_point(np.array(self.history), T) if self.history else None
        if found and self._valid(feature.point_world, prediction):
            return self._accept(feature)
        self.invalid_run += 1
        if not found:
            return feature
        self.refused += 1
        if not self._predicts(prediction):
            return Feature.failed(OUTSIDE, feature.joint)
        assert prediction is not None
        self.predicted += 1
        point_laser = (np.linalg.inv(T) @ np.append(prediction, 1.0))[1:3]
        return Feature.found(point_laser, T, confidence=0.0, joint=feature.joint)

    def _predicts(self, prediction: FloatArray | None) -> bool:
        """Whether a refused frame hands on the prediction (see the module docstring)."""
        if self.settings.on_invalid != "predict" or prediction is None:
            return False
        if self.invalid_run > self.settings.reacquire_frames:
            return False
        window = self.settings.window_mm or 0.0
        return float(np.linalg.norm(prediction - self.history[-1])) <= window

    def _valid(self, point: FloatArray, prediction: FloatArray | None) -> bool:
        window = self.settings.window_mm
        if prediction is None or window is None:
            return True
        if float(np.linalg.norm(point - prediction)) <= window:
            return True
        if self.invalid_run >= self.settings.reacquire_frames:  # re-acquire: start again here
            self.history.clear()
            self.reacquired += 1
            return True
        return False

    def _accept(self, feature: Feature) -> Feature:
        self.history.append(np.array(feature.point_world, dtype=float))
        self.invalid_run = 0
        self.accepted += 1
        return feature
