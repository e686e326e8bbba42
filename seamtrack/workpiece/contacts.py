"""OCCT kernels of the weldment seam finder: where two bodies meet or face each other.

For every pair of planar faces, one of each body, whose outward normals are opposite and whose
planes are at most ``max_gap_mm`` apart, the face of body A is moved onto the plane of body
B's face and their overlap is computed with ``BRepAlgoAPI_Common``: that overlap is the
contact (gap 0) or facing (gap > 0) region. Welds run along its boundary. At each boundary
edge one body or both end (the edge lies on that body's face boundary); a body that ends shows
its next face there (the "wall": a web's side, a sheet's edge, a bevel), a body that goes on
shows its contact face beyond the region. The two visible faces give the seam's torch frame
(the bisector of their outward normals) and the opening angle of the free space between them.
The points lie on the exact edge curves; over a gap they are moved onto the body that goes on
(or to the middle of the gap when both end).

Everything here returns plain numbers and numpy arrays; :mod:`seamtrack.workpiece.weldment`
turns them into classified, named seams. Imported lazily: it needs OCP (CadQuery's OCCT).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray
from OCP.Bnd import Bnd_Box, Bnd_OBB
from OCP.BRep import BRep_Tool
from OCP.BRepAdaptor import BRepAdaptor_Curve, BRepAdaptor_Surface
from OCP.BRepAlgoAPI import BRepAlgoAPI_Common
from OCP.BRepBndLib import BRepBndLib
from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeVertex, BRepBuilderAPI_Transform
from OCP.BRepClass import BRepClass_FaceClassifier
from OCP.BRepClass3d import BRepClass3d_SolidClassifier
from OCP.BRepExtrema import BRepExtrema_DistShapeShape
from OCP.BRepGProp import BRepGProp, BRepGProp_Face
from OCP.BRepTools import BRepTools
from OCP.GeomAbs import GeomAbs_Plane
from OCP.gp import gp_Dir, gp_Lin, gp_Pnt, gp_Trsf, gp_Vec
from OCP.GProp import GProp_GProps
from OCP.IntCurvesFace import IntCurvesFace_ShapeIntersector
from OCP.ShapeAnalysis import ShapeAnalysis_Surface
from OCP.TopAbs import TopAbs_EDGE, TopAbs_FACE, TopAbs_IN, TopAbs_ON
from OCP.TopExp import TopExp, TopExp_Explorer
from OCP.TopoDS import TopoDS, TopoDS_Edge, TopoDS_Face, TopoDS_Shape
from OCP.TopTools import TopTools_IndexedDataMapOfShapeListOfShape

from seamtrack.constants import LEXICOGRAPHIC_TIE_MM

FloatArray = NDArray[np.float64]

#: Points this close are the same point; an edge this close to a face boundary lies on it (mm).
ON_TOL_MM = 1e-4
#: Face normals this close to opposite (rad) make a facing pair.
ANTIPARALLEL_TOL_RAD = math.radians(0.5)
#: Step from a boundary into a face or region when testing which side is which (mm).
SIDE_STEP_MM = 0.02
#: Tolerance of the inside/outside test of a point against a solid (mm).
CLASSIFY_TOL_MM = 1e-7
#: Contact regions smaller than this are touches, not joints (mm^2).
MIN_REGION_AREA_MM2 = 1e-3


@dataclass(frozen=True)
class PlanarFace:
    """A planar face with its outward unit normal and a point of its plane."""

    face: TopoDS_Face
    normal: FloatArray
    point: FloatArray
    lo: FloatArray
    hi: FloatArray


@dataclass(frozen=True)
class Piece:
    """One candidate seam: a chain of boundary edges of one contact region.

    Attributes
    ----------
    bodies : (int, int)
        Indices of body A and body B.
    points : (n, 3) float
        Seam points on the exact geometry (mm), ordered along the chain.
    tangents : (n, 3) float
        Unit tangents along the chain.
    face_normals : (n, 2, 3) float
        Outward unit normals of the visible face of A and of B at each point.
    along : (n, 2, 3) float
        Unit directions from the seam into each visible face, orthogonal to the tangent.
    ends : (bool, bool)
        Whether A, and B, end at this boundary (else its contact face goes on beyond it).
    contact_normal : (3,) float
        Outward normal of A's contact face (towards B).
    gap_mm : float
        Distance between the two contact planes.
    region_extent_mm : float
        Extent of the contact region across the seam (from the seam into the region).
    length_mm : float
    inward : (n, 3) float or None
        Unit directions from each point into the region, in its plane (None: no region).
    plane_a : (3,) float or None
        A point of A's contact plane (None: no region); with ``contact_normal`` and
        ``gap_mm`` it spans the gap a seam across it must see through.
    """

    bodies: tuple[int, int]
    points: FloatArray
    tangents: FloatArray
    face_normals: FloatArray
    along: FloatArray
    ends: tuple[bool, bool]
    contact_normal: FloatArray
    gap_mm: float
    region_extent_mm: float
    length_mm: float
    inward: FloatArray | None = None
    plane_a: FloatArray | None = None


# ----------------------------------------------------------------------------- helpers
def _vec(v: Any) -> FloatArray:
    return np.array(v.Coord() if hasattr(v, "Coord") else v, dtype=np.float64)


def unit_vector(v: FloatArray) -> FloatArray:
    n = float(np.linalg.norm(v))
    return v / n if n > 0 else v


def bounds(shape: TopoDS_Shape) -> tuple[FloatArray, FloatArray]:
    """Axis-aligned bounds (min, max) of a shape, (3,) each."""
    box = Bnd_Box()
    BRepBndLib.Add_s(shape, box)
    x0, y0, z0, x1, y1, z1 = box.Get()
    return np.array([x0, y0, z0]), np.array([x1, y1, z1])


def boxes_meet(
    a: tuple[FloatArray, FloatArray], b: tuple[FloatArray, FloatArray], gap: float
) -> bool:
    """Whether two axis-aligned boxes (min, max) come within ``gap`` of each other."""
    return bool(np.all(a[0] <= b[1] + gap) and np.all(b[0] <= a[1] + gap))


def _explore(shape: TopoDS_Shape, kind: Any, cast: Any) -> list[Any]:
    """The sub-shapes of ``kind`` (a ``TopAbs`` type) of a shape, in order, each through
    ``cast`` (``TopoDS.Face_s``...)."""
    out = []
    explorer = TopExp_Explorer(shape, kind)
    while explorer.More():
        out.append(cast(explorer.Current()))
        explorer.Next()
    return out


def faces(shape: TopoDS_Shape) -> list[TopoDS_Face]:
    """The faces of a shape, in order."""
    return _explore(shape, TopAbs_FACE, TopoDS.Face_s)


def edges(shape: TopoDS_Shape) -> list[TopoDS_Edge]:
    """The edges of a shape, in order."""
    return _explore(shape, TopAbs_EDGE, TopoDS.Edge_s)


def face_normal(face: TopoDS_Face, point: FloatArray) -> FloatArray:
    """Outward unit normal of a face (orientation applied) at the point nearest ``point``."""
    surface = BRep_Tool.Surface_s(face)
    uv = ShapeAnalysis_Surface(surface).ValueOfUV(gp_Pnt(*point), ON_TOL_MM)
    pnt, vec = gp_Pnt(), gp_Vec()
    BRepGProp_Face(face).Normal(uv.X(), uv.Y(), pnt, vec)
    return unit_vector(_vec(vec))


def planar_faces(shape: TopoDS_Shape) -> list[PlanarFace]:
    """Every planar face of a solid with its outward normal and bounds."""
    out = []
    for face in faces(shape):
        if BRepAdaptor_Surface(face).GetType() != GeomAbs_Plane:
            continue
        u0, u1, v0, v1 = BRepTools.UVBounds_s(face)
        pnt, vec = gp_Pnt(), gp_Vec()
        BRepGProp_Face(face).Normal(0.5 * (u0 + u1), 0.5 * (v0 + v1), pnt, vec)
        lo, hi = bounds(face)
        out.append(PlanarFace(face, unit_vector(_vec(vec)), _vec(pnt), lo, hi))
    return out


def area(shape: TopoDS_Shape) -> float:
    props = GProp_GProps()
    BRepGProp.SurfaceProperties_s(shape, props)
    return float(props.Mass())


def distance(a: TopoDS_Shape, b: TopoDS_Shape) -> float:
    """Smallest distance between two shapes (mm)."""
    extrema = BRepExtrema_DistShapeShape(a, b)
    return float(extrema.Value()) if extrema.IsDone() else math.inf


def _translated(shape: TopoDS_Shape, offset: FloatArray) -> TopoDS_Shape:
    trsf = gp_Trsf()
    trsf.SetTranslation(gp_Vec(*offset))
    return BRepBuilderAPI_Transform(shape, trsf, True).Shape()


def _point_to_shape(point: FloatArray, shape: TopoDS_Shape) -> float:
    vertex = BRepBuilderAPI_MakeVertex(gp_Pnt(*point)).Vertex()
    return distance(vertex, shape)


def thin_axis(solid: TopoDS_Shape) -> tuple[FloatArray, float, float]:
    """Direction of a body's smallest extent (its plate normal), and its smallest and middle
    half-sizes, from the oriented bounding box (mm)."""
    obb = Bnd_OBB()
    BRepBndLib.AddOBB_s(solid, obb, False, True, False)
    axes = [
        (obb.XHSize(), _vec(obb.XDirection())),
        (obb.YHSize(), _vec(obb.YDirection())),
        (obb.ZHSize(), _vec(obb.ZDirection())),
    ]
    axes.sort(key=lambda a: a[0])
    return axes[0][1], float(axes[0][0]), float(axes[1][0])


# ----------------------------------------------------------------------------- regions
def facing_regions(
    solid_a: TopoDS_Shape,
    solid_b: TopoDS_Shape,
    max_gap_mm: float,
    min_area_mm2: float = MIN_REGION_AREA_MM2,
    small: list[float] | None = None,
) -> list[tuple[PlanarFace, PlanarFace, float, TopoDS_Face]]:
    """(face of A, face of B, gap, region) for every pair of planar faces that face each other
    within ``max_gap_mm``; the region lies in B's face plane. Regions under ``min_area_mm2``
    are touches, not joints: the square root of each such area goes to ``small``."""
    box_b = bounds(solid_b)
    faces_a = [f for f in planar_faces(solid_a) if boxes_meet((f.lo, f.hi), box_b, max_gap_mm)]
    box_a = bounds(solid_a)
    faces_b = [f for f in planar_faces(solid_b) if boxes_meet((f.lo, f.hi), box_a, max_gap_mm)]
    limit = -math.cos(ANTIPARALLEL_TOL_RAD)
    out = []
    for fa in faces_a:
        for fb in faces_b:
            if float(fa.normal @ fb.normal) > limit:
                continue
            gap = float((fb.point - fa.point) @ fa.normal)
            if not -ON_TOL_MM <= gap <= max_gap_mm + ON_TOL_MM:
                continue
            if not boxes_meet((fa.lo, fa.hi), (fb.lo, fb.hi), max_gap_mm + ON_TOL_MM):
                continue
            gap = max(gap, 0.0)
            moved = _translated(fa.face, gap * fa.normal) if gap > 0 else fa.face
            common = BRepAlgoAPI_Common(moved, fb.face)
            if not common.IsDone():
                continue
            for region in faces(common.Shape()):
                size = area(region)
                if size >= min_area_mm2:
                    out.append((fa, fb, gap, region))
                elif small is not None and size > 0:
                    small.append(math.sqrt(size))
    return out


def _edge_under(face: TopoDS_Face, points: FloatArray) -> TopoDS_Edge | None:
    """The edge of ``face`` on which all ``points`` lie, or None."""
    for edge in edges(face):
        lo, hi = bounds(edge)
        if np.any(points < lo - ON_TOL_MM) or np.any(points > hi + ON_TOL_MM):
            continue  # off the edge's box: off the edge
        if all(_point_to_shape(p, edge) <= ON_TOL_MM for p in points):
            return edge
    return None


def _other_face(
    ancestors: TopTools_IndexedDataMapOfShapeListOfShape, edge: TopoDS_Edge, face: TopoDS_Face
) -> TopoDS_Face | None:
    if not ancestors.Contains(edge):
        return None
    for f in ancestors.FindFromKey(edge):
        if not f.IsSame(face):
            return TopoDS.Face_s(f)
    return None


def _ancestors(solid: TopoDS_Shape) -> TopTools_IndexedDataMapOfShapeListOfShape:
    ancestors = TopTools_IndexedDataMapOfShapeListOfShape()
    TopExp.MapShapesAndAncestors_s(solid, TopAbs_EDGE, TopAbs_FACE, ancestors)
    return ancestors


def inside_face(face: TopoDS_Face, point: FloatArray) -> bool:
    state = BRepClass_FaceClassifier(face, gp_Pnt(*point), ON_TOL_MM).State()
    return state in (TopAbs_IN, TopAbs_ON)


def _side(
    face: TopoDS_Face,
    point: FloatArray,
    normal: FloatArray,
    tangent: FloatArray,
    step_mm: float = SIDE_STEP_MM,
) -> float:
    """+1 if the face lies on the ``normal x tangent`` side of the point, else -1."""
    direction = unit_vector(np.cross(normal, tangent))
    inside = inside_face(face, point + step_mm * direction)
    return 1.0 if inside else -1.0


# ----------------------------------------------------------------------------- sampling
def _edge_ends(edge: TopoDS_Edge) -> tuple[FloatArray, FloatArray]:
    curve = BRepAdaptor_Curve(edge)
    return _vec(curve.Value(curve.FirstParameter())), _vec(curve.Value(curve.LastParameter()))


def sample_edge(
    edge: TopoDS_Edge, forward: bool, tolerance_mm: float, spacing_mm: float
) -> tuple[FloatArray, FloatArray]:
    """Points (n, 3) on the exact edge curve, at most ``spacing_mm`` apart and closer where the
    chord error would exceed ``tolerance_mm``, with unit tangents (n, 3), in chain order."""
    from seamtrack.cad.kit.cadocc import edge_samples

    curve = BRepAdaptor_Curve(edge)
    ts, _ = edge_samples(curve, tolerance_mm, spacing_mm)
    pts, tangents = [], []
    pnt, vec = gp_Pnt(), gp_Vec()
    for t in ts:
        curve.D1(t, pnt, vec)
        pts.append(_vec(pnt))
        tangents.append(unit_vector(_vec(vec)))
    points, tan = np.array(pts), np.array(tangents)
    return (points, tan) if forward else (points[::-1], -tan[::-1])


def lexicographic_first(points: FloatArray, tol_mm: float = LEXICOGRAPHIC_TIE_MM) -> int:
    """Index of the lexicographically smallest point (x, then y, then z), where coordinates
    within ``tol_mm`` of each other count as equal (so float noise never decides)."""
    candidates = np.arange(len(points))
    for axis in range(3):
        values = points[candidates, axis]
        candidates = candidates[values <= values.min() + tol_mm]
    return int(candidates[0])


def chain_edges(edge_list: Sequence[TopoDS_Edge]) -> list[list[tuple[TopoDS_Edge, bool]]]:
    """Group edges into connected chains of (edge, forward); each open chain starts at its
    lexicographically smallest free end, a closed one at its smallest vertex."""
    ends = [_edge_ends(e) for e in edge_list]
    remaining = set(range(len(edge_list)))
    chains = []
    while remaining:
        # Grow one component from any edge, then order it from its smallest free end.
        component = {remaining.pop()}
        grew = True
        while grew:
            grew = False
            for i in list(remaining):
                if any(
                    min(np.linalg.norm(p - q) for p in ends[i] for q in ends[j]) <= ON_TOL_MM
                    for j in component
                ):
                    component.add(i)
                    remaining.discard(i)
                    grew = True
        flat = [(p, i) for i in component for p in ends[i]]
        degree = [sum(np.linalg.norm(p - q) <= ON_TOL_MM for q, _ in flat) for p, _ in flat]
        free = [f for f, d in zip(flat, degree, strict=True) if d == 1] or flat
        start = free[lexicographic_first(np.array([p for p, _ in free]))][0]
        todo, point, chain = set(component), start, []
        while todo:
            gap, i = min(
                (min(np.linalg.norm(ends[k][0] - point), np.linalg.norm(ends[k][1] - point)), k)
                for k in todo
            )
            if gap > ON_TOL_MM:
                break  # a branching component: the rest starts a chain of its own
            todo.discard(i)
            forward = bool(np.linalg.norm(ends[i][0] - point) <= np.linalg.norm(ends[i][1] - point))
            chain.append((edge_list[i], forward))
            point = ends[i][1] if forward else ends[i][0]
        remaining |= todo
        chains.append(chain)
    return chains


# ----------------------------------------------------------------------------- seams
def _opening(along: FloatArray, normals: FloatArray) -> FloatArray:
    """Opening angle (rad) of the free space between two faces, per point.

    ``along`` (n, 2, 3): directions from the seam into each face; ``normals`` (n, 2, 3): their
    outward normals. The angle between the two directions is the opening when the free space
    lies between them (an inside corner, a groove), and 2 pi minus it when the corner is convex.
    """
    u1, u2 = along[:, 0], along[:, 1]
    theta = np.arctan2(np.linalg.norm(np.cross(u1, u2), axis=1), np.sum(u1 * u2, axis=1))
    concave = np.sum((u1 + u2) * (normals[:, 0] + normals[:, 1]), axis=1) >= 0
    return np.where(concave, theta, 2 * np.pi - theta)


def region_pieces(
    solids: tuple[TopoDS_Shape, TopoDS_Shape],
    pair: tuple[int, int],
    fa: PlanarFace,
    fb: PlanarFace,
    gap: float,
    region: TopoDS_Face,
    tolerance_mm: float,
    spacing_mm: float,
) -> list[Piece]:
    """The candidate seams along the boundary of one contact region."""
    ancestors = (_ancestors(solids[0]), _ancestors(solids[1]))
    n_a = fa.normal
    back = -gap * n_a  # from the region (in B's plane) back to A's plane
    groups: list[tuple[tuple[Any, Any], list[TopoDS_Edge]]] = []
    for edge in edges(region):
        curve = BRepAdaptor_Curve(edge)
        u0, u1 = curve.FirstParameter(), curve.LastParameter()
        probes = np.array([_vec(curve.Value(u0 + f * (u1 - u0))) for f in (0.25, 0.5, 0.75)])
        under_a = _edge_under(fa.face, probes + back)
        under_b = _edge_under(fb.face, probes)
        wall_a = _other_face(ancestors[0], under_a, fa.face) if under_a is not None else None
        wall_b = _other_face(ancestors[1], under_b, fb.face) if under_b is not None else None
        if wall_a is None and wall_b is None:
            continue
        for key, members in groups:
            if _same(key[0], wall_a) and _same(key[1], wall_b):
                members.append(edge)
                break
        else:
            groups.append(((wall_a, wall_b), [edge]))
    region_pts = np.vstack([_edge_ends(e)[0] for e in edges(region)])
    pieces = []
    for (wall_a, wall_b), members in groups:
        for chain in chain_edges(members):
            piece = _piece(
                chain, (wall_a, wall_b), fa, fb, gap, region, region_pts, tolerance_mm, spacing_mm
            )
            if piece is not None:
                pieces.append(Piece(pair, *piece))
    return pieces


def _same(a: TopoDS_Face | None, b: TopoDS_Face | None) -> bool:
    return (a is None and b is None) or (a is not None and b is not None and a.IsSame(b))


def _piece(
    chain: list[tuple[TopoDS_Edge, bool]],
    walls: tuple[TopoDS_Face | None, TopoDS_Face | None],
    fa: PlanarFace,
    fb: PlanarFace,
    gap: float,
    region: TopoDS_Face,
    region_pts: FloatArray,
    tolerance_mm: float,
    spacing_mm: float,
) -> tuple[Any, ...] | None:
    parts = [sample_edge(e, fwd, tolerance_mm, spacing_mm) for e, fwd in chain]
    points = np.vstack([p[i > 0 :] for i, (p, _) in enumerate(parts)])
    tangents = np.vstack([t[i > 0 :] for i, (_, t) in enumerate(parts)])
    if len(points) < 2:
        return None
    n_a = fa.normal
    ends = (walls[0] is not None, walls[1] is not None)
    mid = len(points) // 2
    p_mid, t_mid = points[mid], tangents[mid]
    # Step less than the region's width into it (parts far under a millimetre).
    lo, hi = bounds(region)
    step = min(SIDE_STEP_MM, 0.1 * float(np.sort(hi - lo)[1]))
    s_in = _side(region, p_mid, n_a, t_mid, step) * unit_vector(np.cross(n_a, t_mid))
    n = len(points)
    normals = np.empty((n, 2, 3))
    along = np.empty((n, 2, 3))
    offsets = (-gap * n_a, np.zeros(3))  # each body's own copy of the region boundary
    for k, (wall, contact) in enumerate(((walls[0], fa), (walls[1], fb))):
        if wall is None:  # this body goes on beyond the region: its contact face shows
            normals[:, k] = contact.normal
            along[:, k] = -s_in_all(tangents, contact.normal, s_in, t_mid)
            continue
        at = points + offsets[k]
        normals[:, k] = [face_normal(wall, p) for p in at]
        sign = _side(wall, at[mid], normals[mid, k], t_mid, step)
        along[:, k] = sign * unit_vector_rows(np.cross(normals[:, k], tangents))
    if ends == (True, False):
        seam = points  # on B's face, under A's wall
    elif ends == (False, True):
        seam = points + offsets[0]  # on A's face, under B's wall
    else:
        seam = points - 0.5 * gap * n_a  # both end: the middle of the gap
    length = float(np.sum(np.linalg.norm(np.diff(seam, axis=0), axis=1)))
    extent = float(np.max((region_pts - p_mid) @ s_in))
    inward = s_in_all(tangents, n_a, s_in, t_mid)
    return seam, tangents, normals, along, ends, n_a, float(gap), extent, length, inward, fa.point


def s_in_all(tangents: FloatArray, normal: FloatArray, s_mid: FloatArray, t_mid: FloatArray):
    """The in-region direction at every point, with the sign found at the middle point."""
    sign = 1.0 if float(np.cross(normal, t_mid) @ s_mid) > 0 else -1.0
    return sign * unit_vector_rows(np.cross(normal, tangents))


def unit_vector_rows(v: FloatArray) -> FloatArray:
    norms = np.linalg.norm(v, axis=1, keepdims=True)
    return v / np.where(norms > 0, norms, 1.0)


def opening_angles(piece: Piece) -> FloatArray:
    """Opening angle (rad) of the free space at every point of a piece, (n,)."""
    return _opening(piece.along, piece.face_normals)


# ----------------------------------------------------------------------------- free space
class FreeSpace:
    """Ray and point queries against all bodies: is a torch direction free, is a point
    inside material."""

    def __init__(self, solids: Sequence[TopoDS_Shape]):
        self.solids = list(solids)
        self.boxes = [bounds(s) for s in self.solids]
        self._lo = np.array([lo for lo, _ in self.boxes]).reshape(-1, 3) - ON_TOL_MM
        self._hi = np.array([hi for _, hi in self.boxes]).reshape(-1, 3) + ON_TOL_MM
        self._rays = []
        for solid in self.solids:
            intersector = IntCurvesFace_ShapeIntersector()
            intersector.Load(solid, ON_TOL_MM)
            self._rays.append(intersector)

    def near(self, lo: FloatArray, hi: FloatArray, skip: Sequence[int] = ()) -> list[int]:
        """Indices of the bodies whose boxes meet the box (lo, hi), but those in ``skip``."""
        meet = np.all(self._lo <= hi, axis=1) & np.all(self._hi >= lo, axis=1)
        return [int(i) for i in np.flatnonzero(meet) if int(i) not in skip]

    def inside(self, point: FloatArray, skip: Sequence[int] = ()) -> int | None:
        """Index of the body that holds ``point`` in its interior, or None."""
        for i in self.near(point, point, skip):
            classifier = BRepClass3d_SolidClassifier(
                self.solids[i], gp_Pnt(*point), CLASSIFY_TOL_MM
            )
            if classifier.State() == TopAbs_IN:
                return i
        return None

    def blocked(
        self,
        start: FloatArray,
        direction: FloatArray,
        length_mm: float,
        skip: Sequence[int] = (),
        first_mm: float = 0.0,
    ) -> bool:
        """Whether the segment from ``start`` along ``direction``, between ``first_mm`` and
        ``length_mm``, crosses the surface of a body (but those in ``skip``)."""
        end = start + length_mm * np.asarray(direction)
        line = gp_Lin(gp_Pnt(*start), gp_Dir(*direction))
        for i in self.near(np.minimum(start, end), np.maximum(start, end), skip):
            intersector = self._rays[i]
            intersector.Perform(line, first_mm, length_mm)
            if intersector.IsDone() and intersector.NbPnt() > 0:
                return True
        return False

    def sight_blocked(
        self, start: FloatArray, direction: FloatArray, length_mm: float, skip: Sequence[int]
    ) -> bool:
        """Whether a body (but those in ``skip``) stands in the open segment from ``start``
        along ``direction`` for ``length_mm``: its surface crosses the segment, or (crossing
        nothing) the segment's middle lies inside it. Exact for any solids."""
        margin = min(ON_TOL_MM, 0.25 * length_mm)
        if self.blocked(start, direction, length_mm - margin, skip, first_mm=margin):
            return True
        return self.inside(start + 0.5 * length_mm * np.asarray(direction), skip) is not None
