"""Rosenthal's fields (seamtrack.heat.rosenthal) against independent evaluations: the moving
source's Green's function integrated over time, the plate's through-thickness cosine modes, the
heat balance of a contour around the source; their symmetry, their far field, and the finite
plate's two limits (thick and thin)."""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from scipy.integrate import quad
from scipy.special import k0

import seamtrack as st
from seamtrack.errors import SeamtrackError
from seamtrack.heat.materials import THERMAL_MATERIALS
from seamtrack.heat.rosenthal import arc_power_w, process_power_w
from seamtrack.simulation.config import ProcessConfig

STEEL = THERMAL_MATERIALS["carbon_steel"]
Q_W, V = 0.8 * 24.0 * 200.0, 6.0
KW = dict(
    power_w=Q_W,
    speed_mm_s=V,
    conductivity_w_per_mm_k=STEEL.conductivity_w_per_mm_k,
    diffusivity_mm2_per_s=STEEL.diffusivity_mm2_per_s,
)
LAM, A = STEEL.conductivity_w_per_mm_k, STEEL.diffusivity_mm2_per_s
RHO_C = LAM / A
POINTS = np.array(
    [[0.0, 3.0, 0.0], [4.0, 2.0, 1.0], [-6.0, 1.5, 0.5], [-25.0, 8.0, 2.0], [10.0, -5.0, 0.0]]
)


def _time_integral(integrand) -> float:
    """The integral over the time since the source passed, split where it peaks."""
    head, _ = quad(integrand, 0.0, 1.0, limit=400, epsabs=0.0, epsrel=1e-11)
    tail, _ = quad(integrand, 1.0, np.inf, limit=400, epsabs=0.0, epsrel=1e-11)
    return head + tail


def _point_source_green(p: np.ndarray) -> float:
    """A source of q on a half-space's adiabatic surface (twice the infinite body's kernel),
    moving at v: the heat released at time t ago, at (-v t, 0, 0), diffused since."""
    x, y, z = p

    def f(t: float) -> float:
        r2 = (x + V * t) ** 2 + y * y + z * z
        return 2.0 * Q_W / (RHO_C * (4 * math.pi * A * t) ** 1.5) * math.exp(-r2 / (4 * A * t))

    return _time_integral(f)


def _line_source_green(p: np.ndarray, d: float) -> float:
    x, y = p[0], p[1]

    def f(t: float) -> float:
        r2 = (x + V * t) ** 2 + y * y
        return Q_W / (d * RHO_C * 4 * math.pi * A * t) * math.exp(-r2 / (4 * A * t))

    return _time_integral(f)


def test_thick_plate_is_the_time_integral_of_the_moving_point_source() -> None:
    field = st.rosenthal_temperature(POINTS, **KW, ambient_c=0.0)
    independent = [_point_source_green(p) for p in POINTS]
    np.testing.assert_allclose(field, independent, rtol=1e-7)


def test_thin_plate_is_the_time_integral_of_the_moving_line_source() -> None:
    field = st.rosenthal_temperature(POINTS, **KW, thickness_mm=2.5, ambient_c=0.0)
    independent = [_line_source_green(p, 2.5) for p in POINTS]
    np.testing.assert_allclose(field, independent, rtol=1e-7)


def _cosine_modes(p: np.ndarray, d: float, modes: int = 400) -> float:
    """The finite plate's field as its through-thickness cosine modes (the eigenfunctions of the
    adiabatic faces): theta = q / (2 pi lambda d) exp(-k x) [K0(k r) + 2 sum_m cos(m pi z / d)
    K0(r sqrt(k^2 + (m pi / d)^2))], an expansion independent of the images."""
    x, y, z = p
    k, r = V / (2 * A), math.hypot(x, y)
    total = k0(k * r)
    for m in range(1, modes):
        total += 2 * math.cos(m * math.pi * z / d) * k0(r * math.hypot(k, m * math.pi / d))
    return Q_W / (2 * math.pi * LAM * d) * math.exp(-k * x) * total


@pytest.mark.parametrize("d", [2.0, 6.0, 12.0])
def test_image_sources_equal_the_cosine_mode_expansion(d: float) -> None:
    points = np.array([[2.0, 5.0, 0.0], [-8.0, 4.0, d / 3], [-30.0, 6.0, d], [6.0, -9.0, d / 2]])
    field = st.image_source_temperature(points, **KW, thickness_mm=d, ambient_c=0.0)
    independent = [_cosine_modes(p, d) for p in points]
    np.testing.assert_allclose(field, independent, rtol=1e-8)


