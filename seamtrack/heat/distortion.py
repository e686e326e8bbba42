"""Welding distortion from published relations, cheap enough to call every frame: transverse
shrinkage from the heat input (Okerblom's energy form) or from the weld's area (Spraragen and
Ettinger), and the transient angular distortion near the arc from the temperature difference
through the thickness (thermal bending of a plate strip, Timoshenko and Goodier).

Units: mm, s, W, J, K; angles in radians.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.errors import SeamtrackError
from seamtrack.heat.materials import ThermalMaterial
from seamtrack.heat.rosenthal import image_source_temperature


def heat_input_j_per_mm(power_w: float, speed_mm_s: float) -> float:
    """Arc energy per unit length of weld, J/mm: ``power_w / speed_mm_s`` (the power already
    multiplied by the thermal efficiency)."""
    _positive(speed_mm_s, "speed_mm_s")
    if not np.isfinite(power_w) or power_w < 0:
        raise SeamtrackError(f"{power_w!r} W", field="power_w", fix="give a power >= 0 W")
    return float(power_w) / float(speed_mm_s)


def transverse_shrinkage_mm(
    heat_input_j_per_mm: float,
    *,
    thickness_mm: float,
    material: ThermalMaterial,
    coefficient: float = 1.0,
) -> float:
    """Transverse shrinkage of a butt joint, mm, in Okerblom's form
    ``S = A * alpha * Q_w / (rho c t)`` (N. O. Okerblom, *The calculations of deformations of
    welded metal structures*, 1955, English transl. HMSO 1958; as quoted by D. Radaj, *Heat
    Effects of Welding*, Springer 1992).

    ``alpha * Q_w / (rho c t)`` is the plate's whole free thermal expansion across the weld:
    the heat ``Q_w`` per mm of weld, spread over the thickness ``t``, integrates to
    ``Q_w / (rho c t)`` kelvin-millimetres across the plate whatever its shape
    (``tests/test_heat_distortion.py`` checks this on Rosenthal's field). ``A = 1`` takes all
    of it as permanent; a real joint keeps a part (the expansion outside the zone that yields),
    so ``A`` below 1 is a fit to measurements of your own.
    """
    q = float(heat_input_j_per_mm)
    if not np.isfinite(q) or q < 0:
        raise SeamtrackError(f"{q!r} J/mm", field="heat_input_j_per_mm", fix="give >= 0 J/mm")
    t = _positive(thickness_mm, "thickness_mm")
    a = _positive(coefficient, "coefficient")
    if material.expansion_per_k <= 0:
        raise SeamtrackError(
            f"material {material.name!r} has no thermal expansion",
            field="material.expansion_per_k",
            fix="give the material's linear expansion coefficient (1/K)",
        )
    return a * material.expansion_per_k * q / (material.volumetric_heat_j_per_mm3_k * t)


def spraragen_ettinger_shrinkage_mm(
    weld_area_mm2: float, *, thickness_mm: float, root_opening_mm: float
) -> float:
    """Transverse shrinkage of a butt weld, mm, from its cross-section:
    ``S = 0.2 * A_w / t + 0.05 * d`` (W. Spraragen and W. G. Ettinger, "Shrinkage distortion
    in welding", Welding Journal 29 (1950) 292s-294s, 323s-335s; as given by O. W. Blodgett,
    *Design of Welded Structures*, Lincoln Arc Welding Foundation 1966, section 7.7). Any one
    length unit; a fit to measured joints of carbon steel."""
    area = _positive(weld_area_mm2, "weld_area_mm2")
    t = _positive(thickness_mm, "thickness_mm")
    d = float(root_opening_mm)
    if not np.isfinite(d) or d < 0:
        raise SeamtrackError(f"{d!r} mm", field="root_opening_mm", fix="give a gap >= 0 mm")
    return 0.2 * area / t + 0.05 * d


def permanent_angle_rad(
    heat_input_j_per_mm: float, *, thickness_mm: float, peak_rad: float, peak_q_per_h2: float
) -> float:
    """The permanent angular distortion of a single-pass weld (radians, the angle between the
    two plates' faces, edges turned towards the torch) as a function of the heat input
    parameter ``p = Q / h^2`` (J/mm^3): ``peak * (p / p_peak) * exp(1 - p / p_peak)``.

    The parameter and the shape, a rise to a maximum and a fall beyond it (the heat reaches
    the bottom face and the plate heats through, so less of it bends), are those of the
    measurements of M. Watanabe and K. Satoh, "Effect of welding conditions on the shrinkage
    distortion in welded structures", Welding Journal 40 (1961) 377s-384s, on which W.-J. Seong
    built the bead-on-plate database of "Prediction and characteristics of angular distortion
    in multi-layer butt welding", Materials 12 (2019) 1435 (doi:10.3390/ma12091435). This
    closed form through that maximum is this module's; ``peak_rad`` and ``peak_q_per_h2`` are
    a fit to measurements of your process and material (no default here)."""
    q = float(heat_input_j_per_mm)
    if not np.isfinite(q) or q < 0:
        raise SeamtrackError(f"{q!r} J/mm", field="heat_input_j_per_mm", fix="give >= 0 J/mm")
    t = _positive(thickness_mm, "thickness_mm")
    peak = float(peak_rad)
    if not np.isfinite(peak) or peak < 0:
        raise SeamtrackError(f"{peak!r} rad", field="angle_peak", fix="give an angle >= 0")
    p0 = _positive(peak_q_per_h2, "angle_peak_q_per_h2")
    ratio = q / t**2 / p0
    return peak * ratio * float(np.exp(1.0 - ratio))


def thermal_curvature_per_mm(
    temperature_rise_k: ArrayLike, z_mm: ArrayLike, *, thickness_mm: float, expansion_per_k: float
) -> NDArray[np.float64]:
    """Curvature (1/mm) of a free plate strip heated through its thickness:
    ``kappa = 12 alpha / t^3 * integral_0^t theta(z) (t/2 - z) dz`` (the thermal moment over
    the bending stiffness of a beam: S. Timoshenko and J. N. Goodier, *Theory of Elasticity*,
    2nd ed., McGraw-Hill 1951, section 150). z is the depth from the top face; positive
    curvature is a top hotter than the bottom (the strip bends away from the arc).
    A linear rise from ``dT`` on top to 0 below gives ``alpha * dT / t``.

    ``temperature_rise_k`` has the depths on its last axis (samples at ``z_mm``, from 0 to
    ``thickness_mm``), integrated by the trapezoid rule."""
    t = _positive(thickness_mm, "thickness_mm")
    theta = np.asarray(temperature_rise_k, dtype=float)
    z = np.asarray(z_mm, dtype=float)
    moment = np.trapezoid(theta * (t / 2 - z), z, axis=-1)
    return np.asarray(12.0 * expansion_per_k / t**3 * moment, dtype=float)


def transient_angle_rad(
    x_mm: float,
    *,
    power_w: float,
    speed_mm_s: float,
    material: ThermalMaterial,
    thickness_mm: float,
    from_mm: float,
    to_mm: float,
    samples_y: int = 48,
    samples_z: int = 17,
) -> float:
    """The elastic angular distortion (radians) of one plate at ``x_mm`` along the travel from
    the arc (negative behind it): the thermal curvature of
    :func:`thermal_curvature_per_mm` summed across the plate from ``from_mm`` to ``to_mm``
    off the weld line, with the temperature of the finite plate
    (:func:`~seamtrack.heat.rosenthal.image_source_temperature`). Positive: the plate's far
    edge turns away from the torch (top hotter than bottom); it returns to 0 as the heat
    evens out through the thickness. Elastic: the zone that yields near the pool is not
    modelled (start ``from_mm`` outside it)."""
    y0 = _positive(from_mm, "from_mm")
    y1 = float(to_mm)
    if not y1 > y0:
        raise SeamtrackError(
            f"the strip ends at {y1:g} mm, before it starts ({y0:g} mm)",
            field="to_mm",
            fix="give to_mm > from_mm (the plate's width off the weld line)",
        )
    t = _positive(thickness_mm, "thickness_mm")
    y = np.linspace(y0, y1, samples_y)
    z = np.linspace(0.0, t, samples_z)
    grid = np.stack(np.broadcast_arrays(float(x_mm), y[:, None], z[None, :]), axis=-1)
    rise = image_source_temperature(
        grid,
        power_w=power_w,
        speed_mm_s=speed_mm_s,
        conductivity_w_per_mm_k=material.conductivity_w_per_mm_k,
        diffusivity_mm2_per_s=material.diffusivity_mm2_per_s,
        thickness_mm=t,
        ambient_c=0.0,
    )
    kappa = thermal_curvature_per_mm(
        rise, z, thickness_mm=t, expansion_per_k=material.expansion_per_k
    )
    return float(np.trapezoid(kappa, y))


def _positive(value: float, field: str) -> float:
    number = float(value)
    if not np.isfinite(number) or number <= 0:
        raise SeamtrackError(f"{value!r} is not positive", field=field, fix="give a value > 0")
    return number
