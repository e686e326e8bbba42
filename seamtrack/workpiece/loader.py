"""Workpieces from CAD: run a ``cad/`` joint script or read a STEP part, mesh it, find its seam.

``load_workpiece`` meshes the BRep with an absolute chordal tolerance (OCCT
``BRepMesh_IncrementalMesh`` after ``BRepTools.Clean``), measures the deviation it actually got
against the exact surfaces, and samples the seam edge(s) into a
:class:`seamtrack.geometry.seam.Seam`
in the part frame. The seam normals are torch directions: the bisector of the OUTWARD normals
of the two faces that meet at the seam, so the torch points away from the material (into the
groove, out of the fillet corner).

Results are cached on disk (``$SEAMTRACK_CACHE_DIR`` or ``~/.cache/seamtrack``), keyed by the
script or STEP content, the shared ``cad/_paths.py`` helper, the parameters, tolerances, seam
choice and the seamtrack version. A cache hit imports neither CadQuery nor OCP; a corrupt entry
is rebuilt. Clear it with :func:`clear_cache` (or delete the folder :func:`cache_dir` names).

CadQuery and OCP are imported only inside the functions that need them.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import math
import os
import shutil
import sys
import tempfile
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack import constants
from seamtrack._version import __version__
from seamtrack.errors import WorkpieceError
from seamtrack.geometry.seam import Seam
from seamtrack.params import check_params

if TYPE_CHECKING:
    import trimesh

FloatArray = NDArray[np.float64]

#: Bump when the cache layout changes.
CACHE_FORMAT = 1
#: Default angular deflection of the mesher (rad); the chordal tolerance usually governs.
DEFAULT_ANGULAR_TOLERANCE_RAD = 0.5


@dataclass(frozen=True, eq=False)
class Workpiece:
    """A meshed CAD part with its seam.

    Attributes
    ----------
    mesh : trimesh.Trimesh
        Welded, watertight triangle mesh in the part frame (mm, float64).
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
        The script or STEP path that was loaded.
    params : dict
        Parameters given to the script's ``build``.
    tolerance_mm : float
        The requested chordal tolerance.
    from_cache : bool
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
    _shape: Any = field(default=None, repr=False)
    _rebuild: Callable[[], Any] | None = field(default=None, repr=False)

    @property
    def shape(self) -> Any:
        """The CadQuery shape (after a cache hit: rebuilt from the source on first use)."""
        if self._shape is None and self._rebuild is not None:
            object.__setattr__(self, "_shape", self._rebuild())
        return self._shape


# ----------------------------------------------------------------------------- cache
def cache_dir() -> Path:
    """The cache folder: ``$SEAMTRACK_CACHE_DIR`` or ``~/.cache/seamtrack``."""
    env = os.environ.get("SEAMTRACK_CACHE_DIR")
    return Path(env).expanduser() if env else Path.home() / ".cache" / "seamtrack"


def clear_cache(cache_dir: str | Path | None = None) -> int:
    """Delete every cached workpiece; return how many entries were removed."""
    root = Path(cache_dir) if cache_dir is not None else globals()["cache_dir"]()
    root = root / "workpieces"
    if not root.is_dir():
        return 0
    count = 0
    for entry in root.iterdir():
        if entry.is_dir():
            shutil.rmtree(entry, ignore_errors=True)
            count += 1
    return count


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _cache_key(parts: dict[str, Any]) -> str:
    text = json.dumps(parts, sort_keys=True, default=repr)
    return _sha256(text.encode())[:32]


def _read_cache(entry: Path, key: str) -> dict[str, Any] | None:
    """The cached arrays and metadata, or None when missing or corrupt (never trusted blindly)."""
    try:
        meta = json.loads((entry / "meta.json").read_text())
        if meta.get("key") != key or meta.get("format") != CACHE_FORMAT:
            return None
        arrays: dict[str, Any] = {"meta": meta}
        for name in ("mesh.npz", "seam.npz"):
            blob = (entry / name).read_bytes()
            if _sha256(blob) != meta["sha256"][name]:
                return None
            with np.load(entry / name, allow_pickle=False) as data:
                arrays.update({k: np.array(data[k]) for k in data.files})
        v, f, p = arrays["vertices"], arrays["faces"], arrays["points"]
        ok = (
            v.ndim == 2
            and v.shape[1] == 3
            and f.ndim == 2
            and f.shape[1] == 3
            and len(f) == meta["triangle_count"]
            and f.max() < len(v)
            and f.min() >= 0
            and p.ndim == 2
            and p.shape[1] == 3
            and arrays["normals"].shape == p.shape
            and arrays["face_normals"].shape == (len(p), 2, 3)
        )
        return arrays if ok else None
    except (OSError, ValueError, KeyError, TypeError, AttributeError, json.JSONDecodeError):
        return None
    except Exception:  # zipfile.BadZipFile and kin from a truncated npz
        return None


