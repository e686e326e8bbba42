"""Seams of a weldment: every place where two bodies of a part meet closely enough to weld.

``find_seams("frame.step")`` reads every solid of a STEP file (assemblies, compounds and
multi-body parts; or the bodies a ``cad/weldment_*.py`` script builds) and reports each
candidate weld between two bodies, sorted by position, as a :class:`FoundSeam`.

Method: rule-based feature recognition on the CAD assembly, after Kuss, Dietz, Ksensow and
Verl, "Manufacturing task description for robotic welding and automatic feature recognition on
product CAD models", Procedia CIRP 60 (2017) 122-127: geometric relations between the bodies'
faces decide where a weld is and what kind. Here:

1. Body pairs closer than ``max_gap_mm`` (``BRepExtrema_DistShapeShape``) are examined.
2. Every pair of planar faces, one of each body, with opposite outward normals and planes at
   most ``max_gap_mm`` apart, is intersected (``BRepAlgoAPI_Common``, after moving A's face onto
   B's plane): the overlap is a contact region (gap 0) or a facing region (gap > 0).
3. Each boundary of a region is a candidate seam. At it, one body ends (its face next to the
   contact face is a "wall": a web's side, a sheet's edge) and the other goes on, or both end
   (plate ends facing each other). The two faces that show there give the torch frame: the
   tangent of the exact edge, and the bisector of their outward normals; the angle of free space
   between them is the opening angle.
4. Rules name the joint. A body "lies on" the contact when its thinnest direction (oriented
   bounding box) is within 30 deg of the contact normal, else it "stands on" it. One body ends:
   a standing one makes a **fillet** (T) joint, a lying one a **lap** joint (the sheet's edge).
   Both end: two standing bodies make a **butt** joint (its groove angle is the opening angle,
   0 for a square butt), two lying ones an **edge** joint, one of each (or an opening over
   185 deg) an **outside_corner**.
5. Not welds: a boundary across the end of a contact strip where both bodies end flush (opening
   180 deg: the side of a butt joint, the flush end of a web), and stretches whose torch side is
   filled by a third body (a gusset sitting on a fillet line splits it in two; the corner where
   a gusset meets both plates is no seam), and across a gap, stretches where a third body
   stands in it (``clearance``: no line of sight between the faces). Pieces shorter than
   ``min_length_mm`` are dropped.
6. Reachability: the torch direction is free of material for ``torch_length_mm`` (rays).

Ids are ``s1``, ``s2``... in order of the seams' start points (x, then y, then z); names are
``body_a/body_b/k`` (bodies in file order, k counting that pair's seams in the same order).
Seams run from their lexicographically smallest end, like every seam (docs/cad.md).

7. Bodies modelled into each other (sharing volume: a tube pushed through a flange's port)
   are also cut against each other (``crossings.crossing_pieces``): where their surfaces cross,
   on any surface type, and exactly one side of each body's face shows, the line is a seam
   (body A taken as the one that ends there), classified and filtered as above.

Bodies that only touch along curved faces (a tube resting in a saddle), along a line or at a
point give no seam.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.errors import WorkpieceError
from seamtrack.geometry.seam import Seam

FloatArray = NDArray[np.float64]

#: Joint types, as reported.
JOINTS = ("fillet", "lap", "butt", "outside_corner", "edge")
#: A body lies on a contact when its thinnest direction is this close to the contact normal.
LYING_RAD = math.radians(30.0)
#: A body is plate-like when its smallest extent is below this fraction of its middle one.
PLATE_RATIO = 0.6
#: Openings this close to 180 deg are flush (nothing to fill).
FLUSH_RAD = math.radians(1.0)
#: Both ends convex beyond 180 deg by more than this: an outside corner.
CONVEX_RAD = math.radians(5.0)
#: How far along the torch direction a point is tested for a third body filling the joint (mm).
COVER_STEP_MM = 0.05
#: Seam points closer than this are one point (mm).
DUPLICATE_MM = 1e-6
#: Rays for the reachability test start this far out along the torch direction (mm).
REACH_START_MM = 0.05
#: At most this many points of a seam are tested for reachability.
REACH_SAMPLES = 25
#: seam_near_mm picks the found seam within this distance of every given point (mm).
SEAM_NEAR_TOL_MM = 1.0


@dataclass(frozen=True, eq=False)
class FoundSeam:
    """A weld found between two bodies.

    Attributes
    ----------
    id : str
        ``s1``, ``s2``... in order of position.
    name : str
        ``body_a/body_b/k``.
    joint : str
        One of :data:`JOINTS`.
    bodies : (str, str)
    points : (n, 3) float
        Seam points on the exact CAD geometry (mm, part frame), in seam direction.
    tangents : (n, 3) float
        Unit tangents.
    normals : (n, 3) float
        Torch directions: the bisector of the two visible faces' outward normals, orthogonal to
        the tangent (away from the material).
    face_normals : (n, 2, 3) float
        Outward unit normals of the two visible faces (body a's, body b's).
    opening_rad : float
        Angle of free space between the two faces (median over the points); for a butt joint
        it is the groove angle (pi for a square butt).
    gap_mm : float
        Distance between the bodies across the joint.
    length_mm : float
    reachable : bool
        Whether the torch direction is free of material for the torch length at every tested
        point.
    reach_fraction : float
        Share of the tested points where it is.
    ends : (bool, bool)
        Whether body a, and body b, end at the seam (else its face goes on beyond it).
    """

    id: str
    name: str
    joint: str
    bodies: tuple[str, str]
    points: FloatArray
    tangents: FloatArray
    normals: FloatArray
    face_normals: FloatArray
    opening_rad: float
    gap_mm: float
    length_mm: float
    reachable: bool
    reach_fraction: float
    ends: tuple[bool, bool] = (True, True)

    @property
    def view_normal(self) -> FloatArray:
        """The direction a sensor looks from at the start, (3,): the torch direction, except
        for a lap joint, seen square to the sheet that goes on beyond the seam."""
        if self.joint == "lap" and self.ends[0] != self.ends[1]:
            return self.face_normals[0, 1 if self.ends[0] else 0].copy()
        return self.normals[0].copy()

    @property
    def groove_angle_rad(self) -> float | None:
        """A butt joint's groove angle (0 for a square butt); None for other joints."""
        if self.joint != "butt":
            return None
        return 0.0 if abs(self.opening_rad - math.pi) < FLUSH_RAD else self.opening_rad

    @property
    def label(self) -> str:
        """``s3 fillet base/web/1``: how tables and errors name it."""
        return f"{self.id} {self.joint} {self.name}"

    def seam(self, name: str = "") -> Seam:
        """The seam as a :class:`~seamtrack.geometry.seam.Seam` with its torch normals."""
        return Seam.from_points(self.points, self.normals, name=name or self.id)

    def record(self) -> dict[str, Any]:
        """A JSON-ready dict (degrees at this edge only, with their suffix)."""
        groove = self.groove_angle_rad
        return {
            "id": self.id,
            "name": self.name,
            "joint": self.joint,
            "bodies": list(self.bodies),
            "length_mm": self.length_mm,
            "opening_deg": math.degrees(self.opening_rad),
            "groove_deg": None if groove is None else math.degrees(groove),
            "gap_mm": self.gap_mm,
            "reachable": self.reachable,
            "reach_fraction": self.reach_fraction,
            "points_mm": self.points.tolist(),
            "normals": self.normals.tolist(),
        }


