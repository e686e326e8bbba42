"""Narrow-gap butt joint: two thick plates with near-vertical walls on a backing bar.

Run alone: ``python cad/narrow_gap.py [key=value ...] [--step out.step]`` prints a summary (and
exports STEP); in CQ-editor the part is shown. ``build(**params)`` returns a
:class:`seamtrack.cad.kit.cadpaths.Joint`: ``.solid`` (cadquery Shape, mm), ``.seams`` (``{"root":
[edges in order along the seam]}``), ``.seam_solid`` (the part before tack welds).

Cross-section (profile plane, v up, u across; see ``cadpaths``): two plates of
``plate_thickness_mm`` (the groove's depth) and ``plate_width_mm`` each, their walls
``wall_angle_deg`` off vertical (each), ``gap_mm`` apart at the bottom, standing on a backing bar
of ``backing_thickness_mm`` x ``backing_width_mm`` centred under the gap. The groove is
``gap_mm + 2 * plate_thickness_mm * tan(wall_angle)`` wide at the top. The seam is the centre of
the gap on the backing bar (the weld root); the torch direction there is the bar's normal.
Defaults: walls 4 deg off vertical, 25 mm deep, 12 mm wide at the bottom (a narrow-gap GMAW
groove for heavy plate, filled in many passes, two or three beads a layer).
"""

from __future__ import annotations

import math

try:
    from seamtrack.cad.kit import cadpaths
except ImportError:  # run from a copy of cad/ without seamtrack installed
    from kit import cadpaths  # type: ignore[no-redef]

Joint = cadpaths.Joint


def build(
    *,
    plate_thickness_mm: float = 25.0,
    plate_width_mm: float = 50.0,
    gap_mm: float = 12.0,
    wall_angle_deg: float = 4.0,
    backing_thickness_mm: float = 10.0,
    backing_width_mm: float = 40.0,
    path: str = "straight",
    seam_length_mm: float | None = None,
    arc_radius_mm: float = 200.0,
    corner_angle_deg: float = 90.0,
    tacks: int = 0,
    tack_length_mm: float = 8.0,
    tack_height_mm: float = 1.5,
) -> cadpaths.Joint:
    """Build the narrow-gap joint; see the module docstring for the parameters' meaning."""
    params = dict(locals())
    t, w, g = plate_thickness_mm, plate_width_mm, gap_mm
    cadpaths.require(t > 0, "plate_thickness_mm", f"must be > 0, got {t}")
    cadpaths.require(g > 0, "gap_mm", f"must be > 0, got {g}")
    cadpaths.require(
        0 <= wall_angle_deg < 45,
        "wall_angle_deg",
        f"must be in [0, 45) (off vertical), got {wall_angle_deg}",
    )
    flare = t * math.tan(math.radians(wall_angle_deg))
    cadpaths.require(
        flare < w,
        "plate_width_mm",
        f"the wall leans {flare:.2f} mm; plates must be wider than that",
    )
    h = g / 2
    plates = [
        (h + w, 0.0),
        (h + w, t),
        (h + flare, t),
        (h, 0.0),
        (0.0, 0.0),
        (-h, 0.0),
        (-h - flare, t),
        (-h - w, t),
        (-h - w, 0.0),
    ]
    profile = cadpaths.on_backing(plates, g, w, backing_thickness_mm, backing_width_mm)
    return cadpaths.finish_joint([profile], {"root": (0.0, 0.0)}, params, (0.0, 0.0))


if __name__ == "__main__":
    cadpaths.run_script(build)
elif "show_object" in globals():
    show_object(build().solid)  # type: ignore[name-defined]  # noqa: F821
