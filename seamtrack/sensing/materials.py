"""Surface reflectance of the parts the camera looks at: a Lambertian term plus a specular lobe.

A beam of power Phi lit on a surface point sends the radiant intensity (W/sr)

    I(v) = Phi * (rho_d * cos(theta_v) / pi + rho_s * G(beta))

towards a direction v, where theta_v is the angle between v and the surface normal, beta the
angle between v and the mirror direction of the incoming beam, and G a Gaussian lobe normalized
over the solid angle, G(beta) = exp(-beta^2 / (2 s^2)) / (2 pi s^2), whose angular width
s = 2 * roughness_rad (a facet tilted by a slope sigma turns the mirror direction by 2 sigma).
The specular part is also the light of the first bounce that throws a false stripe in a groove
(:mod:`seamtrack.sensing.render` traces it). Fresnel variation with the angle is left out.

The named materials are representative values for red laser light (630-690 nm), chosen to show
the behaviour each surface is known for (a dark, rough, diffuse oxide; a bright, shiny metal),
not measurements of a particular sheet: give your own :class:`Material` for a measured surface.
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass

from seamtrack.errors import SceneError


@dataclass(frozen=True)
class Material:
    """Reflectance of a surface (see the module docstring for the model).

    Attributes
    ----------
    name : str
    diffuse_albedo : float
        rho_d in [0, 1]: the Lambertian share of the light sent back.
    specular_reflectance : float
        rho_s in [0, 1]: the share sent into the specular lobe; rho_d + rho_s <= 1.
    roughness_rad : float
        RMS facet slope (rad); the lobe's angular standard deviation is twice this.
    speckle_contrast : float
        C in [0, 1]: standard deviation over mean of the speckle intensity this surface gives
        in coherent light (1: fully developed speckle, an optically rough surface).
    """

    name: str
    diffuse_albedo: float
    specular_reflectance: float = 0.0
    roughness_rad: float = 0.1
    speckle_contrast: float = 1.0

    def __post_init__(self) -> None:
        for key in ("diffuse_albedo", "specular_reflectance", "speckle_contrast"):
            value = getattr(self, key)
            if not 0.0 <= value <= 1.0:
                raise SceneError(
                    f"{key} = {value} is outside [0, 1]",
                    field=f"workpiece.material.{key}",
                    fix="reflectances and contrasts are fractions between 0 and 1",
                )
        if self.diffuse_albedo + self.specular_reflectance > 1.0 + 1e-12:
            raise SceneError(
                f"diffuse_albedo + specular_reflectance = "
                f"{self.diffuse_albedo + self.specular_reflectance:.3g} > 1: the surface would "
                "send back more light than it receives",
                field="workpiece.material",
                fix="lower one of the two",
            )
        if not (math.isfinite(self.roughness_rad) and 1e-4 <= self.roughness_rad <= 1.0):
            raise SceneError(
                f"roughness_rad = {self.roughness_rad} is outside [1e-4, 1] rad",
                field="workpiece.material.roughness_rad",
                fix="give the RMS facet slope in rad (0.01: polished, 0.3: rough)",
            )

    @property
    def lobe_rad(self) -> float:
        """Angular standard deviation of the specular lobe, 2 * roughness_rad."""
        return 2.0 * self.roughness_rad


#: The named materials (``workpiece.material``), representative values (module docstring).
MATERIALS: dict[str, Material] = {
    m.name: m
    for m in (
        # Hot-rolled plate as delivered: dark grey iron oxide, matte, hardly any gloss.
        Material("mill-scale steel", diffuse_albedo=0.20, specular_reflectance=0.03,
                 roughness_rad=0.30),
        # Blasted or ground carbon steel: lighter, still diffuse.
        Material("blasted steel", diffuse_albedo=0.35, specular_reflectance=0.05,
                 roughness_rad=0.25),
        # Brushed stainless: a strong, fairly wide lobe along with a diffuse part.
        Material("brushed stainless", diffuse_albedo=0.25, specular_reflectance=0.45,
                 roughness_rad=0.08),
        # Bright (rolled, cleaned) aluminium: mostly mirror, a narrow lobe; the groove's
        # false stripe comes from surfaces like this one.
        Material("bright aluminium", diffuse_albedo=0.08, specular_reflectance=0.80,
                 roughness_rad=0.02),
        # A white diffuse target (the calibration plate of a lab): pure Lambert, albedo 1.
        Material("white matte", diffuse_albedo=1.0, specular_reflectance=0.0,
                 roughness_rad=0.3),
    )
}  # fmt: skip

DEFAULT_MATERIAL = "mill-scale steel"


def material(name: str | Material) -> Material:
    """A named material (see :data:`MATERIALS`), or the given :class:`Material` itself."""
    if isinstance(name, Material):
        return name
    found = MATERIALS.get(str(name))
    if found is None:
        close = difflib.get_close_matches(str(name), list(MATERIALS), n=1)
        hint = f"did you mean {close[0]!r}? " if close else ""
        raise SceneError(
            f"unknown material {name!r}",
            field="workpiece.material",
            fix=f"{hint}use one of {', '.join(repr(k) for k in MATERIALS)}",
        )
    return found
