"""Seams where the surfaces of two overlapping solids cross (a tube modelled through a flange's
port, a stud sunk into its plate): the OCCT kernels of :mod:`seamtrack.workpiece.weldment` for
bodies that share volume, beside :mod:`seamtrack.workpiece.contacts` for bodies that touch.
Imported lazily: it needs OCP (CadQuery's OCCT).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from OCP.BRepAlgoAPI import BRepAlgoAPI_Common
from OCP.BRepClass3d import BRepClass3d_SolidClassifier
from OCP.BRepGProp import BRepGProp
from OCP.gp import gp_Pnt
from OCP.GProp import GProp_GProps
from OCP.TopAbs import TopAbs_IN
from OCP.TopoDS import TopoDS, TopoDS_Edge, TopoDS_Face, TopoDS_Shape

from seamtrack.workpiece.contacts import (
    CLASSIFY_TOL_MM,
    FloatArray,
    Piece,
    chain_edges,
    edges,
    face_normal,
    inside_face,
    sample_edge,
    unit_vector,
    unit_vector_rows,
)

#: Bodies whose shared volume is below this fraction of the smaller one only touch (mm^3/mm^3).
OVERLAP_FRACTION = 1e-6
#: Step along a face, away from a crossing line, when testing which side of it shows (mm).
CROSS_STEP_MM = 0.05


def volume(shape: TopoDS_Shape) -> float:
    """Volume of a shape (mm^3)."""
    props = GProp_GProps()
    BRepGProp.VolumeProperties_s(shape, props)
    return abs(float(props.Mass()))


def overlap(solid_a: TopoDS_Shape, solid_b: TopoDS_Shape) -> bool:
    """Whether two solids share volume (one is modelled through the other: a tube pushed
    through a flange's port, a stud sunk into its plate), not only touch."""
    common = BRepAlgoAPI_Common(solid_a, solid_b)
    if not common.IsDone():
        return False
    shared = volume(common.Shape())
    return shared > OVERLAP_FRACTION * min(volume(solid_a), volume(solid_b))


def _showing_side(
    face: TopoDS_Face, point: FloatArray, normal: FloatArray, tangent: FloatArray, other: Any
) -> FloatArray | None:
    """The unit direction, square to the crossing line within ``face``, along which the face
    goes on outside the other body; None unless exactly one side of the line shows."""
    across = unit_vector(np.cross(normal, tangent))
    shows = []
    for sign in (1.0, -1.0):
        q = point + sign * CROSS_STEP_MM * across
        state = BRepClass3d_SolidClassifier(other, gp_Pnt(*q), CLASSIFY_TOL_MM).State()
        shows.append(inside_face(face, q) and state != TopAbs_IN)
    if shows[0] == shows[1]:
        return None
    return across if shows[0] else -across


def crossing_pieces(
    solids: tuple[TopoDS_Shape, TopoDS_Shape],
    pair: tuple[int, int],
    tolerance_mm: float,
    spacing_mm: float,
) -> list[Piece]:
    """Candidate seams where the surfaces of two overlapping solids cross: the line where a
    tube modelled through a flange comes out of the flange's face, on any surface types.

    Each section edge of the two boundaries (``BRepAlgoAPI_Section``) is kept where one side
    of it shows on each body's face (the part of the face outside the other body): there the
    two faces form a corner with free space in front of it. Edges where a face is hidden on
    both sides, or shows on both (a face that only grazes the other body), are no seam. Body
    A counts as the one that ends at the line (a tube at its flange), body B as going on."""
    from OCP.BRepAlgoAPI import BRepAlgoAPI_Section

    section = BRepAlgoAPI_Section(solids[0], solids[1], False)
    section.ComputePCurveOn1(True)
    section.ComputePCurveOn2(True)
    section.Approximation(True)
    section.Build()
    if not section.IsDone():
        return []
    groups: list[tuple[TopoDS_Face, TopoDS_Face, list[TopoDS_Edge]]] = []
    for edge in edges(section.Shape()):
        fa, fb = TopoDS_Shape(), TopoDS_Shape()
        if not (section.HasAncestorFaceOn1(edge, fa) and section.HasAncestorFaceOn2(edge, fb)):
            continue
        for ga, gb, members in groups:
            if ga.IsSame(fa) and gb.IsSame(fb):
                members.append(edge)
                break
        else:
            groups.append((TopoDS.Face_s(fa), TopoDS.Face_s(fb), [edge]))
    pieces = []
    for face_a, face_b, members in groups:
        for chain in chain_edges(members):
            parts = [sample_edge(e, fwd, tolerance_mm, spacing_mm) for e, fwd in chain]
            points = np.vstack([p[i > 0 :] for i, (p, _) in enumerate(parts)])
            tangents = np.vstack([t[i > 0 :] for i, (_, t) in enumerate(parts)])
            if len(points) < 2:
                continue
            n = len(points)
            normals = np.empty((n, 2, 3))
            along = np.empty((n, 2, 3))
            probes = sorted({n // 4, n // 2, (3 * n) // 4})
            shown = True
            for j, (face, other) in enumerate(((face_a, solids[1]), (face_b, solids[0]))):
                normals[:, j] = [face_normal(face, p) for p in points]
                across = unit_vector_rows(np.cross(normals[:, j], tangents))
                signs: set[float] = set()
                for k in probes:  # which side shows, decided where the line runs clear
                    side = _showing_side(face, points[k], normals[k, j], tangents[k], other)
                    signs.add(math.nan if side is None else float(np.sign(side @ across[k])))
                sign = signs.pop() if len(signs) == 1 else math.nan
                if math.isnan(sign):
                    shown = False
                    break
                along[:, j] = sign * across
            if not shown:
                continue
            length = float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1)))
            pieces.append(
                Piece(
                    pair,
                    points,
                    tangents,
                    normals,
                    along,
                    (True, False),
                    normals[n // 2, 1].copy(),
                    0.0,
                    math.inf,
                    length,
                )
            )
    return pieces
