"""The groove and paths a multi-pass job measures and lays its beads along (from
:mod:`seamtrack.multipass.job`): the pass's true path, the groove the sensor measured, the
arc's path from the trace, the ramps and the run-off to the part's ends."""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from seamtrack.control.fill_layout import MeasuredGroove
from seamtrack.control.planner import PassPlan
from seamtrack.geometry.groove_points import (
    LEFT_TOP,
    MIDDLE,
    POINT_INDEX,
    RIGHT_TOP,
)
from seamtrack.geometry.seam import Seam
from seamtrack.geometry.smoothing import station_median
from seamtrack.multipass.aim import aim_point
from seamtrack.sensing.profiles import Feature, laser_to_world
from seamtrack.simulation.loop import Result

if TYPE_CHECKING:
    from seamtrack.workpiece.fill import FillState

FloatArray = NDArray[np.float64]

#: Station spacing of the fill state (mm): the issue's "every <= 0.5 mm".
STATION_SPACING_MM = 0.5

#: A bead that stops this close (mm) to the part's end is run off the edge (:func:`to_the_ends`).
RUN_OFF_MM = 3.0


def pass_path(fill: FillState, reference: str, plan: PassPlan | None, window: int = 4) -> Seam:
    """A pass's true path in the world: at every station the reference point of the true fill
    surface (left or right wall's foot, or the middle; a running median over ``2 window + 1``
    stations, 2 mm: where a toe wets a wall the foot jumps along it from one station to the
    next, faster than any torch follows), moved across the seam by the plan's offset there,
    onto the fill surface the bottom points describe, or a cap bead at the plates' top line
    (:func:`~seamtrack.multipass.aim.aim_point`: where the bead aims, as the tracker does
    with the measured points)."""
    pts = station_median(fill.all_groove_points(), window)
    offset = np.zeros(len(pts)) if plan is None else plan.offset_at(fill.s_mm)
    yz = aim_point(pts, POINT_INDEX[reference], offset, plan is not None and plan.cap)
    local = np.column_stack([np.zeros(len(yz)), yz[:, 0], yz[:, 1], np.ones(len(yz))])
    points = np.einsum("mij,mj->mi", fill.T_world_station, local)[:, :3]
    return Seam.from_points(points, field="passes", name="pass path")


#: One frame's groove: its station's index, its 7 points (7, 2) there and its area.
FrameGroove = tuple[int, FloatArray, float]


def measured_groove(
    frames: list[tuple[Feature, FloatArray]],
    fill: FillState,
    cad_seam: Seam,
    T_station_world: FloatArray | None = None,
    each: list[FrameGroove | None] | None = None,
) -> MeasuredGroove | None:
    """The groove as the pass's sensor measured it (None: in no frame): every frame's 7
    points (the groove extractor's ``edges_laser``) in the frame of the station nearest to
    them, the median per station; stations no frame saw are left out. ``T_station_world``:
    the stations' inverse poses (``np.linalg.inv(fill.T_world_station)``), when the caller
    keeps them (a pass asks this every frame). ``each``: every frame's :func:`frame_groove`,
    when the caller has them (a pass's sense function keeps them as it goes)."""
    if each is None or len(each) != len(frames):
        if len(frames) == 1:  # one frame (a pass's sense function, every frame): no medians
            return one_station(frame_groove(*frames[0], fill, cad_seam, T_station_world), fill)
        if T_station_world is None:
            T_station_world = np.asarray(np.linalg.inv(fill.T_world_station), dtype=np.float64)
        each = [frame_groove(f, T, fill, cad_seam, T_station_world) for f, T in frames]
    found = [one for one in each if one is not None]
    if not found:
        return None
    stations = np.asarray([one[0] for one in found])
    points = np.asarray([one[1] for one in found])
    areas = np.asarray([one[2] for one in found], dtype=float)
    keep = np.unique(stations)
    med_pts = np.stack([np.median(points[stations == k], axis=0) for k in keep])
    med_area = np.array([np.nanmedian(areas[stations == k]) for k in keep])
    return MeasuredGroove(fill.s_mm[keep], med_pts, med_area)


