"""Thermal constants of the metals a scene welds: conductivity (W/(mm K)) and diffusivity
(mm^2/s), with where each value was read.

The values are the tabulated ones at 300 K. Both fall as the plate heats (a carbon steel's
conductivity roughly halves by 800 degC), so a Rosenthal field with them is a room-temperature
estimate; give your own averaged values to :func:`seamtrack.rosenthal_temperature` when the
peak temperatures matter.
"""

from __future__ import annotations

from dataclasses import dataclass

from seamtrack.errors import SeamtrackError

INCROPERA = (
    "Incropera, DeWitt, Bergman, Lavine, Fundamentals of Heat and Mass Transfer, 6th ed. (Wiley "
    "2007), Table A.1, properties at 300 K"
)


@dataclass(frozen=True)
class ThermalMaterial:
    """A metal's thermal constants and the source they were read from."""

    name: str
    conductivity_w_per_mm_k: float
    diffusivity_mm2_per_s: float
    density_kg_m3: float
    specific_heat_j_per_kg_k: float
    source: str
    expansion_per_k: float = 0.0  # linear thermal expansion, 1/K (the distortion models)
    expansion_source: str = ""

    @property
    def volumetric_heat_j_per_mm3_k(self) -> float:
        """rho * c in J/(mm^3 K): conductivity / diffusivity."""
        return self.conductivity_w_per_mm_k / self.diffusivity_mm2_per_s


#: The built-in materials by name. Conductivity k and diffusivity alpha = k / (rho c) as the
#: table gives them (k 60.5, 14.9, 237 W/(m K); alpha 17.7, 3.95, 97.1 x 1e-6 m^2/s); the
#: linear expansion from the handbooks named in ``expansion_source``.
THERMAL_MATERIALS: dict[str, ThermalMaterial] = {
    "carbon_steel": ThermalMaterial(
        "carbon_steel", 0.0605, 17.7, 7854.0, 434.0,
        INCROPERA + ": plain carbon steel (Mn <= 1 %, Si <= 0.1 %)",
        11.7e-6, "ASM Handbook Vol. 1 (1990), AISI 1020, mean over 20-100 degC",
    ),
    "stainless_steel": ThermalMaterial(
        "stainless_steel", 0.0149, 3.95, 7900.0, 477.0, INCROPERA + ": stainless steel AISI 304",
        17.3e-6, "ASM Handbook Vol. 1 (1990), AISI 304, mean over 0-100 degC",
    ),
    "aluminium": ThermalMaterial(
        "aluminium", 0.237, 97.1, 2702.0, 903.0, INCROPERA + ": aluminium, pure",
        23.1e-6, "CRC Handbook of Chemistry and Physics, aluminium at 25 degC",
    ),
}  # fmt: skip


def thermal_material(name: str, *, field: str = "material") -> ThermalMaterial:
    """The built-in material ``name`` (``carbon_steel``, ``stainless_steel``, ``aluminium``)."""
    try:
        return THERMAL_MATERIALS[name]
    except KeyError:
        raise SeamtrackError(
            f"unknown material {name!r}",
            field=field,
            fix=f"use one of {', '.join(sorted(THERMAL_MATERIALS))}",
        ) from None
