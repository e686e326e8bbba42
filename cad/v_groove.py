"""Single-V groove butt joint: two bevelled plates, optional root gap on a backing strip.

Run alone: ``python cad/v_groove.py [key=value ...] [--step out.step]`` prints a summary (and
exports STEP); in CQ-editor the part is shown. ``build(**params)`` returns a
:class:`seamtrack.cad.kit.cadpaths.Joint`: ``.solid`` (cadquery Shape, mm), ``.seams`` (``{"root":
[edges in order along the seam]}``), ``.seam_solid`` (the part before tack welds).

Cross-section (profile plane, v up, u across; see ``cadpaths``): plates of ``plate_thickness_mm``
and ``plate_width_mm`` each, bevelled to an included ``groove_angle_deg`` down to a
``root_face_mm``. With ``root_gap_mm = 0`` the root faces touch (one fused solid) and the seam
is the V bottom, the edge between the two bevel faces. With a root gap the plates sit on a
backing strip and the seam is the centre of the gap on the backing (the weld root); the torch
direction there is the backing's normal.
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
    plate_thickness_mm: float = 10.0,
    plate_width_mm: float = 50.0,
    groove_angle_deg: float = 60.0,
    root_gap_mm: float = 0.0,
    root_face_mm: float = 1.0,
    backing_thickness_mm: float = 3.0,
    backing_width_mm: float = 20.0,
    path: str = "straight",
    seam_length_mm: float | None = None,
    arc_radius_mm: float = 100.0,
    corner_angle_deg: float = 90.0,
    tacks: int = 0,
    tack_length_mm: float = 8.0,
    tack_height_mm: float = 1.5,
) -> cadpaths.Joint:
    """Build the V-groove joint; see the module docstring for the parameters' meaning."""
    params = dict(locals())
    t, w, g, f = plate_thickness_mm, plate_width_mm, root_gap_mm, root_face_mm
    cadpaths.require(t > 0, "plate_thickness_mm", f"must be > 0, got {t}")
    cadpaths.require(
        0 < groove_angle_deg < 180,
        "groove_angle_deg",
        f"must be in (0, 180), got {groove_angle_deg}",
    )
    cadpaths.require(0 <= f < t, "root_face_mm", f"must be in [0, plate_thickness_mm), got {f}")
    cadpaths.require(g >= 0, "root_gap_mm", f"must be >= 0, got {g}")
    cadpaths.require(g < w, "root_gap_mm", f"{g} mm is larger than the plate ({w} mm)")
    cadpaths.require(
        g > 0 or f > 0,
        "root_face_mm",
        "with no root gap the root face must be > 0 (the plates would touch along a line only)",
    )
    bevel = (t - f) * math.tan(math.radians(groove_angle_deg) / 2)
    cadpaths.require(
        bevel < w,
        "plate_width_mm",
        f"the bevel is {bevel:.2f} mm wide; plates must be wider than that",
    )
    h = g / 2
    if g == 0:
        # Seam at the V bottom (0, 0); plates fused along the root face.
        profile = [
            (-w, -f),
            (w, -f),
            (w, t - f),
            (bevel, t - f),
            (0.0, 0.0),
            (-bevel, t - f),
            (-w, t - f),
        ]
        profiles = [profile]
        anchor = (0.0, 0.0)
    else:
        # Seam at the gap centre on the backing (0, 0); plate bottoms at v = 0.
        plates = [
            (h + w, 0.0),
            (h + w, t),
            (h + bevel, t),
            (h, f),
            (h, 0.0),
            (0.0, 0.0),
            (-h, 0.0),
            (-h, f),
            (-h - bevel, t),
            (-h - w, t),
            (-h - w, 0.0),
        ]
        profiles = [cadpaths.on_backing(plates, g, w, backing_thickness_mm, backing_width_mm)]
        anchor = (0.0, f)
    return cadpaths.finish_joint(profiles, {"root": (0.0, 0.0)}, params, anchor)


if __name__ == "__main__":
    cadpaths.run_script(build)
elif "show_object" in globals():
    show_object(build().solid)  # type: ignore[name-defined]  # noqa: F821
