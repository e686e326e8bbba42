"""Synthetic grooves, empty or partly filled with beads, and their 7 true points.

A groove is drawn in the *station frame* of issue 25 (y lateral, left to right; z out of the
groove, towards the torch; the plates' top at z = 0), as its top surface: a polyline ordered by
y, from the left plate over the left wall, the bottom (a backing bar under the root gap, the
beads laid so far) and the right wall to the right plate. Beads are laid with
:func:`seamtrack.workpiece.beads.lay_bead` (mass-conserving caps that wet the walls).

The groove's **7 points** (:func:`groove_points`), in order: the left top corner (the left
plate's top line meets the left wall), the left bottom corner (where the fill surface, or the
bottom of an empty groove, meets the left wall: the wall's foot), three bottom points and the
right bottom corner, right top corner. The bottom points lie on the fill surface at a quarter,
half and three quarters of the way from the left to the right bottom corner, measured across
the groove (along y, the plates' line); where the bottom is open (no surface between the
corners: an empty V without a backing seen) they lie on the line joining the corners. Where a
wall runs into the fill through a round (a U groove's root radius, bare or partly filled) the
bottom corner is the point of the wall's line at the level where the fill surface meets the
round: for an empty U the virtual sharp corner (the wall's line meets the bottom's line), and
as beads fill the round it moves up the wall's line with the fill, joining the fill's toe on
the wall when the round is buried. (Before, a partly filled round kept the empty groove's
virtual corner: a point buried under the first bead, that no sensor sees, and a jump of up to
2.5 mm when the fill reached the wall. The groove's width at the fill level between the walls'
lines is what a fill plan divides into beads.)

Shapes (:data:`GROOVES`):

* ``"v"``: a single-V butt joint on a backing bar, ``angle_deg`` included angle, ``gap_mm`` root
  gap, ``thickness_mm`` plate thickness, no root face (the bevels run down to the backing).
* ``"narrow-gap"``: walls ``wall_deg`` off vertical each, ``depth_mm`` deep, ``bottom_mm`` wide at
  the bottom, on a backing bar.
* ``"u"``: walls ``wall_deg`` off vertical each, a root radius ``radius_mm`` into a flat bottom
  ``bottom_mm`` wide (between the virtual corners), ``depth_mm`` deep.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray
from seamtrack.geometry.groove_points import LEFT_FOOT, MIDDLE, RIGHT_FOOT
from seamtrack.workpiece import beads

GROOVES = ("v", "narrow-gap", "u")
#: Half length of the plates drawn (mm).
_PLATE_MM = 1000.0
_ARC_PIECES = 24

_DEFAULTS: dict[str, dict[str, float]] = {
    "v": {"angle_deg": 60.0, "gap_mm": 2.0, "thickness_mm": 20.0},
    "narrow-gap": {"wall_deg": 4.0, "depth_mm": 25.0, "bottom_mm": 12.0},
    "u": {"wall_deg": 10.0, "radius_mm": 3.0, "bottom_mm": 8.0, "depth_mm": 16.0},
}


@dataclass(frozen=True)
class Groove:
    """An empty groove in the station frame.

    Attributes
    ----------
    kind : str
    surface : (k, 2) float
        Its top surface (y, z), y ascending, z up; the plates at z = 0.
    top : (2, 2) float
        The left and right top corners.
    foot : (2, 2) float
        The walls' virtual feet: where each wall's line meets the bottom (the backing bar, the
        flat bottom); for a V without a gap both are the bevels' intersection.
    params : mapping
    """

    kind: str
    surface: FloatArray
    top: FloatArray
    foot: FloatArray
    params: Any

    @property
    def area_mm2(self) -> float:
        """The groove's area below the line joining its top corners."""
        return remaining_area_mm2(self.surface, self.top)