def _flux_out_of_circle(radius: float, d: float, n: int = 2048) -> float:
    """d * the integral over a circle of (-lambda grad theta - rho c v theta e_x) . n: the heat
    crossing the contour each second in the source's frame (conduction, and the heat the metal
    carries as it flows past at -v)."""
    phi = 2 * math.pi * np.arange(n) / n
    normal = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    pts = radius * normal
    h = 1e-5

    def temp(q: np.ndarray) -> np.ndarray:
        return st.rosenthal_temperature(q, **KW, thickness_mm=d, ambient_c=0.0)

    grad = np.stack([(temp(pts + h * e) - temp(pts - h * e)) / (2 * h) for e in np.eye(2)], axis=1)
    flux = -LAM * np.sum(grad * normal, axis=1) - RHO_C * V * temp(pts) * normal[:, 0]
    return float(d * flux.mean() * 2 * math.pi * radius)


@pytest.mark.parametrize("radius", [0.5, 5.0, 40.0])
def test_thin_plate_heat_balance(radius: float) -> None:
    """All the arc's power crosses any circle around the line source, near or far."""
    assert _flux_out_of_circle(radius, 3.0) == pytest.approx(Q_W, rel=1e-6)


def test_thick_plate_heat_balance_over_a_hemisphere() -> None:
    radius, h = 6.0, 1e-5
    nodes, weights = np.polynomial.legendre.leggauss(96)
    polar = (nodes + 1) * math.pi / 4  # 0 .. pi/2 from the +z axis (into the plate)
    w_polar = weights * math.pi / 4
    azim = 2 * math.pi * np.arange(256) / 256
    th, ph = np.meshgrid(polar, azim, indexing="ij")
    normal = np.stack([np.sin(th) * np.cos(ph), np.sin(th) * np.sin(ph), np.cos(th)], axis=-1)
    pts = radius * normal

    def temp(q: np.ndarray) -> np.ndarray:
        return st.rosenthal_temperature(q, **KW, ambient_c=0.0)

    grad = np.stack([(temp(pts + h * e) - temp(pts - h * e)) / (2 * h) for e in np.eye(3)], -1)
    flux = -LAM * np.sum(grad * normal, axis=-1) - RHO_C * V * temp(pts) * normal[..., 0]
    total = np.sum(flux * np.sin(th) * w_polar[:, None]) * (2 * math.pi / 256) * radius**2
    assert total == pytest.approx(Q_W, rel=1e-6)


@pytest.mark.parametrize("kind", ["thick", "thin", "images"])
def test_fields_are_symmetric_in_y(kind: str) -> None:
    mirrored = POINTS * [1.0, -1.0, 1.0]
    args: dict = {"thick": {}, "thin": {"thickness_mm": 3.0}, "images": {"thickness_mm": 3.0}}[kind]
    f = st.image_source_temperature if kind == "images" else st.rosenthal_temperature
    np.testing.assert_array_equal(f(POINTS, **KW, **args), f(mirrored, **KW, **args))


@pytest.mark.parametrize("thickness", [None, 3.0])
def test_field_tends_to_ambient_far_away_in_every_direction(thickness: float | None) -> None:
    """Ahead and to the side the excess temperature dies exponentially; behind, along the
    cooling wake, as 1/R (thick) or 1/sqrt(r) (thin), its asymptote
    q / (2 pi lambda R) and q / (2 pi lambda d) sqrt(pi / (2 k r))."""
    ambient = -7.5
    k = V / (2 * A)
    for angle in np.linspace(0.0, math.pi, 9):
        direction = np.array([math.cos(angle), math.sin(angle), 0.0])
        far = [st.rosenthal_temperature(r * direction, **KW, thickness_mm=thickness,
                                        ambient_c=ambient) - ambient
               for r in (20.0, 200.0, 1e12)]  # fmt: skip
        assert far[0] > far[1] >= far[2] >= 0.0
        assert far[2] < 0.05
    behind = 1e8
    theta = st.rosenthal_temperature([-behind, 0.0, 0.0], **KW, thickness_mm=thickness,
                                     ambient_c=ambient) - ambient  # fmt: skip
    if thickness is None:
        wake = Q_W / (2 * math.pi * LAM * behind)
    else:
        wake = Q_W / (2 * math.pi * LAM * thickness) * math.sqrt(math.pi / (2 * k * behind))
    assert theta == pytest.approx(wake, rel=1e-6)


