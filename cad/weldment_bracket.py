"""Weldment: a bracket of five plates with fillet, lap and butt joints.

Run alone: ``python cad/weldment_bracket.py [key=value ...] [--step out.step]`` prints a
summary (and exports a STEP assembly of the bodies). ``build(**params)`` returns a
:class:`seamtrack.cad.kit.cadweldment.Weldment`.

Bodies (mm; every plate runs ``length_mm`` along +X from x = 0 unless said otherwise):

- ``base``: 80 wide (y = -40..40), ``plate_mm`` thick, top at z = 0; its +Y edge is bevelled
  for a single-V butt joint (``groove_angle_deg`` included, ``root_face_mm`` at the bottom);
- ``extension``: 30 wide (y = 40..70), bevelled to match: butt joint with the base, root faces
  ``root_gap_mm`` apart about y = 40 (the groove's root line is y = 40, z = root_face_mm -
  plate_mm; its root side, y = 40 on the bottom face, shows the gap);
- ``web``: upright on the base, y = -5..5, ``web_height_mm`` tall: two fillets at y = -+5,
  the one at y = +5 interrupted by the gusset;
- ``gusset``: a right triangle 10 thick (x = length/2 -+ 5) in the corner between the web's
  +Y face and the base, legs 25 along the base (y = 5..30) and 30 up the web: fillets on both
  sides against the base and against the web, and end returns at its toe and its top;
- ``strap``: a ``strap_mm`` sheet lying on the base's -Y edge (y = -60..-30), overlapping it
  by 10: lap joint, the strap's edge on the base at y = -30 and the base's edge under the strap
  at y = -40.
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
    length_mm: float = 120.0,
    plate_mm: float = 10.0,
    web_height_mm: float = 40.0,
    groove_angle_deg: float = 60.0,
    root_face_mm: float = 2.0,
    root_gap_mm: float = 1.0,
    strap_mm: float = 6.0,
) -> cadweldment.Weldment:
    """Build the bracket; see the module docstring for the parameters' meaning."""
    params = dict(locals())
    cadweldment.require(length_mm >= 40, "length_mm", f"must be >= 40, got {length_mm}")
    cadweldment.require(0 < plate_mm <= 20, "plate_mm", f"must be in (0, 20], got {plate_mm}")
    cadweldment.require(
        web_height_mm > 30, "web_height_mm", f"must exceed the gusset (30), got {web_height_mm}"
    )
    cadweldment.require(
        20 <= groove_angle_deg <= 90,
        "groove_angle_deg",
        f"must be in [20, 90], got {groove_angle_deg}",
    )
    cadweldment.require(
        0 < root_face_mm < plate_mm,
        "root_face_mm",
        f"must be in (0, plate_mm), got {root_face_mm}",
    )
    cadweldment.require(0 < strap_mm <= 20, "strap_mm", f"must be in (0, 20], got {strap_mm}")
    cadweldment.require(
        0 <= root_gap_mm <= 4, "root_gap_mm", f"must be in [0, 4], got {root_gap_mm}"
    )
    t, c, g = plate_mm, root_face_mm, root_gap_mm / 2
    bevel = (t - c) * math.tan(math.radians(groove_angle_deg) / 2)  # width of each bevel's top
    cadweldment.require(
        bevel + g < 10, "groove_angle_deg", "the groove would reach the gusset's toe"
    )
    x = (0.0, length_mm)
    mid = length_mm / 2
    base = [(-40.0, -t), (40 - g, -t), (40 - g, c - t), (40 - g - bevel, 0.0), (-40.0, 0.0)]
    extension = [(40 + g, -t), (70.0, -t), (70.0, 0.0), (40 + g + bevel, 0.0), (40 + g, c - t)]
    return Weldment(
        bodies={
            "base": cadweldment.prism(base, x),
            "extension": cadweldment.prism(extension, x),
            "web": cadweldment.box(x, (-5.0, 5.0), (0.0, web_height_mm)),
            "gusset": cadweldment.prism([(5.0, 0.0), (30.0, 0.0), (5.0, 30.0)], (mid - 5, mid + 5)),
            "strap": cadweldment.box(x, (-60.0, -30.0), (0.0, strap_mm)),
        },
        params=params,
    )


if __name__ == "__main__":
    cadweldment.run_script(build)
elif "show_object" in globals():
    show_object(build().compound())  # type: ignore[name-defined]  # noqa: F821
