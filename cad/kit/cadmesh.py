"""Meshing a BRep with an absolute chordal tolerance, in a few hundred bytes a triangle.

OCCT's mesher (``BRepMesh_IncrementalMesh``) holds about 2 KB of scratch a triangle at its
peak (Watson's Delaunay; about 0.8 KB with Delabella), far more than the mesh itself (about 60
bytes a triangle here). So the mesher discretizes the edges at the tolerance but meshes the
faces' interiors at :data:`INTERIOR_FACTOR` times it, where its scratch is small, and the
interiors are refined here in numpy (:func:`refine_interior`): a triangle whose centroid or edge
midpoint strays from the surface (probed at the interpolated UV: ``|S(uv) - p|`` bounds the
distance) is split at that exact surface point ``S(uv)``. Splits at UV midpoints cannot fold
a face; the boundary edges stay the mesher's, shared by the two faces they bound, so the
welded mesh stays watertight. The deviation is then measured exactly (Newton projections of
the worst probes), and where it still exceeds the tolerance (the mesher's edges stray on
twisted B-spline faces) the part is meshed again with a smaller deflection.

Imported lazily by the loader: it needs CadQuery/OCP.
"""

from __future__ import annotations

import ctypes
import math
import time
from dataclasses import dataclass

import cadquery as cq
import numpy as np
from numpy.typing import NDArray
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Surface
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.BRepTools import BRepTools
from OCP.GeomAbs import GeomAbs_Plane
from OCP.gp import gp_Pnt, gp_Vec
from OCP.IMeshTools import IMeshTools_MeshAlgoType_Delabella, IMeshTools_Parameters
from OCP.TopAbs import TopAbs_REVERSED
from OCP.TopLoc import TopLoc_Location

from seamtrack import constants
from seamtrack.errors import WorkpieceError

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: Re-mesh with a smaller deflection at most this many times if the measured deviation is over.
MAX_REMESH = 6
#: Rounds of local refinement (each at least halves a straying chord, so the sag falls ~4x).
MAX_REFINE = 16
#: Triangles probed at a time (the probes' scratch: about 0.5 KB a triangle of a chunk).
CHUNK = 8192
#: The mesher meshes faces' interiors at this many times the tolerance; the rest is refined
#: here (module docstring). 10: the mesher's scratch then stays under a fifth of the final
#: mesh's triangles' worth (measured on the paper groove at 1e-3 mm).
INTERIOR_FACTOR = 30.0


def mesh(
    shape: cq.Shape, tolerance_mm: float, angular_rad: float
) -> tuple[FloatArray, IntArray, float, float, list[int]]:
    """Mesh with an absolute chordal tolerance, measure, and refine where it is exceeded.

    Returns
    -------
    vertices : (n, 3) float
        Per-face nodes (not yet welded across faces).
    faces : (m, 3) int
        Triangles, counter-clockwise seen from outside.
    deviation_mm : float
        Measured largest distance of the mesh from the exact surfaces.
    meshing_time_s : float
        Time spent meshing and refining (all passes).
    counts : list of int
        Triangles of each face, in the order of ``shape.Faces()``.
    """
    spent = 0.0
    deflection = tolerance_mm
    for _ in range(MAX_REMESH + 1):
        t0 = time.perf_counter()
        _mesh_brep(shape, deflection, INTERIOR_FACTOR * deflection, angular_rad)
        faces = read_faces(shape)
        BRepTools.Clean_s(shape.wrapped)  # read: the part keeps no second copy of the mesh
        count = sum(len(f.tris) for f in faces)
        if count > constants.MAX_MESH_TRIANGLES:
            raise _over_budget(tolerance_mm, count, math.nan, count)
        for face in faces:
            if face.adaptor is not None:
                others = sum(len(f.tris) for f in faces) - len(face.tris)
                refine_interior(face, tolerance_mm, constants.MAX_MESH_TRIANGLES - others)
        vertices, triangles, deviation, counts = assemble(faces)
        spent += time.perf_counter() - t0
        if deviation <= tolerance_mm:
            break
        # The mesher's edges undershoot on twisted B-spline faces (measured up to 7x): aim
        # below. The triangle count grows about as 1 / deflection.
        factor = min(0.7, max(0.1, 0.8 * tolerance_mm / deviation))
        needed = len(triangles) / factor
        if needed > constants.MAX_MESH_TRIANGLES:
            raise _over_budget(tolerance_mm, needed, deviation, len(triangles))
        deflection *= factor
    return vertices, triangles, deviation, spent, counts


