"""OCCT kernels behind :mod:`seamtrack.workpiece.loader`: seam edge chains and sampling,
meshing with an absolute tolerance, and measuring the mesh's deviation from the exact surfaces.

Imported lazily by the loader (never by a seam-mode scene): it needs CadQuery/OCP.
"""

from __future__ import annotations

import ctypes
import math
import time
from collections.abc import Sequence
from typing import Any

import cadquery as cq
import numpy as np
from numpy.typing import NDArray
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.BRepGProp import BRepGProp_Face
from OCP.BRepMesh import BRepMesh_IncrementalMesh
from OCP.BRepTools import BRepTools
from OCP.GCPnts import GCPnts_QuasiUniformDeflection, GCPnts_UniformAbscissa
from OCP.GeomAbs import GeomAbs_Plane
from OCP.gp import gp_Pnt, gp_Vec
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_REVERSED
from OCP.TopExp import TopExp
from OCP.TopLoc import TopLoc_Location
from OCP.TopoDS import TopoDS
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape

from seamtrack import constants
from seamtrack.errors import WorkpieceError

FloatArray = NDArray[np.float64]

#: Two seam edges are connected when their ends are closer than this (mm).
CHAIN_TOL_MM = 1e-6
#: Re-mesh with a smaller deflection at most this many times if the measured deviation is over.
MAX_REMESH = 6
#: Rounds of local refinement of a curved face (each at least halves a straying chord).
MAX_REFINE = 12


def _seam_error(message: str, fix: str) -> WorkpieceError:
    return WorkpieceError(message, field="workpiece.seam", fix=fix)


# ----------------------------------------------------------------------------- seam edges
def select_edges(shape: cq.Shape, selector: str, names: Sequence[str]) -> list[cq.Edge]:
    """Edges of ``shape`` matching a CadQuery selector string."""
    try:
        found = cq.Workplane("XY").add(shape).edges(selector).vals()
    except Exception as exc:
        raise _seam_error(
            f"seam {selector!r} is neither a seam name nor a valid selector: {exc}",
            f"use a seam name ({', '.join(names) or 'none'}) or a CadQuery selector "
            "such as '|X and <Z'",
        ) from exc
    edges = [e for e in found if isinstance(e, cq.Edge)]
    if not edges:
        raise _seam_error(
            f"seam selector {selector!r} matches no edge",
            "try the selector in CQ-editor, or give seam_near_mm points",
        )
    return edges


def edges_near(shape: cq.Shape, points: FloatArray) -> list[cq.Edge]:
    """The edge nearest to each point (duplicates dropped).

    A point at a vertex is equally near several edges: then the edge whose interior (not an
    end) is nearest wins; a point that still ties is refused.
    """
    edges = shape.Edges()
    picked: list[cq.Edge] = []
    for i, p in enumerate(points):
        vertex = cq.Vertex.makeVertex(*p)
        dist = np.array([e.distance(vertex) for e in edges])
        tied = [edges[k] for k in np.flatnonzero(dist <= dist.min() + 1e-7)]
        if len(tied) > 1:
            at = cq.Vector(*p)
            tied = [
                e
                for e in tied
                if min((e.startPoint() - at).Length, (e.endPoint() - at).Length) > 1e-6
            ]
        if len(tied) != 1:
            raise WorkpieceError(
                f"seam_near_mm point {i} is equally near {max(len(tied), 2)} edges",
                field="workpiece.seam_near_mm",
                fix="place the points along the seam, away from its ends and corners",
            )
        if not any(tied[0].isSame(e) for e in picked):
            picked.append(tied[0])
    return picked


def lexicographic_first(points: Sequence[FloatArray]) -> FloatArray:
    """The lexicographically smallest point (x, then y, then z); coordinates closer than
    :data:`constants.LEXICOGRAPHIC_TIE_MM` count as equal, so float noise never decides."""
    candidates = list(points)
    for axis in range(3):
        low = min(p[axis] for p in candidates)
        candidates = [p for p in candidates if p[axis] <= low + constants.LEXICOGRAPHIC_TIE_MM]
    return candidates[0]