def groove(kind: str, **params: float) -> Groove:
    """An empty groove of shape ``kind`` (:data:`GROOVES`) with ``params`` (module docstring)."""
    if kind not in _DEFAULTS:
        raise ValueError(f"unknown groove {kind!r}; use one of {', '.join(GROOVES)}")
    unknown = set(params) - set(_DEFAULTS[kind])
    if unknown:
        raise ValueError(f"{kind} has no parameter(s) {sorted(unknown)}")
    p = {**_DEFAULTS[kind], **params}
    L = _PLATE_MM
    if kind == "v":
        half, g, t = math.radians(p["angle_deg"]) / 2, p["gap_mm"], p["thickness_mm"]
        if not (0 < half < math.pi / 2 and g >= 0 and t > 0):
            raise ValueError("v needs 0 < angle_deg < 180, gap_mm >= 0, thickness_mm > 0")
        w = g / 2 + t * math.tan(half)
        bottom = [(-g / 2, -t), (g / 2, -t)] if g > 0 else [(0.0, -t)]
        # With a gap, the backing bar seen through it joins the walls' feet.
        surface = np.array([(-L, 0.0), (-w, 0.0), *bottom, (w, 0.0), (L, 0.0)])
        foot = np.array([bottom[0], bottom[-1]])
    else:
        b, d = p["bottom_mm"], p["depth_mm"]
        a = math.radians(p["wall_deg"])
        if not (0 <= a < math.pi / 2 and b > 0 and d > 0):
            raise ValueError(f"{kind} needs 0 <= wall_deg < 90, bottom_mm > 0, depth_mm > 0")
        w = b / 2 + d * math.tan(a)
        foot = np.array([(-b / 2, -d), (b / 2, -d)])
        if kind == "narrow-gap":
            surface = np.array(
                [(-L, 0.0), (-w, 0.0), (-b / 2, -d), (b / 2, -d), (w, 0.0), (L, 0.0)]
            )
        else:
            surface = _u_surface(w, b, d, a, p["radius_mm"])
    return Groove(kind, surface, np.array([(-w, 0.0), (w, 0.0)]), foot, MappingProxyType(p))


def _u_surface(w: float, b: float, d: float, a: float, r: float) -> FloatArray:
    """A U groove's top surface: walls ``a`` off vertical, a round of radius ``r`` into the
    flat bottom (virtual corners ``b`` apart at depth ``d``)."""
    # Left corner: interior angle 90 deg + a between the bottom (+y) and the wall (up, -y).
    interior = math.pi / 2 + a
    tangent = r / math.tan(interior / 2)
    if tangent >= b / 2 or tangent * math.cos(a) >= d:
        raise ValueError("u: radius_mm too large for the bottom or the depth")
    cx, cz = -b / 2 + tangent, -d + r  # the round's centre
    # From the wall's tangent point (normal (cos a, -sin a) ... ) down to the bottom's.
    start = math.atan2(-math.sin(a) * 1.0, -math.cos(a))  # direction centre -> wall point
    end = -math.pi / 2  # centre -> bottom point
    angles = np.linspace(start, end, _ARC_PIECES + 1) if start < end else None
    if angles is None:
        angles = np.linspace(start, end + 2 * math.pi, _ARC_PIECES + 1)
    arc = np.column_stack([cx + r * np.cos(angles), cz + r * np.sin(angles)])
    left = np.vstack([[(-_PLATE_MM, 0.0), (-w, 0.0)], arc])
    right = left[::-1] * [-1.0, 1.0]
    return np.vstack([left, right])


def remaining_area_mm2(surface: FloatArray, top: FloatArray) -> float:
    """The area between the line joining the top corners and ``surface`` below it."""
    (y0, z0), (y1, z1) = top
    s = surface[(surface[:, 0] >= y0) & (surface[:, 0] <= y1)]
    s = np.vstack([top[0], s, top[1]])
    line = z0 + (s[:, 0] - y0) * (z1 - z0) / max(y1 - y0, 1e-12)
    depth = np.maximum(line - s[:, 1], 0.0)
    return float(np.sum(0.5 * (depth[1:] + depth[:-1]) * np.diff(s[:, 0])))


def on_line(p: FloatArray, a: FloatArray, b: FloatArray, tol: float = 1e-6) -> NDArray[np.bool_]:
    d = b - a
    n = np.array([-d[1], d[0]]) / math.hypot(*d)
    return np.asarray(np.abs((p - a) @ n) <= tol * max(1.0, math.hypot(*d)))


def _z_at(surface: FloatArray, y: float) -> float:
    """z of the surface at y (its top where the surface is steep there)."""
    return float(np.interp(y, surface[:, 0], surface[:, 1]))


