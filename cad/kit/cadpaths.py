"""Shared helpers of the joint scripts: seam paths, profile sweeping, tack welds.

Every joint family is a cross-section drawn in a profile plane ``(u, v)`` and swept along the
seam path. At a path point with unit tangent ``T`` the profile axes are ``v`` = world +Z made
orthogonal to ``T`` ("up", the torch side) and ``u = v x T`` (for travel along +X, ``u`` is +Y).
The sweep keeps that frame (fixed binormal +Z), so plates stay "flat" the way the paper's
3-axis robot sees them. The seam vertex of each profile sits at ``(0, 0)``: the seam IS the
path, so the seam edge of the solid reproduces the path within the sweep tolerance.

Paths (``path=``): ``"straight"`` (+X from the origin), ``"arc"`` (circular, turning left in
the XY plane), ``"corner"`` (two straight legs in the XY plane with a sharp, mitred turn), all
swept with OCCT's ``MakePipeShell`` (exact planes, cylinders and cones); and ``"paper"`` (Eq.
15-17: X = 0..L, Y = 10 cos(pi X/200), Z = 10 sin(pi X/200)), built from the exact
parametrization by :func:`sweep_paper` (rails through 2 mm samples, ruled faces between them).

The result of every ``build(**params)`` is a :class:`Joint`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import cadquery as cq
from OCP.BRepBuilderAPI import BRepBuilderAPI_RightCorner
from OCP.BRepOffsetAPI import BRepOffsetAPI_MakePipeShell
from OCP.gp import gp_Dir

PATHS = ("straight", "arc", "paper", "corner")

#: Sweep approximation tolerance (mm): far below any mesh tolerance we offer.
SWEEP_TOL_MM = 1e-7

#: Spacing of the samples the paper curve is interpolated through (mm).
PAPER_SAMPLE_MM = 2.0

Profile = Sequence[tuple[float, float]]


class ParamError(ValueError):
    """A build parameter that makes no valid part; ``.param`` names it."""

    def __init__(self, param: str, message: str):
        super().__init__(f"{param}: {message}")
        self.param = param


@dataclass(frozen=True)
class Joint:
    """What every ``build(**params)`` returns.

    Attributes
    ----------
    solid : cadquery.Shape
        The part (a Solid, or a Compound of Solids when plates do not touch), tack welds
        included; units mm.
    seams : dict of str to list of cadquery.Edge
        Named seam edge chains, edges in order along the seam. The first entry (always
        ``"root"``) is the default seam; it lies on the path.
    seam_solid : cadquery.Shape
        The shape whose faces bound the seam edges: ``solid`` before tack welds were fused on
        (tacks cover parts of the seam; the seam itself stays where the joint is).
    params : dict
        The parameters the part was built with.
    """

    solid: cq.Shape
    seams: dict[str, list[cq.Edge]]
    seam_solid: cq.Shape
    params: dict[str, object] = field(default_factory=dict)

    def summary(self) -> str:
        """A short human-readable description (what ``python cad/x.py`` prints)."""
        bb = self.solid.BoundingBox()
        lines = [
            f"valid solid: {self.solid.isValid()}, volume {self.solid.Volume():.3f} mm^3",
            f"bounding box: x {bb.xmin:.2f}..{bb.xmax:.2f}, y {bb.ymin:.2f}..{bb.ymax:.2f}, "
            f"z {bb.zmin:.2f}..{bb.zmax:.2f} mm",
        ]
        for name, edges in self.seams.items():
            length = sum(e.Length() for e in edges)
            lines.append(f"seam {name!r}: {len(edges)} edge(s), {length:.3f} mm")
        return "\n".join(lines)


def paper_xyz(x_mm: float) -> tuple[float, float, float]:
    """A point of the paper's curve, Eq. 15-17."""
    phase = math.pi * x_mm / 200.0
    return (x_mm, 10.0 * math.cos(phase), 10.0 * math.sin(phase))


def default_length(path: str, seam_length_mm: float | None) -> float:
    """Seam length: given, or 400 mm (the paper's X range) for ``"paper"`` and 200 mm else."""
    if seam_length_mm is None:
        return 400.0 if path == "paper" else 200.0
    return float(seam_length_mm)