# ----------------------------------------------------------------------------- rules
def classify(ends: tuple[bool, bool], lying: tuple[bool, bool], opening_rad: float) -> str:
    """The joint type from which bodies end at the seam and which lie on the contact."""
    if ends[0] != ends[1]:
        return "lap" if lying[0 if ends[0] else 1] else "fillet"
    if opening_rad > math.pi + CONVEX_RAD:
        return "outside_corner"
    if lying[0] and lying[1]:
        return "edge"
    if not lying[0] and not lying[1]:
        return "butt"
    return "outside_corner"


def is_lying(thin: FloatArray, half_min: float, half_mid: float, normal: FloatArray) -> bool:
    """Whether a body with thinnest direction ``thin`` lies on a contact with ``normal``."""
    plate = half_min < PLATE_RATIO * half_mid
    return bool(plate and abs(float(thin @ normal)) >= math.cos(LYING_RAD))


def torch_directions(face_normals: FloatArray, tangents: FloatArray) -> FloatArray:
    """Bisector of the two outward normals, orthogonal to the tangent, unit; (n, 3)."""
    b = face_normals.sum(axis=1)
    b -= np.sum(b * tangents, axis=1, keepdims=True) * tangents
    norms = np.linalg.norm(b, axis=1, keepdims=True)
    return b / np.where(norms > 0, norms, 1.0)


