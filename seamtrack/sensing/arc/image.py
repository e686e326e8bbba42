"""The arc drawn into the camera's image: :func:`arc_electrons` adds, in electrons per pixel,

1. the plate lit by the arc: each pixel's ray is cast onto the part; the arc's in-band
   intensity J lights the hit point, unless the part stands between (a shadow ray), with
   E = J cos(theta_i) / r^2
   (:func:`seamtrack.sensing.arc.light.irradiance`), which the part's material sends back as
   L = E (rho_d / pi + rho_s G(beta) / cos(theta_v)) (the Lambert + Gaussian-lobe model of
   :mod:`seamtrack.sensing.materials`, the same as the laser's);
2. the plate's glow: emissivity times Planck's radiance through the filter at the temperature
   of :func:`seamtrack.sensing.arc.light.cooling_temperature`;
3. the fume: both dimmed by the fume on the way to the camera, plus the veil it scatters
   (:mod:`seamtrack.sensing.arc.fume`);
   The weld pool (the plate at the melting point) mirrors the arc: it takes :data:`POOL`'s
   reflectance instead of the part's.
4. the arc itself, where the camera sees it: a blob of the column's width carrying
   J A_pupil / r^2;
5. spatter: each droplet's streak over the exposure (:mod:`seamtrack.sensing.arc.spatter`).

A pixel of etendue A_pupil * pitch_h * pitch_v / f^2 that sees a radiance L collects
L * etendue watts; the camera's exposure scale (electrons per watt) is the laser's: a laser of
``laser_power_w`` spread over the fan lights the white reference plane to ``exposure`` of the
full well (:meth:`seamtrack.sensing.render` ``_Optics._exposure_scale``), so arc light and
laser light share one scale. Items 1-3 are computed on a grid coarser by ``coarse_px`` and
interpolated (they vary smoothly), which keeps the cost of the arc near that of the stripe.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.jit import KERNEL
from seamtrack.sensing.arc import fume as fume_model
from seamtrack.sensing.arc import light
from seamtrack.sensing.arc.spatter import draw_spatter
from seamtrack.sensing.materials import Material

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class ArcLight:
    """The arc's settings for one render: ``process``, ``current_a``, the camera's band-pass
    ``band``, the ``spatter``, ``fume`` and ``glow`` switches, ``exposure_s`` the shutter time
    (s; assumed 0.2 ms: trackers under an arc expose for 0.1-1 ms), ``laser_power_w`` the
    laser's power (W; assumed 0.1: seam-tracker line lasers are class 3R-3B, tens to hundreds
    of mW), ``coarse_px`` the step of the grid of the smooth terms."""

    process: str
    current_a: float
    band: light.BandPass
    spatter: bool = True
    fume: bool = True
    glow: bool = True
    exposure_s: float = 2e-4
    laser_power_w: float = 0.1
    coarse_px: int = 32
    #: The heat input for Rosenthal's moving-source field (a scene's ``[process]``); None:
    #: the static 1/R cooling law (:func:`seamtrack.sensing.arc.light.cooling_temperature`).
    heat: light.RosenthalHeat | None = None
    #: Electrons below this share of the full well on a pixel are left out of the smooth terms
    #: (as the renderer leaves out stripe light below a tenth of a grey level).
    min_signal: float = 1e-4


@dataclass(frozen=True)
class ArcView:
    """The camera as the arc model sees it (built by the renderer): ``center`` (3,) world,
    ``rays(u, w)`` the world unit directions of pixel coordinates (edge-based: pixel i spans
    [i, i + 1)), ``project(points)`` world points (n, 3) to (u, w, in_front), the window's
    ``rows`` and ``columns``, the pupil's area (mm^2), a pixel's solid angle (sr) and the
    electrons per watt of the exposure, the full well (electrons)."""

    center: FloatArray
    rays: Callable[[FloatArray, FloatArray], FloatArray]
    project: Callable[[FloatArray], tuple[FloatArray, FloatArray, NDArray[np.bool_]]]
    rows: int
    columns: int
    pupil_area_mm2: float
    pixel_sr: float
    electrons_per_w: float
    full_well_e: float


def _plate_temperature(
    arc: ArcLight, p: FloatArray, arc_mm: FloatArray, up: FloatArray, travel: FloatArray | None
) -> FloatArray:
    """The plate's temperature at ``p``: Rosenthal's field with a heat input and a travel
    direction, else the static cooling law."""
    if arc.heat is not None and travel is not None and len(p):
        return light.rosenthal_plate_temperature(p, arc_mm, travel, up, arc.heat)
    return light.cooling_temperature(np.linalg.norm(p - arc_mm, axis=1), arc.process,
                                     arc.current_a)  # fmt: skip


#: The weld pool's surface: liquid steel, opaque, so its reflectance is 1 - emissivity
#: (Kirchhoff), about 0.65 with :data:`~seamtrack.sensing.arc.light.STEEL_EMISSIVITY`; almost
#: all of it specular (a liquid surface is smooth; its ripples give the narrow lobe, assumed).
POOL = Material("weld pool", diffuse_albedo=0.05, specular_reflectance=0.6, roughness_rad=0.03)


def _brdf(mat: Material, p: FloatArray, n: FloatArray, view_dir: FloatArray,
          arc_mm: FloatArray) -> FloatArray:  # fmt: skip
    """The material's BRDF (1/sr) for the arc's light at ``p`` seen along ``view_dir``:
    rho_d / pi + rho_s G(beta) / cos(theta_v) (the image mode's model, per irradiance)."""
    cos_v = np.clip(np.einsum("ij,ij->i", n, view_dir), 0.05, 1.0)
    brdf = np.full(len(p), mat.diffuse_albedo / math.pi)
    if mat.specular_reflectance > 0 and len(p):
        incoming = p - arc_mm
        incoming /= np.linalg.norm(incoming, axis=1, keepdims=True)
        mirror = incoming - 2.0 * np.einsum("ij,ij->i", incoming, n)[:, None] * n
        beta = np.arccos(np.clip(np.einsum("ij,ij->i", mirror, view_dir), -1.0, 1.0))
        lobe = mat.lobe_rad
        g = np.exp(-0.5 * (beta / lobe) ** 2) / (2.0 * math.pi * lobe**2)
        brdf = brdf + mat.specular_reflectance * g / cos_v
    return brdf


def _smooth_terms(
    arc: ArcLight,
    view: ArcView,
    caster: Any,
    mat: Material,
    arc_mm: FloatArray,
    j: float,
    frame: tuple[FloatArray, FloatArray, FloatArray | None],
) -> FloatArray:
    """Items 1-3 of the module on the coarse grid, interpolated to every pixel (electrons;
    0 where below ``arc.min_signal`` of the full well)."""
    k = max(1, arc.coarse_px)
    cu = np.arange(0.5 * k, view.rows + k, k)
    cw = np.arange(0.5 * k, view.columns + k, k)
    uu, ww = np.meshgrid(cu, cw, indexing="ij")
    d = view.rays(uu.ravel(), ww.ravel())
    hits = caster.first_hit(view.center, d, refine=False)
    radiance = np.zeros(len(d))
    h = hits.hit
    p, n = hits.points[h], hits.normals[h]
    view_dir = -d[h]
    e = light.irradiance(j, arc_mm, p, n)
    blocked = getattr(caster, "line_of_sight_blocked", None)  # a caster of a mesh: shadows
    if blocked is not None and len(p):
        e[blocked(p, arc_mm)] = 0.0
    t = _plate_temperature(arc, p, *frame)
    wet = t >= light.MELT_K - 1e-6  # the pool mirrors the arc
    brdf = np.empty(len(p))
    for surface, where in ((mat, ~wet), (POOL, wet)):
        brdf[where] = _brdf(surface, p[where], n[where], view_dir[where], arc_mm)
    radiance[h] = e * brdf
    if arc.glow:
        radiance[h] += light.glow_radiance(t, arc.band)
    if arc.fume:
        sigma0, scale, albedo = fume_model.fume_sigma(arc.process, arc.current_a)
        length = np.where(h, hits.distance_mm, 2.0 * np.linalg.norm(arc_mm - view.center))
        origin = np.broadcast_to(view.center, d.shape)
        radiance *= fume_model.transmission(origin, d, length, arc_mm, sigma0, scale, n=12)
        radiance += fume_model.veil_radiance(origin, d, length, arc_mm, j, sigma0, scale,
                                             albedo, n=24)  # fmt: skip
    coarse = (radiance * view.pixel_sr * view.pupil_area_mm2 * view.electrons_per_w).reshape(
        uu.shape
    )
    image = np.empty((view.rows, view.columns))
    _interpolate(coarse, _linear_weights(coarse.shape[0], k, view.rows),
                 _linear_weights(coarse.shape[1], k, view.columns),
                 arc.min_signal * view.full_well_e, image)  # fmt: skip
    return image


@dataclass(frozen=True)
class LinearWeights:
    """Linear interpolation of m coarse samples at pixel centres (i + 0.5) k onto n pixels
    (held constant beyond the ends): pixel i takes ``w0[i]`` of sample ``i0[i]`` and ``w1[i]``
    of ``i1[i]`` (i1 = i0 when m is 1: one sample, weight 1)."""

    i0: NDArray[np.int64]
    i1: NDArray[np.int64]
    w0: FloatArray
    w1: FloatArray


def _linear_weights(m: int, k: int, n: int) -> LinearWeights:
    """The weights of :class:`LinearWeights` for m samples every ``k`` pixels onto n."""
    x = np.clip((np.arange(n) + 0.5 - 0.5 * k) / k, 0.0, m - 1.0)
    i0 = np.minimum(np.floor(x).astype(np.int64), max(m - 2, 0))
    f = x - i0 if m > 1 else np.zeros(n)
    i1 = np.minimum(i0 + 1, m - 1)
    return LinearWeights(i0, i1, 1 - f, f)


def _interpolate(coarse: FloatArray, rows: LinearWeights, columns: LinearWeights,
                 floor: float, out: FloatArray) -> None:  # fmt: skip
    """``out`` (n_rows, n_columns) = the coarse grid interpolated along its rows, then its
    columns, with each pixel below ``floor`` set to 0."""
    _interpolate_kernel(coarse, rows.i0, rows.i1, rows.w0, rows.w1, columns.i0, columns.i1,
                        columns.w0, columns.w1, floor, out)  # fmt: skip


@numba.njit(**KERNEL)
def _interpolate_kernel(
    coarse: FloatArray, r0: NDArray[np.int64], r1: NDArray[np.int64], a0: FloatArray,
    a1: FloatArray, c0: NDArray[np.int64], c1: NDArray[np.int64], b0: FloatArray,
    b1: FloatArray, floor: float, out: FloatArray,
) -> None:  # fmt: skip
    """:func:`_interpolate` in one pass over ``out``, row by row. Each interpolated value is
    0 + w0 x0 + w1 x1 in this order (a sparse matrix's product, as the arc's image was first
    drawn: the same bytes; a second term only where its sample is another)."""
    along = np.empty(coarse.shape[1])
    for i in range(out.shape[0]):
        for b in range(coarse.shape[1]):
            v = 0.0 + a0[i] * coarse[r0[i], b]
            if r1[i] != r0[i]:
                v += a1[i] * coarse[r1[i], b]
            along[b] = v
        for j in range(out.shape[1]):
            v = 0.0 + b0[j] * along[c0[j]]
            if c1[j] != c0[j]:
                v += b1[j] * along[c1[j]]
            out[i, j] = 0.0 if v < floor else v


def _splat(image: FloatArray, u: FloatArray, w: FloatArray, electrons: FloatArray) -> None:
    """Add ``electrons`` at pixel coordinates (u, w), shared bilinearly between 4 pixels."""
    u0, w0 = np.floor(u - 0.5), np.floor(w - 0.5)
    fu, fw = u - 0.5 - u0, w - 0.5 - w0
    rows, cols = image.shape
    for du, dw, share in ((0, 0, (1 - fu) * (1 - fw)), (1, 0, fu * (1 - fw)),
                          (0, 1, (1 - fu) * fw), (1, 1, fu * fw)):  # fmt: skip
        r, c = (u0 + du).astype(np.int64), (w0 + dw).astype(np.int64)
        ok = (r >= 0) & (r < rows) & (c >= 0) & (c < cols)
        np.add.at(image, (r[ok], c[ok]), (electrons * share)[ok])


def _point_electrons(view: ArcView, points: FloatArray, intensity: FloatArray) -> FloatArray:
    """Electrons a point source of ``intensity`` (W/sr) at each point puts on the chip over a
    whole exposure: J A_pupil / r^2 (W) times electrons per watt."""
    r2 = np.sum((points - view.center) ** 2, axis=-1)
    return np.asarray(intensity * view.pupil_area_mm2 / r2 * view.electrons_per_w)


def _direct_arc(image: FloatArray, arc: ArcLight, view: ArcView, arc_mm: FloatArray,
                j: float, transmission: float) -> None:  # fmt: skip
    """The arc's column seen directly: a Gaussian blob of the column's projected radius."""
    u, w, front = view.project(arc_mm[None, :])
    if not front[0]:
        return
    total = float(_point_electrons(view, arc_mm[None, :], np.array([j]))[0]) * transmission
    r = light.arc_radius_mm(arc.process, arc.current_a)
    dist = float(np.linalg.norm(arc_mm - view.center))
    # the column's radius in pixels, from the pixel's solid angle (square pixels assumed)
    sigma = max(0.7, 0.5 * r / dist / math.sqrt(view.pixel_sr))
    half = int(math.ceil(4 * sigma))
    r0, c0 = int(math.floor(u[0])), int(math.floor(w[0]))
    rows = np.arange(max(0, r0 - half), min(view.rows, r0 + half + 1))
    cols = np.arange(max(0, c0 - half), min(view.columns, c0 + half + 1))
    if len(rows) == 0 or len(cols) == 0:
        return
    gr = np.exp(-0.5 * ((rows + 0.5 - u[0]) / sigma) ** 2)
    gc = np.exp(-0.5 * ((cols + 0.5 - w[0]) / sigma) ** 2)
    blob = np.outer(gr, gc) / (2.0 * math.pi * sigma**2)
    image[np.ix_(rows, cols)] += total * blob


def _spatter(image: FloatArray, arc: ArcLight, view: ArcView, arc_mm: FloatArray,
             up: FloatArray, t_s: float, rng: np.random.Generator) -> None:  # fmt: skip
    """Each droplet's streak over the exposure, sampled densely enough to be continuous."""
    drops = draw_spatter(rng, arc.process, arc.current_a, arc_mm + 1.0 * up, t_s,
                         arc.exposure_s, up=up)  # fmt: skip
    if len(drops) == 0:
        return
    ends = drops.streaks(t_s, arc.exposure_s, samples=2)
    u, w, _ = view.project(ends.reshape(-1, 3))
    length_px = np.hypot(*(np.stack([u, w]).reshape(2, -1, 2)[..., 1]
                           - np.stack([u, w]).reshape(2, -1, 2)[..., 0]))  # fmt: skip
    samples = int(np.clip(np.nanmax(length_px, initial=1.0) * 1.5, 2, 256))
    path = drops.streaks(t_s, arc.exposure_s, samples=samples)  # (n, k, 3)
    height = (path - arc_mm) @ up
    alive = height > -0.5  # a droplet that reaches the plate is gone
    duration = (t_s + arc.exposure_s - np.maximum(drops.birth_s, t_s)) / arc.exposure_s
    per_sample = drops.intensity_w_sr(arc.band) * np.clip(duration, 0.0, 1.0) / samples
    pts = path.reshape(-1, 3)
    u, w, front = view.project(pts)
    e = _point_electrons(view, pts, np.repeat(per_sample, samples))
    keep = alive.ravel() & front & np.isfinite(u) & np.isfinite(w)
    _splat(image, u[keep], w[keep], e[keep])


def arc_electrons(
    arc: ArcLight,
    view: ArcView,
    caster: Any,
    mat: Material,
    arc_mm: FloatArray,
    up: FloatArray,
    t_s: float,
    rng: np.random.Generator,
    travel: FloatArray | None = None,
) -> FloatArray:
    """Electrons per pixel (rows, columns) of the arc's light in one exposure: the plate it
    lights and heats, the fume, the arc itself and spatter (see the module docstring).
    ``arc_mm`` the arc's root on the part (world), ``up`` the plate's normal there (world,
    unit), ``t_s`` the frame's start; spatter is drawn from ``rng``; ``travel`` the
    direction the arc moves (for Rosenthal's field, with ``arc.heat``)."""
    arc_mm = np.asarray(arc_mm, dtype=np.float64)
    up = np.asarray(up, dtype=np.float64)
    up = up / np.linalg.norm(up)
    column = arc_mm + 0.5 * light.arc_radius_mm(arc.process, arc.current_a) * up
    j = light.arc_in_band_intensity(arc.process, arc.current_a, arc.band)
    image = _smooth_terms(arc, view, caster, mat, column, j, (arc_mm, up, travel))
    transmission = 1.0
    if arc.fume:
        sigma0, scale, _ = fume_model.fume_sigma(arc.process, arc.current_a)
        d = column - view.center
        dist = float(np.linalg.norm(d))
        transmission = float(fume_model.transmission(view.center[None, :], (d / dist)[None, :],
                                                     dist, column, sigma0, scale)[0])  # fmt: skip
    _direct_arc(image, arc, view, column, j, transmission)
    if arc.spatter:
        _spatter(image, arc, view, arc_mm, up, t_s, rng)
    return image


@dataclass(frozen=True)
class ArcFrame:
    """The arc in one frame, what the renderer takes: the settings ``light``, the arc's root
    ``arc_mm`` (3,) on the part, the plate's normal ``up`` (3,) and the direction of travel
    ``travel`` (3,) or None, world frame."""

    light: ArcLight
    arc_mm: FloatArray
    up: FloatArray
    travel: FloatArray | None = None
