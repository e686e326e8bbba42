"""The distortion relations (seamtrack.heat.distortion) against what they rest on: Okerblom's
shrinkage is the free expansion of the heat Rosenthal's field carries, the thermal curvature
is Timoshenko's for a linear gradient, and the transient angle dies as the heat evens out
through the thickness."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest
from scipy.integrate import quad

import seamtrack as st
from seamtrack.errors import SeamtrackError
from seamtrack.heat.distortion import (
    heat_input_j_per_mm,
    spraragen_ettinger_shrinkage_mm,
    thermal_curvature_per_mm,
    transient_angle_rad,
    transverse_shrinkage_mm,
)
from seamtrack.heat.materials import THERMAL_MATERIALS

STEEL = THERMAL_MATERIALS["carbon_steel"]
Q_W, V = 0.65 * 12.0 * 120.0, 3.0


@pytest.mark.parametrize("name", sorted(THERMAL_MATERIALS))
@pytest.mark.parametrize("x", [-40.0, -400.0])
def test_okerblom_shrinkage_is_the_free_expansion_of_rosenthals_heat(name: str, x: float) -> None:
    """alpha * integral of theta across the thin plate, behind the arc, is alpha Q_w/(rho c t):
    the heat per mm of weld spread over the thickness, whatever the field's shape."""
    m, t = THERMAL_MATERIALS[name], 3.0

    def rise(y: float) -> float:
        return float(
            st.rosenthal_temperature(
                [x, y], power_w=Q_W, speed_mm_s=V, thickness_mm=t, ambient_c=0.0,
                conductivity_w_per_mm_k=m.conductivity_w_per_mm_k,
                diffusivity_mm2_per_s=m.diffusivity_mm2_per_s,
            )
        )  # fmt: skip

    across = 2 * quad(rise, 0.0, np.inf, limit=400, epsrel=1e-10)[0]
    expansion = m.expansion_per_k * across
    assert transverse_shrinkage_mm(heat_input_j_per_mm(Q_W, V), thickness_mm=t, material=m) == (
        pytest.approx(expansion, rel=1e-6)
    )


def test_spraragen_ettinger_square_butt() -> None:
    """A square butt with gap g has A_w = g t: S = 0.2 g + 0.05 g."""
    g, t = 2.0, 6.0
    assert spraragen_ettinger_shrinkage_mm(g * t, thickness_mm=t, root_opening_mm=g) == (
        pytest.approx(0.25 * g)
    )


def test_linear_gradient_curvature_is_alpha_dt_over_t() -> None:
    t, rise = 4.0, 150.0
    z = np.linspace(0.0, t, 1001)  # the trapezoid rule's error on a quadratic: 2e-6
    linear = rise * (1 - z / t)
    kappa = thermal_curvature_per_mm(linear, z, thickness_mm=t, expansion_per_k=12e-6)
    assert kappa == pytest.approx(12e-6 * rise / t, rel=1e-5)
    uniform = thermal_curvature_per_mm(np.full_like(z, rise), z, thickness_mm=t,
                                       expansion_per_k=12e-6)  # fmt: skip
    assert abs(uniform) < 1e-15
    hot_bottom = thermal_curvature_per_mm(linear[::-1], z, thickness_mm=t, expansion_per_k=12e-6)
    assert hot_bottom == pytest.approx(-kappa)


def test_transient_angle_turns_away_at_the_arc_and_dies_behind() -> None:
    kw: dict[str, Any] = dict(power_w=Q_W, speed_mm_s=V, material=STEEL, thickness_mm=3.0,
                              from_mm=3.0, to_mm=100.0)  # fmt: skip
    at_arc = transient_angle_rad(0.0, **kw)
    behind = [transient_angle_rad(x, **kw) for x in (-5.0, -10.0, -20.0)]
    far = transient_angle_rad(-200.0, **kw)
    assert at_arc > behind[0] > behind[1] > behind[2] > 0.0
    assert abs(far) < 1e-6 * at_arc
    thicker = transient_angle_rad(0.0, **{**kw, "thickness_mm": 8.0})
    assert thicker > 0.0


def test_transient_angle_is_the_sum_of_the_strips_curvature() -> None:
    """The angle equals the curvature integrated across the plate by an independent
    quadrature (scipy quad over y, the depth by Gauss-Legendre)."""
    t, x = 3.0, -2.0
    nodes, weights = np.polynomial.legendre.leggauss(40)
    z = (nodes + 1) * t / 2

    def kappa(y: float) -> float:
        pts = np.stack([np.full_like(z, x), np.full_like(z, y), z], axis=1)
        rise = st.image_source_temperature(
            pts, power_w=Q_W, speed_mm_s=V, thickness_mm=t, ambient_c=0.0,
            conductivity_w_per_mm_k=STEEL.conductivity_w_per_mm_k,
            diffusivity_mm2_per_s=STEEL.diffusivity_mm2_per_s,
        )  # fmt: skip
        moment = np.sum(weights * rise * (t / 2 - z)) * t / 2
        return 12 * STEEL.expansion_per_k / t**3 * moment

    independent = quad(kappa, 3.0, 60.0, limit=200, epsrel=1e-8)[0]
    angle = transient_angle_rad(x, power_w=Q_W, speed_mm_s=V, material=STEEL, thickness_mm=t,
                                from_mm=3.0, to_mm=60.0, samples_y=400, samples_z=65)  # fmt: skip
    assert angle == pytest.approx(independent, rel=2e-3)
    assert math.isfinite(angle)


@pytest.mark.parametrize(
    ("call", "field"),
    [
        (lambda: heat_input_j_per_mm(900.0, 0.0), "speed_mm_s"),
        (lambda: transverse_shrinkage_mm(300.0, thickness_mm=0.0, material=STEEL),
         "thickness_mm"),
        (lambda: spraragen_ettinger_shrinkage_mm(10.0, thickness_mm=5.0, root_opening_mm=-1.0),
         "root_opening_mm"),
        (lambda: transient_angle_rad(0.0, power_w=Q_W, speed_mm_s=V, material=STEEL,
                                     thickness_mm=3.0, from_mm=5.0, to_mm=4.0), "to_mm"),
    ],
)  # fmt: skip
def test_bad_input_names_the_field(call, field: str) -> None:
    with pytest.raises(SeamtrackError) as info:
        call()
    assert info.value.field == field