def one_station(one: FrameGroove | None, fill: FillState) -> MeasuredGroove | None:
    """One frame's groove (:func:`frame_groove`) as a measured groove of one station."""
    if one is None:
        return None
    i, yz, area = one
    return MeasuredGroove(fill.s_mm[[i]], yz[None], np.array([area], dtype=float))


def frame_groove(
    feature: Feature,
    T_world_sensor: FloatArray,
    fill: FillState,
    cad_seam: Seam,
    T_station_world: FloatArray | None = None,
) -> FrameGroove | None:
    """One frame's 7 points in the frame of the station nearest to them (y ascending), that
    station's index and the frame's area (None: no 7 points in the frame)."""
    edges = np.asarray(feature.edges_laser, dtype=float)
    if not feature or edges.shape != (7, 2) or not np.isfinite(edges).all():
        return None
    world = laser_to_world(T_world_sensor, edges)
    s = float(cad_seam.closest(world[MIDDLE][None]).arc_length_mm[0])
    i = min(int(round((s - fill.s_mm[0]) / STATION_SPACING_MM)), len(fill.s_mm) - 1)
    if T_station_world is None:
        T_station_i = np.linalg.inv(fill.T_world_station[i])
    else:  # the same numbers: numpy inverts a stack matrix by matrix
        T_station_i = T_station_world[i]
    local = (T_station_i @ np.column_stack((world, np.ones(7))).T).T
    yz = local[:, 1:3]
    if yz[LEFT_TOP, 0] > yz[RIGHT_TOP, 0]:  # the laser's left is the stations' right: y ascending
        yz = yz[::-1]
    return i, yz, float(feature.area_mm2)


def true_groove(fill: FillState) -> MeasuredGroove:
    """The CAD groove's 7 points and area (no scan-only pass: the first plan is the nominal
    groove's; later ones are measured)."""
    points = np.stack([fill.groove_points(i) for i in range(len(fill.s_mm))])
    return MeasuredGroove(fill.s_mm, points, fill.remaining_area_mm2())


