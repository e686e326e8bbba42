"""OCCT kernels behind :mod:`seamtrack.workpiece.loader`: seam edge chains and sampling (the
meshing is :mod:`seamtrack.cad.kit.cadmesh`'s).

Imported lazily by the loader (never by a seam-mode scene): it needs CadQuery/OCP.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import cadquery as cq
import numpy as np
from numpy.typing import NDArray
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve
from OCP.BRepGProp import BRepGProp_Face
from OCP.GCPnts import GCPnts_QuasiUniformDeflection, GCPnts_UniformAbscissa
from OCP.gp import gp_Pnt, gp_Vec
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE
from OCP.TopExp import TopExp
from OCP.TopoDS import TopoDS
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape

from seamtrack import constants
from seamtrack.errors import WorkpieceError

FloatArray = NDArray[np.float64]

#: Two seam edges are connected when their ends are closer than this (mm).
CHAIN_TOL_MM = 1e-6


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
