"""Spatter and fume against physical oracles: ballistic paths, Poisson counts, seeded
determinism, Beer-Lambert, the single-scattering veil of a point source."""

import math

import numpy as np
import pytest

from seamtrack.errors import SeamtrackError
from seamtrack.sensing.arc import fume, spatter
from seamtrack.sensing.arc.light import BandPass, glow_radiance


def _draw(seed: int, current: float = 250.0) -> spatter.Spatter:
    rng = np.random.default_rng(seed)
    return spatter.draw_spatter(rng, "mag-short", current, [0.0, 0.0, 0.0], 1.0, 1e-3)


def test_ballistic_path_apex_and_range() -> None:
    s = _draw(1)
    assert len(s) > 10
    i = 0
    v = s.velocity[i]
    t_apex = s.birth_s[i] + v[2] / spatter.G_MM_S2
    apex = s.positions(np.array([t_apex]))[i, 0]
    assert apex[2] == pytest.approx(v[2] ** 2 / (2 * spatter.G_MM_S2), rel=1e-9)
    # back on the plate after 2 v_z / g, having flown v_xy * that
    t_land = s.birth_s[i] + 2 * v[2] / spatter.G_MM_S2
    land = s.positions(np.array([t_land]))[i, 0]
    assert land[2] == pytest.approx(0.0, abs=1e-6)
    assert math.hypot(*land[:2]) == pytest.approx(math.hypot(*v[:2]) * 2 * v[2] / spatter.G_MM_S2)
    assert np.all(s.velocity @ np.array([0.0, 0.0, 1.0]) >= 0)  # into the upper half-space


def test_streak_spans_the_exposure() -> None:
    s = _draw(2)
    t0, tau = 1.0, 1e-3
    streak = s.streaks(t0, tau, samples=5)
    born_before = s.birth_s <= t0
    length = np.linalg.norm(streak[:, -1] - streak[:, 0], axis=1)
    # a droplet in flight over the whole exposure moves |v(t)| tau (g tau^2 negligible)
    speed_mid = np.linalg.norm(s.velocity + s.gravity * (t0 + tau / 2 - s.birth_s)[:, None], axis=1)
    np.testing.assert_allclose(length[born_before], speed_mid[born_before] * tau, rtol=1e-3)
    np.testing.assert_allclose(streak[born_before, 0], s.positions(t0)[born_before])


def test_seeded_determinism_and_poisson_count() -> None:
    a, b, c = _draw(7), _draw(7), _draw(8)
    np.testing.assert_array_equal(a.velocity, b.velocity)
    assert len(a) != len(c) or not np.array_equal(a.velocity, c.velocity)
    stats = spatter.SPATTER["mag-short"]
    mean = spatter.spatter_rate_hz("mag-short", 250.0) * (stats.flight_s + 1e-3)
    counts = [len(_draw(k)) for k in range(20)]
    assert abs(np.mean(counts) - mean) < 5 * math.sqrt(mean / 20)
    assert (
        len(spatter.draw_spatter(np.random.default_rng(0), "tig", 250.0, [0, 0, 0], 0, 1e-3)) == 0
    )


def test_spatter_rate_that_would_not_fit_is_refused() -> None:
    with pytest.raises(SeamtrackError, match="arc.spatter_rate_hz"):
        spatter.draw_spatter(np.random.default_rng(0), "mag-short", 250.0, [0, 0, 0], 0.0,
                             1e-3, rate_hz=1e12)  # fmt: skip


def test_droplet_intensity_is_its_disc_times_glow() -> None:
    s = _draw(3)
    band = BandPass(660.0, 10.0)
    want = glow_radiance(s.temperature_k, band) * math.pi * s.diameter_mm**2 / 4
    np.testing.assert_allclose(s.intensity_w_sr(band), want)


def test_beer_lambert_in_uniform_fume() -> None:
    # scale -> infinity: uniform sigma0, transmission exp(-sigma0 L)
    t = fume.transmission([[0, 0, 0]], [[1.0, 0, 0]], 50.0, [0, 0, 0], 0.02, 1e12)
    assert t[0] == pytest.approx(math.exp(-1.0), rel=1e-9)
    # exponential profile along a ray from the arc: integral = sigma0 L_s (1 - exp(-L/L_s))
    t = fume.transmission([[0, 0, 0]], [[1.0, 0, 0]], 40.0, [0, 0, 0], 0.05, 8.0, n=4000)
    assert t[0] == pytest.approx(math.exp(-0.05 * 8.0 * (1 - math.exp(-5.0))), rel=1e-5)


def test_veil_of_a_point_source_in_thin_uniform_fume() -> None:
    # a line passing at distance b from the source: integral ds / (b^2 + s^2) = pi / b
    # (infinite line) so L = albedo sigma J / (4 pi) * pi / b, optically thin
    b, sigma, j, albedo = 5.0, 1e-9, 3.0, 0.5
    half = 5000.0
    veil = fume.veil_radiance([[-half, b, 0]], [[1.0, 0, 0]], 2 * half, [0, 0, 0], j, sigma,
                              1e12, albedo, n=200000)  # fmt: skip
    want = albedo * sigma * j / (4 * math.pi) * 2 * math.atan(half / b) / b
    assert veil[0] == pytest.approx(want, rel=1e-4)
    assert veil[0] == pytest.approx(albedo * sigma * j / (4 * b), rel=2e-3)