def path_wire(
    path: str,
    seam_length_mm: float | None = None,
    arc_radius_mm: float = 100.0,
    corner_angle_deg: float = 90.0,
) -> cq.Wire:
    """The seam path as a wire starting at the origin, heading +X.

    For ``"paper"``, ``seam_length_mm`` is the X extent (the paper's 0..400 by default).
    """
    if path not in PATHS:
        raise ParamError("path", f"unknown path {path!r}; choose one of {', '.join(PATHS)}")
    length = default_length(path, seam_length_mm)
    if not length > 0:
        raise ParamError("seam_length_mm", f"must be > 0, got {length}")
    if path == "straight":
        return cq.Wire.assembleEdges(
            [cq.Edge.makeLine(cq.Vector(0, 0, 0), cq.Vector(length, 0, 0))]
        )
    if path == "arc":
        if not arc_radius_mm > 0:
            raise ParamError("arc_radius_mm", f"must be > 0, got {arc_radius_mm}")
        angle = length / arc_radius_mm
        if angle >= 2 * math.pi:
            raise ParamError("seam_length_mm", "an arc seam must be shorter than its full circle")
        mid = cq.Vector(
            arc_radius_mm * math.sin(angle / 2), arc_radius_mm * (1 - math.cos(angle / 2)), 0
        )
        end = cq.Vector(arc_radius_mm * math.sin(angle), arc_radius_mm * (1 - math.cos(angle)), 0)
        return cq.Wire.assembleEdges([cq.Edge.makeThreePointArc(cq.Vector(0, 0, 0), mid, end)])
    if path == "paper":
        n = max(2, math.ceil(length / PAPER_SAMPLE_MM))
        xs = [length * i / n for i in range(n + 1)]
        pts = [cq.Vector(*paper_xyz(x)) for x in xs]
        k = math.pi / 200.0

        def tangent(x: float) -> cq.Vector:
            return cq.Vector(1.0, -10.0 * k * math.sin(k * x), 10.0 * k * math.cos(k * x))

        edge = cq.Edge.makeSpline(pts, tangents=[tangent(0.0), tangent(length)], scale=False)
        return cq.Wire.assembleEdges([edge])
    # corner: two legs of half the length each, turning left by corner_angle_deg
    if not 0 < corner_angle_deg < 180:
        raise ParamError("corner_angle_deg", f"must be in (0, 180), got {corner_angle_deg}")
    turn = math.radians(corner_angle_deg)
    half = length / 2
    p1 = cq.Vector(half, 0, 0)
    p2 = p1 + cq.Vector(half * math.cos(turn), half * math.sin(turn), 0)
    return cq.Wire.makePolygon([cq.Vector(0, 0, 0), p1, p2])


def check_lateral_extent(
    path: str,
    profiles: Sequence[Profile],
    seam_length_mm: float | None,
    arc_radius_mm: float,
    corner_angle_deg: float,
) -> None:
    """Refuse profiles that would fold over themselves on curved or cornered paths."""
    left = max(u for profile in profiles for u, _ in profile)
    right = max(-u for profile in profiles for u, _ in profile)
    if path == "arc" and left >= arc_radius_mm:
        raise ParamError(
            "arc_radius_mm",
            f"the part reaches {left:.1f} mm towards the arc centre; use a radius > {left:.1f}",
        )
    if path == "corner":
        half = default_length(path, seam_length_mm) / 2
        reach = max(left, right) * math.tan(math.radians(corner_angle_deg) / 2)
        if reach >= half:
            raise ParamError(
                "seam_length_mm",
                f"each corner leg ({half:.1f} mm) must exceed the mitre reach {reach:.1f} mm",
            )


def _frame(tangent: Sequence[float]) -> tuple[list[float], list[float]]:
    """Profile axes (u, v) for a path tangent: v = +Z made orthogonal to it, u = v x T."""
    t = cq.Vector(*tangent).normalized()
    v = (cq.Vector(0, 0, 1) - t * t.z).normalized()
    u = v.cross(t).normalized()
    return [u.x, u.y, u.z], [v.x, v.y, v.z]


def _paper_rail(x_mm: float, u: float, v: float) -> tuple[float, float, float]:
    """Point of the profile vertex (u, v) in the frame at X = x_mm on the paper curve."""
    k = math.pi / 200.0
    c = paper_xyz(x_mm)
    u_axis, v_axis = _frame((1.0, -10.0 * k * math.sin(k * x_mm), 10.0 * k * math.cos(k * x_mm)))
    return (
        c[0] + u * u_axis[0] + v * v_axis[0],
        c[1] + u * u_axis[1] + v * v_axis[1],
        c[2] + u * u_axis[2] + v * v_axis[2],
    )


