"""The arc's light and the hot plate's glow, through the camera's band-pass filter.

Public functions, for the image model and for the profile-mode statistical model to call:

- :func:`planck_radiance`: a black body's spectral radiance (Planck's law).
- :class:`BandPass`: the sensor's interference filter, Gaussian or top-hat, centre and FWHM;
  :meth:`BandPass.transmission` and :meth:`BandPass.in_band` (the filtered integral).
- :func:`arc_in_band_intensity`: the arc's radiant intensity (W/sr) inside the filter's band,
  by process and current; :func:`arc_in_band_radiance` its radiance over the arc's disc.
- :func:`irradiance`: a point source's irradiance on a surface (inverse square, cosine).
- :func:`cooling_temperature`, :func:`glow_radiance`: the plate's temperature around the arc
  (a static point source's 1/R field, or a caller's field such as
  :func:`seamtrack.heat.rosenthal.rosenthal_temperature`) and its in-band thermal radiance.

Units inside: mm, s, K, nm for wavelengths; radiance in W / (mm^2 sr nm) spectrally,
W / (mm^2 sr) in band; radiant intensity W / sr.

The arc is modelled as a hot plasma column: a grey-body continuum at the column's temperature
times an effective emissivity, plus the shielding gas's atomic lines (argon's Ar I lines in the
red and near infrared). The continuum and lines are what a narrow filter at the laser's
wavelength lets through; 808 nm sits between Ar I's 801.5 and 811.5 nm lines, 660 nm in a
quiet stretch of the argon spectrum, which is why trackers use red lasers.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.errors import SeamtrackError
from seamtrack.heat.rosenthal import rosenthal_temperature

FloatArray = NDArray[np.float64]

#: Planck's constant (J s), the speed of light (m/s) and Boltzmann's constant (J/K), exact in
#: the 2019 SI (BIPM, The International System of Units, 9th edition, 2019).
H_J_S = 6.62607015e-34
C_M_S = 299792458.0
K_J_K = 1.380649e-23

#: Ar I emission lines in the red and near infrared (nm, in air), from the NIST Atomic Spectra
#: Database (Kramida et al., NIST ASD, https://physics.nist.gov/asd). The relative weights
#: (strongest, 811.5 nm, = 1) are assumed, rounded from the order of the table's relative
#: intensities; calibrate against a measured arc spectrum before relying on line ratios.
ARGON_LINES_NM: tuple[tuple[float, float], ...] = (
    (696.54, 0.4),
    (706.72, 0.3),
    (738.40, 0.35),
    (750.39, 0.75),
    (763.51, 0.9),
    (794.82, 0.75),
    (801.48, 0.9),
    (811.53, 1.0),
    (842.46, 0.7),
)

#: The smallest filter width (FWHM) accepted: interference filters for line lasers are 1-40
#: nm wide; below 0.1 nm none is made (and the laser's own line is wider).
MIN_FWHM_NM = 0.1


@dataclass(frozen=True)
class ProcessLight:
    """One process's arc, at the reference current ``current_ref_a``.

    temperature_k : the column's temperature at the reference current. TIG in argon: about
        17 000 K over the column's core at 200 A, up to about 21 000 K near the cathode (Haddad
        and Farmer, J. Phys. D 17 (1984) 1189, "Temperature determinations in a free-burning
        arc. I"). MAG: iron vapour cools the arc's axis to below 10 000 K (Murphy, "The effects
        of metal vapour in arc welding", J. Phys. D 43 (2010) 434001).
    emissivity : the column's effective grey-body emissivity in the red. Assumed (an optically
        thin plasma a few mm deep): set so the direct arc through a 10 nm filter saturates the
        chip by two to four orders of magnitude, as published tracker images show.
    radius_mm : the visible column's radius at the reference current; it grows as sqrt(I).
    line_strength : the Ar I lines' in-band radiance (W / (mm^2 sr)) of the strongest line at
        the reference current (assumed; the argon lines dominate TIG, metal vapour MAG).
    temperature_exponent : T ~ I^exponent (assumed, weak: the column widens more than it
        heats).
    """

    temperature_k: float
    emissivity: float
    radius_mm: float
    line_strength: float
    current_ref_a: float = 200.0
    temperature_exponent: float = 0.1


#: The processes of :class:`seamtrack.simulation.config.ArcConfig` (assumed values are marked
#: in :class:`ProcessLight`).
PROCESSES: dict[str, ProcessLight] = {
    "tig": ProcessLight(temperature_k=17000.0, emissivity=0.02, radius_mm=1.5, line_strength=2e-3),
    "mag-spray": ProcessLight(
        temperature_k=9500.0, emissivity=0.15, radius_mm=2.5, line_strength=1e-3
    ),
    "mag-short": ProcessLight(
        temperature_k=8500.0, emissivity=0.12, radius_mm=2.0, line_strength=5e-4
    ),
}


def planck_radiance(wavelength_nm: ArrayLike, temperature_k: ArrayLike) -> FloatArray:
    """A black body's spectral radiance, W / (mm^2 sr nm): 2 h c^2 / lambda^5 /
    (exp(h c / (lambda k T)) - 1). Zero at T <= 0."""
    lam = np.asarray(wavelength_nm, dtype=np.float64) * 1e-9
    t = np.asarray(temperature_k, dtype=np.float64)
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):
        x = H_J_S * C_M_S / (lam * K_J_K * np.where(t > 0, t, 1.0))
        b = 2.0 * H_J_S * C_M_S**2 / lam**5 / np.expm1(x)  # W / (m^2 sr m)
    b = np.where((t > 0) & np.isfinite(b), b, 0.0)
    return np.asarray(b * 1e-9 * 1e-6)  # per nm, per mm^2


@dataclass(frozen=True)
class BandPass:
    """The camera's band-pass interference filter: ``centre_nm``, ``fwhm_nm`` (full width at
    half maximum), ``shape`` Gaussian or top-hat, peak transmission ``peak``."""

    centre_nm: float
    fwhm_nm: float = 10.0
    shape: Literal["gaussian", "top-hat"] = "gaussian"
    #: Peak transmission of a hard-coated interference filter: 0.9 or more (e.g. Edmund
    #: Optics' and Thorlabs' laser-line filter data sheets); assumed 0.9.
    peak: float = 0.9

    def __post_init__(self) -> None:
        if not (isinstance(self.fwhm_nm, int | float) and self.fwhm_nm >= MIN_FWHM_NM):
            raise SeamtrackError(
                f"{self.fwhm_nm!r} nm is narrower than any band-pass filter",
                field="sensor.filter_fwhm_nm",
                fix=f"give a filter width (FWHM) of at least {MIN_FWHM_NM} nm, e.g. 10",
            )  # fmt: skip
        if not (isinstance(self.centre_nm, int | float) and 200.0 <= self.centre_nm <= 2000.0):
            raise SeamtrackError(
                f"{self.centre_nm!r} nm is not a filter centre", field="sensor.filter_centre_nm",
                fix="give the filter's centre wavelength in nm, 200-2000 (the laser's)",
            )  # fmt: skip
        if not 0.0 < self.peak <= 1.0:
            raise SeamtrackError(f"{self.peak!r}", field="filter peak", fix="a fraction in (0, 1]")

    def transmission(self, wavelength_nm: ArrayLike) -> FloatArray:
        """Transmission at each wavelength: peak * exp(-4 ln2 (d / FWHM)^2) (Gaussian) or
        peak for |d| <= FWHM / 2 (top-hat)."""
        d = np.asarray(wavelength_nm, dtype=np.float64) - self.centre_nm
        if self.shape == "gaussian":
            return np.asarray(self.peak * np.exp(-4.0 * math.log(2.0) * (d / self.fwhm_nm) ** 2))
        return np.asarray(np.where(np.abs(d) <= 0.5 * self.fwhm_nm, self.peak, 0.0))

    @property
    def equivalent_width_nm(self) -> float:
        """The integral of the transmission over wavelength (nm): peak * FWHM * sqrt(pi /
        (4 ln 2)) (Gaussian), peak * FWHM (top-hat)."""
        if self.shape == "gaussian":
            return self.peak * self.fwhm_nm * math.sqrt(math.pi / (4.0 * math.log(2.0)))
        return self.peak * self.fwhm_nm

    def grid(self, n: int = 41) -> tuple[FloatArray, FloatArray]:
        """Wavelengths (nm) spanning the pass band and their quadrature weights (nm) times
        the transmission: sum(weights * f) approximates the integral of T(lambda) f(lambda)."""
        half = (3.0 if self.shape == "gaussian" else 0.5) * self.fwhm_nm
        lam = np.linspace(self.centre_nm - half, self.centre_nm + half, n)
        w = np.full(n, lam[1] - lam[0])
        if self.shape == "top-hat":
            w[0] = w[-1] = 0.5 * w[0]  # trapezoid over the flat top
        else:
            w *= self.transmission(lam) / self.peak
            w *= self.equivalent_width_nm / w.sum()  # the grid's tails carry the exact total
            return lam, w
        return lam, w * self.peak

    def in_band(self, spectral: Callable[[FloatArray], FloatArray]) -> float:
        """The filtered integral of a smooth spectrum, integral T(lambda) f(lambda) dlambda."""
        lam, w = self.grid()
        return float(np.sum(w * spectral(lam)))


def _light(process: str, current_a: float) -> ProcessLight:
    if process not in PROCESSES:
        raise SeamtrackError(
            f"{process!r} is not a process",
            field="arc.process",
            fix=f"one of {', '.join(sorted(PROCESSES))}",
        )
    if not (isinstance(current_a, int | float) and math.isfinite(current_a) and current_a > 0):
        raise SeamtrackError(
            f"{current_a!r} A is not a welding current",
            field="arc.current_a",
            fix="give the welding current in A, e.g. 250",
        )
    return PROCESSES[process]


def arc_temperature_k(process: str, current_a: float) -> float:
    """The arc column's temperature at ``current_a`` (K), T_ref (I / I_ref)^exponent."""
    p = _light(process, current_a)
    return float(p.temperature_k * (current_a / p.current_ref_a) ** p.temperature_exponent)