def groove_points(g: Groove, surface: FloatArray | None = None) -> FloatArray:
    """The 7 true points (7, 2) of groove ``g`` whose top surface is now ``surface`` (default:
    empty), in the station frame (module docstring)."""
    s = g.surface if surface is None else np.asarray(surface, dtype=np.float64)
    feet = []
    for side in (0, 1):
        top, foot = g.top[side], g.foot[side]
        on = on_line(s, top, foot)
        # The surface's vertices on the wall, between the top corner and the foot.
        lo, hi = min(top[1], foot[1]) - 1e-9, max(top[1], foot[1]) + 1e-9
        wall = np.flatnonzero(on & (s[:, 1] >= lo) & (s[:, 1] <= hi) & (s[:, 1] < top[1] - 1e-9))
        if not len(wall):  # the wall is buried: the fill reaches the top
            feet.append(top.copy())
            continue
        lowest = s[wall[np.argmin(s[wall, 1])]]
        if g.kind == "u" and lowest[1] > foot[1] + 1e-9 and _round_below(g, s, side, lowest):
            # The wall runs into the fill (or the bottom) through the round: the wall's line
            # at the level where the fill meets the round.
            z = _fill_level(g, s, side, lowest)
            feet.append(top + (z - top[1]) / (foot[1] - top[1]) * (foot - top))
        else:
            feet.append(lowest.copy())
    left, right = feet
    out = [g.top[0], left]
    for t in (0.25, 0.5, 0.75):
        y = left[0] + t * (right[0] - left[0])
        chord = left[1] + t * (right[1] - left[1])
        inside = s[(s[:, 0] > left[0] + 1e-9) & (s[:, 0] < right[0] - 1e-9)]
        z = _z_at(np.vstack([left, inside, right]), y) if right[0] - left[0] > 1e-9 else chord
        out.append(np.array([y, z]))
    out += [right, g.top[1]]
    return np.array(out)


def _round_below(g: Groove, s: FloatArray, side: int, lowest: FloatArray) -> bool:
    """Whether the wall's lowest surface vertex is the U's own (the round's tangent point on
    the wall: the fill has not buried it, the round, bare or partly filled, lies below)."""
    return bool(np.any(np.all(np.isclose(g.surface, lowest, atol=1e-9), axis=1)))


def _fill_level(g: Groove, s: FloatArray, side: int, tangent: FloatArray) -> float:
    """z where the surface ``s`` leaves the U's round below the wall's tangent point (the
    fill's toe on the round; the bottom's level where the round is bare), to 1 um."""
    sign = 1.0 if side == 0 else -1.0
    reach = abs(float(g.foot[side][0] - tangent[0])) * 2.0 + 1e-3
    y = tangent[0] + sign * np.arange(0.0, reach, 1e-3)
    off = np.abs(np.interp(y, s[:, 0], s[:, 1]) - np.interp(y, g.surface[:, 0], g.surface[:, 1]))
    k = np.flatnonzero(off > 1e-9)
    if not len(k):  # a bare round: the fill surface is the bottom
        return float(g.foot[side][1])
    return float(np.interp(y[k[0]], s[:, 0], s[:, 1]))


def flat_fill(g: Groove, height_mm: float) -> FloatArray:
    """The groove's top surface filled flat to ``height_mm`` above its bottom (a bead-free
    fill surface: a ground-flush fill)."""
    z = float(g.foot[:, 1].min()) + height_mm
    s = g.surface
    out = [s[0]]
    for a, b in itertools.pairwise(s):
        if (a[1] - z) * (b[1] - z) < 0:
            t = (z - a[1]) / (b[1] - a[1])
            out.append(a + t * (b - a))
        out.append(b)
    p = np.array(out)
    p[:, 1] = np.maximum(p[:, 1], z)
    keep = np.r_[True, np.any(np.abs(np.diff(p, axis=0)) > 1e-12, axis=1)]
    return np.asarray(p[keep])