def sweep_paper(
    profiles: Sequence[Profile],
    length_mm: float,
    seam_uv: dict[str, tuple[float, float]],
) -> tuple[cq.Shape, dict[str, list[cq.Edge]]]:
    """Profiles along the paper curve, built from the exact parametrization.

    Every profile vertex traces a rail, computed exactly at X steps of ``PAPER_SAMPLE_MM`` and
    interpolated by a cubic B-spline with exact end derivatives (all rails share the
    parameter X, so the faces between neighbouring rails are exactly ruled, degree 3 x 1).
    The seam rail (0, 0) is the paper curve itself, within ~1e-5 mm. Sweeping with
    ``MakePipeShell`` instead gives degree-11 surfaces that mesh 10-100x slower.
    """
    from OCP.BRepBuilderAPI import BRepBuilderAPI_MakeSolid, BRepBuilderAPI_Sewing
    from OCP.BRepFill import BRepFill
    from OCP.TopoDS import TopoDS

    n = max(4, math.ceil(length_mm / PAPER_SAMPLE_MM))
    xs = [length_mm * i / n for i in range(n + 1)]
    step = 1e-4

    def rail(u: float, v: float) -> cq.Edge:
        pts = [cq.Vector(*_paper_rail(x, u, v)) for x in xs]
        ends = []
        for x in (0.0, length_mm):
            a, b = _paper_rail(x - step, u, v), _paper_rail(x + step, u, v)
            ends.append(cq.Vector(*((q - p) / (2 * step) for p, q in zip(a, b, strict=True))))
        return cq.Edge.makeSpline(pts, tangents=ends, parameters=xs, scale=False, tol=1e-9)

    solids: list[cq.Solid] = []
    rails: dict[tuple[float, float], cq.Edge] = {}
    for profile in profiles:
        edges = [rail(u, v) for u, v in profile]
        rails.update({(u, v): e for (u, v), e in zip(profile, edges, strict=True)})
        sewing = BRepBuilderAPI_Sewing(1e-6)
        for a, b in zip(edges, edges[1:] + edges[:1], strict=True):
            sewing.Add(BRepFill.Face_s(a.wrapped, b.wrapped))
        for end in (0.0, 1.0):
            corners = [e.positionAt(end) for e in edges]
            sewing.Add(cq.Face.makeFromWires(cq.Wire.makePolygon(corners, close=True)).wrapped)
        sewing.Perform()
        maker = BRepBuilderAPI_MakeSolid(TopoDS.Shell_s(sewing.SewedShape()))
        solid = cq.Solid(maker.Solid())
        if solid.Volume() < 0:
            solid = cq.Solid(solid.wrapped.Reversed())
        solids.append(solid)
    shape: cq.Shape = solids[0] if len(solids) == 1 else cq.Compound.makeCompound(solids)
    seams: dict[str, list[cq.Edge]] = {}
    for name, uv in seam_uv.items():
        mid = rails[uv].positionAt(0.5)
        seams[name] = [min(shape.Edges(), key=lambda e: (e.positionAt(0.5) - mid).Length)]
    return shape, seams


def _start_frame(wire: cq.Wire) -> tuple[cq.Vector, cq.Vector, cq.Vector]:
    """Origin, u axis and v axis of the profile plane at the start of the path."""
    origin = wire.startPoint()
    tangent = wire.tangentAt(0.0).normalized()
    up = cq.Vector(0, 0, 1)
    v_axis = (up - tangent * up.dot(tangent)).normalized()
    u_axis = v_axis.cross(tangent).normalized()
    return origin, u_axis, v_axis


