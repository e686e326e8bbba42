"""Cross-sections of a part along its seam: station frames, sections' upper envelopes, and the
groove's corners in a section (the geometry under :class:`seamtrack.workpiece.fill.FillState`).

A station's frame has x along the seam tangent, z along the seam's torch normal (out of the
groove) and y = z x x; a section is the part's triangles cut by the station's plane (x = 0),
kept as its upper envelope seen from the torch (the highest z at each lateral y) on a grid.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.errors import WorkpieceError
from seamtrack.geometry.seam import Seam

__all__ = ["bottom_corners", "fill_gaps", "section_envelopes", "station_frames", "top_corners"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

#: Height (mm) below the plate top at which the groove's edge (top corner) starts.
CORNER_DROP_MM = 0.05
#: A wall is steeper than this (rad from horizontal); below it the walk down a wall stops.
WALL_MIN_SLOPE_RAD = math.radians(40.0)
#: A surface node counts as covered where it lies this far (mm) above the empty groove.
COVERED_MM = 1e-9


def station_frames(seam: Seam, s_mm: FloatArray) -> FloatArray:
    """(m, 4, 4) station frames: x tangent, z torch normal, y = z x x, origin on the seam."""
    knots = seam.arc_length_mm
    tangents = np.column_stack([np.interp(s_mm, knots, seam.tangents[:, k]) for k in range(3)])
    tangents /= np.linalg.norm(tangents, axis=1, keepdims=True)
    normals = np.column_stack([np.interp(s_mm, knots, seam.normals[:, k]) for k in range(3)])
    normals -= np.sum(normals * tangents, axis=1, keepdims=True) * tangents
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    lateral = np.cross(normals, tangents)
    frames = np.tile(np.eye(4), (len(s_mm), 1, 1))
    frames[:, :3, 0], frames[:, :3, 1], frames[:, :3, 2] = tangents, lateral, normals
    frames[:, :3, 3] = seam.interpolate(s_mm)
    return frames


def section_envelopes(
    triangles: ArrayLike, T_world_station: ArrayLike, y_mm: ArrayLike, reach_mm: float
) -> FloatArray:
    """Upper envelopes of a triangle soup's sections by each station's plane, on a lateral grid.

    Parameters
    ----------
    triangles : (F, 3, 3) float
        The part's triangles (world, mm).
    T_world_station : (m, 4, 4) float
    y_mm : (K,) float
        Lateral grid (station y).
    reach_mm : float
        Section segments farther than this from the station's origin are ignored (another part
        of a curved seam's workpiece cut by the same plane).

    Returns
    -------
    (m, K) float
        The highest z of the section at each y (NaN where the plane meets no material).
    """
    tri = np.asarray(triangles, dtype=np.float64)
    frames = np.asarray(T_world_station, dtype=np.float64)
    y = np.asarray(y_mm, dtype=np.float64)
    out = np.full((len(frames), len(y)), np.nan)
    centroids = tri.mean(axis=1)
    radius = np.linalg.norm(tri - centroids[:, None, :], axis=2).max(axis=1)
    for i, T in enumerate(frames):
        origin, axis_x, axis_y, axis_z = T[:3, 3], T[:3, 0], T[:3, 1], T[:3, 2]
        near = np.linalg.norm(centroids - origin, axis=1) <= reach_mm + radius
        d_c = (centroids[near] - origin) @ axis_x
        cand = tri[near][np.abs(d_c) <= radius[near]]
        if len(cand) == 0:
            continue
        d = (cand - origin) @ axis_x  # (f, 3) signed distances; 0 counts as in front
        side = d >= 0
        points = []
        for a, b in ((0, 1), (1, 2), (2, 0)):
            cross = side[:, a] != side[:, b]
            t = np.where(cross, d[:, a] / np.where(cross, d[:, a] - d[:, b], 1.0), 0.0)
            p = cand[:, a] + t[:, None] * (cand[:, b] - cand[:, a])
            points.append((cross, p))
        crossing = np.stack([c for c, _ in points], axis=1)  # (f, 3)
        has = crossing.sum(axis=1) == 2
        if not np.any(has):
            continue
        pts = np.stack([p for _, p in points], axis=1)[has]  # (f', 3 edges, 3)
        first = np.argmax(crossing[has], axis=1)
        second = 2 - np.argmax(crossing[has][:, ::-1], axis=1)
        rows = np.arange(len(pts))
        seg = np.stack([pts[rows, first], pts[rows, second]], axis=1) - origin  # (f', 2, 3)
        sy, sz = seg @ axis_y, seg @ axis_z
        keep = np.hypot(sy, sz).min(axis=1) <= reach_mm
        sy, sz = sy[keep], sz[keep]
        order = np.argsort(sy, axis=1)
        sy, sz = np.take_along_axis(sy, order, 1), np.take_along_axis(sz, order, 1)
        width = sy[:, 1] - sy[:, 0]
        ok = width > 1e-12
        sy, sz, width = sy[ok], sz[ok], width[ok]
        inside = (y[None, :] >= sy[:, :1]) & (y[None, :] <= sy[:, 1:])
        zz = sz[:, :1] + (y[None, :] - sy[:, :1]) * ((sz[:, 1] - sz[:, 0]) / width)[:, None]
        env = np.where(inside, zz, -np.inf).max(axis=0, initial=-np.inf)
        out[i] = np.where(np.isfinite(env), env, np.nan)
    return out


def top_corners(y: FloatArray, z: FloatArray) -> tuple[FloatArray, FloatArray, IntArray]:
    """Plate tops (m, 2), the groove's top corners (m, 2, 2) and their node index (m, 2)."""
    m, k = z.shape
    edge = max(3, k // 40)
    plate = np.column_stack([np.median(z[:, :edge], axis=1), np.median(z[:, -edge:], axis=1)])
    low_left = z < plate[:, :1] - CORNER_DROP_MM
    low_right = z < plate[:, 1:] - CORNER_DROP_MM
    if not np.all(low_left.any(axis=1)):
        raise WorkpieceError(
            "a station's section has no groove below the plates' top",
            field="workpiece",
            fix="check the seam lies in a groove below both plates' tops (the groove's "
            "workpiece.params, or the seam workpiece.seam / workpiece.seam_near_mm picks)",
        )
    j_left = np.argmax(low_left, axis=1)  # first node below the left plate
    j_right = k - 1 - np.argmax(low_right[:, ::-1], axis=1)  # last node below the right plate
    corners = np.empty((m, 2, 2))
    rows = np.arange(m)
    j_left, j_right = np.clip(j_left, 2, k - 3), np.clip(j_right, 2, k - 3)
    for side, j, step in ((0, j_left, 1), (1, j_right, -1)):
        j1 = np.clip(j + step, 0, k - 1)
        zj, zj1 = z[rows, j], z[rows, j1]
        # Extend the wall line (nodes j, j+step) up to the plate's top.
        dz = np.where(np.abs(zj1 - zj) > 1e-12, zj1 - zj, np.nan)
        yc = y[j] + (plate[:, side] - zj) * (y[j1] - y[j]) / dz
        j2 = np.clip(j - 2 * step, 0, k - 1)
        lo_y = np.minimum(y[j2], y[j])
        hi_y = np.maximum(y[j2], y[j])
        yc = np.where(np.isfinite(yc), np.clip(yc, lo_y, hi_y), y[j - step])
        corners[:, side, 0] = yc
        corners[:, side, 1] = plate[:, side]
    return plate, corners, np.column_stack([j_left - 1, j_right + 1])


def bottom_corners(
    y: FloatArray, surface: FloatArray, base: FloatArray, top_idx: IntArray
) -> IntArray:
    """(m, 2) node index of the left and right bottom corners: the foot of the uncovered wall.

    Walk from each top corner down the wall while the surface is the empty groove's (no bead)
    and descends steeply; the last node of the walk is the corner.
    """
    k = surface.shape[1]
    dz = np.diff(surface, axis=1)
    dy = np.diff(y)
    steep = np.tan(WALL_MIN_SLOPE_RAD)
    uncovered = surface - base <= COVERED_MM
    idx = np.arange(k - 1)
    # Left wall: cell c (nodes c, c+1) descends to the right.
    ok_left = (dz < 0) & (-dz / dy >= steep) & uncovered[:, :-1] & uncovered[:, 1:]
    stop_left = ~ok_left & (idx >= top_idx[:, :1])
    first_stop = np.where(stop_left, idx, k - 1).min(axis=1)
    left = np.maximum(first_stop, top_idx[:, 0])
    ok_right = (dz > 0) & (dz / dy >= steep) & uncovered[:, :-1] & uncovered[:, 1:]
    stop_right = ~ok_right & (idx + 1 <= top_idx[:, 1:])
    last_stop = np.where(stop_right, idx + 1, 0).max(axis=1)
    right = np.minimum(last_stop, top_idx[:, 1])
    right = np.maximum(right, left)
    return np.column_stack([left, right])


def fill_gaps(env: FloatArray, field_name: str) -> FloatArray:
    """Fill a section's NaN nodes: beyond the material's ends with the nearest end's z (the plate
    goes on), between with the section's lowest z (a gap with nothing under it)."""
    finite = np.isfinite(env)
    if not np.all(finite.any(axis=1)):
        raise WorkpieceError(
            "a station's plane misses the part",
            field=field_name,
            fix="check the seam lies on the part (its normals point out of the groove)",
        )
    k = env.shape[1]
    rows = np.arange(len(env))
    first = np.argmax(finite, axis=1)
    last = k - 1 - np.argmax(finite[:, ::-1], axis=1)
    idx = np.arange(k)
    out = np.where(idx < first[:, None], env[rows, first][:, None], env)
    out = np.where(idx > last[:, None], env[rows, last][:, None], out)
    low = np.nanmin(env, axis=1, keepdims=True)
    return np.where(np.isnan(out), low, out)