def arc_radius_mm(process: str, current_a: float) -> float:
    """The visible arc column's radius (mm): r_ref sqrt(I / I_ref) (the current density of
    the column stays roughly constant)."""
    p = _light(process, current_a)
    return float(p.radius_mm * math.sqrt(current_a / p.current_ref_a))


def arc_in_band_radiance(process: str, current_a: float, band: BandPass) -> float:
    """The arc's radiance inside ``band`` (W / (mm^2 sr)) over its disc: the grey-body
    continuum's filtered integral plus the Ar I lines weighted by the filter's transmission
    (lines far narrower than any filter)."""
    p = _light(process, current_a)
    t = arc_temperature_k(process, current_a)
    scale = current_a / p.current_ref_a
    continuum = band.in_band(lambda lam: p.emissivity * planck_radiance(lam, t))
    lam = np.array([line[0] for line in ARGON_LINES_NM])
    weight = np.array([line[1] for line in ARGON_LINES_NM])
    lines = p.line_strength * scale * float(np.sum(weight * band.transmission(lam)))
    return continuum + lines


def arc_in_band_intensity(process: str, current_a: float, band: BandPass) -> float:
    """The arc's radiant intensity in ``band`` (W / sr) towards a viewer: its in-band
    radiance times the column's projected area (a disc of :func:`arc_radius_mm` seen from the
    side, 2 r x 2 r: taken as pi r^2 whatever the direction)."""
    r = arc_radius_mm(process, current_a)
    return arc_in_band_radiance(process, current_a, band) * math.pi * r * r