def sweep(
    profiles: Sequence[Profile],
    path: cq.Wire,
    seam_uv: dict[str, tuple[float, float]],
) -> tuple[cq.Shape, dict[str, list[cq.Edge]]]:
    """Sweep closed profile polygons along the path; return the shape and its seam edges.

    Parameters
    ----------
    profiles : list of (k, 2) sequences of (u, v) in mm
        Closed polygons (last vertex not repeated); one solid each.
    path : cadquery.Wire
    seam_uv : dict of str to (u, v)
        Profile vertices whose swept edges are seams.
    """
    origin, u_axis, v_axis = _start_frame(path)
    solids: list[cq.Solid] = []
    seams: dict[str, list[cq.Edge]] = {}
    for profile in profiles:
        pts = [origin + u_axis * u + v_axis * v for u, v in profile]
        wire = cq.Wire.makePolygon(pts, close=True)
        builder = BRepOffsetAPI_MakePipeShell(path.wrapped)
        builder.SetMode(gp_Dir(0.0, 0.0, 1.0))
        builder.SetTransitionMode(BRepBuilderAPI_RightCorner)
        builder.SetTolerance(SWEEP_TOL_MM, SWEEP_TOL_MM, 1e-4)
        builder.Add(wire.wrapped, False, False)
        builder.Build()
        if not builder.IsDone():
            raise ParamError("path", "the profile could not be swept along the path")
        builder.MakeSolid()
        solid = cq.Solid(builder.Shape())
        if solid.Volume() < 0:
            solid = cq.Solid(solid.wrapped.Reversed())
        solids.append(solid)
        for name, (u, v) in seam_uv.items():
            if not any(abs(pu - u) < 1e-12 and abs(pv - v) < 1e-12 for pu, pv in profile):
                continue
            target = origin + u_axis * u + v_axis * v
            vertex = min(wire.Vertices(), key=lambda vx: (vx.Center() - target).Length)
            seams[name] = _order_along(_generated_edges(builder, vertex), target)
    missing = set(seam_uv) - set(seams)
    if missing:
        raise ValueError(f"seam vertices {sorted(missing)} are not profile vertices")
    shape: cq.Shape = solids[0] if len(solids) == 1 else cq.Compound.makeCompound(solids)
    return shape, seams


def _generated_edges(builder: BRepOffsetAPI_MakePipeShell, vertex: cq.Vertex) -> list[cq.Edge]:
    from OCP.TopAbs import TopAbs_EDGE

    out: list[cq.Edge] = []
    for shape in builder.Generated(vertex.wrapped):
        if shape.ShapeType() == TopAbs_EDGE:
            out.append(cq.Edge(shape))
        else:
            out.extend(cq.Shape.cast(shape).Edges())
    return out


def _order_along(edges: list[cq.Edge], start: cq.Vector) -> list[cq.Edge]:
    """Chain edges starting from the one that touches ``start``."""
    remaining = list(edges)
    ordered: list[cq.Edge] = []
    point = start
    while remaining:

        def gap(e: cq.Edge, point: cq.Vector = point) -> float:
            return min((e.startPoint() - point).Length, (e.endPoint() - point).Length)

        nxt = min(remaining, key=gap)
        remaining.remove(nxt)
        ordered.append(nxt)
        s, e = nxt.startPoint(), nxt.endPoint()
        point = e if (s - point).Length <= (e - point).Length else s
    return ordered


def add_tacks(
    shape: cq.Shape,
    path: cq.Wire,
    tacks: int,
    tack_length_mm: float,
    tack_height_mm: float,
    anchor_uv: tuple[float, float] = (0.0, 0.0),
) -> cq.Shape:
    """Fuse ``tacks`` short cylinders (radius ``tack_height_mm``) onto the seam.

    Tacks sit at arc lengths (i + 1/2) L / n along the path, centred on the profile point
    ``anchor_uv``, with their axes along the local tangent.
    """
    if tacks < 0 or int(tacks) != tacks:
        raise ParamError("tacks", f"must be a whole number >= 0, got {tacks}")
    if tacks == 0:
        return shape
    if not tack_length_mm > 0:
        raise ParamError("tack_length_mm", f"must be > 0, got {tack_length_mm}")
    if not tack_height_mm > 0:
        raise ParamError("tack_height_mm", f"must be > 0, got {tack_height_mm}")
    length = path.Length()
    if tacks * tack_length_mm >= length:
        raise ParamError("tacks", f"{tacks} tacks of {tack_length_mm} mm do not fit on the seam")
    bumps = []
    up = cq.Vector(0, 0, 1)
    for i in range(int(tacks)):
        s = (i + 0.5) / tacks
        centre = path.positionAt(s)
        tangent = path.tangentAt(s).normalized()
        v_axis = (up - tangent * up.dot(tangent)).normalized()
        u_axis = v_axis.cross(tangent)
        centre = centre + u_axis * anchor_uv[0] + v_axis * anchor_uv[1]
        base = centre - tangent * (tack_length_mm / 2)
        bumps.append(cq.Solid.makeCylinder(tack_height_mm, tack_length_mm, base, tangent))
    fused = shape.fuse(*bumps).clean()
    return fused