def _over_budget(tolerance_mm: float, needed: float, deviation: float, n: int) -> WorkpieceError:
    reached = "" if math.isnan(deviation) else f" (the mesh reached {deviation:.2g} mm with {n:,})"
    return WorkpieceError(
        f"meeting {tolerance_mm:.3g} mm on this part takes more than {needed:.2g} triangles"
        f"{reached}, more than the "
        f"{constants.MAX_MESH_TRIANGLES:.0e} that fit in memory",
        field="workpiece.tolerance_mm",
        fix=f"use a coarser tolerance (e.g. {2 * tolerance_mm:.2g} mm)",
    )


def _mesh_brep(shape: cq.Shape, edges: float, interior: float, angular_rad: float) -> None:
    """OCCT's mesher: serial, Delabella's Delaunay (the same nodes as Watson's, under half its
    scratch memory), the edges at ``edges`` and the faces' interiors at ``interior`` (mm); then
    the freed scratch handed back to the system."""
    BRepTools.Clean_s(shape.wrapped)
    params = IMeshTools_Parameters()
    params.Deflection = edges
    params.DeflectionInterior = interior
    params.Angle = angular_rad
    params.Relative = False
    params.InParallel = False  # the parallel mesher holds about half as much again
    params.MeshAlgo = IMeshTools_MeshAlgoType_Delabella
    BRepMesh_IncrementalMesh(shape.wrapped, params)
    try:  # glibc keeps freed pages otherwise
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):  # not glibc: nothing to do
        pass


# ------------------------------------------------------------------------------- faces
@dataclass
class Face:
    """One face's triangulation being refined: located nodes, their UV (curved faces), the
    triangles (the face's own orientation), and its boundary edges' discretizations."""

    nodes: FloatArray
    uv: FloatArray | None
    tris: IntArray
    adaptor: BRepAdaptor_Surface | None  # None for a plane: its chords lie on it
    reversed: bool


def read_faces(shape: cq.Shape) -> list[Face]:
    """Every face's triangulation, located, with its UV nodes on curved faces."""
    faces = []
    for f in shape.Faces():
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(f.wrapped, loc)
        if tri is None:
            raise WorkpieceError(
                "a face could not be meshed",
                field="workpiece.tolerance_mm",
                fix="try a larger tolerance, or repair the part",
            )
        trsf = loc.Transformation()
        n_nodes = tri.NbNodes()
        nodes = np.empty((n_nodes, 3))
        for i in range(n_nodes):
            nodes[i] = tri.Node(i + 1).Transformed(trsf).Coord()
        tris = np.empty((tri.NbTriangles(), 3), dtype=np.int64)
        for i in range(len(tris)):
            tris[i] = tri.Triangle(i + 1).Get()
        tris -= 1
        adaptor = BRepAdaptor_Surface(f.wrapped)
        uv = None
        if adaptor.GetType() == GeomAbs_Plane:
            adaptor = None
        else:
            uv = np.empty((n_nodes, 2))
            for i in range(n_nodes):
                uv[i] = tri.UVNode(i + 1).Coord()
        faces.append(Face(nodes, uv, tris, adaptor, f.wrapped.Orientation() == TopAbs_REVERSED))
    return faces


