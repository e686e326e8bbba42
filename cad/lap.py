"""Lap joint: a top sheet lying over a bottom sheet; the seam is the top sheet's edge.

Run alone: ``python cad/lap.py [key=value ...] [--step out.step]`` prints a summary (and exports
STEP); in CQ-editor the part is shown. ``build(**params)`` returns a
:class:`seamtrack.cad.kit.cadpaths.Joint`: ``.solid`` (cadquery Shape, mm), ``.seams`` (``{"root":
[edges in order along the seam]}``), ``.seam_solid`` (the part before tack welds).

Cross-section (profile plane, v up, u across; see ``cadpaths``): the bottom sheet
(``bottom_thickness_mm``) has its top at v = 0 and spans ``sheet_width_mm``, reaching
``overlap_mm`` under the top sheet (+u side); the top sheet (``top_thickness_mm``,
``sheet_width_mm`` wide) starts at u = 0, ``sheet_gap_mm`` above the bottom sheet. The seam is
the corner between the top sheet's edge face and the bottom sheet's top face. With a gap the
sheets are two solids in one compound and the seam is the line on the bottom sheet under the
top sheet's edge; the torch direction there is the bottom sheet's normal.
"""

from __future__ import annotations

try:
    from seamtrack.cad.kit import cadpaths
except ImportError:  # run from a copy of cad/ without seamtrack installed
    from kit import cadpaths  # type: ignore[no-redef]

Joint = cadpaths.Joint


def build(
    *,
    bottom_thickness_mm: float = 3.0,
    top_thickness_mm: float = 3.0,
    sheet_width_mm: float = 50.0,
    overlap_mm: float = 20.0,
    sheet_gap_mm: float = 0.0,
    path: str = "straight",
    seam_length_mm: float | None = None,
    arc_radius_mm: float = 100.0,
    corner_angle_deg: float = 90.0,
    tacks: int = 0,
    tack_length_mm: float = 8.0,
    tack_height_mm: float = 1.5,
) -> cadpaths.Joint:
    """Build the lap joint; see the module docstring for the parameters' meaning."""
    params = dict(locals())
    t1, t2, w, o, g = (
        bottom_thickness_mm,
        top_thickness_mm,
        sheet_width_mm,
        overlap_mm,
        sheet_gap_mm,
    )
    cadpaths.require(t1 > 0, "bottom_thickness_mm", f"must be > 0, got {t1}")
    cadpaths.require(t2 > 0, "top_thickness_mm", f"must be > 0, got {t2}")
    cadpaths.require(0 < o < w, "overlap_mm", f"must be in (0, sheet_width_mm), got {o}")
    cadpaths.require(g >= 0, "sheet_gap_mm", f"must be >= 0, got {g}")
    lo = o - w
    top = [(w, g), (w, g + t2), (0.0, g + t2), (0.0, g)]
    if g == 0:
        profiles = [[(lo, -t1), (o, -t1), (o, 0.0), *top, (lo, 0.0)]]
    else:
        profiles = [[(lo, -t1), (o, -t1), (o, 0.0), (0.0, 0.0), (lo, 0.0)], [top[-1], *top[:-1]]]
    return cadpaths.finish_joint(profiles, {"root": (0.0, 0.0)}, params)


if __name__ == "__main__":
    cadpaths.run_script(build)
elif "show_object" in globals():
    show_object(build().solid)  # type: ignore[name-defined]  # noqa: F821
