"""ISO 9692-1 grooves as weldx defines them, built as two plates along our seam paths.

A scene's ``workpiece.groove = {type = "VGroove", t_mm = 10, alpha_deg = 60, b_mm = 1, c_mm =
1}`` names a groove class of ``weldx.welding.groove.iso_9692_1`` (``IGroove``, ``VGroove``,
``VVGroove``, ``UVGroove``, ``UGroove``, ``HVGroove``, ``HUGroove``, ``DVGroove``, ``DUGroove``,
``DHVGroove``, ``DHUGroove``) and its parameters by weldx's names with the unit as suffix:
lengths ``_mm``, angles ``_deg`` (``t_mm``, ``alpha_deg``, ``beta_deg``, ``R_mm``, ``b_mm``,
``c_mm``, ``h_mm``, ``h1_mm``, ...). weldx draws the groove's cross-section
(``groove.to_profile``); its two plates are swept along the path the scene's
``[workpiece.params]`` give (``path``, ``seam_length_mm``, ``arc_radius_mm``,
``corner_angle_deg``, as for every joint script) and ``plate_width_mm`` (each plate's extent
from the gap, default 50). Arcs (U grooves) become polylines within ``tolerance_mm``.

The seam is the groove's root: the middle of the gap at the height where the groove's walls
begin (the top of the root faces; the top of the plates for an I groove; between the two V's of
a double groove, the upper one's). It is the path itself: the profile is placed so. Its torch
direction bisects the two walls' normals; the opening angle is the angle between the walls.

weldx is an optional extra: ``pip install 'seamtrack[weldx]'``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.errors import WorkpieceError
from seamtrack.workpiece.groove_rules import (
    check_groove,
    check_number,
    check_path_params,
    check_plate_width,
)

FloatArray = NDArray[np.float64]

FIELD = "workpiece.groove"
#: Parameters of the groove part besides the path's, with their defaults.
PLATE_DEFAULTS = {"plate_width_mm": 50.0}
PATH_PARAMS = ("path", "seam_length_mm", "arc_radius_mm", "corner_angle_deg")


def weldx_module() -> Any:
    """``weldx``, or an error that says which ``pip install`` brings it."""
    try:
        import weldx
    except ImportError:
        raise WorkpieceError(
            "weldx is not installed",
            field=FIELD,
            fix="pip install 'seamtrack[weldx]'",
        ) from None
    return weldx


def groove_classes() -> dict[str, Any]:
    """The ISO 9692-1 groove classes weldx defines, by name."""
    weldx_module()
    from weldx.welding.groove import iso_9692_1

    return {
        name: getattr(iso_9692_1, name)
        for name in dir(iso_9692_1)
        if name.endswith("Groove") and name not in ("IsoBaseGroove", "FFGroove")
    }


def _unit(name: str) -> str:
    return "deg" if name.startswith(("alpha", "beta")) else "mm"


def _fields(cls: Any) -> dict[str, bool]:
    """The groove's parameters (not ``code_number``) and whether each is required."""
    out = {}
    for f in dataclasses.fields(cls):
        if f.name == "code_number" or not f.init:
            continue
        missing = f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING
        out[f.name] = missing
    return out


def groove_spec(groove: dict[str, Any]) -> dict[str, Any]:
    """Check a groove table against weldx and ISO 9692-1 and return it normalized (floats,
    sorted keys).

    Raises
    ------
    WorkpieceError
        weldx missing, a type weldx does not define, a parameter it does not take, one it
        needs that is missing, a value that is not a finite number, or one outside what
        ISO 9692-1 means by it (:mod:`seamtrack.workpiece.groove_rules`).
    """
    if not isinstance(groove, dict) or not isinstance(groove.get("type"), str):
        raise WorkpieceError(
            f"a groove needs a type, got {groove!r}",
            field=f"{FIELD}.type",
            fix='give e.g. {type = "VGroove", t_mm = 10, alpha_deg = 60, b_mm = 1, c_mm = 1}',
        )
    classes = groove_classes()
    kind = groove["type"]
    if kind == "FFGroove":
        raise WorkpieceError(
            "FFGroove is weldx's frame (fillet and flange) groove, not a butt groove of two "
            "plates that seamtrack builds",
            field=f"{FIELD}.type",
            fix=f"use one of {', '.join(sorted(classes))}; for a fillet joint use a joint "
            "script (cad/fillet_t.py)",
        )
    if kind not in classes:
        raise WorkpieceError(
            f"weldx defines no groove {kind!r}",
            field=f"{FIELD}.type",
            fix=f"use one of {', '.join(sorted(classes))}",
        )
    fields = _fields(classes[kind])
    keys = {f"{name}_{_unit(name)}": name for name in fields}
    spec: dict[str, Any] = {"type": kind}
    for key, value in groove.items():
        if key == "type":
            continue
        if key not in keys:
            raise WorkpieceError(
                f"{kind} takes no {key!r}",
                field=f"{FIELD}.{key}",
                fix=f"{kind} takes {', '.join(keys)}",
            )
        spec[key] = check_number(value, f"{FIELD}.{key}")
    missing = [k for k, name in keys.items() if fields[name] and k not in spec]
    if missing:
        raise WorkpieceError(
            f"{kind} needs {', '.join(missing)}",
            field=f"{FIELD}.{missing[0]}",
            fix=f"add {', '.join(missing)} (weldx's {kind} parameters, unit in the suffix)",
        )
    values = _defaults(classes[kind])  # weldx's defaults (DUGroove: a 3 mm root face)
    values.update({keys[k]: v for k, v in spec.items() if k != "type"})
    check_groove(kind, values, given={keys[k] for k in spec if k != "type"})
    return dict(sorted(spec.items()))