def _runs(covered: NDArray[np.bool_]) -> list[tuple[int, int]]:
    """(first, last) index of each run of False."""
    runs, start = [], None
    for i, c in enumerate(covered):
        if not c and start is None:
            start = i
        if c and start is not None:
            runs.append((start, i - 1))
            start = None
    if start is not None:
        runs.append((start, len(covered) - 1))
    return runs


# ----------------------------------------------------------------------------- finding
@dataclass(frozen=True)
class SeamSearch:
    """How weld seams are searched for between bodies (:func:`find_seams`' options, mm).

    Attributes
    ----------
    max_gap_mm : float
        Bodies and faces farther apart than this are not joined.
    torch_length_mm : float
        Length of free space the torch direction needs to count as reachable.
    tolerance_mm : float
        Chord tolerance of the seam polylines.
    spacing_mm : float
        Largest spacing of seam points.
    min_length_mm : float
        Shorter pieces are dropped.
    """

    max_gap_mm: float = 1.0
    torch_length_mm: float = 100.0
    tolerance_mm: float = 0.01
    spacing_mm: float = 1.0
    min_length_mm: float = 1.0

    def check(self) -> None:
        """Each option a finite number > 0, or an error naming it."""
        for name, value in vars(self).items():
            if not (isinstance(value, int | float) and math.isfinite(value) and value > 0):
                raise WorkpieceError(f"{name} must be > 0, got {value!r}", field=name, fix="e.g. 1")


def find_seams(
    source: str | Path,
    *,
    max_gap_mm: float = 1.0,
    torch_length_mm: float = 100.0,
    tolerance_mm: float = 0.01,
    spacing_mm: float = 1.0,
    min_length_mm: float = 1.0,
    field: str = "workpiece.step",
    **params: Any,
) -> list[FoundSeam]:
    """Every candidate weld of a weldment, sorted by position.

    Parameters
    ----------
    source : str or Path
        A STEP file, or a weldment script (``cad/weldment_*.py`` or its built-in name).
    max_gap_mm, torch_length_mm, tolerance_mm, spacing_mm, min_length_mm : float
        The search's options (:class:`SeamSearch`).
    field : str
        The name errors give the source (a scene key or a command-line argument).
    **params
        Parameters of a weldment script's ``build``.

    Returns
    -------
    list of FoundSeam
    """
    search = SeamSearch(max_gap_mm, torch_length_mm, tolerance_mm, spacing_mm, min_length_mm)
    args = (search, field)
    settings = tuple(sorted(params.items()))
    try:
        hash(settings)
    except TypeError:  # parameters that cannot key a cache: search without one
        return list(_find(str(source), *args, settings))
    return list(_find_memo(str(source), _content_key(source, field), *args, settings))


def _content_key(source: str | Path, field: str) -> str:
    """What the found seams depend on besides the settings: the file's bytes (a STEP file, or
    a weldment script and the shared helpers), so that an edited file is searched again."""
    from seamtrack.workpiece.cache import sha256
    from seamtrack.workpiece.sources import helper_hash, resolve

    kind, path = resolve(source, None if field.startswith("workpiece.") else field)
    return sha256(path.read_bytes()) + ("" if kind == "step" else helper_hash())


@functools.lru_cache(maxsize=16)
def _find_memo(source: str, _content: str, *rest: Any) -> tuple[FoundSeam, ...]:
    return _find(source, *rest)


def _find(
    source: str, search: SeamSearch, field: str, params: tuple[tuple[str, Any], ...]
) -> tuple[FoundSeam, ...]:
    bodies = load_bodies(source, field, dict(params))
    return tuple(seams_of_bodies(bodies, search, source=Path(source).name, field=field))


def load_bodies(source: str | Path, field: str, params: dict[str, Any]) -> list[tuple[str, Any]]:
    """The named bodies of a STEP file or a weldment script."""
    from seamtrack.workpiece.sources import read_bodies, resolve, run_script

    kind, path = resolve(source, None if field.startswith("workpiece.") else field)
    if kind == "step":
        if params:
            raise WorkpieceError(
                "a STEP part takes no parameters",
                field=f"workpiece.params.{next(iter(params))}",
                fix="remove the parameters, or load the part's script instead",
            )
        return read_bodies(path, field)
    result = run_script(path, params)
    if result.bodies is None:
        return [(f"body{i + 1}", s) for i, s in enumerate(result.solid.Solids())]
    return result.bodies