def finish(
    profiles: Sequence[Profile],
    seam_uv: dict[str, tuple[float, float]],
    params: dict[str, object],
    *,
    path: str,
    seam_length_mm: float | None,
    arc_radius_mm: float,
    corner_angle_deg: float,
    tacks: int,
    tack_length_mm: float,
    tack_height_mm: float,
    tack_anchor_uv: tuple[float, float] = (0.0, 0.0),
) -> Joint:
    """Path, lateral checks, sweep, tacks, validity: the tail every family shares."""
    wire = path_wire(path, seam_length_mm, arc_radius_mm, corner_angle_deg)
    check_lateral_extent(path, profiles, seam_length_mm, arc_radius_mm, corner_angle_deg)
    if path == "paper":
        shape, seams = sweep_paper(profiles, default_length(path, seam_length_mm), seam_uv)
    else:
        shape, seams = sweep(profiles, wire, seam_uv)
    solid = add_tacks(shape, wire, tacks, tack_length_mm, tack_height_mm, tack_anchor_uv)
    if not solid.isValid():
        raise ParamError("path", "these parameters make an invalid solid")
    return Joint(solid=solid, seams=seams, seam_solid=shape, params=dict(params))


#: The path and tack keywords every swept joint's ``build()`` takes, passed on to :func:`finish`.
PATH_KEYS = (
    "path",
    "seam_length_mm",
    "arc_radius_mm",
    "corner_angle_deg",
    "tacks",
    "tack_length_mm",
    "tack_height_mm",
)


def finish_joint(
    profiles: Sequence[Profile],
    seam_uv: dict[str, tuple[float, float]],
    params: dict[str, object],
    tack_anchor_uv: tuple[float, float] = (0.0, 0.0),
) -> Joint:
    """:func:`finish` with the path and tack keywords (:data:`PATH_KEYS`) read from ``params``,
    the ``build()``'s own arguments (``dict(locals())``)."""
    path_keys: dict[str, Any] = {key: params[key] for key in PATH_KEYS}
    return finish(profiles, seam_uv, params, tack_anchor_uv=tack_anchor_uv, **path_keys)


def on_backing(
    plates: Profile, gap_mm: float, plate_width_mm: float, thickness_mm: float, width_mm: float
) -> list[tuple[float, float]]:
    """Two plates across an open root gap, set on a backing strip centred under the gap (the
    weld root at (0, 0), the plates' bottoms at v = 0): the strip's checks, then one outline.

    ``plates`` is the plates' outline from the +u plate's bottom outer corner round to the -u
    plate's (both at v = 0); the strip's corners close it below.
    """
    require(thickness_mm > 0, "backing_thickness_mm", "an open root gap needs a backing strip > 0")
    require(width_mm > gap_mm, "backing_width_mm", f"must be wider than the root gap ({gap_mm} mm)")
    require(
        width_mm / 2 <= gap_mm / 2 + plate_width_mm,
        "backing_width_mm",
        "must not be wider than the plates",
    )
    half = width_mm / 2
    return [(-half, -thickness_mm), (half, -thickness_mm), (half, 0.0), *plates, (-half, 0.0)]


def require(condition: bool, param: str, message: str) -> None:
    """Raise :class:`ParamError` for ``param`` unless ``condition``."""
    if not condition:
        raise ParamError(param, message)


def script_args(argv: Sequence[str] | None = None) -> tuple[dict[str, object], str | None]:
    """A cad script's command line, ``[key=value ...] [--step OUT.step]``: the keyword arguments
    of its ``build()`` (numbers where they parse) and the STEP file to write, if any."""
    import sys

    args = list(sys.argv[1:] if argv is None else argv)
    out = None
    if "--step" in args:
        i = args.index("--step")
        out = args[i + 1]
        del args[i : i + 2]
    params: dict[str, object] = {}
    for arg in args:
        key, _, text = arg.partition("=")
        value: object
        try:
            value = int(text)
        except ValueError:
            try:
                value = float(text)
            except ValueError:
                value = text
        params[key] = value
    return params, out


def run_script(build, argv: Sequence[str] | None = None) -> None:  # type: ignore[no-untyped-def]
    """Command line of a joint script: ``python cad/x.py [key=value ...] [--step OUT.step]``."""
    params, out = script_args(argv)
    joint = build(**params)
    print(joint.summary())
    if out:
        cq.exporters.export(joint.solid, out)
        print(f"wrote {out}")