def irradiance(
    intensity_w_sr: float, source: ArrayLike, points: ArrayLike, normals: ArrayLike
) -> FloatArray:
    """Irradiance (W / mm^2) at ``points`` (n, 3) with unit ``normals`` (n, 3) from an
    isotropic point source of ``intensity_w_sr`` at ``source`` (3,): I cos(theta) / r^2 (zero
    on the far side)."""
    p = np.atleast_2d(np.asarray(points, dtype=np.float64))
    n = np.atleast_2d(np.asarray(normals, dtype=np.float64))
    d = np.asarray(source, dtype=np.float64) - p
    r2 = np.maximum(np.einsum("ij,ij->i", d, d), 1e-12)
    cos = np.clip(np.einsum("ij,ij->i", d, n) / np.sqrt(r2), 0.0, 1.0)
    return np.asarray(intensity_w_sr * cos / r2)


#: Iron's melting point (K): 1811 K (CRC Handbook of Chemistry and Physics).
MELT_K = 1811.0
#: Room temperature (K).
ROOM_K = 293.15
#: Spectral emissivity of molten and hot oxidised steel in the red, about 0.3-0.4 (the value
#: used in two-colour pyrometry of steel; e.g. Touloukian and DeWitt, Thermophysical
#: Properties of Matter vol. 7, 1970); 0.35 taken.
STEEL_EMISSIVITY = 0.35