def seams_of_bodies(
    bodies: Sequence[tuple[str, Any]],
    search: SeamSearch = SeamSearch(),
    *,
    source: str = "the part",
    field: str = "workpiece.step",
) -> list[FoundSeam]:
    """Every candidate weld between the given (name, solid) bodies; see :func:`find_seams`."""
    from seamtrack.workpiece import clearance, contacts

    search.check()
    max_gap_mm, torch_length_mm, tolerance_mm, spacing_mm, min_length_mm = (
        search.max_gap_mm, search.torch_length_mm, search.tolerance_mm, search.spacing_mm,
        search.min_length_mm,
    )  # fmt: skip
    if len(bodies) < 2:
        raise WorkpieceError(
            f"{source} holds {len(bodies)} solid: seams are found where two bodies meet",
            field=field,
            fix="export the weldment's parts as separate solids (an assembly or a multi-body "
            "part), or pick a seam of one solid with workpiece.seam = <edge selector>",
        )
    solids = [b.wrapped for _, b in bodies]
    names = [n for n, _ in bodies]
    space = contacts.FreeSpace(solids)
    thin = [contacts.thin_axis(s) for s in solids]
    nearest = (math.inf, 0, 1)
    raw: list[tuple[tuple[int, int], dict[str, Any]]] = []
    met = clearance.Findings()
    # Tiny regions are slivers of the booleans, unless the seams wanted are tiny too.
    min_area = contacts.MIN_REGION_AREA_MM2 * min(1.0, min_length_mm) ** 2
    for i in range(len(solids)):
        for j in range(i + 1, len(solids)):
            if not contacts.boxes_meet(space.boxes[i], space.boxes[j], max_gap_mm):
                continue
            d = contacts.distance(solids[i], solids[j])
            nearest = min(nearest, (d, i, j))
            if d > max_gap_mm:
                continue
            pieces = _pair_pieces(
                solids, (i, j), d, space, met, max_gap_mm, min_area, tolerance_mm, spacing_mm
            )
            for piece in pieces:
                for candidate in _candidates(piece, space, thin, min_length_mm, met):
                    raw.append(((i, j), candidate))
    if not raw:
        if nearest[0] > max_gap_mm:
            raise _too_far(solids, names, nearest, max_gap_mm, source, field)
        raise clearance.no_seam_error(
            met, solids, names, source=source, field_name=field, min_length_mm=min_length_mm
        )
    seams = [_finish(pair, c, names, space, torch_length_mm) for pair, c in raw]
    return _number(seams)


def _pair_pieces(
    solids: list[Any],
    pair: tuple[int, int],
    distance_mm: float,
    space: Any,
    met: Any,
    max_gap_mm: float,
    min_area: float,
    tolerance_mm: float,
    spacing_mm: float,
) -> list[Any]:
    """The seam pieces where two bodies face each other (across a free gap, or in contact) or
    where their surfaces cross; a gap filled by a third body is noted in ``met``, not a seam."""
    from seamtrack.workpiece import clearance, contacts, crossings

    i, j = pair
    pieces = []
    for fa, fb, gap, region in contacts.facing_regions(
        solids[i], solids[j], max_gap_mm, min_area, met.short_mm
    ):
        if gap > contacts.ON_TOL_MM:  # facing across a gap: is it free?
            filler = clearance.gap_filled(region, fa.normal, gap, space, pair)
            if filler is not None:
                met.filled.append((i, j, filler))
                continue
        pieces += contacts.region_pieces(
            (solids[i], solids[j]), pair, fa, fb, gap, region, tolerance_mm, spacing_mm
        )
    if distance_mm <= contacts.ON_TOL_MM and crossings.overlap(solids[i], solids[j]):
        met.overlapping.append(pair)
        pieces += crossings.crossing_pieces((solids[i], solids[j]), pair, tolerance_mm, spacing_mm)
    return pieces


