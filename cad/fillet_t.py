"""Fillet-welded T joint: a web standing on a flange, optionally tilted, optionally with a gap.

Run alone: ``python cad/fillet_t.py [key=value ...] [--step out.step]`` prints a summary (and
exports STEP); in CQ-editor the part is shown. ``build(**params)`` returns a
:class:`seamtrack.cad.kit.cadpaths.Joint`: ``.solid`` (cadquery Shape, mm), ``.seams`` (``{"root":
[...], "root_opposite": [...]}``, edges in order along the seam), ``.seam_solid`` (the part
before tack welds).

Cross-section (profile plane, v up, u across; see ``cadpaths``): a flange plate
(``flange_width_mm`` x ``flange_thickness_mm``) with its top at v = 0; a web of
``web_thickness_mm`` and ``web_height_mm`` (measured along the web) standing at
``web_angle_deg`` from the flange (90 = upright; smaller leans the web over the ``root`` side),
``web_gap_mm`` above the flange. The ``root`` seam is the fillet corner on the -u side of the
web (on the path); ``root_opposite`` is the other corner. With a gap the flange and web are two
solids in one compound and the seams are the lines on the flange top under the web's faces;
the torch direction there is the flange normal.
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
    flange_thickness_mm: float = 10.0,
    flange_width_mm: float = 100.0,
    web_thickness_mm: float = 10.0,
    web_height_mm: float = 50.0,
    web_angle_deg: float = 90.0,
    web_gap_mm: float = 0.0,
    path: str = "straight",
    seam_length_mm: float | None = None,
    arc_radius_mm: float = 100.0,
    corner_angle_deg: float = 90.0,
    tacks: int = 0,
    tack_length_mm: float = 8.0,
    tack_height_mm: float = 1.5,
) -> cadpaths.Joint:
    """Build the T joint; see the module docstring for the parameters' meaning."""
    params = dict(locals())
    tf, wf, tw, hw, g = (
        flange_thickness_mm,
        flange_width_mm,
        web_thickness_mm,
        web_height_mm,
        web_gap_mm,
    )
    for name, value in (
        ("flange_thickness_mm", tf),
        ("flange_width_mm", wf),
        ("web_thickness_mm", tw),
        ("web_height_mm", hw),
    ):
        cadpaths.require(value > 0, name, f"must be > 0, got {value}")
    cadpaths.require(
        30 <= web_angle_deg <= 150, "web_angle_deg", f"must be in [30, 150], got {web_angle_deg}"
    )
    cadpaths.require(g >= 0, "web_gap_mm", f"must be >= 0, got {g}")
    angle = math.radians(web_angle_deg)
    foot = tw / math.sin(angle)  # width of the web's horizontal foot
    lean = (-hw * math.cos(angle), hw * math.sin(angle))  # web direction (upright: (0, h))
    cadpaths.require(
        wf > foot + 2 * abs(lean[0]) + 1e-9,
        "flange_width_mm",
        f"the flange must be wider than the web's footprint ({foot + 2 * abs(lean[0]):.1f} mm)",
    )
    lo, hi = foot / 2 - wf / 2, foot / 2 + wf / 2  # flange centred under the web's foot
    web = [(0.0, g), (foot, g), (foot + lean[0], g + lean[1]), (lean[0], g + lean[1])]
    if g == 0:
        profiles = [[(lo, -tf), (hi, -tf), (hi, 0.0), *web[1:], web[0], (lo, 0.0)]]
    else:
        flange = [(lo, -tf), (hi, -tf), (hi, 0.0), (foot, 0.0), (0.0, 0.0), (lo, 0.0)]
        profiles = [flange, web]
    return cadpaths.finish_joint(
        profiles, {"root": (0.0, 0.0), "root_opposite": (foot, 0.0)}, params
    )


if __name__ == "__main__":
    cadpaths.run_script(build)
elif "show_object" in globals():
    show_object(build().solid)  # type: ignore[name-defined]  # noqa: F821