# ------------------------------------------------------------------------------ interior
def refine_interior(face: Face, tolerance_mm: float, budget: int) -> None:
    """Split a curved face's triangles where a probe strays from the surface.

    A straying edge midpoint is replaced by the surface point at its interpolated UV, splitting
    the two triangles that share the edge (an edge on the face's boundary is left: the mesher
    discretized it at the tolerance); a straying centroid splits its triangle in three at its
    surface point. Only the new and changed triangles are probed again; more than ``budget``
    triangles is refused (:data:`seamtrack.constants.MAX_MESH_TRIANGLES` for the part). Probes
    are taken in chunks, and the neighbours of straying edges looked up among the edges' keys
    alone: the scratch stays a few dozen bytes a triangle.
    """
    assert face.adaptor is not None and face.uv is not None
    nodes, uv, tris = face.nodes, face.uv, face.tris
    todo = np.arange(len(tris))
    for _ in range(MAX_REFINE):
        sag = _sags(face.adaptor, nodes, uv, tris[todo])
        offenders = np.flatnonzero(sag > tolerance_mm)
        if not len(offenders):
            break
        m = len(todo)
        is_edge = offenders >= m
        # Edges first (a straying chord also drags its triangles' centroids off the surface),
        # the farthest first: a long chord is split before its neighbours' shorter ones
        # (the other way round a sliver beside it could take every round's split).
        offenders = offenders[np.lexsort((-sag[offenders], ~is_edge))]
        owner = todo[np.where(offenders < m, offenders, (offenders - m) // 3)]
        slot = (offenders - m) % 3
        # The neighbour across a directed edge p -> q holds q -> p.
        across = _neighbours(tris, owner, slot, offenders >= m)
        # A triangle with a straying edge waits for that edge's split (which also pulls its
        # centroid in): splitting its centroid instead would keep the long edge (a cycle).
        waiting = set(owner[offenders >= m].tolist())
        changed: set[int] = set()
        guesses = np.empty((len(offenders), 2))  # the split points' UV
        added = np.empty((2 * len(offenders), 3), dtype=np.int64)
        n_added = n_new = 0
        n_nodes = len(nodes)
        for k, t, j, other in zip(
            offenders.tolist(), owner.tolist(), slot.tolist(), across.tolist(), strict=True
        ):
            if t in changed or (k < m and t in waiting):
                continue
            mid = n_nodes + n_new
            if k < m:  # the centroid: three triangles around its surface point
                a, b, c = tris[t].tolist()
                guesses[n_new] = (uv[a] + uv[b] + uv[c]) / 3.0
                tris[t] = a, b, mid
                added[n_added : n_added + 2] = (b, c, mid), (c, a, mid)
                n_added += 2
                changed.add(t)
            else:  # the edge p -> q (corner j - 1 to corner j), and its neighbour's q -> p
                if other < 0 or other in changed:
                    continue  # the face's boundary, or a neighbour already split this round
                p, q = int(tris[t][j - 1]), int(tris[t][j])
                guesses[n_new] = 0.5 * (uv[p] + uv[q])
                for u in (t, other):
                    row = tris[u].tolist()
                    i = next(i for i in range(3) if {row[i - 1], row[i]} == {p, q})
                    start, end, opposite = row[i - 1], row[i], row[(i + 1) % 3]
                    tris[u] = start, mid, opposite
                    added[n_added] = mid, end, opposite
                    n_added += 1
                    changed.add(u)
            n_new += 1
        if not n_new:
            break
        first_new = len(tris)
        if first_new + n_added > budget:
            over = constants.MAX_MESH_TRIANGLES - budget + first_new + n_added
            raise _over_budget(tolerance_mm, over, float(sag.max()), over - n_added)
        nodes = np.vstack([nodes, surface_points(face.adaptor, guesses[:n_new])])
        uv = np.vstack([uv, guesses[:n_new]])
        tris = np.vstack([tris, added[:n_added]])
        todo = np.concatenate([np.array(sorted(changed)), np.arange(first_new, len(tris))])
    face.nodes, face.uv, face.tris = nodes, uv, tris


def _neighbours(
    tris: IntArray, owner: IntArray, slot: IntArray, is_edge: NDArray[np.bool_]
) -> IntArray:
    """For each straying edge (corner ``slot - 1`` to ``slot`` of triangle ``owner``), the
    triangle across it (-1 on the face's boundary); -1 for centroids."""
    out = np.full(len(owner), -1, dtype=np.int64)
    if not is_edge.any():
        return out
    n = int(tris.max()) + 1
    t, j = owner[is_edge], slot[is_edge]
    wanted = tris[t, j] * n + tris[t, (j - 1) % 3]  # q -> p: the neighbour's direction
    found: dict[int, int] = {}
    for column in range(3):  # directed edges corner column - 1 -> column, a column at a time
        key = tris[:, column - 1] * n + tris[:, column]
        hit = np.flatnonzero(np.isin(key, wanted))
        found.update(zip(key[hit].tolist(), hit.tolist(), strict=True))
    out[is_edge] = [found.get(w, -1) for w in wanted.tolist()]
    return out


def _sags(
    adaptor: BRepAdaptor_Surface, nodes: FloatArray, uv: FloatArray, tris: IntArray
) -> FloatArray:
    """Each probe's distance to the surface point at its interpolated UV (an upper bound of its
    distance to the surface): centroids (m,) then edge midpoints (3m,), as :func:`_probes`
    orders them; taken :data:`CHUNK` triangles at a time."""
    m = len(tris)
    out = np.empty(4 * m)
    for start in range(0, m, CHUNK):
        chunk = tris[start : start + CHUNK]
        c = len(chunk)
        probes, guesses = _probes(nodes[chunk]), _probes(uv[chunk])
        d = np.linalg.norm(surface_points(adaptor, guesses) - probes, axis=1)
        out[start : start + c] = d[:c]
        out[m + 3 * start : m + 3 * (start + c)] = d[c:]
    return out


def _probe(points: FloatArray, tris: IntArray, i: int) -> FloatArray:
    """Probe ``i`` of :func:`_probes`'s order, in ``points`` (the nodes or their UV)."""
    m = len(tris)
    if i < m:
        return points[tris[i]].mean(axis=0)
    t, j = divmod(i - m, 3)
    return 0.5 * (points[tris[t, j]] + points[tris[t, j - 1]])


# ----------------------------------------------------------------------------- measuring
def assemble(faces: list[Face]) -> tuple[FloatArray, IntArray, float, list[int]]:
    """All faces' nodes and outward triangles, the measured deviation, triangles per face."""
    deviation = 0.0
    all_v, all_f, counts, offset = [], [], [], 0
    for face in faces:
        tris = face.tris
        if face.adaptor is not None and face.uv is not None:
            deviation = _surface_distance(face, deviation)
        if face.reversed:
            tris = tris[:, ::-1]
        all_v.append(face.nodes)
        all_f.append(tris + offset)
        counts.append(len(tris))
        offset += len(face.nodes)
    return np.vstack(all_v), np.vstack(all_f), float(deviation), counts


def triangulation(shape: cq.Shape) -> tuple[FloatArray, IntArray, float, list[int]]:
    """The mesher's own triangulation of every face (no refinement) and its deviation."""
    return assemble(read_faces(shape))


def _probes(corners: FloatArray) -> FloatArray:
    """Centroids (m, d) then edge midpoints (3m, d) of triangles given as (m, 3, d) corners."""
    mids = 0.5 * (corners + np.roll(corners, 1, axis=1))
    return np.concatenate([corners.mean(axis=1), mids.reshape(-1, corners.shape[2])])


def surface_points(adaptor: BRepAdaptor_Surface, uv: FloatArray) -> FloatArray:
    """S(u, v) for each row of ``uv`` (filled in place: a list of tuples would cost ~0.5 KB a
    point)."""
    out = np.empty((len(uv), 3))
    for i in range(len(uv)):
        out[i] = adaptor.Value(uv[i, 0], uv[i, 1]).Coord()
    return out


def _surface_distance(face: Face, floor: float) -> float:
    """Largest distance of a curved face's probe points to its exact (located) surface, or
    ``floor``.

    Each probe's distance is first bounded above by its distance to S(uv) at its interpolated
    UV; probes are then projected exactly (Newton on the surface) in decreasing order of that
    bound until no remaining bound can beat the largest exact distance found.
    """
    assert face.adaptor is not None and face.uv is not None
    bound = _sags(face.adaptor, face.nodes, face.uv, face.tris)
    best = floor
    for i in np.argsort(-bound):
        if bound[i] <= best:
            break
        point, guess = _probe(face.nodes, face.tris, i), _probe(face.uv, face.tris, i)
        best = max(best, min(bound[i], foot(face.adaptor, point, guess)[0]))
    return best


def foot(
    adaptor: BRepAdaptor_Surface, point: FloatArray, uv: FloatArray
) -> tuple[float, FloatArray, FloatArray]:
    """Distance from a point to the surface, the foot point and its uv: Gauss-Newton from a
    nearby UV."""
    u, v = float(uv[0]), float(uv[1])
    target = gp_Pnt(*point)
    p, du, dv = gp_Pnt(), gp_Vec(), gp_Vec()
    for _ in range(20):
        adaptor.D1(u, v, p, du, dv)
        r = gp_Vec(p, target)
        a, b, c = du.Dot(du), du.Dot(dv), dv.Dot(dv)
        ru, rv = du.Dot(r), dv.Dot(r)
        det = a * c - b * b
        if det <= 0:
            break
        step_u, step_v = (c * ru - b * rv) / det, (a * rv - b * ru) / det
        u, v = u + step_u, v + step_v
        if abs(step_u) * math.sqrt(a) + abs(step_v) * math.sqrt(c) < 1e-12:
            break
    point_on = adaptor.Value(u, v)
    return float(point_on.Distance(target)), np.array(point_on.Coord()), np.array([u, v])