def _write_cache(
    entry: Path, key: str, arrays: dict[str, FloatArray], meta: dict[str, Any]
) -> None:
    entry.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".tmp-", dir=entry.parent))
    try:
        np.savez(tmp / "mesh.npz", vertices=arrays["vertices"], faces=arrays["faces"])
        np.savez(
            tmp / "seam.npz",
            points=arrays["points"],
            normals=arrays["normals"],
            face_normals=arrays["face_normals"],
        )
        sums = {n: _sha256((tmp / n).read_bytes()) for n in ("mesh.npz", "seam.npz")}
        full = {**meta, "key": key, "format": CACHE_FORMAT, "sha256": sums}
        (tmp / "meta.json").write_text(json.dumps(full, indent=1, default=repr))
        if entry.exists():
            shutil.rmtree(entry, ignore_errors=True)
        os.replace(tmp, entry)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)


# ----------------------------------------------------------------------------- sources
def builtin_joints() -> list[str]:
    """Names of the packaged joint scripts (``seamtrack.cad``)."""
    folder = resources.files("seamtrack.cad")
    return sorted(
        p.name[:-3]
        for p in folder.iterdir()
        if p.name.endswith(".py") and not p.name.startswith("_")
    )


def _helper_hash() -> str:
    """Hash of the shared helpers: a change in them changes every part."""
    folder = resources.files("seamtrack.cad")
    return _sha256(b"".join(folder.joinpath(n).read_bytes() for n in ("_paths.py", "_occ.py")))


def _resolve(source: str | Path) -> tuple[str, Path]:
    """('script' | 'step', path) for a script path, a built-in name or a STEP path."""
    text = str(source)
    path = Path(text).expanduser()
    suffix = path.suffix.lower()
    if suffix in (".step", ".stp"):
        if not path.is_file():
            raise WorkpieceError(
                f"STEP file {text!r} does not exist",
                field="workpiece.step",
                fix="give the path of a .step/.stp file",
            )
        return "step", path
    if suffix == "" and not path.exists() and text in builtin_joints():
        return "script", Path(str(resources.files("seamtrack.cad").joinpath(text + ".py")))
    if not path.is_file():
        raise WorkpieceError(
            f"script {text!r} does not exist",
            field="workpiece.script",
            fix=f"give a cad/*.py path or a built-in joint: {', '.join(builtin_joints())}",
        )
    if suffix != ".py":
        raise WorkpieceError(
            f"{text!r} is not a Python script (.py) or a STEP file",
            field="workpiece.script",
            fix="give a CadQuery script cad/<joint>.py or a .step file",
        )
    return "script", path


def _load_module(path: Path) -> Any:
    name = "seamtrack_cad_script_" + _sha256(str(path.resolve()).encode())[:12]
    spec = importlib.util.spec_from_file_location(name, path)
    if spec is None or spec.loader is None:
        raise WorkpieceError(
            f"cannot load {path}", field="workpiece.script", fix="give a Python file"
        )
    module = importlib.util.module_from_spec(spec)
    sys.path.insert(0, str(path.parent))  # scripts may import helpers beside them
    try:
        spec.loader.exec_module(module)
    except Exception as exc:
        raise WorkpieceError(
            f"{path.name} failed to import: {type(exc).__name__}: {exc}",
            field="workpiece.script",
            fix="run the script alone to see the full traceback and fix it",
        ) from exc
    finally:
        sys.path.remove(str(path.parent))
    return module


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


