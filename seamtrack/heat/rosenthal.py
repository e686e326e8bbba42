"""Rosenthal's quasi-steady temperature fields of a heat source moving at constant speed over a
plate (D. Rosenthal, "The theory of moving sources of heat and its application to metal
treatments", Trans. ASME 68 (1946) 849-866), in the source's frame: x along the travel (the
source at the origin, x > 0 ahead of it), y across, z into the plate from the top face.

With theta = T - T0, k = v / (2 a), lambda the conductivity and a the diffusivity:

- thick plate (a point source on the surface of a half-space):
  ``theta = q / (2 pi lambda R) exp(-k (x + R))``, R = |(x, y, z)|;
- thin plate of thickness d (a line source through it, the heat uniform through the thickness):
  ``theta = q / (2 pi lambda d) exp(-k x) K0(k r)``, r = |(x, y)|, written with the scaled
  ``k0e(u) = exp(u) K0(u)`` as ``exp(-k (x + r)) k0e(k r)`` so that neither factor over- or
  underflows far from the source;
- a plate of finite thickness d (the point source on its top face, both faces adiabatic): the
  point source and its images in the two faces, at z = 2 n d for every integer n,
  ``theta = q / (2 pi lambda) sum_n exp(-k (x + R_n)) / R_n``. It is the thick plate when
  d >> a / v and tends to the thin plate when d << a / v.

Heat losses from the faces are left out (as in Rosenthal's solutions), and so is any change of
the constants with temperature. The fields are those of a point or line: meaningful outside the
weld pool, infinite at the source itself (asked there, they raise :class:`SeamtrackError`).
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.special import k0e

from seamtrack.errors import SeamtrackError

#: Points closer than this to the source (to its axis, for the line source) are at the
#: singularity: the point and line sources' fields are infinite there.
SINGULAR_RADIUS_MM = 1e-6
#: The image sum stops when the estimated rest is below this fraction of the sum.
IMAGE_RTOL = 1e-13
#: At most this many images on each side (a plate thinner than about a / v / 10^4 is a thin
#: plate: use ``thickness_mm`` with :func:`rosenthal_temperature`).
MAX_IMAGES = 200_000


class ArcProcess(Protocol):
    """What the heat input needs of a scene's ``[process]``
    (:class:`seamtrack.simulation.config.ProcessConfig`)."""

    voltage_v: float
    current_a: float
    thermal_efficiency: float


def arc_power_w(*, voltage_v: float, current_a: float, thermal_efficiency: float) -> float:
    """The heat the arc puts into the plate, W: ``thermal_efficiency * U * I``."""
    _check_positive(voltage_v, "process.voltage_v")
    _check_positive(current_a, "process.current_a")
    eta = _finite(thermal_efficiency, "process.thermal_efficiency")
    if not 0.0 < eta <= 1.0:
        raise SeamtrackError(
            f"a thermal efficiency of {eta:g} is not a fraction of the arc's power",
            field="process.thermal_efficiency",
            fix="give a value in (0, 1] (about 0.8 for MIG/MAG, 0.6-0.7 for TIG)",
        )
    return eta * float(voltage_v) * float(current_a)


def process_power_w(process: ArcProcess) -> float:
    """:func:`arc_power_w` of a scene's ``[process]`` section."""
    return arc_power_w(
        voltage_v=process.voltage_v,
        current_a=process.current_a,
        thermal_efficiency=process.thermal_efficiency,
    )