def pool_radius_mm(process: str, current_a: float) -> float:
    """The weld pool's radius (mm) around the arc: where the plate is at the melting point.
    Assumed 2.5 mm at 200 A, growing as sqrt(I) (a pool of the arc's width and more)."""
    _light(process, current_a)
    return 2.5 * math.sqrt(current_a / 200.0)


def cooling_temperature(
    distance_mm: ArrayLike, process: str, current_a: float, room_k: float = ROOM_K
) -> FloatArray:
    """The plate's temperature (K) at ``distance_mm`` from the arc: a static point source's
    field on a thick plate, T0 + (T_melt - T0) r_pool / R (Rosenthal's solution at zero
    speed), capped at the melting point inside the pool."""
    r = np.asarray(distance_mm, dtype=np.float64)
    rp = pool_radius_mm(process, current_a)
    return np.asarray(room_k + (MELT_K - room_k) * np.minimum(1.0, rp / np.maximum(r, 1e-9)))


def glow_radiance(
    temperature_k: ArrayLike, band: BandPass, emissivity: float = STEEL_EMISSIVITY
) -> FloatArray:
    """The hot plate's in-band thermal radiance (W / (mm^2 sr)): emissivity times Planck's
    radiance through the filter, at each temperature."""
    t = np.asarray(temperature_k, dtype=np.float64)
    lam, w = band.grid()
    b = planck_radiance(lam[None, :], t.reshape(-1, 1))
    return np.asarray((emissivity * b @ w).reshape(t.shape))


@dataclass(frozen=True)
class RosenthalHeat:
    """The heat input for the moving source's field (a scene's ``[process]``):
    ``power_w`` into the plate (:func:`seamtrack.heat.rosenthal.arc_power_w`), the travel
    ``speed_mm_s`` and the plate's ``conductivity_w_per_mm_k`` and ``diffusivity_mm2_per_s``
    (:data:`seamtrack.heat.materials.THERMAL_MATERIALS`)."""

    power_w: float
    speed_mm_s: float
    conductivity_w_per_mm_k: float
    diffusivity_mm2_per_s: float


def rosenthal_plate_temperature(
    points_mm: ArrayLike,
    arc_mm: ArrayLike,
    travel: ArrayLike,
    up: ArrayLike,
    heat: RosenthalHeat,
    room_k: float = ROOM_K,
) -> FloatArray:
    """The plate's temperature (K) at world ``points_mm`` (n, 3) from Rosenthal's thick-plate
    field (:func:`seamtrack.heat.rosenthal.rosenthal_temperature`) of a source at ``arc_mm``
    moving along ``travel`` on a plate of normal ``up``; capped at the melting point (the
    field describes the plate outside the pool), the points taken on the surface."""
    u = np.asarray(up, dtype=np.float64)
    u = u / np.linalg.norm(u)
    x = np.asarray(travel, dtype=np.float64)
    x = x - np.dot(x, u) * u
    x = x / np.linalg.norm(x)
    y = np.cross(u, x)
    d = np.atleast_2d(np.asarray(points_mm, dtype=np.float64)) - np.asarray(arc_mm, float)
    local = np.stack([d @ x, d @ y, np.zeros(len(d))], axis=1)
    r = np.hypot(local[:, 0], local[:, 1])
    local[r < 0.05, 0] = 0.05  # inside the pool (capped below): off the singular point
    t_c = rosenthal_temperature(
        local, power_w=heat.power_w, speed_mm_s=heat.speed_mm_s,
        conductivity_w_per_mm_k=heat.conductivity_w_per_mm_k,
        diffusivity_mm2_per_s=heat.diffusivity_mm2_per_s, ambient_c=room_k - 273.15,
    )  # fmt: skip
    return np.asarray(np.minimum(t_c + 273.15, MELT_K))