def chain(edges: Sequence[cq.Edge], what: str) -> list[tuple[cq.Edge, bool]]:
    """Order edges into one connected chain: (edge, forward) pairs.

    The chain starts at its lexicographically smallest free end (x, then y, then z; see
    :func:`lexicographic_first`), so the same edges give the same seam direction whatever
    their order or orientation.
    """
    ends = [(np.array(e.startPoint().toTuple()), np.array(e.endPoint().toTuple())) for e in edges]
    flat = [p for pair in ends for p in pair]

    def degree(p: FloatArray) -> int:
        return sum(bool(np.linalg.norm(p - q) <= CHAIN_TOL_MM) for q in flat)

    free = [p for p in flat if degree(p) == 1]
    start = lexicographic_first(free or flat)
    remaining = list(range(len(edges)))
    out: list[tuple[cq.Edge, bool]] = []
    point = start
    while remaining:
        dist = [
            (min(np.linalg.norm(ends[i][0] - point), np.linalg.norm(ends[i][1] - point)), i)
            for i in remaining
        ]
        gap, i = min(dist)
        if gap > CHAIN_TOL_MM:
            raise _seam_error(
                f"{what} gives {len(edges)} edges that do not form one connected seam",
                "narrow the selector to one connected chain of edges, or use seam_near_mm",
            )
        remaining.remove(i)
        forward = bool(np.linalg.norm(ends[i][0] - point) <= np.linalg.norm(ends[i][1] - point))
        out.append((edges[i], forward))
        point = ends[i][1] if forward else ends[i][0]
    return out


def edge_samples(
    curve: BRepAdaptor_Curve, tolerance_mm: float, spacing_mm: float
) -> tuple[FloatArray, FloatArray]:
    """Parameters (n,) and points (n, 3) along an edge's exact curve, at most ``spacing_mm``
    apart and closer where the chord error would exceed ``tolerance_mm``, in the curve's
    direction. The two samplers' merged parameters may give near-duplicates: points closer
    than 1e-4 of the spacing to the last kept one (or to the end) are left out."""
    u0, u1 = curve.FirstParameter(), curve.LastParameter()
    params = {u0, u1}
    for sampler in (
        GCPnts_QuasiUniformDeflection(curve, tolerance_mm, u0, u1),
        GCPnts_UniformAbscissa(curve, spacing_mm, u0, u1),
    ):
        if sampler.IsDone():
            params.update(sampler.Parameter(i) for i in range(1, sampler.NbPoints() + 1))
    ts = np.array(sorted(params))
    pts = np.array([curve.Value(t).Coord() for t in ts])
    keep = np.ones(len(ts), dtype=bool)
    last = pts[0]
    for i in range(1, len(ts) - 1):
        if (
            np.linalg.norm(pts[i] - last) < 1e-4 * spacing_mm
            or np.linalg.norm(pts[-1] - pts[i]) < 1e-4 * spacing_mm
        ):
            keep[i] = False
        else:
            last = pts[i]
    return ts[keep], pts[keep]