def _too_far(
    solids: list[Any],
    names: list[str],
    nearest: tuple[float, int, int],
    max_gap_mm: float,
    source: str,
    field: str,
) -> WorkpieceError:
    """The error when no two bodies come within ``max_gap_mm``, naming the nearest pair."""
    from seamtrack.workpiece import contacts

    if math.isinf(nearest[0]):  # no bounding boxes met: measure every pair
        nearest = min(
            (contacts.distance(solids[i], solids[j]), i, j)
            for i in range(len(solids))
            for j in range(i + 1, len(solids))
        )
    a, b = names[nearest[1]], names[nearest[2]]
    where = "" if math.isinf(nearest[0]) else f" (nearest: {a} and {b}, {nearest[0]:.3g} mm)"
    return WorkpieceError(
        f"{source}: no two of its {len(names)} bodies come within {max_gap_mm:g} mm of "
        f"each other{where}",
        field=field,
        fix="check the bodies' placement and units, or raise max_gap_mm",
    )


def _candidates(
    piece: Any,
    space: Any,
    thin: list[tuple[FloatArray, float, float]],
    min_length_mm: float,
    met: Any,
) -> list[dict[str, Any]]:
    """The welds along one boundary piece: classified, flush ends and covered stretches out
    (a third body on the torch side, or standing in the gap); what was dropped goes to ``met``
    (:class:`~seamtrack.workpiece.clearance.Findings`)."""
    from seamtrack.workpiece.clearance import gap_blocked
    from seamtrack.workpiece.contacts import opening_angles

    opening = opening_angles(piece)
    median = float(np.median(opening))
    if min(median, 2 * math.pi - median) < FLUSH_RAD:
        return []  # a knife edge: no free space between the faces
    if abs(median - math.pi) < FLUSH_RAD and piece.length_mm < piece.region_extent_mm:
        return []  # flush across the end of a contact strip: nothing to weld
    lying = tuple(
        is_lying(thin[b][0], thin[b][1], thin[b][2], piece.contact_normal) for b in piece.bodies
    )
    joint = classify(piece.ends, lying, median)  # type: ignore[arg-type]
    torch = torch_directions(piece.face_normals, piece.tangents)

    def hidden(point: FloatArray, k: int) -> bool:
        if space.inside(point + COVER_STEP_MM * torch[k], skip=piece.bodies) is not None:
            return True
        return piece.inward is not None and gap_blocked(piece, point, piece.inward[k], space)

    covered = np.array([hidden(p, k) for k, p in enumerate(piece.points)])
    if covered.all() and piece.gap_mm > 0:
        met.filled.append((*piece.bodies, None))
    out = []
    for first, last in _runs(covered):
        lo, hi = max(first - 1, 0), min(last + 1, len(covered) - 1)
        points = piece.points[lo : hi + 1].copy()
        # Move an end that lies inside a covering body back to where the cover begins.
        if lo < first:
            points[0] = _edge_of_cover(hidden, piece, first, first - 1)
        if hi > last:
            points[-1] = _edge_of_cover(hidden, piece, last, last + 1)
        index = np.arange(lo, hi + 1)
        # A sample that lies where the cover begins duplicates the refined end: drop it.
        step = np.linalg.norm(np.diff(points, axis=0), axis=1)
        keep = np.ones(len(points), dtype=bool)
        keep[1:-1] &= step[1:] > DUPLICATE_MM  # a near-duplicate before the last point
        keep[1:-1] &= step[:-1] > DUPLICATE_MM  # ... and after the first
        points, index = points[keep], index[keep]
        length = float(np.sum(np.linalg.norm(np.diff(points, axis=0), axis=1)))
        if length < min_length_mm or len(points) < 2:
            met.short_mm.append(length)
            continue
        out.append(
            {
                "joint": joint,
                "points": points,
                "tangents": piece.tangents[index],
                "face_normals": piece.face_normals[index],
                "normals": torch[index],
                "opening": float(np.median(opening[index])),
                "gap": piece.gap_mm,
                "length": length,
                "ends": piece.ends,
            }
        )
    return out


def _edge_of_cover(hidden: Any, piece: Any, free: int, covered: int) -> FloatArray:
    """The point between a free and a covered sample where the cover begins (bisection;
    ``hidden(point, k)`` tests a point with the directions of sample ``k``)."""
    a, b = piece.points[free], piece.points[covered]
    for _ in range(40):
        mid = 0.5 * (a + b)
        if not hidden(mid, free):
            a = mid
        else:
            b = mid
    return 0.5 * (a + b)


