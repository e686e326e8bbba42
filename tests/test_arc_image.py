"""The arc drawn into an image, on a pinhole camera with analytic projection: the direct arc's
inverse square, the plate's Lambertian radiance from the arc, seeded spatter."""

import math
from typing import Any

import numpy as np
import pytest

from seamtrack.sensing.arc import light
from seamtrack.sensing.arc.image import ArcLight, ArcView, arc_electrons
from seamtrack.sensing.materials import Material

F, PITCH, N = 10.0, 0.01, 200  # focal length, pixel pitch (mm), pixels a side


class Miss:
    def first_hit(self, origin: Any, d: Any, refine: bool = False) -> Any:
        n = len(d)

        class H:
            hit = np.zeros(n, bool)
            points = np.full((n, 3), np.nan)
            normals = np.full((n, 3), np.nan)
            distance_mm = np.full(n, np.nan)

        return H()


class Floor:
    """The plane z = 0, normal +z."""

    def first_hit(self, origin: Any, d: Any, refine: bool = False) -> Any:
        o = np.asarray(origin, float)
        t = -o[2] / d[:, 2]

        class H:
            hit = t > 0
            points = o + t[:, None] * d
            normals = np.tile([0.0, 0.0, 1.0], (len(d), 1))
            distance_mm = t

        return H()


def view(height: float) -> ArcView:
    """A pinhole camera at (0, 0, height) looking down -z; pixel (u, w) <-> x, y."""
    c = np.array([0.0, 0.0, height])

    def rays(u: Any, w: Any) -> Any:
        d = np.stack([(u - N / 2) * PITCH, (w - N / 2) * PITCH, -F * np.ones_like(u)], axis=1)
        return d / np.linalg.norm(d, axis=1, keepdims=True)

    def project(p: Any) -> Any:
        depth = c[2] - p[:, 2]
        return p[:, 0] / depth * F / PITCH + N / 2, p[:, 1] / depth * F / PITCH + N / 2, depth > 0

    return ArcView(center=c, rays=rays, project=project, rows=N, columns=N, pupil_area_mm2=1.0,
                   pixel_sr=PITCH**2 / F**2, electrons_per_w=1e12, full_well_e=1e4)  # fmt: skip


ARC = ArcLight("mag-spray", 250.0, light.BandPass(660.0, 10.0), spatter=False, fume=False,
               glow=False, min_signal=0.0)  # fmt: skip
BLACK = Material("black", diffuse_albedo=0.0)


def test_direct_arc_falls_off_as_inverse_square() -> None:
    j = light.arc_in_band_intensity("mag-spray", 250.0, ARC.band)
    up = np.array([0.0, 0.0, 1.0])
    totals = []
    for h in (100.0, 200.0):
        img = arc_electrons(ARC, view(h), Miss(), BLACK, np.zeros(3), up, 0.0,
                            np.random.default_rng(0))  # fmt: skip
        r = h - 0.5 * light.arc_radius_mm("mag-spray", 250.0)  # the column's centre
        assert img.sum() == pytest.approx(j / r**2 * 1e12, rel=1e-3)
        totals.append(img.sum())
    assert totals[0] / totals[1] == pytest.approx(
        ((200 - 0.5 * light.arc_radius_mm("mag-spray", 250.0)) / (100 - 0.5 * light.arc_radius_mm(
            "mag-spray", 250.0))) ** 2, rel=1e-3)  # fmt: skip


def test_plate_lit_by_the_arc_is_lambertian() -> None:
    white = Material("white", diffuse_albedo=1.0)
    arc = ArcLight("tig", 200.0, light.BandPass(660.0, 10.0), spatter=False, fume=False,
                   glow=False, min_signal=0.0, coarse_px=1)  # fmt: skip
    arc_at = np.array([0.0, 0.0, 0.0])
    img = arc_electrons(arc, view(100.0), Floor(), white, arc_at, np.array([0, 0, 1.0]), 0.0,
                        np.random.default_rng(0))  # fmt: skip
    j = light.arc_in_band_intensity("tig", 200.0, arc.band)
    z = 0.5 * light.arc_radius_mm("tig", 200.0)  # the column's centre above the plate
    # the pixel seeing the plate at (x, 0, 0), x = 0.5 mm... from the centre: (u - N/2) pitch
    u = 150
    x = (u + 0.5 - N / 2) * PITCH / F * 100.0
    e = j * z / (x**2 + z**2) ** 1.5  # I cos / r^2 with cos = z / r
    want = e / math.pi * PITCH**2 / F**2 * 1.0 * 1e12
    assert img[u, N // 2] == pytest.approx(want, rel=2e-2)


def test_spatter_is_seeded() -> None:
    arc = ArcLight("mag-short", 300.0, light.BandPass(660.0, 10.0), fume=False, glow=False)
    up = np.array([0.0, 0.0, 1.0])
    a, b, c = (arc_electrons(arc, view(100.0), Miss(), BLACK, np.zeros(3), up, 0.0,
                             np.random.default_rng(s)) for s in (1, 1, 2))  # fmt: skip
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