def _run_script(path: Path, params: dict[str, Any]) -> tuple[Any, Any, dict[str, list[Any]]]:
    """Run ``build(**params)``; return (solid, seam solid, named seam edges)."""
    import cadquery as cq

    module = _load_module(path)
    build = getattr(module, "build", None)
    if not callable(build):
        raise WorkpieceError(
            f"{path.name} has no build() function",
            field="workpiece.script",
            fix="define build(**params) returning the solid and its seam "
            "edges (see cad/v_groove.py)",
        )
    check_params(build, params, "workpiece.params", WorkpieceError)  # names, types, finite
    try:
        result = build(**params)
    except Exception as exc:
        param = getattr(exc, "param", None)
        where = f"workpiece.params.{param}" if isinstance(param, str) else "workpiece.script"
        raise WorkpieceError(
            f"{path.name} build() failed: {exc}",
            field=where,
            fix=f"change {param} (the script's docstring says what it means)"
            if param
            else "check the parameters against the script's docstring",
        ) from exc
    if hasattr(result, "solid") and hasattr(result, "seams"):
        solid, seams = result.solid, dict(result.seams)
        seam_solid = getattr(result, "seam_solid", None) or solid
    elif isinstance(result, tuple) and len(result) == 2:
        solid, seams = result[0], dict(result[1])
        seam_solid = solid
    else:
        solid, seams, seam_solid = result, {}, result
    solid, seam_solid = (_as_shape(s, cq) for s in (solid, seam_solid))
    if solid is None or not solid.Solids() or not solid.isValid():
        raise WorkpieceError(
            f"{path.name} build({_fmt(params)}) made no valid solid",
            field="workpiece.params",
            fix="change the parameters (gaps, angles, thicknesses) to ones that make a real part",
        )
    return solid, seam_solid, seams


def _as_shape(obj: Any, cq: Any) -> Any:
    if isinstance(obj, cq.Workplane):
        vals = [v for v in obj.vals() if isinstance(v, cq.Shape)]
        return vals[0] if len(vals) == 1 else (cq.Compound.makeCompound(vals) if vals else None)
    return obj if isinstance(obj, cq.Shape) else None


def _fmt(params: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v!r}" for k, v in params.items())


def _read_step(path: Path) -> Any:
    import cadquery as cq

    head = path.read_bytes()[:200]
    if not head.strip():
        raise WorkpieceError(
            f"{path.name} is empty", field="workpiece.step", fix="export the part again as STEP"
        )
    if b"ISO-10303-21" not in head:
        raise WorkpieceError(
            f"{path.name} is not a STEP file (no ISO-10303-21 header)",
            field="workpiece.step",
            fix="export the part as STEP AP203/AP214",
        )
    try:
        shapes = [v for v in cq.importers.importStep(str(path)).vals() if isinstance(v, cq.Shape)]
    except Exception as exc:
        raise WorkpieceError(
            f"{path.name} could not be read: {exc}",
            field="workpiece.step",
            fix="export the part again as STEP",
        ) from exc
    solids = [s for shape in shapes for s in shape.Solids()]
    if not solids:
        raise WorkpieceError(
            f"{path.name} holds no solid",
            field="workpiece.step",
            fix="export a closed solid body, not surfaces or curves",
        )
    return solids[0] if len(solids) == 1 else cq.Compound.makeCompound(solids)


def _seam_edges(
    occ: Any, shape: Any, named: dict[str, list[Any]], seam: str | None, near: ArrayLike | None
) -> list[Any]:
    """The seam edges: near given points, by name, or by selector (unordered)."""
    if near is not None:
        points = np.atleast_2d(np.asarray(near, dtype=np.float64))
        if points.ndim != 2 or points.shape[1] != 3 or not np.isfinite(points).all():
            raise WorkpieceError(
                "seam_near_mm must be finite (m, 3) points",
                field="workpiece.seam",
                fix="give x, y, z triples in mm",
            )
        return list(occ.edges_near(shape, points))
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


