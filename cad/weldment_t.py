"""Weldment: a T of two separate plates, a web standing on a flange (two fillet welds).

Run alone: ``python cad/weldment_t.py [key=value ...] [--step out.step]`` prints a summary (and
exports a STEP assembly of the two bodies). ``build(**params)`` returns a
:class:`seamtrack.cad.kit.cadweldment.Weldment` with the bodies ``flange`` and ``web``.

Geometry (mm): the flange is ``flange_width_mm`` wide (across Y, centred on y = 0),
``flange_thickness_mm`` thick with its top at z = 0, and ``length_mm`` long along +X from
x = 0. The web (``web_thickness_mm`` thick, ``web_height_mm`` measured along the web) stands on
it over the whole length, its foot centred on y = 0, tilted by ``web_angle_deg`` from the
flange (90 = upright; smaller leans it towards -Y), ``web_gap_mm`` above the flange. The lines
of contact (the fillet seams) are y = -f/2 and y = +f/2 on z = 0, with f = web_thickness_mm /
sin(web_angle_deg) the width of the web's foot.
"""

from __future__ import annotations

import math

try:
    from seamtrack.cad.kit import cadweldment
except ImportError:  # run from a copy of cad/ without seamtrack installed
    from kit import cadweldment  # type: ignore[no-redef]

Weldment = cadweldment.Weldment


def build(
    *,
    flange_thickness_mm: float = 10.0,
    flange_width_mm: float = 80.0,
    web_thickness_mm: float = 10.0,
    web_height_mm: float = 40.0,
    web_angle_deg: float = 90.0,
    web_gap_mm: float = 0.0,
    length_mm: float = 100.0,
) -> cadweldment.Weldment:
    """Build the T; see the module docstring for the parameters' meaning."""
    params = dict(locals())
    for name in ("flange_thickness_mm", "flange_width_mm", "web_thickness_mm", "web_height_mm"):
        cadweldment.require(params[name] > 0, name, f"must be > 0, got {params[name]}")
    cadweldment.require(length_mm > 0, "length_mm", f"must be > 0, got {length_mm}")
    cadweldment.require(
        30 <= web_angle_deg <= 150, "web_angle_deg", f"must be in [30, 150], got {web_angle_deg}"
    )
    cadweldment.require(web_gap_mm >= 0, "web_gap_mm", f"must be >= 0, got {web_gap_mm}")
    angle = math.radians(web_angle_deg)
    foot = web_thickness_mm / math.sin(angle)
    lean = (-web_height_mm * math.cos(angle), web_height_mm * math.sin(angle))
    cadweldment.require(
        flange_width_mm / 2 > foot / 2 + abs(lean[0]),
        "flange_width_mm",
        f"the flange must be wider than the web's footprint ({foot + 2 * abs(lean[0]):.1f} mm)",
    )
    g = web_gap_mm
    web = [
        (-foot / 2, g),
        (foot / 2, g),
        (foot / 2 + lean[0], g + lean[1]),
        (-foot / 2 + lean[0], g + lean[1]),
    ]
    return Weldment(
        bodies={
            "flange": cadweldment.box(
                (0.0, length_mm),
                (-flange_width_mm / 2, flange_width_mm / 2),
                (-flange_thickness_mm, 0.0),
            ),
            "web": cadweldment.prism(web, (0.0, length_mm)),
        },
        params=params,
    )


if __name__ == "__main__":
    cadweldment.run_script(build)
elif "show_object" in globals():
    show_object(build().compound())  # type: ignore[name-defined]  # noqa: F821
