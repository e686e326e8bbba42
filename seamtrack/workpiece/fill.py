"""The fill state of a groove along its seam: cross-sections, beads laid pass by pass, a mesh.

A multi-pass job keeps one :class:`FillState`: the groove's cross-section at stations every
``spacing_mm`` (<= 0.5 mm) along the seam, each sampled on a lateral grid of ``lateral_step_mm``.

Stations
--------
Station ``i`` sits at arc length ``s_mm[i]``; its frame ``T_world_station[i]`` has its origin on
the seam, x along the seam tangent (travel direction), z along the seam's torch normal (out of
the groove, towards the torch) and y = z x x (lateral, left of travel). A section is the part's
mesh cut by the station's plane (x = 0), reduced to its upper envelope seen from the torch (the
highest z at each lateral y): the surface a bead lands on and a laser line sees.

Deposition
----------
:meth:`FillState.deposit` lays one pass along the torch's ACTUAL path: at each station the bead's
centre is where the path crosses the station's plane (its lateral coordinate plus the planned
offset), its area the path's area there (mass conservation at the actual travel speed, so a torch
that slowed down left a fatter bead). Each station's bead conforms to the surface below
(:func:`seamtrack.workpiece.beads.lay_beads_on_grid`); the area between the new and the old
surface equals the bead's area at every station (trapezoid area of the grid, to 1e-9 relative).

Mesh
----
:meth:`FillState.mesh` is the fill's top surface (triangles between consecutive stations, world
frame) where beads lie, one grid node wider on each side, those extra nodes sunk 0.02 mm into the
part so a ray cannot slip between fill and wall. Concatenated with the part's mesh, ray casting
(nearest hit) sees the beads.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial import cKDTree

from seamtrack.errors import SceneError, WorkpieceError
from seamtrack.geometry.seam import Seam
from seamtrack.workpiece.beads import BeadShape, lay_beads_on_grid

if TYPE_CHECKING:
    import trimesh

__all__ = ["FillState", "PassBeads", "section_envelopes"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

#: Height (mm) below the plate top at which the groove's edge (top corner) starts.
CORNER_DROP_MM = 0.05
#: A wall is steeper than this (rad from horizontal); below it the walk down a wall stops.
WALL_MIN_SLOPE_RAD = math.radians(40.0)
#: Fill nodes next to a bead are sunk this far into the part (mm) to seal the mesh seam.
SEAL_DEPTH_MM = 0.02
#: Lateral margin (mm) of the station grid beyond the groove's top corners.
GRID_MARGIN_MM = 8.0
#: A surface node counts as covered where it lies this far (mm) above the empty groove.
COVERED_MM = 1e-9


@dataclass(frozen=True, eq=False)
class PassBeads:
    """One pass's bead at every station.

    Attributes
    ----------
    y_centre_mm : (m,) float
        Bead centre (station y) where the torch path crossed the station (NaN: not laid there).
    area_mm2 : (m,) float
        Area laid at each station (0 where the torch did not pass).
    toes : (m, 2, 2) float
        Left and right toe (y, z): where the cap meets the surface below (NaN: no bead).
    margin_mm : (m, 2) float
        Left and right toe to the wall of the empty groove at the toe's height, laterally
        (<= 0: the toe is on the wall, fused; > 0: a gap, the notch's width).
    lo, hi : (m,) int
        First and last grid node the bead covers (``lo > hi``: none).
    z_before, z_after : (m, K) float
        The surface under the bead and the surface with it, on the state's lateral grid.
    shape : BeadShape
    offset_mm : float
    """

    y_centre_mm: FloatArray
    area_mm2: FloatArray
    toes: FloatArray
    margin_mm: FloatArray
    lo: IntArray
    hi: IntArray
    z_before: FloatArray = field(repr=False)
    z_after: FloatArray = field(repr=False)
    shape: BeadShape = field(default_factory=BeadShape)
    offset_mm: float = 0.0

    def polygon(self, y_mm: FloatArray, i: int) -> FloatArray:
        """The deposited region at station ``i`` as a closed polygon (p, 2); (0, 2) if none."""
        lo, hi = int(self.lo[i]), int(self.hi[i])
        if lo > hi:
            return np.zeros((0, 2))
        a, b = max(lo - 1, 0), min(hi + 1, len(y_mm) - 1)
        top = np.column_stack([y_mm[a : b + 1], self.z_after[i, a : b + 1]])
        bottom = np.column_stack([y_mm[a : b + 1], self.z_before[i, a : b + 1]])[::-1]
        return np.concatenate([top, bottom])


def _station_frames(seam: Seam, s_mm: FloatArray) -> FloatArray:
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


def _top_corners(y: FloatArray, z: FloatArray) -> tuple[FloatArray, FloatArray, IntArray]:
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
            fix="check the seam lies in a groove, or widen half_width_mm",
        )
    j_left = np.argmax(low_left, axis=1)  # first node below the left plate
    j_right = k - 1 - np.argmax(low_right[:, ::-1], axis=1)  # last node below the right plate
    corners = np.empty((m, 2, 2))
    rows = np.arange(m)
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


def _bottom_corners(
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


@dataclass(frozen=True, eq=False)
class FillState:
    """The groove's cross-sections along the seam, with the beads laid so far.

    Build with :meth:`from_mesh` (or :meth:`from_profiles` for analytic sections); every
    :meth:`deposit` returns a new state with one more pass. See the module docstring.

    Attributes
    ----------
    s_mm : (m,) float
        Station arc lengths along the seam.
    T_world_station : (m, 4, 4) float
    y_mm : (K,) float
        The lateral grid shared by all stations (station y, mm).
    base_z, surface_z : (m, K) float
        The empty groove's top surface and the current one (base + beads) on the grid.
    beads : tuple of PassBeads
        One per pass laid, in order.
    plate_top : (m, 2) float
        z of the left and right plates' top at each station.
    top_corners : (m, 2, 2) float
        The groove's left and right top corners (y, z).
    """

    s_mm: FloatArray
    T_world_station: FloatArray
    y_mm: FloatArray
    base_z: FloatArray = field(repr=False)
    surface_z: FloatArray = field(repr=False)
    beads: tuple[PassBeads, ...]
    plate_top: FloatArray
    top_corners: FloatArray
    top_index: IntArray = field(repr=False)
    base_bottom: IntArray = field(repr=False)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_profiles(
        cls, s_mm: ArrayLike, T_world_station: ArrayLike, y_mm: ArrayLike, base_z: ArrayLike
    ) -> FillState:
        """A state from empty-groove sections already sampled on a lateral grid.

        ``s_mm`` (m,), ``T_world_station`` (m, 4, 4), ``y_mm`` (K,) strictly increasing,
        ``base_z`` (m, K) finite; each section must reach above its groove on both sides.
        """
        s = np.asarray(s_mm, dtype=np.float64)
        frames = np.asarray(T_world_station, dtype=np.float64)
        y = np.asarray(y_mm, dtype=np.float64)
        z = np.array(base_z, dtype=np.float64)
        if z.shape != (len(s), len(y)) or frames.shape != (len(s), 4, 4):
            raise WorkpieceError(
                f"shapes disagree: s {s.shape}, frames {frames.shape}, y {y.shape}, z {z.shape}",
                field="fill",
            )
        if not np.all(np.isfinite(z)) or np.any(np.diff(y) <= 0):
            raise WorkpieceError(
                "sections must be finite on a strictly increasing lateral grid", field="fill"
            )
        plate, corners, top_idx = _top_corners(y, z)
        bottom = _bottom_corners(y, z, z, top_idx)
        return cls(s, frames, y, z, z, (), plate, corners, top_idx, bottom)

    @classmethod
    def from_mesh(
        cls,
        mesh: Any,
        seam: Seam,
        spacing_mm: float = 0.5,
        half_width_mm: float | None = None,
        lateral_step_mm: float = 0.05,
    ) -> FillState:
        """Sections of a part's mesh along its seam (the empty groove).

        Parameters
        ----------
        mesh : trimesh.Trimesh
            The part (world frame, mm).
        seam : Seam
            The groove's seam (its normals the torch directions, out of the groove).
        spacing_mm : float
            Station spacing, in (0, 0.5] (the last station sits at the seam's end).
        half_width_mm : float, optional
            Half the lateral grid's width; default the groove's top half-width + 8 mm.
        lateral_step_mm : float
            The lateral grid's step (mm).
        """
        for name, value in (("spacing_mm", spacing_mm), ("lateral_step_mm", lateral_step_mm)):
            if not (math.isfinite(value) and value > 0):
                raise WorkpieceError(f"must be > 0, got {value}", field=f"fill.{name}")
        if spacing_mm > 0.5:
            raise WorkpieceError(
                f"must be <= 0.5 mm, got {spacing_mm}", field="fill.spacing_mm", fix="use 0.5"
            )
        length = seam.length_mm
        n = max(2, math.ceil(length / spacing_mm) + 1)
        s = np.linspace(0.0, length, n)
        # Keep the end stations a hair inside the part: its end faces lie in their planes.
        s[0], s[-1] = min(1e-3, length / 4), max(length - 1e-3, 3 * length / 4)
        frames = _station_frames(seam, s)
        tri = np.asarray(mesh.triangles, dtype=np.float64)
        if half_width_mm is None:
            probe_y = np.arange(-60.0, 60.0 + 1e-9, 0.25)
            probes = frames[np.unique(np.linspace(0, n - 1, 7).astype(int))]
            env = section_envelopes(tri, probes, probe_y, 90.0)
            finite = np.isfinite(env)
            if not np.all(finite.any(axis=1)):
                _fill_gaps(env, "workpiece")  # raises
            # Keep the span where every probe finds material at both ends (the plates).
            first = np.argmax(finite, axis=1).max()
            last = len(probe_y) - 1 - np.argmax(finite[:, ::-1], axis=1).max()
            span = slice(first, last + 1)
            _, corners, _ = _top_corners(probe_y[span], _fill_gaps(env[:, span], "workpiece"))
            reach = min(-probe_y[first], probe_y[last])
            half_width_mm = min(float(np.abs(corners[:, :, 0]).max()) + GRID_MARGIN_MM, reach)
        half = float(half_width_mm)
        steps = math.ceil(half / lateral_step_mm)
        y = np.linspace(-steps * lateral_step_mm, steps * lateral_step_mm, 2 * steps + 1)
        env = section_envelopes(tri, frames, y, math.hypot(half, half) + 30.0)
        return cls.from_profiles(s, frames, y, _fill_gaps(env, "workpiece"))

    # ------------------------------------------------------------------ views of the state
    @property
    def n_stations(self) -> int:
        return len(self.s_mm)

    @property
    def n_passes(self) -> int:
        return len(self.beads)

    @property
    def base(self) -> tuple[FloatArray, ...]:
        """Per station, the empty groove's top surface (K, 2) (y, z)."""
        return tuple(np.column_stack([self.y_mm, z]) for z in self.base_z)

    @property
    def surface(self) -> tuple[FloatArray, ...]:
        """Per station, the current top surface (K, 2) (y, z)."""
        return tuple(np.column_stack([self.y_mm, z]) for z in self.surface_z)

    def bead_polygons(self, station: int) -> list[FloatArray]:
        """The bead of every pass at one station, as closed (p, 2) polygons (empty: none)."""
        return [b.polygon(self.y_mm, station) for b in self.beads]

    def groove_points(self, i: int) -> FloatArray:
        """The groove's true 7 points at station ``i`` (7, 2) (y, z), station frame.

        Left top corner, left bottom corner (the foot of the uncovered left wall, where it meets
        the fill or the root), the fill surface (or root) at 1/4, 1/2 and 3/4 of the way between
        the bottom corners, right bottom corner, right top corner.
        """
        i = int(i)
        z = self.surface_z[i]
        bottom = _bottom_corners(self.y_mm, z[None], self.base_z[i][None], self.top_index[i][None])
        left = np.array([self.y_mm[bottom[0, 0]], z[bottom[0, 0]]])
        right = np.array([self.y_mm[bottom[0, 1]], z[bottom[0, 1]]])
        ys = left[0] + (right[0] - left[0]) * np.array([0.25, 0.5, 0.75])
        middle = np.column_stack([ys, np.interp(ys, self.y_mm, z)])
        corners = self.top_corners[i]
        return np.vstack([corners[0], left, middle, right, corners[1]])

    def _top_line(self) -> tuple[FloatArray, NDArray[np.bool_]]:
        """z of the line joining the top corners on the grid (m, K), and the nodes between."""
        (y0, z0), (y1, z1) = self.top_corners[:, 0].T, self.top_corners[:, 1].T
        y = self.y_mm[None, :]
        line = z0[:, None] + (y - y0[:, None]) * ((z1 - z0) / (y1 - y0))[:, None]
        between = (y >= y0[:, None]) & (y <= y1[:, None])
        return line, between

    def remaining_area_mm2(self) -> FloatArray:
        """(m,) groove area left below the line joining the top corners (mm^2)."""
        line, between = self._top_line()
        depth = np.where(between, np.maximum(line - self.surface_z, 0.0), 0.0)
        return np.trapezoid(depth, self.y_mm, axis=1)

    def reinforcement_mm(self) -> FloatArray:
        """(m, 2) min and max height of the surface above the plates' top line (mm).

        Taken across the groove's top width (between the top corners); negative min: the
        groove is not filled there (underfill).
        """
        line, between = self._top_line()
        height = self.surface_z - line
        return np.column_stack(
            [
                np.where(between, height, np.inf).min(axis=1),
                np.where(between, height, -np.inf).max(axis=1),
            ]
        )

    def sidewall_margin_mm(self) -> FloatArray:
        """(m, n_pass) the nearer toe's lateral distance to the wall (<= 0 fused, > 0 a gap).

        NaN where the pass laid no bead.
        """
        if not self.beads:
            return np.zeros((self.n_stations, 0))
        margins = np.stack([b.margin_mm for b in self.beads], axis=1)  # (m, p, 2)
        return np.min(margins, axis=2)

    # ------------------------------------------------------------------ deposition
    def _stations_on_path(
        self, tcp_world: FloatArray, area_mm2: FloatArray
    ) -> tuple[FloatArray, FloatArray, NDArray[np.bool_]]:
        """Each station's torch position in its own frame (m, 3), the path's area there (m,),
        and where the path covers the station (m,).

        A path point's arc length is its nearest station's plus its offset along that station's
        tangent; the torch is taken never to go back along the seam.
        """
        origins = self.T_world_station[:, :3, 3]
        tangents = self.T_world_station[:, :3, 0]
        _, nearest = cKDTree(origins).query(tcp_world)
        s_path = self.s_mm[nearest] + np.sum((tcp_world - origins[nearest]) * tangents[nearest], 1)
        s_path = np.maximum.accumulate(s_path)
        keep = np.concatenate([[True], np.diff(s_path) > 1e-9])
        s_path, pts, area = s_path[keep], tcp_world[keep], area_mm2[keep]
        covered = (self.s_mm >= s_path[0]) & (self.s_mm <= s_path[-1])
        at = np.column_stack([np.interp(self.s_mm, s_path, pts[:, k]) for k in range(3)])
        local = np.einsum("mji,mj->mi", self.T_world_station[:, :3, :3], at - origins)
        return local, np.interp(self.s_mm, s_path, area), covered

    def deposit(
        self,
        tcp_world: ArrayLike,
        area_mm2: ArrayLike,
        shape: BeadShape,
        offset_mm: float = 0.0,
    ) -> FillState:
        """A new state with one more pass laid along the torch's actual path.

        Parameters
        ----------
        tcp_world : (n, 3) float
            The torch's path (the run's trace, tracking errors included), in travel order.
        area_mm2 : (n,) float
            Bead area at each path point (mass conservation at the actual speed), >= 0.
        shape : BeadShape
        offset_mm : float
            Lateral offset of the bead's centre from the torch's path (station y).
        """
        path = np.asarray(tcp_world, dtype=np.float64)
        area = np.asarray(area_mm2, dtype=np.float64)
        if path.ndim != 2 or path.shape[1] != 3 or len(path) < 2:
            raise SceneError(f"must be (n >= 2, 3), got {path.shape}", field="tcp_world")
        if area.shape != (len(path),) or not np.all(np.isfinite(area)) or np.any(area < 0):
            raise SceneError("must be (n,) finite and >= 0, one per path point", field="area_mm2")
        if not (np.all(np.isfinite(path)) and math.isfinite(offset_mm)):
            raise SceneError("holds a NaN or infinite value", field="tcp_world")
        local, station_area, covered = self._stations_on_path(path, area)
        y_centre = local[:, 1] + offset_mm
        laid_here = covered & (station_area > 0)
        outside = laid_here & (
            (y_centre < self.top_corners[:, 0, 0]) | (y_centre > self.top_corners[:, 1, 0])
        )
        if np.any(outside):
            i = int(np.flatnonzero(outside)[0])
            raise SceneError(
                f"the bead's centre {y_centre[i]:.2f} mm at s = {self.s_mm[i]:.1f} mm lies "
                f"outside the groove ({self.top_corners[i, 0, 0]:.2f} .. "
                f"{self.top_corners[i, 1, 0]:.2f} mm)",
                field="offset_mm",
                fix="keep the bead's offset inside the groove's top width",
            )
        station_area = np.where(laid_here, station_area, 0.0)
        y_safe = np.where(laid_here, y_centre, 0.0)
        grid = lay_beads_on_grid(self.y_mm, self.surface_z, y_safe, station_area, shape)
        margins = self._margins(grid.toes)
        beads = PassBeads(
            y_centre_mm=np.where(laid_here, y_centre, np.nan),
            area_mm2=grid.area_mm2,
            toes=grid.toes,
            margin_mm=margins,
            lo=grid.lo,
            hi=grid.hi,
            z_before=self.surface_z,
            z_after=grid.z_new,
            shape=shape,
            offset_mm=float(offset_mm),
        )
        return replace(self, surface_z=grid.z_new, beads=(*self.beads, beads))

    def _margins(self, toes: FloatArray) -> FloatArray:
        """(m, 2) each toe's lateral distance from the empty groove's wall at the toe's height."""
        m = self.n_stations
        out = np.full((m, 2), np.nan)
        for i in np.flatnonzero(np.isfinite(toes[:, 0, 0])):
            top_l, top_r = self.top_index[i]
            bot_l, bot_r = self.base_bottom[i]
            zb = self.base_z[i]
            # Left wall: nodes top_l..bot_l, z falling as y rises; interp wants z ascending.
            wy, wz = self.y_mm[top_l : bot_l + 1][::-1], zb[top_l : bot_l + 1][::-1]
            out[i, 0] = toes[i, 0, 0] - np.interp(toes[i, 0, 1], wz, wy)
            wy, wz = self.y_mm[bot_r : top_r + 1], zb[bot_r : top_r + 1]
            out[i, 1] = np.interp(toes[i, 1, 1], wz, wy) - toes[i, 1, 0]
        return np.where(out < 1e-6, np.minimum(out, 0.0), out)

    # ------------------------------------------------------------------ mesh
    def mesh(self) -> trimesh.Trimesh:
        """The fill's top surface where beads lie (world frame), to join to the part's mesh.

        Triangles between consecutive stations over the covered grid nodes, one node wider on
        each side (those nodes sunk :data:`SEAL_DEPTH_MM` into the part). Empty without beads.
        """
        import trimesh

        m, k = self.surface_z.shape
        covered = self.surface_z - self.base_z > COVERED_MM
        grown = covered.copy()
        grown[:, 1:] |= covered[:, :-1]
        grown[:, :-1] |= covered[:, 1:]
        z = np.where(covered, self.surface_z, self.base_z - SEAL_DEPTH_MM)
        cell = grown[:-1, :-1] & grown[:-1, 1:] & grown[1:, :-1] & grown[1:, 1:]
        cell &= covered[:-1, :-1] | covered[:-1, 1:] | covered[1:, :-1] | covered[1:, 1:]
        if not np.any(cell):
            return trimesh.Trimesh(np.zeros((0, 3)), np.zeros((0, 3), dtype=np.int64))
        ii, kk = np.nonzero(cell)
        a = ii * k + kk
        b, c, d = a + 1, a + k, a + k + 1
        faces = np.concatenate([np.column_stack([a, c, b]), np.column_stack([b, c, d])])
        mask = np.zeros(m * k, dtype=bool)
        mask[faces.ravel()] = True
        used = np.flatnonzero(mask)
        remap = np.full(m * k, -1, dtype=np.int64)
        remap[used] = np.arange(len(used))
        rows, cols = np.divmod(used, k)
        T = self.T_world_station[rows]
        local = np.column_stack([self.y_mm[cols], z[rows, cols]])
        verts = T[:, :3, 3] + T[:, :3, 1] * local[:, :1] + T[:, :3, 2] * local[:, 1:]
        return trimesh.Trimesh(verts, remap[faces], process=False)


def _fill_gaps(env: FloatArray, field_name: str) -> FloatArray:
    """Fill a section's NaN nodes (no material under them) with the section's lowest z."""
    if np.all(np.isnan(env), axis=1).any():
        raise WorkpieceError(
            "a station's plane misses the part",
            field=field_name,
            fix="check the seam lies on the part (its normals point out of the groove)",
        )
    low = np.nanmin(env, axis=1, keepdims=True)
    return np.where(np.isnan(env), low, env)
