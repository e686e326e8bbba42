"""The arc's light model against physical oracles: Planck's law, filter integrals, inverse
square, the static point source's 1/R field."""

import math

import numpy as np
import pytest

from seamtrack.errors import SeamtrackError
from seamtrack.sensing.arc import light
from seamtrack.sensing.arc.light import BandPass


def test_planck_ratio_between_two_wavelengths() -> None:
    # B(l1)/B(l2) = (l2/l1)^5 (exp(c2/(l2 T)) - 1) / (exp(c2/(l1 T)) - 1), c2 = hc/k
    c2 = 1.438776877e-2  # second radiation constant (m K), CODATA 2018
    for t in (1800.0, 3000.0, 9500.0):
        l1, l2 = 660e-9, 808e-9
        want = (l2 / l1) ** 5 * math.expm1(c2 / (l2 * t)) / math.expm1(c2 / (l1 * t))
        got = light.planck_radiance(660.0, t) / light.planck_radiance(808.0, t)
        assert got == pytest.approx(want, rel=1e-8)


def test_planck_integrates_to_stefan_boltzmann() -> None:
    t = 3000.0
    lam = np.linspace(50.0, 200000.0, 400001)
    total = np.trapezoid(light.planck_radiance(lam, t), lam) * math.pi  # W/mm^2
    sigma = 5.670374419e-8  # W m^-2 K^-4 (CODATA 2018)
    assert total * 1e6 == pytest.approx(sigma * t**4, rel=1e-3)
    assert float(light.planck_radiance(660.0, 0.0)) == 0.0


@pytest.mark.parametrize("shape", ["gaussian", "top-hat"])
def test_filter_transmission_and_equivalent_width(shape: str) -> None:
    f = BandPass(centre_nm=660.0, fwhm_nm=10.0, shape=shape, peak=0.9)  # type: ignore[arg-type]
    assert float(f.transmission(660.0)) == pytest.approx(0.9)
    assert float(f.transmission(660.0 + 4.999)) == pytest.approx(
        0.9 if shape == "top-hat" else 0.9 * 2 ** (-((4.999 / 5.0) ** 2)), rel=1e-9
    )
    assert float(f.transmission(690.0)) < 1e-9
    lam = np.linspace(560.0, 760.0, 200001)
    assert np.trapezoid(f.transmission(lam), lam) == pytest.approx(f.equivalent_width_nm, rel=1e-4)
    # A flat spectrum of 1 through the filter: its equivalent width
    assert f.in_band(lambda x: np.ones_like(x)) == pytest.approx(f.equivalent_width_nm, rel=1e-9)
    # A smooth spectrum (Planck) through a narrow filter: ~ T-integral x value at the centre
    b = f.in_band(lambda x: light.planck_radiance(x, 2500.0))
    assert b == pytest.approx(f.equivalent_width_nm * float(light.planck_radiance(660.0, 2500.0)),
                              rel=2e-2)  # fmt: skip


def test_filter_rejects_too_narrow() -> None:
    with pytest.raises(SeamtrackError, match="filter_fwhm_nm"):
        BandPass(centre_nm=660.0, fwhm_nm=0.05)


def test_inverse_square_and_cosine() -> None:
    src = np.array([0.0, 0.0, 10.0])
    pts = np.array([[0.0, 0.0, 0.0], [0.0, 0.0, -10.0], [10.0, 0.0, 0.0]])
    n = np.tile([0.0, 0.0, 1.0], (3, 1))
    e = light.irradiance(2.0, src, pts, n)
    assert e[0] == pytest.approx(2.0 / 100.0)
    assert e[1] == pytest.approx(e[0] / 4.0)  # twice the distance
    assert e[2] == pytest.approx(2.0 / 200.0 * math.cos(math.pi / 4))
    assert light.irradiance(2.0, src, [[0, 0, 0]], [[0, 0, -1.0]])[0] == 0.0


def test_arc_brighter_with_current_and_lines_pass_whole() -> None:
    red = BandPass(660.0, 10.0)
    for process in light.PROCESSES:
        j = [light.arc_in_band_intensity(process, i, red) for i in (100.0, 250.0, 350.0)]
        assert j[0] < j[1] < j[2]
    # a 1 nm top-hat on Ar I 811.5 nm passes the whole line on top of the continuum
    on_line = BandPass(811.53, 1.0, shape="top-hat", peak=1.0)
    p = light.PROCESSES["tig"]
    t = light.arc_temperature_k("tig", 200.0)
    continuum = p.emissivity * float(light.planck_radiance(811.53, t))  # x 1 nm
    assert light.arc_in_band_radiance("tig", 200.0, on_line) == pytest.approx(
        continuum + p.line_strength, rel=1e-3
    )
    with pytest.raises(SeamtrackError, match="arc.current_a"):
        light.arc_in_band_intensity("mag-spray", -5.0, red)


def test_cooling_field_is_one_over_r_and_glow_follows_planck() -> None:
    t = light.cooling_temperature([5.0, 10.0, 20.0, 0.1], "mag-spray", 250.0)
    rise = t - light.ROOM_K
    assert rise[1] == pytest.approx(rise[0] / 2) and rise[2] == pytest.approx(rise[0] / 4)
    assert t[3] == pytest.approx(light.MELT_K)
    band = BandPass(660.0, 1.0, shape="top-hat", peak=1.0)
    g = light.glow_radiance(np.array([1500.0, 1811.0]), band, emissivity=0.5)
    want = 0.5 * band.in_band(lambda lam: light.planck_radiance(lam, 1811.0))
    assert g[1] == pytest.approx(want, rel=1e-9)
    assert g[1] / g[0] == pytest.approx(
        float(light.planck_radiance(660.0, 1811.0) / light.planck_radiance(660.0, 1500.0)),
        rel=1e-3,
    )


def test_rosenthal_plate_field_is_the_heat_modules_in_the_source_frame() -> None:
    from seamtrack.heat.rosenthal import rosenthal_temperature

    heat = light.RosenthalHeat(5000.0, 5.0, 0.04, 10.0)
    arc = np.array([10.0, 20.0, 3.0])
    # travel along world -y on a plate of normal +z: source-frame x = -(world y - 20)
    pts = arc + np.array([[0.0, -8.0, 0.0], [0.0, 12.0, 0.0], [5.0, 0.0, 0.0]])
    got = light.rosenthal_plate_temperature(pts, arc, [0.0, -1.0, 0.0], [0, 0, 1.0], heat)
    local = np.array([[8.0, 0.0, 0.0], [-12.0, 0.0, 0.0], [0.0, 5.0, 0.0]])
    want = rosenthal_temperature(local, power_w=5000.0, speed_mm_s=5.0,
                                 conductivity_w_per_mm_k=0.04, diffusivity_mm2_per_s=10.0,
                                 ambient_c=light.ROOM_K - 273.15) + 273.15  # fmt: skip
    np.testing.assert_allclose(got, np.minimum(want, light.MELT_K))
    assert got[1] > got[0]  # behind the arc is hotter than ahead at a similar distance