def arc_path(
    result: Result, period_s: float, floor_mm_s: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The torch's path while the arc burns, its times and speeds (decimated to
    ``period_s``): from the first to the last tick at which the torch moves at least half the
    slowest process speed (the approach to the first measured point included: the torch
    starts on the groove at the seam's start); the speed bounded below by ``floor_mm_s``."""
    trace = result.trace
    idx = trace.decimated(period_s)
    path, t = trace.tcp_world[idx], trace.t_s[idx]
    if len(path) < 3:
        return path, t, np.full(len(path), floor_mm_s)
    speed = np.linalg.norm(np.gradient(path, t, axis=0), axis=1)
    moving = np.flatnonzero(speed >= 0.5 * floor_mm_s)
    if len(moving) < 2:
        return path[:0], t[:0], speed[:0]
    keep = slice(moving[0], moving[-1] + 1)
    return path[keep], t[keep], np.maximum(speed[keep], floor_mm_s)


def ramped(
    speed: FloatArray,
    planned: FloatArray,
    fraction: float = 0.95,
    handover: tuple[int, int] = (0, 0),
) -> FloatArray:
    """The speed that sets the bead's area: the actual one, except while the torch speeds up
    from rest at the start and brakes to rest at the end (before it first reaches, and after
    it last runs at, ``fraction`` of the planned speed there), where the wire feed follows the
    travel speed (a controller's synchronised arc start and crater) and the bead has its
    planned area.

    The end's braking is not one clean ramp: the tracker slows on to the last point its
    sensor saw, a millimetre or two before the plate's edge, at a fifth or so under the
    plan, then to rest. Counted at the actual speed there (a threshold of 0.8 took it so),
    that stretch laid a bead a third fatter than planned at every pass's end, the next pass's
    sensor saw the bump and its torch rose over it, and the bumps piled up layer on layer
    (a 2 mm crown over the last 5 mm of a 100 mm seam, the fill passes' trackers 0.5-1.2 mm
    off the smoothed fill surface there). Within 5 % of the plan the torch is welding; below
    it, at the ends, the crater is.

    The start is the same: the torch runs at the plan on its approach to the first point its
    sensor measured, then slows as the tracker takes over (to 3.4 mm/s for a 4.6 mm/s plan,
    over a millimetre or two), the ``handover`` (path indices, from to: :func:`handover`).
    Counted at the actual speed, that laid a bead a third fatter 10 mm into every pass, at
    the same place every pass (the sensor's look-ahead): a 1.9 mm bump by the third layer,
    which the next torch met as its first measured point and overshot by 2-4 mm. The start
    ramp ends at the first point at the plan's speed after the last slow one of the
    handover."""
    out = speed.copy()
    fast = speed >= fraction * planned
    if not fast.any():
        return planned.copy()
    first = int(np.argmax(fast))
    slow = np.flatnonzero(~fast[handover[0] : handover[1]])
    if len(slow):
        after = np.flatnonzero(fast[handover[0] + slow[-1] :])
        first = max(first, handover[0] + slow[-1] + int(after[0]) if len(after) else first)
    last = len(fast) - 1 - int(np.argmax(fast[::-1]))
    out[:first] = planned[:first]
    out[last + 1 :] = planned[last + 1 :]
    return out


#: How far past the first point its sensor measured (mm) a torch may still be slowing as the
#: tracker takes over from its approach (:func:`ramped`; up to 4 mm past it measured on
#: multipass-v-groove's 12-pass plan, the slowest 2.9 mm/s of 4.6 planned).
HANDOVER_MM = 6.0


def handover(result: Result, path_s_mm: FloatArray) -> tuple[int, int]:
    """The indices of the arc's path (its points' arc lengths ``path_s_mm``, ascending) from
    where the torch reaches the first point its sensor measured (the loop's welding portion
    starts: the end of its approach) to :data:`HANDOVER_MM` past it ((0, 0): none)."""
    welding = np.flatnonzero(result.trace.welding)
    if not len(welding) or not len(path_s_mm):
        return 0, 0
    s_on = float(result.trace.arc_length_mm[welding[0]])
    lo, hi = np.searchsorted(path_s_mm, [s_on, s_on + HANDOVER_MM])
    return int(lo), int(hi)


def to_the_ends(path: FloatArray, area: FloatArray, seam: Seam) -> tuple[FloatArray, FloatArray]:
    """The path carried on along the seam to the part's ends where it stops within
    :data:`RUN_OFF_MM` of them (the torch stops at the last seam point its sensor saw, a
    fraction of a mm before the plate's edge; a welder runs the bead off the edge), with the
    area at its end."""
    if len(path) < 2:
        return path, area
    s = seam.closest(path[[0, -1]]).arc_length_mm
    ends = seam.interpolate([0.0, seam.length_mm])
    head = [ends[0] + (path[0] - seam.interpolate([s[0]])[0])] if 0 < s[0] <= RUN_OFF_MM else []
    gap = seam.length_mm - s[1]
    tail = [ends[1] + (path[-1] - seam.interpolate([s[1]])[0])] if 0 < gap <= RUN_OFF_MM else []
    path = np.vstack([*head, path, *tail])
    area = np.concatenate([area[:1]] * len(head) + [area] + [area[-1:]] * len(tail))
    return path, area


def settled(groove: MeasuredGroove, half_window: int = 4) -> MeasuredGroove:
    """``groove`` with its 7 points a running median over 2 * half_window + 1 stations (cut
    short at the ends): what a frame is checked against. At a part's end the last station's
    frames see the stripe leave the part (a groove 0.8 mm wide at the root, where the fill
    lies 7-10 mm up), and the pass before's median there is as wrong as the frame it would
    reject."""
    if len(groove) <= 2:
        return groove
    points = station_median(groove.points, half_window, cut_ends=True)
    return MeasuredGroove(groove.s_mm, points, groove.area_mm2)