def _defaults(cls: Any) -> dict[str, float]:
    """A groove class's default parameters that have a value, in mm and deg by weldx name."""
    out = {}
    for f in dataclasses.fields(cls):
        value: Any = f.default
        if f.init and hasattr(value, "to") and hasattr(value, "magnitude"):
            out[f.name] = float(value.to(_unit(f.name)).magnitude)
    return out


def groove_object(spec: dict[str, Any]) -> Any:
    """The weldx groove of a (checked) spec."""
    weldx = weldx_module()
    cls = groove_classes()[spec["type"]]
    kwargs = {
        key.rsplit("_", 1)[0]: weldx.Q_(value, key.rsplit("_", 1)[1])
        for key, value in spec.items()
        if key != "type"
    }
    try:
        return cls(**kwargs)
    except Exception as exc:  # weldx's own checks (e.g. a negative thickness)
        raise WorkpieceError(
            f"weldx refuses {spec}: {exc}", field=FIELD, fix="check the groove's parameters"
        ) from exc


# ----------------------------------------------------------------------------- profile
def plate_profiles(spec: dict[str, Any], plate_width_mm: float, tolerance_mm: float):
    """The two plates' cross-sections (u, v) in mm, the root at (0, 0), and the walls.

    Returns
    -------
    plates : list of (k, 2) float
        Closed polygons (last vertex not repeated), weldx's x as u and y - root as v.
    walls : (2, 2) float
        Unit direction of each plate's groove wall, from its root corner up to its top edge
        (u, v); (0, 0) where the root is at the top (an I groove: no wall).
    normals : (2, 2) float
        Outward unit normal of the face each plate shows at the root: its wall's, towards the
        gap, or its top face's (0, 1) where it has no wall.
    """
    groove = groove_object(spec)
    weldx = weldx_module()
    try:
        profile = groove.to_profile(width_default=weldx.Q_(plate_width_mm, "mm"))
    except Exception as exc:
        raise WorkpieceError(
            f"weldx cannot draw {spec}: {exc}", field=FIELD, fix="check the groove's parameters"
        ) from exc
    plates = []
    for shape in profile.shapes:
        pts: list[FloatArray] = []
        for segment in shape.segments:
            pts += _segment_points(segment, tolerance_mm)
        poly = np.array(pts)
        keep = np.r_[True, np.linalg.norm(np.diff(poly, axis=0), axis=1) > 1e-9]
        plates.append(poly[keep])
    if len(plates) != 2:
        raise WorkpieceError(
            f"{spec['type']} draws {len(plates)} plates, not 2",
            field=f"{FIELD}.type",
            fix="use a butt-joint groove (two plates)",
        )
    inner = [p[np.abs(p[:, 0]) <= np.abs(p[:, 0]).min() + 1e-9] for p in plates]
    root = min(float(face[:, 1].max()) for face in inner)
    walls, normals = [], []
    for plate, face in zip(plates, inner, strict=True):
        corner = np.array([face[0, 0], root])
        top = plate[np.abs(plate[:, 1] - plate[:, 1].max()) < 1e-9]
        wall = top[np.argmin(np.abs(top[:, 0]))] - corner
        length = float(np.linalg.norm(wall))
        if length < 1e-9:
            walls.append(np.zeros(2))
            normals.append(np.array([0.0, 1.0]))
            continue
        wall /= length
        toward_gap = -math.copysign(1.0, float(plate[:, 0].mean()))
        normal = np.array([wall[1], -wall[0]])
        normals.append(normal if normal[0] * toward_gap > 0 else -normal)
        walls.append(wall)
    shifted = [np.column_stack([p[:, 0], p[:, 1] - root]) for p in plates]
    return shifted, np.array(walls), np.array(normals)


