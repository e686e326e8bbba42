"""Fume: the smoke above the arc, which dims the light that crosses it (Beer-Lambert) and
scatters the arc's light into a veiling glow.

The fume's extinction coefficient falls off from the arc as exp(-r / ``scale_mm``):
sigma(r) = sigma_0 exp(-r / L). A ray's transmission is exp(-integral sigma ds)
(:func:`transmission`); the arc's light scattered into it (single scattering, isotropic phase
function, albedo ``albedo``) is the veiling radiance
L_v = albedo / (4 pi) * integral sigma(s) J T(s) / r(s)^2 ds (:func:`veil_radiance`).
sigma_0 grows with the current as the fume formation rate does (assumed linear; GMAW fume
formation rates rise steeply with current and are highest in short-circuit and globular
transfer, cf. the AWS F1.2 fume-rate method and the many reports measured with it); the
values in :data:`FUME` are assumed round values.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class FumeStats:
    """One process's fume at ``current_ref_a``: ``sigma_per_mm`` the extinction coefficient
    next to the arc, ``scale_mm`` its fall-off length, ``albedo`` the share of extinction that
    is scattering (iron-oxide particles in the red; assumed)."""

    sigma_per_mm: float
    scale_mm: float = 8.0
    albedo: float = 0.6
    current_ref_a: float = 200.0


FUME: dict[str, FumeStats] = {
    "mag-short": FumeStats(sigma_per_mm=0.02),
    "mag-spray": FumeStats(sigma_per_mm=0.03),
    "tig": FumeStats(sigma_per_mm=0.002),
}


def fume_sigma(process: str, current_a: float) -> tuple[float, float, float]:
    """(sigma_0 per mm, scale mm, albedo) at ``current_a``."""
    f = FUME[process]
    return f.sigma_per_mm * current_a / f.current_ref_a, f.scale_mm, f.albedo


def _samples(
    origin: FloatArray, direction: FloatArray, length: FloatArray, n: int
) -> tuple[FloatArray, FloatArray]:
    s = (np.arange(n) + 0.5) / n  # midpoints
    ds = length / n
    pts = origin[:, None, :] + direction[:, None, :] * (length[:, None] * s)[..., None]
    return pts, ds


def transmission(
    origin: ArrayLike,
    direction: ArrayLike,
    length_mm: ArrayLike,
    arc_mm: ArrayLike,
    sigma0_per_mm: float,
    scale_mm: float,
    n: int = 32,
) -> FloatArray:
    """Each ray's transmission through the fume: exp(-integral sigma ds) over ``length_mm``
    from ``origin`` (m, 3) along unit ``direction`` (m, 3) (midpoint rule, ``n`` steps)."""
    o = np.atleast_2d(np.asarray(origin, dtype=np.float64))
    d = np.atleast_2d(np.asarray(direction, dtype=np.float64))
    length = np.broadcast_to(np.asarray(length_mm, dtype=np.float64), (len(o),))
    pts, ds = _samples(o, d, length, n)
    r = np.linalg.norm(pts - np.asarray(arc_mm, dtype=np.float64), axis=2)
    tau = np.sum(sigma0_per_mm * np.exp(-r / scale_mm), axis=1) * ds
    return np.asarray(np.exp(-tau))


def veil_radiance(
    origin: ArrayLike,
    direction: ArrayLike,
    length_mm: ArrayLike,
    arc_mm: ArrayLike,
    intensity_w_sr: float,
    sigma0_per_mm: float,
    scale_mm: float,
    albedo: float,
    n: int = 32,
    core_mm: float = 1.0,
) -> FloatArray:
    """Each ray's veiling radiance (W / (mm^2 sr)): the arc's light (``intensity_w_sr``)
    scattered into it by the fume along ``length_mm``, attenuated on the way to the viewer
    (single scattering, isotropic phase function 1 / (4 pi)). r is floored at ``core_mm``
    (inside the arc's own column)."""
    o = np.atleast_2d(np.asarray(origin, dtype=np.float64))
    d = np.atleast_2d(np.asarray(direction, dtype=np.float64))
    length = np.broadcast_to(np.asarray(length_mm, dtype=np.float64), (len(o),))
    pts, ds = _samples(o, d, length, n)
    r = np.maximum(np.linalg.norm(pts - np.asarray(arc_mm, dtype=np.float64), axis=2), core_mm)
    sigma = sigma0_per_mm * np.exp(-r / scale_mm)
    tau_to_viewer = (np.cumsum(sigma, axis=1) - 0.5 * sigma) * ds[:, None]
    scattered = albedo * sigma * intensity_w_sr / r**2 / (4.0 * math.pi)
    return np.asarray(np.sum(scattered * np.exp(-tau_to_viewer), axis=1) * ds)