def rosenthal_temperature(
    points_mm: ArrayLike,
    *,
    power_w: float,
    speed_mm_s: float,
    conductivity_w_per_mm_k: float,
    diffusivity_mm2_per_s: float,
    thickness_mm: float | None = None,
    ambient_c: float = 20.0,
) -> NDArray[np.float64]:
    """Rosenthal's quasi-steady temperature (degrees Celsius) at points in the source's frame.

    Parameters
    ----------
    points_mm : array_like, shape (..., 3)
        Points in the moving source's frame, mm: x along the travel (the source at the origin),
        y across, z into the plate (0 on the top face). With ``thickness_mm`` a point may have
        two coordinates (x, y): the thin plate's field does not vary through the thickness.
    power_w : float
        Heat into the plate, W (``thermal_efficiency * U * I``: :func:`arc_power_w`).
    speed_mm_s : float
        Travel speed, mm/s, > 0.
    conductivity_w_per_mm_k, diffusivity_mm2_per_s : float
        The plate's conductivity and diffusivity
        (:data:`seamtrack.heat.materials.THERMAL_MATERIALS` has cited values).
    thickness_mm : float, optional
        ``None``: a thick plate (point source on a half-space). A value: a thin plate of that
        thickness (line source, heat uniform through the thickness). For a plate in between,
        :func:`image_source_temperature`.
    ambient_c : float
        The plate's temperature far from the arc.

    Returns
    -------
    numpy.ndarray, shape points_mm.shape[:-1]
    """
    k, scale = _constants(
        power_w, speed_mm_s, conductivity_w_per_mm_k, diffusivity_mm2_per_s, ambient_c
    )
    if thickness_mm is None:
        p = _points(points_mm, dims=(3,))
        _check_depth(p, None)
        x = p[..., 0]
        big_r = np.sqrt(np.sum(p * p, axis=-1))
        _check_singular(big_r, "the point source")
        theta = scale * np.exp(-k * (x + big_r)) / big_r
        return np.asarray(ambient_c + theta, dtype=float)
    d = _check_positive(thickness_mm, "thickness_mm")
    p = _points(points_mm, dims=(2, 3))
    if p.shape[-1] == 3:
        _check_depth(p, d)
    x = p[..., 0]
    r = np.hypot(x, p[..., 1])
    _check_singular(r, "the line source's axis")
    theta = scale / d * np.exp(-k * (x + r)) * k0e(k * r)
    return np.asarray(ambient_c + theta, dtype=float)


def image_source_temperature(
    points_mm: ArrayLike,
    *,
    power_w: float,
    speed_mm_s: float,
    conductivity_w_per_mm_k: float,
    diffusivity_mm2_per_s: float,
    thickness_mm: float,
    ambient_c: float = 20.0,
) -> NDArray[np.float64]:
    """The temperature (degrees Celsius) of a plate of finite thickness: the point source on
    its top face and its images in both faces (z = 2 n d), summed until the rest is below
    :data:`IMAGE_RTOL` of the sum. Arguments as :func:`rosenthal_temperature`; points need
    0 <= z <= ``thickness_mm``."""
    k, scale = _constants(
        power_w, speed_mm_s, conductivity_w_per_mm_k, diffusivity_mm2_per_s, ambient_c
    )
    d = _check_positive(thickness_mm, "thickness_mm")
    p = _points(points_mm, dims=(3,))
    _check_depth(p, d)
    shape = p.shape[:-1]
    flat = p.reshape(-1, 3)
    x, rho2, z = flat[:, 0], flat[:, 0] ** 2 + flat[:, 1] ** 2, flat[:, 2]
    r0 = np.sqrt(rho2 + z * z)
    _check_singular(r0, "the point source")
    total = np.exp(-k * (x + r0)) / r0
    n, block = 1, 16
    while True:
        shifts = 2.0 * d * np.arange(n, n + block)
        terms = np.zeros((flat.shape[0], block))
        for sign in (-1.0, 1.0):
            big_r = np.sqrt(rho2[:, None] + (z[:, None] + sign * shifts[None, :]) ** 2)
            terms += np.exp(-k * (x[:, None] + big_r)) / big_r
        total += terms.sum(axis=1)
        last, before = terms[:, -1], terms[:, -2]
        with np.errstate(divide="ignore", invalid="ignore"):
            ratio = np.where(before > 0, last / before, 0.0)
            rest = np.where(ratio < 1.0, last * ratio / (1.0 - ratio), np.inf)
        n += block
        if np.all(rest <= IMAGE_RTOL * total):
            break
        if n > MAX_IMAGES:
            raise SeamtrackError(
                f"a {d:g} mm plate needs more than {MAX_IMAGES} image sources at this speed "
                "and diffusivity",
                field="thickness_mm",
                fix="the plate is thin: use rosenthal_temperature(..., thickness_mm=...) "
                "(the line source)",
            )
        block = min(2 * block, 4096)
    return np.asarray(ambient_c + scale * total, dtype=float).reshape(shape)


