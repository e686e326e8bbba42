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
from seamtrack.geometry.groove_points import BOTTOM, LEFT_TOP, N_POINTS, RIGHT_TOP
from seamtrack.geometry.seam import Seam
from seamtrack.workpiece.beads import BeadShape, lay_beads_on_grid
from seamtrack.workpiece.sections import (
    COVERED_MM,
    bottom_corners,
    fill_gaps,
    section_envelopes,
    station_frames,
    top_corners,
)

if TYPE_CHECKING:
    import trimesh

__all__ = ["FillState", "PassBeads", "section_envelopes"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.intp]

#: Fill nodes next to a bead are sunk this far into the part (mm) to seal the mesh seam.
SEAL_DEPTH_MM = 0.02
#: The fill mesh keeps a grid node where a surface bends by more than this (mm, 2nd difference).
MESH_KINK_MM = 1e-3
#: Lateral margin (mm) of the station grid beyond the groove's top corners.
GRID_MARGIN_MM = 12.0
#: The probe sections that find the groove's top corners reach at least this far (mm) either
#: side of the seam, and as far as the part does.
PROBE_HALF_WIDTH_MM = 60.0


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
        plate, corners, top_idx = top_corners(y, z)
        bottom = bottom_corners(y, z, z, top_idx)
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
            Half the lateral grid's width; default the groove's top half-width plus
            :data:`GRID_MARGIN_MM` (room for cap beads spreading onto the plates).
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
        # Keep the end stations inside the part: its end faces lie in their planes, and a
        # polyline seam's end tangent (a chord's) tilts the plane out of a curved part's end.
        inset = min(spacing_mm / 2, length / 4)
        s[0], s[-1] = inset, length - inset
        frames = station_frames(seam, s)
        tri = np.asarray(mesh.triangles, dtype=np.float64)
        if half_width_mm is None:  # probe across the whole part (at least +-60 mm)
            probes = frames[np.unique(np.linspace(0, n - 1, 9).astype(int))[1:-1]]
            vertices = np.asarray(mesh.vertices, dtype=np.float64)
            across = max(float(np.abs((vertices - T[:3, 3]) @ T[:3, 1]).max()) for T in probes)
            probe_half = max(PROBE_HALF_WIDTH_MM, math.ceil(across))
            probe_y = np.arange(-probe_half, probe_half + 1e-9, 0.25)
            env = fill_gaps(section_envelopes(tri, probes, probe_y, probe_half + 30.0),
                            "workpiece")  # fmt: skip
            _, corners, _ = top_corners(probe_y, env)
            half_width_mm = float(np.abs(corners[:, :, 0]).max()) + GRID_MARGIN_MM
        half = float(half_width_mm)
        steps = math.ceil(half / lateral_step_mm)
        y = np.linspace(-steps * lateral_step_mm, steps * lateral_step_mm, 2 * steps + 1)
        env = section_envelopes(tri, frames, y, math.hypot(half, half) + 30.0)
        return cls.from_profiles(s, frames, y, fill_gaps(env, "workpiece"))

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
        the bottom corners, right bottom corner, right top corner. Bottom points are grid nodes
        (within ``lateral_step_mm`` of the true corner). Where the fill buries a wall and
        spills over the plate beside it (a cap), that side's top and bottom corners are the
        fill's toe on the plate, where a sensor sees the plate's line end (the corner under
        the metal is seen by none); :attr:`top_corners` stay the groove's.
        """
        return self.all_groove_points(np.array([int(i)]))[0]

    def all_groove_points(self, stations: ArrayLike | None = None) -> FloatArray:
        """(m', 7, 2) :meth:`groove_points` at several stations at once (default all)."""
        idx = np.arange(self.n_stations) if stations is None else np.asarray(stations, np.intp)
        z = self.surface_z[idx]
        bottom = bottom_corners(self.y_mm, z, self.base_z[idx], self.top_index[idx])
        bottom, top = _spilled(self.y_mm, z, self.base_z[idx], self.top_index[idx], bottom,
                               self.top_corners[idx])  # fmt: skip
        rows = np.arange(len(idx))
        y_left, y_right = self.y_mm[bottom[:, 0]], self.y_mm[bottom[:, 1]]
        frac = np.array([0.0, 0.25, 0.5, 0.75, 1.0])
        ys = y_left[:, None] + (y_right - y_left)[:, None] * frac
        # Piecewise-linear surface at ys (rows differ): interpolate on the shared grid.
        j = np.clip(np.searchsorted(self.y_mm, ys) - 1, 0, len(self.y_mm) - 2)
        y0, y1 = self.y_mm[j], self.y_mm[j + 1]
        t = (ys - y0) / (y1 - y0)
        zs = z[rows[:, None], j] * (1 - t) + z[rows[:, None], j + 1] * t
        zs[:, 0], zs[:, -1] = z[rows, bottom[:, 0]], z[rows, bottom[:, 1]]
        out = np.empty((len(idx), N_POINTS, 2))
        out[:, LEFT_TOP], out[:, RIGHT_TOP] = top[:, 0], top[:, 1]
        out[:, BOTTOM, 0], out[:, BOTTOM, 1] = ys, zs
        return out

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
        # the groove's top width, or as far as a fill spilled over the plates reaches
        seen = self.all_groove_points()
        lo = np.minimum(self.top_corners[:, 0, 0], seen[:, LEFT_TOP, 0])
        hi = np.maximum(self.top_corners[:, 1, 0], seen[:, RIGHT_TOP, 0])
        outside = laid_here & ((y_centre < lo) | (y_centre > hi))
        if np.any(outside):
            i = int(np.flatnonzero(outside)[0])
            raise SceneError(
                f"the bead's centre {y_centre[i]:.2f} mm at s = {self.s_mm[i]:.1f} mm lies "
                f"outside the groove ({lo[i]:.2f} .. {hi[i]:.2f} mm)",
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
        y, base = self.y_mm, self.base_z
        m, k = base.shape
        rows = np.arange(m)
        idx = np.arange(k)
        out = np.full((m, 2), np.nan)
        laid = np.isfinite(toes[:, 0, 0])
        for side in (0, 1):
            top, foot = self.top_index[:, side], self.base_bottom[:, side]
            z_toe = np.where(laid, toes[:, side, 1], 0.0)
            # Walk down the wall from the top corner: the first node at or below the toe's height.
            if side == 0:
                on_wall = (idx >= top[:, None]) & (idx <= foot[:, None])
                below = on_wall & (base <= z_toe[:, None])
                j = np.where(below.any(axis=1), np.argmax(below, axis=1), foot)
                j_prev = np.clip(j - 1, 0, k - 1)
            else:
                on_wall = (idx <= top[:, None]) & (idx >= foot[:, None])
                below = on_wall & (base <= z_toe[:, None])
                j = np.where(below.any(axis=1), k - 1 - np.argmax(below[:, ::-1], axis=1), foot)
                j_prev = np.clip(j + 1, 0, k - 1)
            z_j, z_p = base[rows, j], base[rows, j_prev]
            drop = z_p - z_j
            t = np.where(drop > 0, np.clip((z_p - z_toe) / np.where(drop > 0, drop, 1), 0, 1), 1)
            y_wall = y[j_prev] + t * (y[j] - y[j_prev])
            gap = toes[:, side, 0] - y_wall if side == 0 else y_wall - toes[:, side, 0]
            out[:, side] = np.where(laid, gap, np.nan)
        return np.where(out < 1e-6, np.minimum(out, 0.0), out)

    # ------------------------------------------------------------------ mesh
    def mesh(self, stride: int = 4) -> trimesh.Trimesh:
        """The fill's top surface where beads lie (world frame), to join to the part's mesh.

        Triangles between consecutive stations over the covered grid nodes, one node wider on
        each side (those nodes sunk :data:`SEAL_DEPTH_MM` into the part). Laterally every
        ``stride``-th grid node is kept, plus every node where some station's surface bends by
        more than :data:`MESH_KINK_MM` (toes, wall contacts, bead valleys), so the mesh stays
        within about that of the state's surface with a fraction of the triangles. Empty without
        beads. ``vertex_attributes["pass"]`` holds each vertex's top pass (-1: none).
        """
        import trimesh

        m, k_full = self.surface_z.shape
        covered_full = self.surface_z - self.base_z > COVERED_MM
        bend = np.abs(np.diff(self.surface_z, n=2, axis=1)) > MESH_KINK_MM
        keep = np.zeros(k_full, dtype=bool)
        keep[:: max(int(stride), 1)] = True
        keep[[0, -1]] = True
        keep[1:-1] |= bend.any(axis=0)
        cols_kept = np.flatnonzero(keep)
        # A kept node is next to the fill if any node up to its kept neighbours is covered.
        run = np.concatenate([np.zeros((m, 1), np.intp), np.cumsum(covered_full, axis=1)], 1)
        left = np.concatenate([[0], cols_kept[:-1]])
        right = np.concatenate([cols_kept[1:] + 1, [k_full]])
        near = (run[:, right] - run[:, left]) > 0
        covered = covered_full[:, cols_kept]
        k = len(cols_kept)
        grown = covered | near
        z = np.where(covered_full, self.surface_z, self.base_z - SEAL_DEPTH_MM)[:, cols_kept]
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
        local = np.column_stack([self.y_mm[cols_kept[cols]], z[rows, cols]])
        verts = T[:, :3, 3] + T[:, :3, 1] * local[:, :1] + T[:, :3, 2] * local[:, 1:]
        out = trimesh.Trimesh(verts, remap[faces], process=False)
        out.vertex_attributes["pass"] = self.top_pass()[rows, cols_kept[cols]]
        return out

    def top_pass(self) -> IntArray:
        """(m, K) the index of the pass whose bead forms the surface at each node (-1: none)."""
        top = np.full(self.surface_z.shape, -1, dtype=np.intp)
        for p, bead in enumerate(self.beads):
            top = np.where(bead.z_after - bead.z_before > COVERED_MM, p, top)
        return top


def _spilled(
    y: FloatArray, z: FloatArray, base: FloatArray, top_idx: IntArray, bottom: IntArray,
    top: FloatArray,
) -> tuple[IntArray, FloatArray]:  # fmt: skip
    """The bottom corners' nodes (m, 2) and the top corners (m, 2, 2) where the fill buries a
    wall (its foot at the top corner, metal there) and spills over the plate beside it: both
    at the fill's toe, the outermost node, walking out from the top corner, under metal more
    than ``COVERED_MM`` thick."""
    bottom, top = bottom.copy(), np.array(top, dtype=float, copy=True)
    covered = z - base > COVERED_MM
    rows = np.arange(len(z))
    for side, step in ((0, -1), (1, 1)):
        t = top_idx[:, side]
        for r in np.flatnonzero((bottom[:, side] == t) & covered[rows, t]):
            k = int(t[r])
            while 0 < k + step < z.shape[1] - 1 and covered[r, k + step]:
                k += step
            bottom[r, side] = k
            top[r, side] = (y[k], z[r, k])
    return bottom, top