def _finish(
    pair: tuple[int, int], c: dict[str, Any], names: list[str], space: Any, torch_length: float
) -> dict[str, Any]:
    points, normals = c["points"], c["normals"]
    # Interior points only: at an end the torch direction may graze the body that ends it.
    inner = (1, len(points) - 2) if len(points) > 2 else (0, len(points) - 1)
    idx = np.unique(np.linspace(*inner, min(REACH_SAMPLES, len(points))).round().astype(int))
    free = [
        not space.blocked(points[k] + REACH_START_MM * normals[k], normals[k], torch_length)
        for k in idx
    ]
    return {
        **c,
        "pair": pair,
        "bodies": (names[pair[0]], names[pair[1]]),
        "reach": float(np.mean(free)),
    }


def _start_key(points: FloatArray) -> tuple[float, ...]:
    """Sort key: start point, then end point, rounded so float noise never decides."""
    ends = np.concatenate([points[0], points[-1]])
    return tuple(float(v) for v in np.round(ends / 1e-3) * 1e-3)


def _number(seams: list[dict[str, Any]]) -> list[FoundSeam]:
    seams = sorted(seams, key=lambda s: _start_key(s["points"]))
    for s in seams:  # results are shared (find_seams caches them): keep them read-only
        for key in ("points", "tangents", "normals", "face_normals"):
            s[key] = np.array(s[key], dtype=np.float64)
            s[key].setflags(write=False)
    per_pair: dict[tuple[int, int], int] = {}
    out = []
    for k, s in enumerate(seams):
        index = per_pair.get(s["pair"], 0)
        per_pair[s["pair"]] = index + 1
        out.append(
            FoundSeam(
                id=f"s{k + 1}",
                name=f"{s['bodies'][0]}/{s['bodies'][1]}/{index}",
                joint=s["joint"],
                bodies=s["bodies"],
                points=s["points"],
                tangents=s["tangents"],
                normals=s["normals"],
                face_normals=s["face_normals"],
                opening_rad=s["opening"],
                gap_mm=s["gap"],
                length_mm=s["length"],
                reachable=bool(s["reach"] == 1.0),
                reach_fraction=s["reach"],
                ends=s["ends"],
            )
        )
    return out


# ----------------------------------------------------------------------------- choosing
def seam_near_points(near_mm: ArrayLike) -> FloatArray:
    """``workpiece.seam_near_mm`` as (m, 3) float points, checked finite."""
    points = np.atleast_2d(np.asarray(near_mm, dtype=np.float64))
    if points.ndim != 2 or points.shape[1] != 3 or not np.isfinite(points).all():
        raise WorkpieceError(
            "seam_near_mm must be finite (m, 3) points",
            field="workpiece.seam_near_mm",
            fix="give x, y, z triples in mm",
        )
    return points


def pick_seam(
    seams: Sequence[FoundSeam],
    seam: str | None,
    near_mm: ArrayLike | None,
    source: str,
) -> FoundSeam:
    """The found seam a scene names (by id or name) or lies near (``seam_near_mm``)."""
    listing = "; ".join(s.label for s in seams)
    if near_mm is not None:
        points = seam_near_points(near_mm)
        far = [float(s.seam().closest(points).distance_mm.max()) for s in seams]
        best = int(np.argmin(far))
        if far[best] > SEAM_NEAR_TOL_MM:
            raise WorkpieceError(
                f"no seam of {source} lies within {SEAM_NEAR_TOL_MM:g} mm of every "
                f"seam_near_mm point (nearest: {seams[best].id}, {far[best]:.3g} mm)",
                field="workpiece.seam_near_mm",
                fix=f"give points on one of the seams ({listing}), or workpiece.seam = an id",
            )
        return seams[best]
    if seam is None:
        raise WorkpieceError(
            f"{source} is a weldment with {len(seams)} seams; which one?",
            field="workpiece.seam",
            fix=f"give workpiece.seam = one of: {listing} (seamtrack seams PART lists them)",
        )
    for s in seams:
        if seam in (s.id, s.name):
            return s
    raise WorkpieceError(
        f"{seam!r} names no seam of {source}",
        field="workpiece.seam",
        fix=f"use an id or name: {listing}",
    )
