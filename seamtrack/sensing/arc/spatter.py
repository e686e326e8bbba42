"""Spatter: glowing droplets thrown from the arc on ballistic paths, drawn seeded.

:func:`draw_spatter` draws the droplets in flight during one exposure (birth times, launch
points, velocities, diameters, temperatures) from a seeded :class:`numpy.random.Generator`;
:meth:`Spatter.positions` is the ballistic path p0 + v t + g t^2 / 2 (no drag: a 0.3 mm iron
droplet's drag time, rho d / (0.75 C_d rho_air v) ~ 0.5 s, is far longer than the tens of
milliseconds it flies within the sensor's view); :meth:`Spatter.streaks` samples each path over
the exposure, the streak the camera draws; :meth:`Spatter.intensity_w_sr` is a droplet's
in-band radiant intensity (a grey sphere at its temperature, through the filter).

The statistics by process and current are in :data:`SPATTER`. They are assumed round values
(to be calibrated on published high-speed measurements). Their order is published: TIG throws
almost no spatter, MAG always some, and spray transfer far less than short-circuiting
(E. Schubert, "Cause of weld spatter: GMAW welding and electric arc", Binzel-Abicor, 2021,
https://blog.binzel-abicor.com/cause-of-weld-spatter-gmaw-welding-and-electric-arc; LWTech,
"Welding pipe: Spatter", https://openwa.pressbooks.pub/lwtechweldingpipe/chapter/spatter:
spatter falls with lower current and with spray transfer). A mass check: at 250 A a 1.2 mm wire
fed at about 10 m/min melts about 1.5 g/s; 420 droplets/s of 0.2 mm (mag-spray at 250 A here)
are about 14 mg/s, 1 % of it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.errors import SeamtrackError
from seamtrack.sensing.arc.light import STEEL_EMISSIVITY, BandPass, glow_radiance

FloatArray = NDArray[np.float64]

#: Standard gravity (mm/s^2): 9.80665 m/s^2 (CGPM 1901, exact by definition).
G_MM_S2 = 9806.65

#: The most droplets one frame may draw (memory: 8 doubles each, a few MB at most).
MAX_DROPLETS = 200_000


@dataclass(frozen=True)
class SpatterStats:
    """One process's spatter at ``current_ref_a`` (all assumed, round values; see the module
    docstring): ``rate_hz`` droplets per second (it scales as (I / I_ref)^rate_exponent),
    ``diameter_mm`` the median diameter (lognormal, ``diameter_sigma`` the log's standard
    deviation), ``speed_mm_s`` the median launch speed (lognormal, ``speed_sigma``; scales
    as (I / I_ref)^0.5), ``temperature_k`` the mean droplet temperature (normal, sd
    ``temperature_sd_k``; droplets leave above iron's melting point, 1811 K),
    ``flight_s`` the longest flight followed."""

    rate_hz: float
    diameter_mm: float = 0.3
    diameter_sigma: float = 0.5
    speed_mm_s: float = 3000.0
    speed_sigma: float = 0.4
    temperature_k: float = 2300.0
    temperature_sd_k: float = 150.0
    flight_s: float = 0.03
    current_ref_a: float = 200.0
    rate_exponent: float = 1.5


SPATTER: dict[str, SpatterStats] = {
    "mag-short": SpatterStats(rate_hz=2000.0),
    "mag-spray": SpatterStats(rate_hz=300.0, diameter_mm=0.2, speed_mm_s=4000.0),
    "tig": SpatterStats(rate_hz=0.0),
}


@dataclass(frozen=True)
class Spatter:
    """Droplets (n of them): ``birth_s`` (n,), ``origin`` (n, 3) mm, ``velocity`` (n, 3)
    mm/s, ``diameter_mm`` (n,), ``temperature_k`` (n,), ``gravity`` (3,) mm/s^2."""

    birth_s: FloatArray
    origin: FloatArray
    velocity: FloatArray
    diameter_mm: FloatArray
    temperature_k: FloatArray
    gravity: FloatArray

    def __len__(self) -> int:
        return len(self.birth_s)

    def positions(self, t_s: ArrayLike) -> FloatArray:
        """Each droplet's position at time(s) ``t_s``: (n, 3), or (n, k, 3) for k times;
        p0 + v (t - t_b) + g (t - t_b)^2 / 2 (before its birth: its launch point)."""
        t = np.asarray(t_s, dtype=np.float64)
        dt = np.maximum(t[..., None] - self.birth_s if t.ndim else t - self.birth_s, 0.0)
        if t.ndim:
            dt = dt.T  # (n, k)
            return np.asarray(
                self.origin[:, None, :]
                + self.velocity[:, None, :] * dt[..., None]
                + 0.5 * self.gravity * dt[..., None] ** 2
            )
        return np.asarray(
            self.origin + self.velocity * dt[:, None] + 0.5 * self.gravity * dt[:, None] ** 2
        )

    def streaks(self, t0_s: float, exposure_s: float, samples: int = 8) -> FloatArray:
        """Each droplet's path over the exposure [t0, t0 + exposure], at ``samples`` times
        from the later of t0 and its birth: (n, samples, 3)."""
        start = np.maximum(self.birth_s, t0_s)
        frac = np.linspace(0.0, 1.0, samples)
        t = start[:, None] + (t0_s + exposure_s - start)[:, None] * frac
        dt = t - self.birth_s[:, None]
        return np.asarray(
            self.origin[:, None, :]
            + self.velocity[:, None, :] * dt[..., None]
            + 0.5 * self.gravity * dt[..., None] ** 2
        )

    def intensity_w_sr(self, band: BandPass, emissivity: float = STEEL_EMISSIVITY) -> FloatArray:
        """Each droplet's in-band radiant intensity (W/sr): its glow radiance times its disc,
        pi d^2 / 4."""
        radiance = glow_radiance(self.temperature_k, band, emissivity)
        return np.asarray(radiance * math.pi * self.diameter_mm**2 / 4.0)


def spatter_rate_hz(process: str, current_a: float) -> float:
    """Droplets thrown per second at ``current_a``."""
    s = SPATTER[process]
    return float(s.rate_hz * (current_a / s.current_ref_a) ** s.rate_exponent)


def draw_spatter(
    rng: np.random.Generator,
    process: str,
    current_a: float,
    arc_mm: ArrayLike,
    t0_s: float,
    exposure_s: float,
    *,
    up: ArrayLike = (0.0, 0.0, 1.0),
    rate_hz: float | None = None,
) -> Spatter:
    """The droplets in flight during the exposure [t0, t0 + exposure] from an arc at
    ``arc_mm`` (3,): born in [t0 - flight, t0 + exposure] at ``rate_hz`` (default
    :func:`spatter_rate_hz`), a Poisson count; launched into the half-space above the plate
    (``up``, the plate's normal; gravity along -``up``), uniformly over the hemisphere."""
    if process not in SPATTER:
        raise SeamtrackError(f"{process!r} is not a process", field="arc.process",
                             fix=f"one of {', '.join(sorted(SPATTER))}")  # fmt: skip
    stats = SPATTER[process]
    rate = spatter_rate_hz(process, current_a) if rate_hz is None else rate_hz
    window = stats.flight_s + exposure_s
    if not (math.isfinite(rate) and rate >= 0.0):
        raise SeamtrackError(f"{rate!r} droplets/s", field="arc.spatter_rate_hz",
                             fix="give a rate of droplets per second >= 0")  # fmt: skip
    if rate * window > MAX_DROPLETS / 2:
        raise SeamtrackError(
            f"{rate:g} droplets/s puts about {rate * window:.3g} droplets in one frame",
            field="arc.spatter_rate_hz",
            fix=f"give a rate below {MAX_DROPLETS / 2 / window:.3g} droplets/s",
        )
    n = int(rng.poisson(rate * window))
    u = np.asarray(up, dtype=np.float64)
    u = u / np.linalg.norm(u)
    a = np.array([1.0, 0.0, 0.0]) if abs(u[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    e1 = np.cross(u, a)
    e1 /= np.linalg.norm(e1)
    e2 = np.cross(u, e1)
    cos_el = rng.uniform(0.0, 1.0, n)  # uniform over the hemisphere: cos uniform
    az = rng.uniform(0.0, 2.0 * math.pi, n)
    sin_el = np.sqrt(1.0 - cos_el**2)
    direction = cos_el[:, None] * u + sin_el[:, None] * (
        np.cos(az)[:, None] * e1 + np.sin(az)[:, None] * e2
    )
    scale = math.sqrt(current_a / stats.current_ref_a)
    speed = stats.speed_mm_s * scale * np.exp(stats.speed_sigma * rng.standard_normal(n))
    return Spatter(
        birth_s=t0_s - stats.flight_s + window * rng.uniform(0.0, 1.0, n),
        origin=np.tile(np.asarray(arc_mm, dtype=np.float64), (n, 1)),
        velocity=direction * speed[:, None],
        diameter_mm=stats.diameter_mm * np.exp(stats.diameter_sigma * rng.standard_normal(n)),
        temperature_k=stats.temperature_k + stats.temperature_sd_k * rng.standard_normal(n),
        gravity=-G_MM_S2 * u,
    )