def _segment_points(segment: Any, tolerance_mm: float) -> list[FloatArray]:
    points = np.asarray(segment.points.m, dtype=np.float64).T
    if type(segment).__name__ != "ArcSegment":
        return [points[0], points[-1]]
    start, end, centre = points  # weldx: start, end, centre
    radius = float(np.linalg.norm(start - centre))
    a0 = math.atan2(*(start - centre)[::-1])
    a1 = math.atan2(*(end - centre)[::-1])
    sweep = (a1 - a0) % (2 * math.pi)
    if not segment.arc_winding_ccw:
        sweep -= 2 * math.pi
    step = 2 * math.acos(max(-1.0, 1 - min(tolerance_mm, radius) / radius))
    n = max(2, math.ceil(abs(sweep) / step) + 1)
    angles = a0 + sweep * np.linspace(0.0, 1.0, n)
    return list(centre + radius * np.column_stack([np.cos(angles), np.sin(angles)]))


# ----------------------------------------------------------------------------- part
def build_groove(
    groove: dict[str, Any], tolerance_mm: float, spacing_mm: float, **params: Any
) -> dict[str, Any]:
    """The groove's two plates along the path, its root seam and torch frame (the fields of
    the loader's ``_Built``: shape, points, face_normals, torch, name, joint, opening_rad)."""
    from seamtrack.cad.kit import cadpaths
    from seamtrack.workpiece.contacts import edges, sample_edge

    spec = groove_spec(groove)
    for key in params:
        if key not in PATH_PARAMS and key not in PLATE_DEFAULTS:
            raise WorkpieceError(
                f"a groove part takes no {key!r}",
                field=f"workpiece.params.{key}",
                fix=f"give {', '.join((*PATH_PARAMS, *PLATE_DEFAULTS))}",
            )
    width = check_plate_width(params.get("plate_width_mm", PLATE_DEFAULTS["plate_width_mm"]))
    check_path_params(params)
    plates, walls, normals = plate_profiles(spec, width, tolerance_mm)
    path_args = {
        "path": params.get("path", "straight"),
        "seam_length_mm": params.get("seam_length_mm"),
        "arc_radius_mm": params.get("arc_radius_mm", 100.0),
        "corner_angle_deg": params.get("corner_angle_deg", 90.0),
    }
    try:
        wire = cadpaths.path_wire(**path_args)
        profiles = [[tuple(map(float, p)) for p in plate] for plate in plates]
        joint = cadpaths.finish(profiles, {}, {}, tacks=0, tack_length_mm=8.0,
                              tack_height_mm=1.5, **path_args)  # fmt: skip
    except cadpaths.ParamError as exc:
        raise WorkpieceError(
            f"the groove part failed: {exc}",
            field=f"workpiece.params.{exc.param}",
            fix=f"change {exc.param}",
        ) from exc
    chain = [sample_edge(e, True, tolerance_mm, spacing_mm) for e in edges(wire.wrapped)]
    points = np.vstack([p[i > 0 :] for i, (p, _) in enumerate(chain)])
    tangents = np.vstack([t[i > 0 :] for i, (_, t) in enumerate(chain)])
    up = np.array([0.0, 0.0, 1.0])
    v_axis = up - (tangents @ up)[:, None] * tangents
    v_axis /= np.linalg.norm(v_axis, axis=1, keepdims=True)
    u_axis = np.cross(v_axis, tangents)
    face_normals = np.stack(
        [n_u * u_axis + n_v * v_axis for n_u, n_v in normals], axis=1
    )  # (n, 2, 3)
    torch = face_normals.sum(axis=1)
    if np.any(np.all(walls == 0.0, axis=1)):
        opening = math.pi  # no groove wall: the plates' top faces show, flush
    else:
        opening = math.acos(float(np.clip(walls[0] @ walls[1], -1.0, 1.0)))
    return {
        "shape": joint.solid,
        "points": points,
        "face_normals": face_normals,
        "torch": torch,
        "name": f"{spec['type']}:root",
        "joint": "butt",
        "opening_rad": opening,
    }
