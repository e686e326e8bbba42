"""Where a workpiece comes from: a ``cad/`` script (a joint or a weldment) or a STEP file.

A joint script's ``build(**params)`` returns a ``Joint`` (one solid and its named seam edges);
a weldment script's returns a ``Weldment`` (named, separate bodies). A STEP file holds one
solid or many (an assembly, a compound, a multi-body part): :func:`read_bodies` gives every
solid with its name and placement.

CadQuery and OCP are imported only inside the functions that need them.
"""

from __future__ import annotations

import importlib.util
import re
import sys
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any

from seamtrack.errors import WorkpieceError
from seamtrack.params import check_params
from seamtrack.workpiece.cache import sha256

#: Built-in scripts whose name starts so are weldments (several bodies), not joints.
WELDMENT_PREFIX = "weldment_"
#: The shared helpers of the cad/ scripts: a change in them changes every part.
HELPERS = ("kit/cadpaths.py", "kit/cadocc.py", "kit/cadmesh.py", "kit/cadweldment.py")


@dataclass(frozen=True)
class ScriptResult:
    """What a script built: one solid with named seams, or a weldment's named bodies."""

    solid: Any
    seam_solid: Any
    seams: dict[str, list[Any]]
    bodies: list[tuple[str, Any]] | None = None


def _scripts() -> list[str]:
    folder = resources.files("seamtrack.cad")
    return sorted(
        p.name[:-3]
        for p in folder.iterdir()
        if p.name.endswith(".py") and not p.name.startswith("_")
    )


def builtin_joints() -> list[str]:
    """Names of the packaged joint scripts (``seamtrack.cad``), weldments excluded."""
    return [n for n in _scripts() if not n.startswith(WELDMENT_PREFIX)]


def builtin_weldments() -> list[str]:
    """Names of the packaged weldment scripts (``seamtrack.cad.weldment_*``)."""
    return [n for n in _scripts() if n.startswith(WELDMENT_PREFIX)]


def helper_hash() -> str:
    """Hash of the shared helpers of the cad/ scripts."""
    folder = resources.files("seamtrack.cad")
    return sha256(b"".join(folder.joinpath(n).read_bytes() for n in HELPERS))


def resolve(source: str | Path, field: str | None = None) -> tuple[str, Path]:
    """('script' | 'step', path) for a script path, a built-in name or a STEP path; errors
    name ``field`` (default: ``workpiece.step`` or ``workpiece.script``)."""
    text = str(source)
    path = Path(text).expanduser()
    suffix = path.suffix.lower()
    if suffix in (".step", ".stp"):
        if not path.is_file():
            raise WorkpieceError(
                f"STEP file {text!r} does not exist",
                field=field or "workpiece.step",
                fix="give the path of a .step/.stp file",
            )
        return "step", path
    if suffix == "" and not path.exists() and text in _scripts():
        return "script", Path(str(resources.files("seamtrack.cad").joinpath(text + ".py")))
    if not path.is_file():
        raise WorkpieceError(
            f"script {text!r} does not exist",
            field=field or "workpiece.script",
            fix=f"give a cad/*.py path or a built-in joint: {', '.join(builtin_joints())} "
            f"(weldments: {', '.join(builtin_weldments())})",
        )
    if suffix != ".py":
        raise WorkpieceError(
            f"{text!r} is not a Python script (.py) or a STEP file",
            field=field or "workpiece.script",
            fix="give a CadQuery script cad/<joint>.py or a .step file",
        )
    return "script", path


def _load_module(path: Path) -> Any:
    name = "seamtrack_cad_script_" + sha256(str(path.resolve()).encode())[:12]
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


def run_script(path: Path, params: dict[str, Any]) -> ScriptResult:
    """Run ``build(**params)``: a joint's solid and named seams, or a weldment's bodies."""
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
    if hasattr(result, "bodies") and isinstance(result.bodies, dict):
        bodies = [(str(k), _as_shape(v, cq)) for k, v in result.bodies.items()]
        if not bodies or any(b is None or not b.isValid() for _, b in bodies):
            raise WorkpieceError(
                f"{path.name} build({_fmt(params)}) made an invalid body",
                field="workpiece.params",
                fix="change the parameters to ones that make real plates",
            )
        compound = cq.Compound.makeCompound([b for _, b in bodies])
        return ScriptResult(compound, compound, {}, bodies)
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
    return ScriptResult(solid, seam_solid, seams)


def _as_shape(obj: Any, cq: Any) -> Any:
    if isinstance(obj, cq.Workplane):
        vals = [v for v in obj.vals() if isinstance(v, cq.Shape)]
        return vals[0] if len(vals) == 1 else (cq.Compound.makeCompound(vals) if vals else None)
    return obj if isinstance(obj, cq.Shape) else None


