"""Defects of real scanner profiles that the synthetic generators do not draw (issue 42, item 7).

Each is a seeded, labelled change of a profile or of a joint's cross-section; the label (the
true seam point of a V-groove, the 7 points of a groove) is the noise-free truth of the
geometry drawn, never moved by a defect that only changes what the sensor reports:

* :func:`far_outlier`: one valid point moved along its ray until it lies ``distance_mm``
  (150 mm) from the nearest other valid point (a stray reflection off the torch, a cable);
* :func:`second_bounce`: a run of columns in the groove reports the mirror image of a stretch
  of the opposite wall's stripe in the wall it lies on (a specular wall acts as a mirror: the
  camera sees the lit opposite wall in it and triangulates the virtual image; on a 60 deg V it
  lies at the root's depth under the mirror flank, on a 145 deg V below the root, under the
  other flank, 37.5 deg off the vertical);
* :func:`hide_wall`: the upper part of one wall, from its top corner down a share of its
  length, returns nothing (the camera cannot see it: a gap in the points between the plate
  and the fill);
* :func:`v_section`: a V-groove cross-section with hi-lo (the right plate ``step_mm`` lower)
  and the right plate tilted ``tilt_deg`` about its root corner (angular distortion);
* :func:`groove_hi_lo`, :func:`groove_tilt`: the same for a groove of
  :mod:`seamtrack.features.synthetic_groove` (station frame), before it is filled.

Walls are given in the laser frame as (2, 2) (top corner, bottom corner) pairs, left then
right: the V-groove's (top edge, root), the groove's (top corner, bottom corner) of its 7
points. Every random draw comes from the ``rng`` passed in.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seamtrack.features.synthetic_groove import Groove
from seamtrack.sensing.profiles import Profile, Reason

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

#: The far outlier's distance from the rest of the profile (mm; issue 42, item 7).
OUTLIER_MM = 150.0
#: Length of the opposite wall's stretch mirrored by a second bounce (mm, uniform).
BOUNCE_SPAN_MM = (1.0, 3.0)
#: Share of a wall's length hidden from its top corner down (uniform).
HIDDEN_SHARE = (0.5, 0.9)
#: A hi-lo step's foot lies this far inside the groove from the higher wall's foot (mm).
_STEP_IN_MM = 0.01
#: Half length of the plates drawn (mm), as :mod:`seamtrack.features.synthetic`'s.
_FAR_MM = 1000.0


@dataclass(frozen=True)
class Defect:
    """What a defect did to a profile (its label beside the geometry's truth).

    Attributes
    ----------
    variant : str
    columns : (k,) int
        The columns it changed (the outlier's, the ghost's, the hidden ones).
    ghost_laser : (k, 2) float
        The points it put there (the outlier, the ghost run); (0, 2) for a hidden wall.
    span_laser : (2, 2) float
        The hidden stretch of wall (top, bottom) or the mirrored stretch of the opposite wall;
        NaN for the outlier.
    side : int
        The wall hidden or acting as the mirror (0 left, 1 right); -1 for the outlier.
    """

    variant: str
    columns: IntArray
    ghost_laser: FloatArray
    span_laser: FloatArray
    side: int = -1


def _with(profile: Profile, points: FloatArray, reason: NDArray[np.uint8]) -> Profile:
    valid = reason == Reason.VALID
    out = np.where(valid[:, None], points, np.nan)
    return Profile(out, valid=valid, reason=reason, T_world_sensor=profile.T_world_sensor)


def _reason(profile: Profile) -> NDArray[np.uint8]:
    if profile.reason is not None:
        return np.array(profile.reason, dtype=np.uint8)
    return np.where(_valid(profile), Reason.VALID, Reason.MISS).astype(np.uint8)


def _valid(profile: Profile) -> NDArray[np.bool_]:
    return np.asarray(profile.valid, dtype=bool)


def nearest_other_mm(points: FloatArray, index: int) -> float:
    """Distance (mm) from ``points[index]`` to the nearest other finite point of ``points``."""
    p = np.asarray(points, dtype=np.float64)
    others = np.delete(p, index, axis=0)
    others = others[np.isfinite(others).all(axis=1)]
    return float(np.min(np.hypot(*(others - p[index]).T)))


def far_outlier(
    profile: Profile, rng: np.random.Generator, distance_mm: float = OUTLIER_MM
) -> tuple[Profile, Defect]:
    """``profile`` with one valid point (drawn uniformly) moved along its ray, away from the
    sensor, until its nearest other valid point is ``distance_mm`` away."""
    pts = np.array(profile.points_laser, dtype=np.float64)
    lit = np.flatnonzero(_valid(profile))
    i = int(lit[rng.integers(0, len(lit))])
    ray = pts[i] / math.hypot(*pts[i])
    others = np.delete(pts[lit], np.searchsorted(lit, i), axis=0)
    r = math.hypot(*pts[i])
    for _ in range(200):  # d(min distance)/dr is ~1 once the point has left the profile
        gap = distance_mm - float(np.min(np.hypot(*(others - r * ray).T)))
        r += gap
        if abs(gap) < 1e-9:
            break
    pts[i] = r * ray
    defect = Defect("outlier", np.array([i]), pts[[i]].copy(), np.full((2, 2), np.nan))
    return _with(profile, pts, _reason(profile)), defect


def _mirror(points: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
    """(k, 2) ``points`` mirrored through the line from ``a`` to ``b``."""
    d = (b - a) / math.hypot(*(b - a))
    rel = points - a
    along = rel @ d
    return np.asarray(a + 2 * along[:, None] * d - rel)


def second_bounce(
    profile: Profile,
    walls: FloatArray,
    rng: np.random.Generator,
    span_mm: tuple[float, float] = BOUNCE_SPAN_MM,
) -> tuple[Profile, Defect]:
    """``profile`` with a second-bounce ghost: a stretch of one wall's stripe (``span_mm``
    long, uniform, placed uniformly along the wall) mirrored through the other wall's line,
    each ghost point in the column whose ray passes nearest it (the column's point replaced,
    as a sensor keeps one peak a column), where that column lies between the top corners.

    ``walls`` : (2, 2, 2) float, the (top, bottom) corners of the left and right wall."""
    w = np.asarray(walls, dtype=np.float64)
    side = int(rng.integers(0, 2))
    src_top, src_bottom = w[1 - side]
    length = math.hypot(*(src_bottom - src_top))
    span = min(float(rng.uniform(*span_mm)), length)
    start = float(rng.uniform(0.0, length - span))
    unit = (src_bottom - src_top) / length
    t = start + np.linspace(0.0, span, max(2, int(span / 0.002)))
    stretch = src_top + t[:, None] * unit
    ghost = _mirror(stretch, w[side, 0], w[side, 1])
    pts = np.array(profile.points_laser, dtype=np.float64)
    reason = _reason(profile)
    lit = np.flatnonzero(reason == Reason.VALID)
    angles = np.arctan2(pts[lit, 0], pts[lit, 1])  # rays: points stay on their column's ray
    order = np.argsort(angles)
    lo, hi = sorted(math.atan2(*c) for c in (w[0, 0], w[1, 0]))
    g_angle = np.arctan2(ghost[:, 0], ghost[:, 1])
    inside = (g_angle > lo) & (g_angle < hi)
    ghost, g_angle = ghost[inside], g_angle[inside]
    k = np.clip(np.searchsorted(angles[order], g_angle), 1, max(1, len(order) - 1))
    nearer = np.abs(angles[order][k - 1] - g_angle) < np.abs(angles[order][k] - g_angle)
    cols = lit[order[np.where(nearer, k - 1, k)]]
    cols, first = np.unique(cols, return_index=True)
    pts[cols] = ghost[first]
    defect = Defect(
        "reflection", cols, ghost[first].copy(), np.array([stretch[0], stretch[-1]]), side
    )
    return _with(profile, pts, reason), defect


def hide_wall(
    profile: Profile,
    walls: FloatArray,
    rng: np.random.Generator,
    share: tuple[float, float] = HIDDEN_SHARE,
) -> tuple[Profile, Defect]:
    """``profile`` with the upper part of one wall (drawn) unseen: every column whose ray
    passes between the wall's top corner and the point ``share`` (uniform) of the way down to
    its bottom corner returns nothing (``Reason.OCCLUDED``)."""
    w = np.asarray(walls, dtype=np.float64)
    side = int(rng.integers(0, 2))
    top, bottom = w[side]
    end = top + float(rng.uniform(*share)) * (bottom - top)
    lo, hi = sorted((math.atan2(*top), math.atan2(*end)))
    pts = np.array(profile.points_laser, dtype=np.float64)
    reason = _reason(profile)
    with np.errstate(invalid="ignore"):
        angle = np.arctan2(pts[:, 0], pts[:, 1])
        cols = np.flatnonzero((reason == Reason.VALID) & (angle > lo) & (angle < hi))
    reason[cols] = Reason.OCCLUDED
    defect = Defect("occlusion", cols, np.empty((0, 2)), np.array([top, end]), side)
    return _with(profile, pts, reason), defect


# ----------------------------------------------------------------- cross-sections
def _rotate(points: FloatArray, centre: FloatArray, angle_rad: float) -> FloatArray:
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    rel = np.asarray(points, dtype=np.float64) - centre
    return np.asarray(centre + rel @ np.array([[c, s], [-s, c]]))


def v_section(
    angle_deg: float = 60.0, depth_mm: float = 7.0, step_mm: float = 0.0, tilt_deg: float = 0.0
) -> tuple[FloatArray, FloatArray, FloatArray, float]:
    """A V-groove with no gap and no root face in the joint frame of
    :mod:`seamtrack.features.synthetic` (y lateral, z into the part), as ``section`` for
    :func:`~seamtrack.features.synthetic.synthetic_profile`: the right plate ``step_mm`` deeper
    (hi-lo; its root corner under the left's, joined by a vertical face), then turned by
    ``tilt_deg`` about its root corner (positive: its top rises from the root outward).

    Returns (segments (k, 2, 2), seam (2,), top edges (2, 2), gap 0): the seam is the midpoint
    of the two root corners (:func:`~seamtrack.features.synthetic.joint_section`'s)."""
    half = math.radians(angle_deg) / 2
    if not (0 < half < math.pi / 2 and depth_mm > 0):
        raise ValueError("v_section needs 0 < angle_deg < 180 and depth_mm > 0")
    w, t, m = depth_mm * math.tan(half), depth_mm, step_mm
    root_r = np.array([0.0, t + m])
    right = np.array([[0.0, t + m], [w, m], [_FAR_MM, m]])
    right = _rotate(right, root_r, -math.radians(tilt_deg))
    left = np.array([[-_FAR_MM, 0.0], [-w, 0.0], [0.0, t]])
    v = np.vstack([left, right])
    segs = np.stack([v[:-1], v[1:]], axis=1)
    segs = segs[np.hypot(*(segs[:, 1] - segs[:, 0]).T) > 0]
    return segs, np.array([0.0, t + m / 2]), np.array([[-w, 0.0], right[1]]), 0.0


def _right_side(g: Groove) -> NDArray[np.bool_]:
    """The surface vertices of ``g``'s right plate and wall: from its right foot on."""
    foot_y = float(g.foot[1, 0])
    return np.asarray(g.surface[:, 0] >= foot_y - 1e-12)


def groove_hi_lo(g: Groove, step_mm: float) -> Groove:
    """``g`` (empty) with its right plate and wall ``step_mm`` lower (station frame, z up;
    negative: higher). The bottom (a backing bar under a gap) stays at the lower plate's
    foot; the higher plate's wall ends at its own foot, above it, joined to the bottom by a
    vertical step (its butt face's edge, seen through the gap)."""
    right = _right_side(g)
    surface = g.surface.copy()
    surface[right, 1] -= step_mm
    top, foot = g.top.copy(), g.foot.copy()
    top[1, 1] -= step_mm
    foot[1, 1] -= step_mm
    i = int(np.flatnonzero(right)[0])  # the right foot's vertex
    low = float(min(foot[0, 1], foot[1, 1]))
    # The step's foot lies _STEP_IN_MM inside the groove from the higher foot, so that the
    # bottom between the feet is a surface of its own (groove_points puts the bottom points
    # on it, not on the feet's chord).
    if step_mm > 0:  # the left foot stands above the bottom
        surface = np.insert(surface, i, [foot[0, 0] + _STEP_IN_MM, low], axis=0)
    elif step_mm < 0:  # the right foot stands above the bottom
        surface = np.insert(surface, i, [foot[1, 0] - _STEP_IN_MM, low], axis=0)
    return dataclasses.replace(g, surface=surface, top=top, foot=foot)


def groove_tilt(g: Groove, tilt_deg: float) -> Groove:
    """``g`` (empty) with its right plate and wall turned by ``tilt_deg`` about the right
    wall's foot (positive: the plate's top rises from the groove outward)."""
    right = _right_side(g)
    centre = g.foot[1]
    surface = g.surface.copy()
    angle = math.radians(tilt_deg)
    surface[right] = _rotate(surface[right], centre, angle)
    top = g.top.copy()
    top[1] = _rotate(top[[1]], centre, angle)[0]
    return dataclasses.replace(g, surface=surface, top=top)
