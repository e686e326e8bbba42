"""Weldment: a base plate with parallel uprights, each a separate solid (two fillets each).

The kind of part a welding demo cell uses: fillets 10 mm apart on either side of an upright,
the next upright's fillets beyond, so a sensor set up for one fillet must not report its
neighbour. Run alone: ``python cad/weldment_uprights.py [key=value ...] [--step out.step]``.
``build(**params)`` returns a :class:`seamtrack.cad.kit.cadweldment.Weldment` with the bodies
``base``, ``upright1`` ... ``uprightN`` (from -Y to +Y).

Geometry (mm): the base is ``base_width_mm`` wide (across Y, centred on y = 0),
``base_thickness_mm`` thick with its top at z = 0, ``length_mm`` long along +X from x = 0. The
``uprights`` (``upright_thickness_mm`` thick, ``upright_height_mm`` tall) run its whole length,
``spacing_mm`` apart centre to centre, centred on y = 0; their fillets lie on z = 0 at
y = c -+ upright_thickness_mm / 2 for each upright centre c.
"""

from __future__ import annotations

try:
    from seamtrack.cad.kit import cadweldment
except ImportError:  # run from a copy of cad/ without seamtrack installed
    from kit import cadweldment  # type: ignore[no-redef]

Weldment = cadweldment.Weldment


def build(
    *,
    base_width_mm: float = 100.0,
    base_thickness_mm: float = 10.0,
    uprights: int = 3,
    upright_thickness_mm: float = 10.0,
    upright_height_mm: float = 40.0,
    spacing_mm: float = 30.0,
    length_mm: float = 80.0,
) -> cadweldment.Weldment:
    """Build the part; see the module docstring for the parameters' meaning."""
    params = dict(locals())
    for name in ("base_width_mm", "base_thickness_mm", "upright_thickness_mm", "length_mm"):
        cadweldment.require(params[name] > 0, name, f"must be > 0, got {params[name]}")
    cadweldment.require(
        upright_height_mm > 0, "upright_height_mm", f"must be > 0, got {upright_height_mm}"
    )
    cadweldment.require(
        uprights >= 1 and int(uprights) == uprights,
        "uprights",
        f"must be a whole number >= 1, got {uprights}",
    )
    count = int(uprights)
    cadweldment.require(
        spacing_mm > upright_thickness_mm or count == 1,
        "spacing_mm",
        f"uprights overlap: spacing {spacing_mm} <= thickness {upright_thickness_mm}",
    )
    span = (count - 1) * spacing_mm + upright_thickness_mm
    cadweldment.require(
        span < base_width_mm, "base_width_mm", f"the uprights span {span:.1f} mm; widen the base"
    )
    bodies = {
        "base": cadweldment.box(
            (0.0, length_mm), (-base_width_mm / 2, base_width_mm / 2), (-base_thickness_mm, 0.0)
        )
    }
    for i in range(count):
        centre = (i - (count - 1) / 2) * spacing_mm
        half = upright_thickness_mm / 2
        bodies[f"upright{i + 1}"] = cadweldment.box(
            (0.0, length_mm), (centre - half, centre + half), (0.0, upright_height_mm)
        )
    return Weldment(bodies=bodies, params=params)


if __name__ == "__main__":
    cadweldment.run_script(build)
elif "show_object" in globals():
    show_object(build().compound())  # type: ignore[name-defined]  # noqa: F821
