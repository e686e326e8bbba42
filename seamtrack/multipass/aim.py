"""Where a pass of a multi-pass job aims: a point off one of the groove's 7 points on the fill
surface (or, for a cap bead, at the plates' line), and the planned point a frame gives until
the pass's sensor first measures the groove.

Frames: the 7 points are in station frames (x along the seam, y lateral ascending, z out of the
groove), ordered left top corner, left foot, three bottom points, right foot, right top corner.
mm throughout.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.control.planner import MeasuredGroove, PassPlan
from seamtrack.geometry.groove_points import (
    BOTTOM,
    LEFT_FOOT,
    LEFT_TOP,
    POINT_INDEX,
    RIGHT_FOOT,
    RIGHT_TOP,
)
from seamtrack.sensing.profiles import Feature

if TYPE_CHECKING:
    from seamtrack.workpiece.fill import FillState

FloatArray = NDArray[np.float64]


def planned_feature(
    feature: Feature, T_world_sensor: FloatArray, fill: FillState, plan: PassPlan,
    previous: MeasuredGroove, spacing_mm: float,
) -> Feature:  # fmt: skip
    """Until the pass's sensor first measures the groove, a frame that does not (a crowned
    fill's first millimetres, a spatter, the arc's start) gives the planned point instead: the
    plan's reference point as the pass before measured it where the laser plane crosses the
    seam (the offset is added after, as to a measured point), so the tracker starts along the
    plan rather than stopping (beyond the stations measured before, up to 10 mm, their end's
    point). The feature carries the pass before's 7 points there (``edges_laser``), so a
    bead offset from a top corner aims at the fill surface under it, as from a measured
    frame, not at the corner's height (a torch of the 12-pass plan started 9 mm high).
    Frames off the part, or where the laser plane crosses no station, stay failed.
    ``spacing_mm``: the stations'."""
    if feature.stripe_points == 0 or not len(previous):
        return feature
    origin = fill.T_world_station[:, :3, 3]
    across = np.abs((origin - T_world_sensor[:3, 3]) @ T_world_sensor[:3, 0])
    i = int(np.argmin(across))
    reach = 10.0  # mm: the plan held this far beyond the stations measured before
    if across[i] > spacing_mm or not (
        previous.s_mm[0] - reach <= fill.s_mm[i] <= previous.s_mm[-1] + reach
    ):
        return feature
    s = fill.s_mm[i]
    yz = np.array([[np.interp(s, previous.s_mm, previous.points[:, r, c]) for c in (0, 1)]
                   for r in range(7)])  # fmt: skip
    world = fill.T_world_station[i] @ np.column_stack([np.zeros(7), yz, np.ones(7)]).T
    laser = np.linalg.solve(T_world_sensor, world)[1:3].T
    area = float(np.interp(s, previous.s_mm, previous.area_mm2))
    return Feature.found(laser[POINT_INDEX[plan.reference]], T_world_sensor, confidence=0.0,
                         joint=feature.joint or "groove", edges_laser=laser,
                         area_mm2=area)  # fmt: skip


def wall_deg(groove: MeasuredGroove, margin_deg: float = 12.0) -> float:
    """The groove extractor's ``wall_deg`` for the passes after the scan: the walls' angle
    off the plates as the scan measured them, less ``margin_deg`` (at least 35 deg, its
    default). A bead's flank by a buried wall, shallower than the bevel, is then no wall."""
    p = groove.points
    top = p[:, RIGHT_TOP] - p[:, LEFT_TOP]
    angles = []
    for a, b in ((LEFT_TOP, LEFT_FOOT), (RIGHT_TOP, RIGHT_FOOT)):
        wall = p[:, b] - p[:, a]
        cos = np.abs(np.sum(wall * top, axis=1)) / np.maximum(
            np.linalg.norm(wall, axis=1) * np.linalg.norm(top, axis=1), 1e-12
        )
        angles.append(np.degrees(np.arccos(np.clip(np.median(cos), 0.0, 1.0))))
    return float(max(35.0, min(angles) - margin_deg))


def offset_point(points: FloatArray, index: int, offset_mm: Any) -> FloatArray:
    """(m, 2) the point ``offset_mm`` (m,) across the groove from row ``index`` of the 7
    points ``points`` (m, 7, 2) (station frame, y ascending), on the surface the 7 points
    describe (piecewise linear: the walls from the top corners to the feet and the fill
    surface between; the bottom five alone where a wall leans over its foot; beyond the top
    corners, a top corner's height): where a bead laid off the reference aims. A bead beside
    the middle of a fill surface that slopes there (a bead's flank) aims at the surface under
    it, not at the middle's height."""
    points = np.asarray(points, dtype=float).reshape(-1, 7, 2)
    y = points[:, index, 0] + np.broadcast_to(np.asarray(offset_mm, dtype=float), len(points))
    z = np.array([np.interp(yi, *_profile(p)) for yi, p in zip(y, points, strict=True)])
    return np.column_stack([y, z])


def aim_point(points: FloatArray, index: int, offset_mm: Any, cap: bool = False) -> FloatArray:
    """(m, 2) where a bead ``offset_mm`` (m,) across the groove from row ``index`` of the 7
    points ``points`` (m, 7, 2) aims: a fill bead at the fill surface under it
    (:func:`offset_point`), a cap bead (``cap``) at the height of the plates' top line there
    (the line through the top corners, rows LEFT_TOP and RIGHT_TOP).

    Why a cap bead is aimed at the plates' line: the cap is laid on a fill surface left
    between the last fill beads' crowns and the valleys between them, a millimetre or two
    bumpy, partly buried walls, then the cap's own beads beside it; where the surface under
    a bead lies depends on which piece of it the 7 points' straight lines happen to cross,
    and a torch aimed there bobs by as much from one station to the next (2 mm on a bead's
    flank by a half-buried wall). A welder sets the cap's torch height from the plates'
    surfaces either side, which no bead changes, and leaves the arc's length (the
    power source's voltage control) to take up the fill surface's few tenths under it; the
    cap's crown is measured from that line too. Across the seam the cap bead still goes
    where its reference and offset put it."""
    yz = offset_point(points, index, offset_mm)
    if cap:
        p = np.asarray(points, dtype=float).reshape(-1, 7, 2)
        (y0, z0), (y1, z1) = p[:, LEFT_TOP].T, p[:, RIGHT_TOP].T
        span = np.where(np.abs(y1 - y0) > 1e-9, y1 - y0, 1.0)
        yz[:, 1] = z0 + (yz[:, 0] - y0) * (z1 - z0) / span
    return yz


def _profile(p: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The 7 points' y and z as a function of y (the bottom five where a wall leans over)."""
    rows = p if np.all(np.diff(p[:, 0]) >= 0) else p[BOTTOM]
    return rows[:, 0], rows[:, 1]
