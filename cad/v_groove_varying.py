"""Single-V groove whose root gap varies along a straight seam (a fit-up that wanders).

Run alone: ``python cad/v_groove_varying.py [key=value ...] [--step out.step]`` prints a summary
(and exports STEP); in CQ-editor the part is shown. ``build(**params)`` returns a
:class:`seamtrack.cad.kit.cadpaths.Joint`: ``.solid`` (cadquery Shape, mm), ``.seams`` (``{"root":
[edges in order along the seam]}``), ``.seam_solid`` (the part itself, no tacks).

Cross-section at ``x`` along the seam (+X from the origin; u = +Y across, v = +Z up): two plates
of ``plate_thickness_mm`` bevelled to an included ``groove_angle_deg`` down to a
``root_face_mm``, on a backing strip, with a root gap

    g(x) = root_gap_mm + gap_amplitude_mm * sin(2 pi gap_periods x / seam_length_mm)

so the whole groove is ``2 * gap_amplitude_mm`` wider or narrower than nominal along the seam
(each plate moves by half of it; the bevel angle stays). The plates are lofted through sections
every ``section_step_mm`` with ruled faces between them (chordal error of the sine
``amplitude * (2 pi periods / L)^2 * step^2 / 16``, 1e-3 mm at the defaults). The seam is the
centre of the gap on the backing (the weld root), a straight line; the torch direction there is
the backing's normal. Straight seams only.
"""

from __future__ import annotations

import math

import cadquery as cq

try:
    from seamtrack.cad.kit import cadpaths
except ImportError:  # run from a copy of cad/ without seamtrack installed
    from kit import cadpaths  # type: ignore[no-redef]

Joint = cadpaths.Joint


def gap_at(x_mm: float, params: dict[str, float]) -> float:
    """The root gap (mm) at ``x_mm`` along the seam."""
    phase = 2 * math.pi * params["gap_periods"] * x_mm / params["seam_length_mm"]
    return params["root_gap_mm"] + params["gap_amplitude_mm"] * math.sin(phase)


def build(
    *,
    plate_thickness_mm: float = 20.0,
    plate_width_mm: float = 50.0,
    groove_angle_deg: float = 60.0,
    root_gap_mm: float = 4.0,
    gap_amplitude_mm: float = 2.0,
    gap_periods: float = 1.0,
    root_face_mm: float = 1.0,
    backing_thickness_mm: float = 6.0,
    backing_width_mm: float = 30.0,
    seam_length_mm: float = 300.0,
    section_step_mm: float = 5.0,
) -> cadpaths.Joint:
    """Build the varying-gap V-groove; see the module docstring for the parameters' meaning."""
    params = dict(locals())
    t, w, f, length = plate_thickness_mm, plate_width_mm, root_face_mm, seam_length_mm
    amp = gap_amplitude_mm
    cadpaths.require(t > 0, "plate_thickness_mm", f"must be > 0, got {t}")
    cadpaths.require(length > 0, "seam_length_mm", f"must be > 0, got {length}")
    cadpaths.require(
        0 < groove_angle_deg < 180,
        "groove_angle_deg",
        f"must be in (0, 180), got {groove_angle_deg}",
    )
    cadpaths.require(0 <= f < t, "root_face_mm", f"must be in [0, plate_thickness_mm), got {f}")
    cadpaths.require(amp >= 0, "gap_amplitude_mm", f"must be >= 0, got {amp}")
    cadpaths.require(
        root_gap_mm - amp > 0,
        "gap_amplitude_mm",
        f"the gap must stay open: root_gap_mm - gap_amplitude_mm = {root_gap_mm - amp} <= 0",
    )
    cadpaths.require(0 < section_step_mm <= length, "section_step_mm", f"must be in (0, {length}]")
    cadpaths.require(
        backing_width_mm > root_gap_mm + amp,
        "backing_width_mm",
        f"must be wider than the widest gap ({root_gap_mm + amp} mm)",
    )
    bevel = (t - f) * math.tan(math.radians(groove_angle_deg) / 2)
    cadpaths.require(bevel < w, "plate_width_mm", f"plates must be wider than the bevel ({bevel})")
    outer = (root_gap_mm + amp) / 2 + w  # plate outer faces stay put: the plates' width varies
    b = backing_width_mm / 2

    def section(x: float) -> cq.Wire:
        h = gap_at(x, params) / 2
        outline = [
            (-b, -backing_thickness_mm),
            (b, -backing_thickness_mm),
            (b, 0.0),
            (outer, 0.0),
            (outer, t),
            (h + bevel, t),
            (h, f),
            (h, 0.0),
            (0.0, 0.0),
            (-h, 0.0),
            (-h, f),
            (-h - bevel, t),
            (-outer, t),
            (-outer, 0.0),
            (-b, 0.0),
        ]
        return cq.Wire.makePolygon([cq.Vector(x, u, v) for u, v in outline], close=True)

    n = max(2, math.ceil(length / section_step_mm) + 1)
    xs = [length * i / (n - 1) for i in range(n)]
    solid = cq.Solid.makeLoft([section(x) for x in xs], True)
    if solid.Volume() < 0:
        solid = cq.Solid(solid.wrapped.Reversed())
    if not solid.isValid():
        raise cadpaths.ParamError("seam_length_mm", "these parameters make an invalid solid")
    seam_edges = [
        e
        for e in solid.Edges()
        if all(abs(p.y) < 1e-9 and abs(p.z) < 1e-9 for p in (e.startPoint(), e.endPoint()))
        and abs(e.startPoint().x - e.endPoint().x) > 1e-9
    ]
    seam_edges.sort(key=lambda e: min(e.startPoint().x, e.endPoint().x))
    return Joint(solid=solid, seams={"root": seam_edges}, seam_solid=solid, params=params)


if __name__ == "__main__":
    cadpaths.run_script(build)
elif "show_object" in globals():
    show_object(build().solid)  # type: ignore[name-defined]  # noqa: F821
