"""Square butt joint: two square-edged plates, root gap on a backing strip, high-low misalignment.

Run alone: ``python cad/square_butt.py [key=value ...] [--step out.step]`` prints a summary (and
exports STEP); in CQ-editor the part is shown. ``build(**params)`` returns a
:class:`seamtrack.cad.kit.cadpaths.Joint`: ``.solid`` (cadquery Shape, mm), ``.seams`` (``{"root":
[edges in order along the seam]}``), ``.seam_solid`` (the part before tack welds).

Cross-section (profile plane, v up, u across; see ``cadpaths``): the plate on the -u side has
``plate_thickness_mm``; the plate on the +u side is ``misalignment_mm`` thicker (its top stands
higher, bottoms flush: "high-low"). With a ``root_gap_mm`` > 0 the plates sit on a backing
strip and the seam is the centre of the gap on the backing (the weld root). Without a gap the
plates are fused and the seam is the top corner of the thinner plate at the joint (a plain
split line in the top face when there is no misalignment either).
"""

from __future__ import annotations

try:
    from seamtrack.cad.kit import cadpaths
except ImportError:  # run from a copy of cad/ without seamtrack installed
    from kit import cadpaths  # type: ignore[no-redef]

Joint = cadpaths.Joint


def build(
    *,
    plate_thickness_mm: float = 10.0,
    plate_width_mm: float = 50.0,
    root_gap_mm: float = 1.0,
    misalignment_mm: float = 0.0,
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
    """Build the square butt joint; see the module docstring for the parameters' meaning."""
    params = dict(locals())
    t, w, g, m = plate_thickness_mm, plate_width_mm, root_gap_mm, misalignment_mm
    cadpaths.require(t > 0, "plate_thickness_mm", f"must be > 0, got {t}")
    cadpaths.require(w > 0, "plate_width_mm", f"must be > 0, got {w}")
    cadpaths.require(g >= 0, "root_gap_mm", f"must be >= 0, got {g}")
    cadpaths.require(g < w, "root_gap_mm", f"{g} mm is larger than the plate ({w} mm)")
    cadpaths.require(m >= 0, "misalignment_mm", f"must be >= 0, got {m}")
    h = g / 2
    if g == 0:
        # Seam at the top of the joint (0, 0); plates fused along their square edges.
        profile = [(-w, -t), (w, -t), (w, m), (0.0, m), (0.0, 0.0), (-w, 0.0)]
        if m == 0:
            profile = [(-w, -t), (w, -t), (w, 0.0), (0.0, 0.0), (-w, 0.0)]
        anchor = (0.0, 0.0)
    else:
        plates = [
            (h + w, 0.0),
            (h + w, t + m),
            (h, t + m),
            (h, 0.0),
            (0.0, 0.0),
            (-h, 0.0),
            (-h, t),
            (-h - w, t),
            (-h - w, 0.0),
        ]
        profile = cadpaths.on_backing(plates, g, w, backing_thickness_mm, backing_width_mm)
        anchor = (0.0, t)
    return cadpaths.finish_joint([profile], {"root": (0.0, 0.0)}, params, anchor)


if __name__ == "__main__":
    cadpaths.run_script(build)
elif "show_object" in globals():
    show_object(build().solid)  # type: ignore[name-defined]  # noqa: F821
