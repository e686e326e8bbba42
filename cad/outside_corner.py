"""Outside corner joint: two plates meeting at 90 deg edge to edge, leaving an outside V groove.

Run alone: ``python cad/outside_corner.py [key=value ...] [--step out.step]`` prints a summary
(and exports STEP); in CQ-editor the part is shown. ``build(**params)`` returns a
:class:`seamtrack.cad.kit.cadpaths.Joint`: ``.solid`` (cadquery Shape, mm), ``.seams`` (``{"root":
[edges in order along the seam]}``), ``.seam_solid`` (the part before tack welds).

Cross-section (profile plane, v up, u across; see ``cadpaths``): a roof of two square-cut plates
(``plate_thickness_mm``, ``plate_width_mm`` along each plate), each sloping down at 45 deg. The
plates overlap over ``root_face_mm`` of their thickness at the inner corner, so their end faces
form a 90 deg V groove on the outside whose bottom is the seam (at the origin); the torch
direction there is straight up, the bisector of the two end faces.
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
    plate_thickness_mm: float = 6.0,
    plate_width_mm: float = 40.0,
    root_face_mm: float = 2.0,
    path: str = "straight",
    seam_length_mm: float | None = None,
    arc_radius_mm: float = 100.0,
    corner_angle_deg: float = 90.0,
    tacks: int = 0,
    tack_length_mm: float = 8.0,
    tack_height_mm: float = 1.5,
) -> cadpaths.Joint:
    """Build the outside corner joint; see the module docstring for the parameters' meaning."""
    params = dict(locals())
    t, w, f = plate_thickness_mm, plate_width_mm, root_face_mm
    cadpaths.require(t > 0, "plate_thickness_mm", f"must be > 0, got {t}")
    cadpaths.require(0 < f < t, "root_face_mm", f"must be in (0, plate_thickness_mm), got {f}")
    cadpaths.require(w > t, "plate_width_mm", f"must exceed the plate thickness, got {w}")
    e = t - f  # depth of the V along each end face
    r2 = math.sqrt(0.5)

    # Right plate frame: along (r2, -r2) (down the roof), outward normal (r2, r2).
    def right(x: float, y: float) -> tuple[float, float]:
        return (r2 * (x + y), r2 * (y - x))

    half = [right(0.0, e), right(w, e), right(w, -f), right(f, -f)]
    left = [(-u, v) for u, v in half]
    # Both halves end at the inner corner (0, -sqrt(2) f): keep it once.
    profile = [(0.0, 0.0), *half, *list(reversed(left))[1:]]
    return cadpaths.finish_joint([profile], {"root": (0.0, 0.0)}, params)


if __name__ == "__main__":
    cadpaths.run_script(build)
elif "show_object" in globals():
    show_object(build().solid)  # type: ignore[name-defined]  # noqa: F821