def sample_seam(
    shape: cq.Shape, chained: list[tuple[cq.Edge, bool]], tolerance_mm: float, spacing_mm: float
) -> tuple[FloatArray, FloatArray]:
    """Seam points and both adjacent faces' outward unit normals.

    Points are spaced at most ``spacing_mm`` apart and closer where the chord error would
    exceed ``tolerance_mm``; they lie on the exact edge curves.

    Returns
    -------
    points : (n, 3) float
    face_normals : (n, 2, 3) float
    """
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(shape.wrapped, TopAbs_EDGE, TopAbs_FACE, ancestors)
    points: list[FloatArray] = []
    normals: list[FloatArray] = []
    for n_edge, (edge, forward) in enumerate(chained):
        if not ancestors.Contains(edge.wrapped):
            raise _seam_error(
                "a seam edge is not an edge of the part",
                "return seam edges taken from the solid itself",
            )
        faces: list[Any] = []
        for f in ancestors.FindFromKey(edge.wrapped):
            if not any(f.IsSame(g) for g in faces):
                faces.append(f)
        if len(faces) != 2:
            raise _seam_error(
                f"a seam edge borders {len(faces)} face(s), not 2",
                "pick an edge where two faces of the part meet",
            )
        curve = BRepAdaptor_Curve(edge.wrapped)
        ts, pts = edge_samples(curve, tolerance_mm, spacing_mm)
        if not forward:
            ts, pts = ts[::-1], pts[::-1]
        face_n = np.empty((len(ts), 2, 3))
        edge_d = TopoDS.Edge_s(edge.wrapped)
        for k, f in enumerate(faces):
            face = TopoDS.Face_s(f)
            pcurve = BRep_Tool.CurveOnSurface_s(edge_d, face, 0.0, 0.0)
            props = BRepGProp_Face(face)  # normal follows the face orientation: outward
            pnt, vec = gp_Pnt(), gp_Vec()
            for i, t in enumerate(ts):
                uv = pcurve.Value(t)
                props.Normal(uv.X(), uv.Y(), pnt, vec)
                face_n[i, k] = vec.Coord()
        face_n /= np.linalg.norm(face_n, axis=2, keepdims=True)
        start = 1 if n_edge else 0  # the previous edge already gave the shared point
        points.append(pts[start:])
        normals.append(face_n[start:])
    return np.vstack(points), np.vstack(normals)


# ----------------------------------------------------------------------------- meshing
def mesh(
    shape: cq.Shape, tolerance_mm: float, angular_rad: float
) -> tuple[FloatArray, NDArray[np.int64], float, float, list[int]]:
    """Mesh with an absolute chordal tolerance, measure, and refine where it is exceeded.

    BRepMesh meets its deflection on most of a curved face but strays by up to 7x on a few
    long triangles of twisted B-spline faces (10 probes in 10^5 on the paper groove). Those
    triangles are split where they stray, at the exact surface point (:func:`_refine`), instead
    of re-meshing the whole part finer: the mesh keeps BRepMesh's size (1.9e5 triangles for the
    paper groove at 1e-3 mm, where re-meshing reached 1.66e6). A face whose deviation lies on
    its boundary (shared with a neighbour) cannot be split alone: then the part is re-meshed
    with a smaller deflection, as before.

    Returns
    -------
    vertices : (n, 3) float
        Per-face nodes (not yet welded across faces).
    faces : (m, 3) int
        Triangles, counter-clockwise seen from outside.
    deviation_mm : float
        Measured largest distance of the mesh from the exact surfaces.
    meshing_time_s : float
        Time spent in ``BRepMesh_IncrementalMesh`` (all passes).
    counts : list of int
        Triangles of each face, in the order of ``shape.Faces()``.
    """
    deflection = tolerance_mm
    spent = 0.0
    for _ in range(MAX_REMESH + 1):
        BRepTools.Clean_s(shape.wrapped)
        t0 = time.perf_counter()
        # Serial: the parallel mesher holds about half as much memory again per triangle.
        BRepMesh_IncrementalMesh(shape.wrapped, deflection, False, angular_rad, False)
        spent += time.perf_counter() - t0
        _release_freed_memory()  # the mesher's scratch, before the arrays are built
        vertices, faces, deviation, counts = triangulation(shape, tolerance_mm)
        if deviation <= tolerance_mm and len(faces) <= constants.MAX_MESH_TRIANGLES:
            break
        # BRepMesh undershoots on twisted B-spline faces (measured up to 7x): aim below.
        factor = min(0.7, max(0.1, 0.8 * tolerance_mm / deviation))
        # The triangle count grows about as 1 / deflection; refuse a pass that would not fit
        # in memory instead of running it.
        needed = len(faces) / factor if deviation > tolerance_mm else len(faces)
        if needed > constants.MAX_MESH_TRIANGLES:
            raise WorkpieceError(
                f"meeting {tolerance_mm:.3g} mm on this part takes about {needed:.2g} triangles "
                f"(BRepMesh reached {deviation:.2g} mm with {len(faces):,}), more than the "
                f"{constants.MAX_MESH_TRIANGLES:.0e} that fit in memory",
                field="workpiece.tolerance_mm",
                fix=f"use a coarser tolerance (e.g. {2 * tolerance_mm:.2g} mm)",
            )
        deflection *= factor
    BRepTools.Clean_s(shape.wrapped)  # the part keeps no second copy of the mesh
    return vertices, faces, deviation, spent, counts