def fill(
    g: Groove,
    layers: int,
    *,
    bead_area_mm2: float = 20.0,
    width_to_height: float = 3.0,
    kind: str = "parabola",
    rng: np.random.Generator | None = None,
    jitter_mm: float = 0.0,
) -> tuple[FloatArray, list[FloatArray]]:
    """Lay ``layers`` layers of beads in ``g`` (corners first, then towards the middle), each
    of ``bead_area_mm2``; beads per layer from the layer's width over a bead's. ``jitter_mm``:
    each bead's lateral position moved by up to that (uniform, from ``rng``).

    Returns the final top surface and the surface after each bead."""
    shape = beads.BeadShape(kind=kind, width_to_height=width_to_height)
    h_bead = math.sqrt(bead_area_mm2 / (2 / 3 * width_to_height))  # a parabola's height
    w_bead = width_to_height * h_bead
    s = g.surface.copy()
    history = []
    for _ in range(layers):
        pts = groove_points(g, s)
        (yl, _), (yr, _) = pts[LEFT_FOOT], pts[RIGHT_FOOT]
        width = max(yr - yl, 0.0)
        n = max(1, int(round(width / (0.8 * w_bead))))
        if n == 1:
            centres: Sequence[float] = [0.5 * (yl + yr)]
        else:
            inset = 0.5 * w_bead * 0.8
            c = np.linspace(yl + inset, yr - inset, n)
            order = np.argsort(np.abs(np.arange(n) - (n - 1) / 2))[::-1]  # corners first
            centres = list(c[order])
        for y in centres:
            if rng is not None and jitter_mm > 0:
                y = float(y + rng.uniform(-jitter_mm, jitter_mm))
            s = np.asarray(beads.lay_bead(s, float(y), bead_area_mm2, shape), dtype=np.float64)
            history.append(s)
    return s, history


def section_segments(surface: FloatArray) -> FloatArray:
    """(k, 2, 2) segments of the surface in the joint frame of
    :mod:`seamtrack.features.synthetic` (z into the part: z_J = -z)."""
    v = np.column_stack([surface[:, 0], -surface[:, 1]])
    segs = np.stack([v[:-1], v[1:]], axis=1)
    return np.asarray(segs[np.hypot(*(segs[:, 1] - segs[:, 0]).T) > 0])


def to_joint(points: FloatArray) -> FloatArray:
    """Station-frame points (y, z up) in the joint frame (y, z into the part)."""
    return np.column_stack([points[:, 0], -points[:, 1]])


@dataclass(frozen=True, eq=False)
class GrooveTruth:
    """What a synthetic groove profile shows: the 7 points in the laser plane and in the
    station frame, the remaining area (below the top corners' line) and the pose."""

    points_laser: FloatArray
    points_station: FloatArray
    area_mm2: float
    T_world_sensor: FloatArray
    kind: str


def groove_profile(
    g: Groove,
    surface: FloatArray | None = None,
    *,
    rng: np.random.Generator,
    artefacts: Any = "default",
    sensor: Any = None,
    rays: int = 2048,
    **pose: Any,
) -> tuple[Any, GrooveTruth]:
    """The profile a sensor measures across groove ``g`` whose top surface is ``surface``
    (default: empty), and its :class:`GrooveTruth`.

    ``artefacts``: a :class:`~seamtrack.features.artefacts.SensorArtefacts` (default: the
    real-sensor model's defaults) or None (an exact profile, pixel-quantized by ``sensor``).
    ``sensor``: default the ``wide`` preset (40-80 mm field of view), unquantized under the
    artefact model. ``pose``: the pose arguments of
    :func:`~seamtrack.features.synthetic.synthetic_profile` (``pitch_deg``, ``roll_deg``,
    ``lateral_offset_mm``, ``standoff_mm``, with its defaults); the frames' joint frame is the
    station frame with z flipped (into the part)."""
    import dataclasses

    from seamtrack.features.artefacts import SensorArtefacts, real_sensor_profile
    from seamtrack.features.synthetic import line_in_laser_plane, synthetic_profile
    from seamtrack.sensing.sensor import preset

    s = g.surface if surface is None else np.asarray(surface, dtype=np.float64)
    pts = groove_points(g, s)
    joint_pts = to_joint(pts)
    section = (section_segments(s), joint_pts[MIDDLE], to_joint(g.top), math.nan)
    pose = {**pose, "rays": rays, "section": section}
    if artefacts is None:
        base = preset("wide") if sensor is None else sensor
        profile, truth = synthetic_profile("groove", base, **pose)
    else:
        a = SensorArtefacts() if isinstance(artefacts, str) else artefacts
        base = dataclasses.replace(preset("wide"), quantize=False) if sensor is None else sensor
        profile, truth = real_sensor_profile("groove", rng, artefacts=a, sensor=base, **pose)
    T = truth.T_world_sensor
    return profile, GrooveTruth(
        points_laser=line_in_laser_plane(T, joint_pts),
        points_station=pts,
        area_mm2=remaining_area_mm2(s, g.top),
        T_world_sensor=T,
        kind=g.kind,
    )