# ----------------------------------------------------------------------------- loading
def load_workpiece(
    source: str | Path,
    *,
    tolerance_mm: float = 0.01,
    angular_tolerance_rad: float = DEFAULT_ANGULAR_TOLERANCE_RAD,
    seam: str | None = None,
    seam_near_mm: ArrayLike | None = None,
    seam_spacing_mm: float = 1.0,
    cache: bool = True,
    cache_dir: str | Path | None = None,
    **params: Any,
) -> Workpiece:
    """Build or read a CAD part, mesh it with an absolute tolerance and extract its seam.

    Parameters
    ----------
    source : str or Path
        A joint script (``"cad/v_groove.py"``), a built-in joint name (``"v_groove"``) or a
        STEP file (``.step`` / ``.stp``).
    tolerance_mm : float
        Chordal tolerance of the mesh and of the seam polyline (mm, absolute).
    angular_tolerance_rad : float
        Angular deflection of the mesher.
    seam : str, optional
        A seam name the script returns (default: its first, ``"root"``) or a CadQuery edge
        selector string (``"|X and <Z"``); needed for STEP files unless ``seam_near_mm``.
    seam_near_mm : (m, 3) float, optional
        Points near the seam: the edges nearest to them form the seam.
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
    if not seam_spacing_mm > 0:
        raise WorkpieceError(
            f"seam spacing must be > 0, got {seam_spacing_mm}",
            field="workpiece.seam_spacing_mm",
            fix="give e.g. 1.0 (mm)",
        )
    import trimesh  # here, not at import: seam-mode scenes never load it

    kind, path = _resolve(source)
    if kind == "step" and params:
        name = next(iter(params))
        raise WorkpieceError(
            "a STEP part takes no parameters",
            field=f"workpiece.params.{name}",
            fix="remove the parameters, or load the part's script instead",
        )
    near = None if seam_near_mm is None else np.asarray(seam_near_mm, dtype=np.float64).tolist()
    content = path.read_bytes()
    key = _cache_key(
        {
            "kind": kind,
            "content": _sha256(content),
            "helpers": _helper_hash(),
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

    def rebuild() -> Any:
        return _run_script(path, params)[0] if kind == "script" else _read_step(path)

    if cache:
        hit = _read_cache(entry, key)
        if hit is not None:
            meta = hit["meta"]
            mesh = trimesh.Trimesh(hit["vertices"], hit["faces"], process=False)
            return Workpiece(
                mesh=mesh,
                seam=Seam.from_points(
                    hit["points"], hit["normals"], name=meta["name"], field="workpiece.seam"
                ),
                seam_face_normals=hit["face_normals"],
                deviation_mm=meta["deviation_mm"],
                triangle_count=len(hit["faces"]),
                meshing_time_s=meta["meshing_time_s"],
                source=str(path),
                params=dict(params),
                tolerance_mm=float(tolerance_mm),
                from_cache=True,
                _rebuild=rebuild,
            )
    if kind == "script":
        solid, seam_solid, named = _run_script(path, params)
    else:
        solid = seam_solid = _read_step(path)
        named = {}
    from seamtrack.cad import _occ

    chained = _occ.chain(_seam_edges(_occ, seam_solid, named, seam, seam_near_mm), "the seam")
    points, face_normals = _occ.sample_seam(
        seam_solid, chained, float(tolerance_mm), float(seam_spacing_mm)
    )
    torch = face_normals.sum(axis=1)  # bisector of the outward normals: away from the material
    _check_mesh_budget(float(solid.BoundingBox().DiagonalLength), tolerance_mm)
    vertices, faces, deviation, spent = _occ.mesh(
        solid, float(tolerance_mm), float(angular_tolerance_rad)
    )
    mesh = trimesh.Trimesh(vertices, faces, process=True)  # welds shared edge nodes
    name = (
        f"{path.stem}:{seam or (next(iter(named)) if named and seam_near_mm is None else 'seam')}"
    )
    seam_obj = Seam.from_points(points, torch, name=name, field="workpiece.seam")
    if cache:
        meta = {
            "name": name,
            "deviation_mm": deviation,
            "meshing_time_s": spent,
            "triangle_count": len(mesh.faces),
            "source": str(path),
            "params": params,
            "tolerance_mm": tolerance_mm,
            "seamtrack": __version__,
        }
        arrays = {
            "vertices": np.asarray(mesh.vertices),
            "faces": np.asarray(mesh.faces),
            "points": seam_obj.points,
            "normals": torch,  # the input of Seam.from_points, so a hit rebuilds the same seam
            "face_normals": face_normals,
        }
        try:
            _write_cache(entry, key, arrays, meta)
        except OSError:
            pass  # a read-only cache costs speed, not correctness
    return Workpiece(
        mesh=mesh,
        seam=seam_obj,
        seam_face_normals=face_normals,
        deviation_mm=deviation,
        triangle_count=len(mesh.faces),
        meshing_time_s=spent,
        source=str(path),
        params=dict(params),
        tolerance_mm=float(tolerance_mm),
        _shape=solid,
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