def _constants(
    power_w: float, speed: float, conductivity: float, diffusivity: float, ambient_c: float
) -> tuple[float, float]:
    """k = v / (2 a) (1/mm) and q / (2 pi lambda) (K mm)."""
    q = _finite(power_w, "power_w")
    if q < 0:
        raise SeamtrackError(
            f"a heat input of {q:g} W takes heat out of the plate",
            field="power_w",
            fix="give the heat into the plate, >= 0 W (thermal efficiency x U x I)",
        )
    v = _finite(speed, "speed_mm_s")
    if v <= 0:
        raise SeamtrackError(
            f"a travel speed of {v:g} mm/s has no quasi-steady field (Rosenthal's solutions "
            "are for a source moving at constant speed)",
            field="speed_mm_s",
            fix="give the torch's travel speed, > 0 mm/s",
        )
    lam = _check_positive(conductivity, "conductivity_w_per_mm_k")
    a = _check_positive(diffusivity, "diffusivity_mm2_per_s")
    _finite(ambient_c, "ambient_c")
    return v / (2.0 * a), q / (2.0 * math.pi * lam)


def _finite(value: Any, field: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise SeamtrackError(f"{value!r} is not a number", field=field, fix="give a number")
    if not math.isfinite(float(value)):
        raise SeamtrackError(f"{value!r} is not finite", field=field, fix="give a finite number")
    return float(value)


def _check_positive(value: Any, field: str) -> float:
    number = _finite(value, field)
    if number <= 0:
        raise SeamtrackError(f"{number:g} is not positive", field=field, fix="give a value > 0")
    return number


def _points(points_mm: ArrayLike, *, dims: tuple[int, ...]) -> NDArray[np.float64]:
    try:
        p = np.asarray(points_mm, dtype=float)
    except (TypeError, ValueError):
        raise SeamtrackError(
            "the points are not an array of numbers", field="points_mm", fix="give (..., 3) mm"
        ) from None
    if p.ndim == 0 or p.shape[-1] not in dims:
        raise SeamtrackError(
            f"points of shape {p.shape} have no {' or '.join(map(str, dims))} coordinates",
            field="points_mm",
            fix="give points of shape (..., 3): x along the travel, y across, z into the plate",
        )
    if not np.all(np.isfinite(p)):
        raise SeamtrackError(
            "a point has a NaN or infinite coordinate", field="points_mm", fix="give finite mm"
        )
    return p


def _check_depth(p: NDArray[np.float64], thickness: float | None) -> None:
    z = p[..., 2]
    low = np.flatnonzero(z.ravel() < 0)
    if low.size:
        raise SeamtrackError(
            f"point {low[0]} lies above the plate (z = {z.ravel()[low[0]]:g} mm)",
            field="points_mm",
            fix="z is the depth into the plate: give z >= 0",
        )
    if thickness is not None:
        deep = np.flatnonzero(z.ravel() > thickness)
        if deep.size:
            raise SeamtrackError(
                f"point {deep[0]} lies below the plate (z = {z.ravel()[deep[0]]:g} mm > the "
                f"thickness {thickness:g} mm)",
                field="points_mm",
                fix="give 0 <= z <= thickness_mm",
            )


def _check_singular(distance: NDArray[np.float64], what: str) -> None:
    inside = np.flatnonzero(distance.ravel() < SINGULAR_RADIUS_MM)
    if inside.size:
        raise SeamtrackError(
            f"point {inside[0]} lies on {what} ({distance.ravel()[inside[0]]:g} mm from it), "
            "where the field is infinite",
            field="points_mm",
            fix=f"ask for points at least {SINGULAR_RADIUS_MM:g} mm from the source (the "
            "Rosenthal field describes the plate outside the weld pool)",
        )