def _release_freed_memory() -> None:
    """Hand the heap's freed pages back to the system (glibc keeps them otherwise)."""
    try:
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):  # not glibc: nothing to do
        pass


def triangulation(
    shape: cq.Shape, tolerance_mm: float | None = None
) -> tuple[FloatArray, NDArray[np.int64], float, list[int]]:
    """Every face's triangulation (orientation and location applied) and its measured deviation.

    The deviation probes each triangle's centroid and edge midpoints (where a chord strays
    furthest from a surface) and projects them onto the face's exact surface: exactly for
    planes, by Newton iteration from the mesh's own UV coordinates otherwise. With
    ``tolerance_mm``, curved faces are first refined inside until no probe strays further
    (:func:`_refine`). Returns the vertices, the triangles, the deviation and the triangles of
    each face.
    """
    all_v: list[FloatArray] = []
    all_f: list[NDArray[np.int64]] = []
    counts: list[int] = []
    deviation = 0.0
    offset = 0
    for face in shape.Faces():
        loc = TopLoc_Location()
        tri = BRep_Tool.Triangulation_s(face.wrapped, loc)
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
        adaptor = BRepAdaptor_Surface(face.wrapped)
        if adaptor.GetType() == GeomAbs_Plane:
            plane = adaptor.Plane()
            normal = np.array(plane.Axis().Direction().Coord())
            dist = np.abs((_probes(nodes[tris]) - np.array(plane.Location().Coord())) @ normal)
            deviation = max(deviation, float(dist.max(initial=0.0)))
        else:
            uv = np.empty((n_nodes, 2))
            for i in range(n_nodes):
                uv[i] = tri.UVNode(i + 1).Coord()
            if tolerance_mm is not None:
                nodes, uv, tris = _refine(adaptor, nodes, uv, tris, tolerance_mm)
            deviation = _surface_distance(
                adaptor, _probes(nodes[tris]), _probes(uv[tris]), deviation
            )
        if face.wrapped.Orientation() == TopAbs_REVERSED:
            tris = tris[:, ::-1]
        all_v.append(nodes)
        all_f.append(tris + offset)
        counts.append(len(tris))
        offset += len(nodes)
    return np.vstack(all_v), np.vstack(all_f), float(deviation), counts


