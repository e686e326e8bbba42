"""How a pass of a multi-pass job steers its torch: the sense function the loop calls at every
frame, which records the frame, refuses a frame below the fill the pass before measured, starts
the pass on the plan until its sensor sees the groove, moves the measured point to where the
plan's bead aims, and sets the tracker's speed along the seam from the plan (or from the
planner's ``adapt`` answer at the station the sensor sees).

Frames: the 7 groove points are in station frames (:mod:`seamtrack.multipass.paths`); features
in the laser's and the world's. mm, s.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.control.fill_layout import MeasuredGroove
from seamtrack.control.planner import PassPlan
from seamtrack.errors import PluginRuntimeError, plugin_failed
from seamtrack.geometry.groove_points import LEFT_FOOT, MIDDLE, POINT_INDEX, RIGHT_FOOT
from seamtrack.geometry.seam import Seam
from seamtrack.multipass.aim import aim_point, planned_feature
from seamtrack.multipass.paths import (
    STATION_SPACING_MM,
    FrameGroove,
    frame_groove,
    measured_groove,
    one_station,
    settled,
)
from seamtrack.sensing.profiles import Feature
from seamtrack.simulation.assemble import Parts

if TYPE_CHECKING:
    from seamtrack.workpiece.fill import FillState

FloatArray = NDArray[np.float64]

#: A frame whose fill surface lies this far (mm) below the pass before's is no groove.
FILL_DROP_MM = 1.0

#: References no bead moves (the bevels' top edges): a cap bead's frame that misses one takes
#: it from the pass before's measurement.
FIXED_REFERENCES = ("left_top", "right_top")


class SteeredSense:
    """A pass's sense function: records every frame's feature in ``frames`` (and, in ``each``,
    its groove: :func:`~seamtrack.multipass.paths.frame_groove`), moves the measured point by
    the plan's lateral offset there (station frame), and sets the tracker's speed along the
    seam from the plan; ``adapt(groove_ahead, plan)`` (a planner's, optional) may replace the
    speed and offset at the station the sensor sees, for when the torch gets there. A frame
    whose fill surface lies more than :data:`FILL_DROP_MM` below the one the pass before
    measured there (``previous``, a running median along the seam:
    :func:`~seamtrack.multipass.paths.settled`; the fill only grows) is taken as no groove.
    Until the pass's sensor measures the groove, the torch follows the plan on ``expected``
    (``previous`` with its pass's bead added: :func:`~seamtrack.control.fill_layout.after_bead`),
    else on ``previous``. ``plan`` None: the scan pass, which only records."""

    def __init__(
        self,
        parts: Parts,
        fill: FillState,
        cad_seam: Seam,
        plan: PassPlan | None,
        frames: list[tuple[Feature, FloatArray]],
        adapt: Callable[[MeasuredGroove, PassPlan], Any] | None = None,
        planner_name: str = "planner",
        previous: MeasuredGroove | None = None,
        each: list[FrameGroove | None] | None = None,
        expected: MeasuredGroove | None = None,
    ) -> None:
        self.sense = parts.sense
        self.fill, self.cad_seam, self.plan = fill, cad_seam, plan
        self.frames, self.each = frames, each
        self.adapt, self.planner_name = adapt, planner_name
        self.guide = previous if expected is None else expected
        self.T_sensor_tcp = np.linalg.inv(np.asarray(parts.robot.T_tcp_sensor, dtype=float))
        self.lateral = fill.T_world_station[:, :3, 1]
        self.T_station_world = np.asarray(np.linalg.inv(fill.T_world_station), dtype=np.float64)
        self.s_stations = fill.s_mm
        self.set_speed = getattr(parts.tracker, "set_speed", None)
        #: what a frame is checked against
        self.floor = None if previous is None else settled(previous)
        #: speed, offset per station, from the planner's adapt (NaN: the plan's)
        self.adapted = np.full((len(self.s_stations), 2), np.nan)
        #: the pass's sensor has measured the groove
        self.seen = False

    def station(self, s: float) -> int:
        return min(int(np.searchsorted(self.s_stations, s)), len(self.s_stations) - 1)

    def __call__(self, T_world_sensor: FloatArray, t_s: float, hint: Any = None) -> Feature:
        if hint is not None:
            feature = self.sense(T_world_sensor, t_s, hint)
        else:
            feature = self.sense(T_world_sensor, t_s)
        self.frames.append((feature, T_world_sensor))
        plan = self.plan
        if plan is None:
            return feature
        feature, now = self.checked(feature, T_world_sensor)
        planned = None  # the pass before's groove where this frame gives none (not yet seen)
        if feature:
            self.seen = True
        elif self.guide is not None and (
            not self.seen or (plan.cap and plan.reference in FIXED_REFERENCES)
        ):
            # not yet seen: start on the plan; a cap bead's top corner, which no bead moves,
            # and whose height is the cap's aim: where the pass before measured it (a cap's
            # edge bead puts the sensor so far off the groove's middle that the far plate
            # leaves its stripe now and then)
            feature = planned_feature(feature, T_world_sensor, self.fill, plan, self.guide,
                                      STATION_SPACING_MM)  # fmt: skip
            planned = one_station(frame_groove(feature, T_world_sensor, self.fill, self.cad_seam,
                                               self.T_station_world), self.fill)  # fmt: skip
        if feature:
            feature = self.aimed(feature, plan, now, planned, t_s)
        if self.set_speed is not None:
            self.set_tracker_speed(T_world_sensor, plan)
        return feature

    def checked(
        self, feature: Feature, T_world_sensor: FloatArray
    ) -> tuple[Feature, MeasuredGroove | None]:
        """The frame's feature (failed where it lies below the fill the pass before measured)
        and its 7 points at their station (measured once: the checks share it)."""
        one = frame_groove(feature, T_world_sensor, self.fill, self.cad_seam,
                           self.T_station_world)  # fmt: skip
        now = one_station(one, self.fill)
        if (
            feature
            and self.floor is not None
            and below_the_fill(self.frames[-1], self.fill, self.cad_seam, self.floor, now)
        ):
            feature = Feature.failed("below the fill the pass before measured", feature.joint)
            self.frames[-1] = (feature, T_world_sensor)
            one = now = None
        if self.each is not None:
            self.each.append(one)
        return feature, now

    def aimed(
        self,
        feature: Feature,
        plan: PassPlan,
        now: MeasuredGroove | None,
        planned: MeasuredGroove | None,
        t_s: float,
    ) -> Feature:
        """The feature moved to where the plan's bead aims at the station it sees."""
        s = float(self.cad_seam.closest(feature.point_world[None]).arc_length_mm[0])
        i = self.station(s)
        if self.adapt is not None and now is not None:
            self.adapted[i] = adapted_answer(self.adapt, now, plan, self.planner_name, t_s)
        offset = self.adapted[i, 1] if np.isfinite(self.adapted[i, 1]) else float(plan.offset_at(s))
        own = offset or plan.cap or plan.reference not in ("left", "right", "centre")
        here = (now if now is not None else planned) if own else None
        if here is not None:  # on the fill surface the frame measured, under the bead
            k = min(int(np.searchsorted(self.s_stations, here.s_mm[0])), len(self.s_stations) - 1)
            y, z = aim_point(here.points, POINT_INDEX[plan.reference], offset, plan.cap)[0]
            point = (self.fill.T_world_station[k] @ np.array([0.0, y, z, 1.0]))[:3]
            feature = dataclasses.replace(feature, point_world=point)
        elif offset:  # the planned point (no groove measured yet)
            point = feature.point_world + offset * self.lateral[i]
            feature = dataclasses.replace(feature, point_world=point)
        return feature

    def set_tracker_speed(self, T_world_sensor: FloatArray, plan: PassPlan) -> None:
        """The tracker's speed at the torch's station: the planner's adapted one, else the
        plan's."""
        assert self.set_speed is not None
        tcp = (T_world_sensor @ self.T_sensor_tcp)[:3, 3]
        s_tcp = float(self.cad_seam.closest(tcp[None]).arc_length_mm[0])
        speed = self.adapted[self.station(s_tcp), 0]
        self.set_speed(float(speed) if np.isfinite(speed) else float(plan.speed_at(s_tcp)))


def below_the_fill(
    frame: tuple[Feature, FloatArray],
    fill: FillState,
    seam: Seam,
    previous: MeasuredGroove,
    now: MeasuredGroove | bool | None = False,
) -> bool:
    """Whether a frame's fill surface (its middle bottom point) lies more than
    :data:`FILL_DROP_MM` below the one measured there by the pass before, or its bottom
    corners lie more than twice that inside the pass before's (the fill surface only widens
    up a V's walls; a frame that shows part of it, at the part's end, is no groove).
    ``now``: the frame's :func:`~seamtrack.multipass.paths.measured_groove`, when the caller
    has it already."""
    if now is False:
        now = measured_groove([frame], fill, seam)
    assert now is None or isinstance(now, MeasuredGroove)
    if now is None or not len(previous):
        return False
    at = now.s_mm[0]
    p = previous.points
    left_before = float(np.interp(at, previous.s_mm, p[:, LEFT_FOOT, 0]))
    right_before = float(np.interp(at, previous.s_mm, p[:, RIGHT_FOOT, 0]))
    middle_before = float(np.interp(at, previous.s_mm, p[:, MIDDLE, 1]))
    here = now.points[0]
    return bool(
        here[MIDDLE, 1] < middle_before - FILL_DROP_MM
        or here[LEFT_FOOT, 0] > left_before + 2 * FILL_DROP_MM
        or here[RIGHT_FOOT, 0] < right_before - 2 * FILL_DROP_MM
    )


def adapted_answer(
    adapt: Callable[[MeasuredGroove, PassPlan], Any],
    ahead: MeasuredGroove,
    plan: PassPlan,
    name: str,
    t_s: float,
) -> tuple[float, float]:
    """A planner's ``adapt`` answer checked: (speed, offset), NaN where it keeps the plan."""
    try:
        answer = adapt(ahead, plan)
    except Exception as exc:  # the user's planner may fail in any way
        raise plugin_failed("planner.name", name, "adapt", t_s, exc) from exc
    if answer is None:
        return math.nan, math.nan
    try:
        speed, offset = (float(v) for v in answer)
    except (TypeError, ValueError):
        speed, offset = math.nan, math.inf
    if not (math.isfinite(offset) and math.isfinite(speed) and speed > 0):
        raise PluginRuntimeError(
            f"{name!r} adapt() returned {answer!r} at t = {t_s:.6g} s",
            field="planner.name",
            fix="return (speed_mm_s > 0, offset_mm), or None to keep the plan",
        )
    return speed, offset