def _fmt(params: dict[str, Any]) -> str:
    return ", ".join(f"{k}={v!r}" for k, v in params.items())


def read_step(path: Path, field: str = "workpiece.step") -> Any:
    """The solid of a STEP file, or a compound of its solids when it holds several."""
    import cadquery as cq

    solids = [s for _, s in read_bodies(path, field)]
    return solids[0] if len(solids) == 1 else cq.Compound.makeCompound(solids)


def read_bodies(path: Path, field: str = "workpiece.step") -> list[tuple[str, Any]]:
    """Every solid of a STEP file (assemblies and compounds included) with its name.

    Names come from the STEP product or instance (``/`` becomes ``_``; a solid without one is
    ``body<i>``; repeats get ``.2``, ``.3``...); placements are applied.

    Returns
    -------
    bodies : list of (str, cadquery.Solid)
    """
    head = path.read_bytes()[:200]
    if not head.strip():
        raise WorkpieceError(f"{path.name} is empty", field=field, fix="export the part again")
    if b"ISO-10303-21" not in head:
        raise WorkpieceError(
            f"{path.name} is not a STEP file (no ISO-10303-21 header)",
            field=field,
            fix="export the part as STEP AP203/AP214",
        )
    try:
        found = _xcaf_solids(path)
    except Exception as exc:
        raise WorkpieceError(
            f"{path.name} could not be read: {exc}", field=field, fix="export the part again"
        ) from exc
    if not found:
        raise WorkpieceError(
            f"{path.name} holds no solid",
            field=field,
            fix="export closed solid bodies, not surfaces or curves",
        )
    bases = [
        re.sub(r"[/\s]+", "_", n).strip("_") or f"body{i + 1}" for i, (n, _) in enumerate(found)
    ]
    out: list[tuple[str, Any]] = []
    taken = set(bases)  # a repeat's suffix never takes a name another body has in the file
    seen: dict[str, int] = {}
    for base, (_, solid) in zip(bases, found, strict=True):
        seen[base] = seen.get(base, 0) + 1
        name = base
        if seen[base] > 1:
            while f"{base}.{seen[base]}" in taken:
                seen[base] += 1
            name = f"{base}.{seen[base]}"
            taken.add(name)
        out.append((name, solid))
    return out


def _xcaf_solids(path: Path) -> list[tuple[str, Any]]:
    """(name, located solid) for every solid of the file, walking its assembly tree."""
    import cadquery as cq
    from OCP.IFSelect import IFSelect_RetDone
    from OCP.STEPCAFControl import STEPCAFControl_Reader
    from OCP.TCollection import TCollection_ExtendedString
    from OCP.TDataStd import TDataStd_Name
    from OCP.TDF import TDF_Label, TDF_LabelSequence
    from OCP.TDocStd import TDocStd_Document
    from OCP.TopLoc import TopLoc_Location
    from OCP.XCAFDoc import XCAFDoc_DocumentTool

    reader = STEPCAFControl_Reader()
    reader.SetNameMode(True)
    if reader.ReadFile(str(path)) != IFSelect_RetDone:
        raise ValueError("the STEP reader failed")
    doc = TDocStd_Document(TCollection_ExtendedString("XmlOcaf"))
    reader.Transfer(doc)
    tool = XCAFDoc_DocumentTool.ShapeTool_s(doc.Main())

    def name_of(label: Any) -> str:
        attr = TDataStd_Name()
        if label.FindAttribute(TDataStd_Name.GetID_s(), attr):
            return str(attr.Get().ToExtString())
        return ""

    out: list[tuple[str, Any]] = []

    def walk(label: Any, location: Any, name: str) -> None:
        if tool.IsAssembly_s(label):
            components = TDF_LabelSequence()
            tool.GetComponents_s(label, components)
            for i in range(1, components.Length() + 1):
                component = components.Value(i)
                referred = TDF_Label()
                tool.GetReferredShape_s(component, referred)
                where = location.Multiplied(tool.GetLocation_s(component))
                walk(referred, where, name_of(component) or name_of(referred))
            return
        shape = tool.GetShape_s(label).Moved(location)
        solids = cq.Shape.cast(shape).Solids()
        for k, solid in enumerate(solids):
            out.append((name if len(solids) == 1 else f"{name}.{k + 1}", solid))

    labels = TDF_LabelSequence()
    tool.GetFreeShapes(labels)
    for i in range(1, labels.Length() + 1):
        walk(labels.Value(i), TopLoc_Location(), name_of(labels.Value(i)))
    return out