def _refine(
    adaptor: BRepAdaptor_Surface,
    nodes: FloatArray,
    uv: FloatArray,
    tris: NDArray[np.int64],
    tolerance_mm: float,
) -> tuple[FloatArray, FloatArray, NDArray[np.int64]]:
    """Split a face's triangles where a probe strays from the surface by more than the tolerance.

    A straying edge midpoint is replaced by its exact surface point, splitting the two
    triangles that share the edge (an edge on the face's boundary is left: the neighbouring
    face shares it); a straying centroid splits its triangle in three at the surface point.
    Each split at least halves the chord, so the sag falls about fourfold a round; only the new
    and changed triangles are probed again. Straying probes are few (10 in 10^5 on the paper
    groove): the arrays grow by a few rows a round.
    """
    todo = np.arange(len(tris))
    for _ in range(MAX_REFINE):
        corners = tris[todo]
        offenders = _straying(adaptor, _probes(nodes[corners]), _probes(uv[corners]), tolerance_mm)
        if not offenders:
            break
        m, n0 = len(todo), len(nodes)
        points: list[FloatArray] = []
        params: list[FloatArray] = []
        added: list[list[int]] = []
        changed: set[int] = set()
        # Edges first: a straying chord also drags its triangles' centroids off the surface.
        for k, (point, param) in sorted(offenders, key=lambda o: o[0] < m):
            t = int(todo[k if k < m else (k - m) // 3])
            if t in changed:
                continue
            mid = n0 + len(points)
            a, b, c = (int(i) for i in tris[t])
            if k < m:  # the centroid: three triangles around its surface point
                tris[t] = a, b, mid
                added += [[b, c, mid], [c, a, mid]]
                changed.add(t)
            else:  # the edge p -> q (corner j - 1 to corner j), and its neighbour's q -> p
                j = (k - m) % 3
                p, q = int(tris[t][j - 1]), int(tris[t][j])
                across = np.flatnonzero(((np.roll(tris, 1, axis=1) == q) & (tris == p)).any(axis=1))
                if len(across) != 1 or int(across[0]) in changed:
                    continue  # the face's boundary (or a neighbour already split this round)
                for u in (t, int(across[0])):
                    row = [int(i) for i in tris[u]]
                    i = next(i for i in range(3) if {row[i - 1], row[i]} == {p, q})
                    start, end, opposite = row[i - 1], row[i], row[(i + 1) % 3]
                    tris[u] = start, mid, opposite
                    added.append([mid, end, opposite])
                    changed.add(u)
            points.append(point)
            params.append(param)
        if not points:
            break
        first_new = len(tris)
        nodes = np.vstack([nodes, points])
        uv = np.vstack([uv, params])
        tris = np.vstack([tris, np.array(added, dtype=np.int64)])
        todo = np.concatenate([np.array(sorted(changed)), np.arange(first_new, len(tris))])
    return nodes, uv, tris


def _straying(
    adaptor: BRepAdaptor_Surface, probes: FloatArray, guesses: FloatArray, tolerance_mm: float
) -> list[tuple[int, tuple[FloatArray, FloatArray]]]:
    """Probes farther than the tolerance from the surface: (index, (surface point, its uv))."""
    bound = _sag_bound(adaptor, probes, guesses)
    found = []
    for i in np.flatnonzero(bound > tolerance_mm):
        distance, point, param = _foot(adaptor, probes[i], guesses[i])
        if distance > tolerance_mm:
            found.append((int(i), (point, param)))
    return found


def _probes(corners: FloatArray) -> FloatArray:
    """Centroids (m, d) then edge midpoints (3m, d) of triangles given as (m, 3, d) corners."""
    mids = 0.5 * (corners + np.roll(corners, 1, axis=1))
    return np.concatenate([corners.mean(axis=1), mids.reshape(-1, corners.shape[2])])


def _sag_bound(adaptor: BRepAdaptor_Surface, probes: FloatArray, guesses: FloatArray) -> FloatArray:
    """Each probe's distance to S(uv) at its interpolated UV: an upper bound of its distance to
    the surface (filled in place: a list of tuples would cost ~0.5 KB a triangle)."""
    surface_points = np.empty_like(probes)
    for i in range(len(probes)):
        surface_points[i] = adaptor.Value(guesses[i, 0], guesses[i, 1]).Coord()
    surface_points -= probes
    return np.sqrt(np.einsum("ij,ij->i", surface_points, surface_points))


def _surface_distance(
    adaptor: BRepAdaptor_Surface, probes: FloatArray, guesses: FloatArray, floor: float
) -> float:
    """Largest distance of probe points to the face's exact (located) surface, or ``floor``.

    Each probe's distance is first bounded above by its distance to S(uv) at its interpolated
    UV; probes are then projected exactly (Newton on the surface) in decreasing order of that
    bound until no remaining bound can beat the largest exact distance found.
    """
    bound = _sag_bound(adaptor, probes, guesses)
    best = floor
    for i in np.argsort(-bound):
        if bound[i] <= best:
            break
        best = max(best, min(bound[i], _foot(adaptor, probes[i], guesses[i])[0]))
    return best


def _foot(
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
    foot = adaptor.Value(u, v)
    return float(foot.Distance(target)), np.array(foot.Coord()), np.array([u, v])