def test_images_in_a_thick_plate_tend_to_the_point_source() -> None:
    thick = st.rosenthal_temperature(POINTS, **KW)
    errors = [
        np.max(np.abs(st.image_source_temperature(POINTS, **KW, thickness_mm=d) - thick) / thick)
        for d in (10.0, 30.0, 100.0, 1000.0)
    ]
    assert all(b < a for a, b in itertools.pairwise(errors))
    assert errors[-1] < 1e-12


def test_images_in_a_thin_plate_tend_to_the_line_source() -> None:
    """A 0.3 mm plate: away from the arc (r >= 10 d) the images sum to the line source."""
    d = 0.3
    pts = np.array([[3.0, 2.0, 0.0], [-20.0, 4.0, 0.15], [0.0, -6.0, 0.3], [10.0, 0.0, 0.1]])
    images = st.image_source_temperature(pts, **KW, thickness_mm=d)
    line = st.rosenthal_temperature(pts, **KW, thickness_mm=d)
    np.testing.assert_allclose(images, line, rtol=1e-9)


def test_thin_plate_takes_two_coordinates_and_ignores_the_depth() -> None:
    two = st.rosenthal_temperature(POINTS[:, :2], **KW, thickness_mm=3.0)
    three = st.rosenthal_temperature(POINTS, **KW, thickness_mm=3.0)
    np.testing.assert_array_equal(two, three)


def test_material_diffusivity_is_conductivity_over_rho_c() -> None:
    """The table's own consistency: alpha = k / (rho c) within its rounding."""
    for m in THERMAL_MATERIALS.values():
        rho_c = m.density_kg_m3 * m.specific_heat_j_per_kg_k * 1e-9  # J/(mm^3 K)
        assert m.conductivity_w_per_mm_k / rho_c == pytest.approx(m.diffusivity_mm2_per_s, rel=0.01)


def test_heat_input_is_efficiency_times_voltage_times_current() -> None:
    process = ProcessConfig(voltage_v=22.0, current_a=180.0, thermal_efficiency=0.75)
    assert process_power_w(process) == pytest.approx(0.75 * 22.0 * 180.0)


@pytest.mark.parametrize(
    ("call", "field"),
    [
        (lambda: st.rosenthal_temperature(POINTS, **{**KW, "speed_mm_s": 0.0}), "speed_mm_s"),
        (lambda: st.rosenthal_temperature(POINTS, **{**KW, "speed_mm_s": -2.0}), "speed_mm_s"),
        (lambda: st.rosenthal_temperature([[0.0, 0.0, 0.0]], **KW), "points_mm"),
        (lambda: st.rosenthal_temperature([[0.0, 0.0, 2.0]], **KW, thickness_mm=3.0),
         "points_mm"),
        (lambda: st.image_source_temperature([[0.0, 0.0, 0.0]], **KW, thickness_mm=3.0),
         "points_mm"),
        (lambda: st.rosenthal_temperature([[1.0, 0.0, -1.0]], **KW), "points_mm"),
        (lambda: st.image_source_temperature([[1.0, 0.0, 4.0]], **KW, thickness_mm=3.0),
         "points_mm"),
        (lambda: st.rosenthal_temperature([[math.nan, 0.0, 0.0]], **KW), "points_mm"),
        (lambda: st.rosenthal_temperature(POINTS, **{**KW, "power_w": -1.0}), "power_w"),
        (lambda: st.rosenthal_temperature(POINTS, **KW, thickness_mm=0.0), "thickness_mm"),
        (lambda: st.rosenthal_temperature(POINTS, **{**KW, "diffusivity_mm2_per_s": 0.0}),
         "diffusivity_mm2_per_s"),
        (lambda: arc_power_w(voltage_v=24.0, current_a=200.0, thermal_efficiency=1.2),
         "process.thermal_efficiency"),
    ],
)  # fmt: skip
def test_bad_input_names_the_field(call, field: str) -> None:
    with pytest.raises(SeamtrackError) as info:
        call()
    assert info.value.field == field
    assert "\n" not in str(info.value)
