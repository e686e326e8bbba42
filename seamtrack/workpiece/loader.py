"""Workpieces from CAD: run a ``cad/`` joint script or read a STEP part, mesh it, find its seam.

``load_workpiece`` meshes the BRep with an absolute chordal tolerance (OCCT
``BRepMesh_IncrementalMesh`` after ``BRepTools.Clean``), measures the deviation it actually got
against the exact surfaces, and samples the seam edge(s) into a
:class:`seamtrack.geometry.seam.Seam`
in the part frame. The seam normals are torch directions: the bisector of the OUTWARD normals
of the two faces that meet at the seam, so the torch points away from the material (into the
groove, out of the fillet corner).

Results are cached on disk (``$SEAMTRACK_CACHE_DIR`` or ``~/.cache/seamtrack``), keyed by the
script or STEP content, the shared ``cad/kit/cadpaths.py`` helper, the parameters, tolerances, seam
choice and the seamtrack version. A cache hit imports neither CadQuery nor OCP; a corrupt entry
is rebuilt. Clear it with :func:`clear_cache` (or delete the folder :func:`cache_dir` names).

CadQuery and OCP are imported only inside the functions that need them.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack import constants
from seamtrack._version import __version__
from seamtrack.errors import WorkpieceError
from seamtrack.geometry.seam import Seam
from seamtrack.workpiece.cache import (
    cache_dir,
    cache_key,
    clear_cache,
    read_cache,
    sha256,
    source_hash,
    write_cache,
)
from seamtrack.workpiece.sources import (
    builtin_joints,
    builtin_weldments,
    helper_hash,
    read_bodies,
    read_step,
    resolve,
    run_script,
)
from seamtrack.workpiece.weldment import seam_near_points

if TYPE_CHECKING:
    import trimesh

__all__ = [
    "DEFAULT_ANGULAR_TOLERANCE_RAD",
    "Workpiece",
    "builtin_joints",
    "builtin_weldments",
    "cache_dir",
    "clear_cache",
    "load_workpiece",
    "mesh_tradeoff",
]

FloatArray = NDArray[np.float64]

#: Default angular deflection of the mesher (rad); the chordal tolerance usually governs.
DEFAULT_ANGULAR_TOLERANCE_RAD = 0.5
#: The modules whose code decides a weldment's or a groove's seam (part of the cache key).
FINDER_MODULES = ("contacts.py", "weldment.py", "grooves.py")


@dataclass(frozen=True, eq=False)
class Workpiece:
    """A meshed CAD part with its seam.

    Attributes
    ----------
    mesh : trimesh.Trimesh
        Triangle mesh in the part frame (mm, float64). One solid: welded and watertight. Several
        solids (a weldment, plates with a gap): one welded, watertight shell per solid, the shells
        concatenated; where bodies touch, their contact faces lie on each other inside the part
        (the laser never sees them).
    seam : Seam
        Seam points (n, 3) sampled along the seam edge(s); normals are torch directions (the
        bisector of the two adjacent faces' outward normals: away from the material).
    seam_face_normals : (n, 2, 3) float
        Outward unit normals of the two faces that meet at each seam point.
    deviation_mm : float
        Largest distance from the mesh to the exact surfaces, measured (triangle centroids and
        edge midpoints projected onto their BRep faces).
    triangle_count : int
    meshing_time_s : float
        Time spent in the mesher (all passes).
    source : str
        The script or STEP path that was loaded (or the groove's type).
    params : dict
        Parameters given to the script's ``build``.
    tolerance_mm : float
        The requested chordal tolerance.
    from_cache : bool
    joint : str
        The joint type when it is known (a weldment's found seam, a weldx groove: ``"fillet"``,
        ``"lap"``, ``"butt"``, ``"outside_corner"``, ``"edge"``), else ``""``.
    opening_rad : float
        Angle of free space between the two faces at the seam (median; nan when unknown).
    view_normal : (3,) float or None
        The direction a sensor should look from at the seam's start (part frame) when it is not
        the torch direction (a lap joint: square to its sheets); None: the torch direction.
    """

    mesh: trimesh.Trimesh
    seam: Seam
    seam_face_normals: FloatArray
    deviation_mm: float
    triangle_count: int
    meshing_time_s: float
    source: str
    params: dict[str, Any]
    tolerance_mm: float
    from_cache: bool = False
    joint: str = ""
    opening_rad: float = math.nan
    view_normal: FloatArray | None = None
    _shape: Any = field(default=None, repr=False)
    _rebuild: Callable[[], Any] | None = field(default=None, repr=False)

    @property
    def shape(self) -> Any:
        """The CadQuery shape (after a cache hit: rebuilt from the source on first use)."""
        if self._shape is None and self._rebuild is not None:
            object.__setattr__(self, "_shape", self._rebuild())
        return self._shape


@dataclass(frozen=True)
class _Built:
    """A part before meshing: the shape, its seam samples and what is known of the joint."""

    shape: Any
    points: FloatArray
    face_normals: FloatArray
    torch: FloatArray
    name: str
    joint: str = ""
    opening_rad: float = math.nan
    view: FloatArray | None = None


def _check_mesh_budget(diagonal_mm: float, tolerance_mm: float) -> None:
    """Refuse a tolerance so fine for the part's size that its mesh would not fit in memory
    (the paper's 420 mm part at 1e-3 mm, a ratio of 2.4e-6, is 1.7 million triangles)."""
    finest = constants.MIN_MESH_TOLERANCE_RATIO * diagonal_mm
    if tolerance_mm < finest:
        raise WorkpieceError(
            f"meshing tolerance {tolerance_mm:.3g} mm on a part {diagonal_mm:.0f} mm across "
            f"is finer than {constants.MIN_MESH_TOLERANCE_RATIO:.0e} of its size: the mesh "
            "would not fit in memory",
            field="workpiece.tolerance_mm",
            fix=f"use at least {finest:.2g} mm for this part",
        )


def _seam_edges(
    occ: Any, shape: Any, named: dict[str, list[Any]], seam: str | None, near: ArrayLike | None
) -> list[Any]:
    """The seam edges: near given points, by name, or by selector (unordered)."""
    if near is not None:
        return list(occ.edges_near(shape, seam_near_points(near)))
    if seam is None:
        if not named:
            raise WorkpieceError(
                "no seam given",
                field="workpiece.seam",
                fix="give seam=<CadQuery edge selector> or seam_near_mm=<points near the seam>",
            )
        return list(next(iter(named.values())))
    if seam in named:
        return list(named[seam])
    return list(occ.select_edges(shape, seam, list(named)))


def _check_numbers(tolerance_mm: float, angular_tolerance_rad: float, spacing_mm: float) -> None:
    if not (
        isinstance(tolerance_mm, int | float) and math.isfinite(tolerance_mm) and tolerance_mm > 0
    ):
        raise WorkpieceError(
            f"tolerance must be a number > 0, got {tolerance_mm!r}",
            field="workpiece.tolerance_mm",
            fix="give e.g. 0.01 (mm)",
        )
    if not angular_tolerance_rad > 0:
        raise WorkpieceError(
            f"angular tolerance must be > 0, got {angular_tolerance_rad}",
            field="workpiece.angular_tolerance_rad",
            fix="give e.g. 0.5 (rad)",
        )
    if not spacing_mm > 0:
        raise WorkpieceError(
            f"seam spacing must be > 0, got {spacing_mm}",
            field="workpiece.seam_spacing_mm",
            fix="give e.g. 1.0 (mm)",
        )


def _build(
    kind: str,
    path: Path | None,
    params: dict[str, Any],
    groove: dict[str, Any] | None,
    seam: str | None,
    seam_near_mm: ArrayLike | None,
    tolerance_mm: float,
    spacing_mm: float,
) -> _Built:
    """Build or read the part and sample its seam (exact CAD geometry)."""
    if kind == "groove":
        from seamtrack.workpiece.grooves import build_groove

        assert groove is not None
        return _Built(**build_groove(groove, tolerance_mm, spacing_mm, **params))
    assert path is not None
    if kind == "script":
        result = run_script(path, params)
        bodies = result.bodies
        solid, seam_solid, named = result.solid, result.seam_solid, result.seams
    else:
        bodies = read_bodies(path)
        solid = seam_solid = read_step(path) if len(bodies) == 1 else None
        named = {}
    if bodies is not None and len(bodies) > 1:  # a weldment: its seams are found, not picked
        from seamtrack.workpiece.weldment import SeamSearch, pick_seam, seams_of_bodies

        search = SeamSearch(tolerance_mm=tolerance_mm, spacing_mm=spacing_mm)
        found = seams_of_bodies(bodies, search, source=path.name)
        chosen = pick_seam(found, seam, seam_near_mm, path.name)
        import cadquery as cq

        return _Built(
            cq.Compound.makeCompound([b for _, b in bodies]),
            chosen.points,
            chosen.face_normals,
            chosen.normals,
            f"{path.stem}:{chosen.id}",
            chosen.joint,
            chosen.opening_rad,
            chosen.view_normal,
        )
    from seamtrack.cad.kit import cadocc

    chained = cadocc.chain(_seam_edges(cadocc, seam_solid, named, seam, seam_near_mm), "the seam")
    points, face_normals = cadocc.sample_seam(seam_solid, chained, tolerance_mm, spacing_mm)
    torch = face_normals.sum(axis=1)  # bisector of the outward normals: away from the material
    label = seam or (next(iter(named)) if named and seam_near_mm is None else "seam")
    return _Built(solid, points, face_normals, torch, f"{path.stem}:{label}")


def _mesh(shape: Any, tolerance_mm: float, angular_rad: float) -> tuple[Any, float, float]:
    """The mesh (one welded, watertight shell per solid), its measured deviation and time."""
    import trimesh

    from seamtrack.cad.kit import cadmesh

    vertices, faces, deviation, spent, counts = cadmesh.mesh(shape, tolerance_mm, angular_rad)
    solids = shape.Solids()
    if len(solids) == 1:
        return trimesh.Trimesh(vertices, faces, process=True), deviation, spent
    # Faces come solid by solid: weld each solid's nodes on their own, so that shells that
    # touch stay separate closed surfaces.
    per_solid = [len(s.Faces()) for s in solids]
    shells, first = [], 0
    bounds = np.concatenate([[0], np.cumsum(counts)])
    for n in per_solid:
        chosen = faces[bounds[first] : bounds[first + n]]
        shell = trimesh.Trimesh(vertices, chosen, process=True)
        shell.remove_unreferenced_vertices()
        shells.append(shell)
        first += n
    return trimesh.util.concatenate(shells), deviation, spent


# ----------------------------------------------------------------------------- loading
def load_workpiece(
    source: str | Path | None = None,
    *,
    tolerance_mm: float = 0.01,
    angular_tolerance_rad: float = DEFAULT_ANGULAR_TOLERANCE_RAD,
    seam: str | None = None,
    seam_near_mm: ArrayLike | None = None,
    groove: dict[str, Any] | None = None,
    seam_spacing_mm: float = 1.0,
    cache: bool = True,
    cache_dir: str | Path | None = None,
    **params: Any,
) -> Workpiece:
    """Build or read a CAD part, mesh it with an absolute tolerance and extract its seam.

    Parameters
    ----------
    source : str or Path, optional
        A joint or weldment script (``"cad/v_groove.py"``), a built-in name (``"v_groove"``,
        ``"weldment_bracket"``) or a STEP file (``.step`` / ``.stp``); None with ``groove``.
    tolerance_mm : float
        Chordal tolerance of the mesh and of the seam polyline (mm, absolute).
    angular_tolerance_rad : float
        Angular deflection of the mesher.
    seam : str, optional
        A joint script: a seam name it returns (default: its first, ``"root"``) or a CadQuery
        edge selector (``"|X and <Z"``). A weldment (a weldment script, a STEP file of several
        solids): the id or name of a found seam (``"s3"``, ``"base/web/0"``; see
        :func:`seamtrack.workpiece.weldment.find_seams`). A one-solid STEP file: a selector.
    seam_near_mm : (m, 3) float, optional
        Points near the seam: the edges nearest to them form the seam; on a weldment, the found
        seam within 1 mm of every point.
    groove : dict, optional
        An ISO 9692-1 groove as weldx defines it (``{"type": "VGroove", "t_mm": 10,
        "alpha_deg": 60, "b_mm": 1, "c_mm": 1}``): its two plates are swept along the path
        the ``params`` give (``path``, ``seam_length_mm``, ``plate_width_mm`` ...); needs weldx.
    seam_spacing_mm : float
        Largest spacing of the seam points (finer where the chord tolerance needs it).
    cache : bool
        Read and write the on-disk cache.
    cache_dir : str or Path, optional
        Cache folder; default :func:`cache_dir`.
    **params
        Parameters of the script's ``build`` (``root_gap_mm=1.5, path="arc"``...).

    Returns
    -------
    Workpiece
    """
    _check_numbers(tolerance_mm, angular_tolerance_rad, seam_spacing_mm)
    import trimesh  # here, not at import: seam-mode scenes never load it

    path: Path | None
    if groove is not None:
        from seamtrack.workpiece.grooves import groove_spec

        if source is not None:
            raise WorkpieceError(
                "a groove builds its own part: give either a script/STEP or a groove",
                field="workpiece.groove",
                fix="remove workpiece.script / workpiece.step, or the groove",
            )
        groove = groove_spec(groove)
        kind, path, content = "groove", None, json.dumps(groove, sort_keys=True).encode()
    else:
        if source is None:
            raise WorkpieceError(
                "no part given",
                field="workpiece.script",
                fix="give a script, a STEP file or a groove",
            )
        kind, path = resolve(source)
        content = path.read_bytes()
    if kind == "step" and params:
        name = next(iter(params))
        raise WorkpieceError(
            "a STEP part takes no parameters",
            field=f"workpiece.params.{name}",
            fix="remove the parameters, or load the part's script instead",
        )
    near = None if seam_near_mm is None else np.asarray(seam_near_mm, dtype=np.float64).tolist()
    key = cache_key(
        {
            "kind": kind,
            "content": sha256(content),
            "helpers": helper_hash(),
            "finder": source_hash(*FINDER_MODULES),
            "params": params,
            "tolerance_mm": float(tolerance_mm),
            "angular_rad": float(angular_tolerance_rad),
            "seam": seam,
            "near": near,
            "spacing": float(seam_spacing_mm),
            "version": __version__,
        }
    )
    root = (Path(cache_dir) if cache_dir is not None else globals()["cache_dir"]()) / "workpieces"
    entry = root / key
    label = str(path) if path is not None else f"groove {groove['type'] if groove else ''}"

    def rebuild() -> Any:
        return _build(
            kind, path, params, groove, seam, seam_near_mm, tolerance_mm, seam_spacing_mm
        ).shape

    if cache:
        hit = read_cache(entry, key)
        if hit is not None:
            meta = hit["meta"]
            return Workpiece(
                mesh=trimesh.Trimesh(hit["vertices"], hit["faces"], process=False),
                seam=Seam.from_points(
                    hit["points"], hit["normals"], name=meta["name"], field="workpiece.seam"
                ),
                seam_face_normals=hit["face_normals"],
                deviation_mm=meta["deviation_mm"],
                triangle_count=len(hit["faces"]),
                meshing_time_s=meta["meshing_time_s"],
                source=label,
                params=dict(params),
                tolerance_mm=float(tolerance_mm),
                from_cache=True,
                joint=meta.get("joint", ""),
                opening_rad=float(meta.get("opening_rad") or math.nan),
                view_normal=None if meta.get("view") is None else np.array(meta["view"]),
                _rebuild=rebuild,
            )
    built = _build(
        kind, path, params, groove, seam, seam_near_mm, float(tolerance_mm), seam_spacing_mm
    )
    _check_mesh_budget(float(built.shape.BoundingBox().DiagonalLength), tolerance_mm)
    mesh, deviation, spent = _mesh(built.shape, float(tolerance_mm), float(angular_tolerance_rad))
    seam_obj = Seam.from_points(built.points, built.torch, name=built.name, field="workpiece.seam")
    if cache:
        meta = {
            "name": built.name,
            "deviation_mm": deviation,
            "meshing_time_s": spent,
            "triangle_count": len(mesh.faces),
            "source": label,
            "params": params,
            "tolerance_mm": tolerance_mm,
            "joint": built.joint,
            "opening_rad": None if math.isnan(built.opening_rad) else built.opening_rad,
            "view": None if built.view is None else [float(v) for v in built.view],
            "seamtrack": __version__,
        }
        arrays = {
            "vertices": np.asarray(mesh.vertices),
            "faces": np.asarray(mesh.faces),
            "points": seam_obj.points,
            "normals": built.torch,  # the input of Seam.from_points: a hit rebuilds the same seam
            "face_normals": built.face_normals,
        }
        try:
            write_cache(entry, key, arrays, meta)
        except OSError:
            pass  # a read-only cache costs speed, not correctness
    return Workpiece(
        mesh=mesh,
        seam=seam_obj,
        seam_face_normals=built.face_normals,
        deviation_mm=deviation,
        triangle_count=len(mesh.faces),
        meshing_time_s=spent,
        source=label,
        params=dict(params),
        tolerance_mm=float(tolerance_mm),
        joint=built.joint,
        opening_rad=built.opening_rad,
        view_normal=built.view,
        _shape=built.shape,
        _rebuild=rebuild,
    )


def mesh_tradeoff(
    tolerances: Iterable[float] = (1, 0.1, 0.01, 0.001),
    paths: Iterable[str] = ("arc", "paper"),
    joint: str = "v_groove",
    **params: Any,
) -> list[dict[str, Any]]:
    """Mesh size, time and measured deviation per tolerance (no cache): the speed/accuracy trade.

    Returns
    -------
    rows : list of dict
        Keys ``joint, path, tolerance_mm, triangles, meshing_time_s, deviation_mm``.
    """
    rows = []
    for path in paths:
        for tol in tolerances:
            part = load_workpiece(joint, tolerance_mm=float(tol), cache=False, path=path, **params)
            rows.append(
                {
                    "joint": joint,
                    "path": path,
                    "tolerance_mm": float(tol),
                    "triangles": part.triangle_count,
                    "meshing_time_s": part.meshing_time_s,
                    "deviation_mm": part.deviation_mm,
                }
            )
    return rows
