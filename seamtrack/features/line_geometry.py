"""The laser plane's line geometry, once for every extractor.

* :class:`Line`: a straight piece of a profile as the Python side of the extractors holds it
  (its inliers, centroid, unit direction, the inliers' coordinates along it, rms residual);
  built from a fit by :meth:`Line.from_fit` and turned end for end by :meth:`Line.flipped`.
* :class:`LineThrough`: its compiled form, what numba kernels pass (centroid and unit direction,
  as floats); :class:`LineFit` and :class:`LineAlong` add the rms and the coordinates.
* The total-least-squares fit: :func:`principal_angle` of the centred second moments, through
  chosen points (:func:`fit_points`, :func:`fit_line`) or through spans of points
  (:func:`fit_spans`, :func:`fit_range`).
* Collinear groups: whether a group's anchor line :func:`holds` a piece.
* :class:`Point`.

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray, IntArray
from seamtrack.jit import KERNEL


class Point(NamedTuple):
    """A point in the laser plane (y, z; mm)."""

    y: float
    z: float


class LineThrough(NamedTuple):
    """A line, compiled form: its centroid (``cy``, ``cz``) and unit direction (``dy``,
    ``dz``)."""

    cy: float
    cz: float
    dy: float
    dz: float


class LineFit(NamedTuple):
    """A total-least-squares line: centroid (y, z), unit direction (y, z), rms residual."""

    cy: float
    cz: float
    dy: float
    dz: float
    rms: float


class LineAlong(NamedTuple):
    """A :class:`LineFit` and its points' coordinates along the line."""

    cy: float
    cz: float
    dy: float
    dz: float
    rms: float
    along: FloatArray


@dataclass
class Line:
    """A straight piece of a profile (internal to the extractors; mutable while built).

    ``index`` are the inliers' positions in the kept points (column order); ``direction``
    points along increasing column; ``t`` are the inliers' coordinates along it.
    """

    index: NDArray[np.intp]
    centroid: FloatArray
    direction: FloatArray
    t: FloatArray
    rms: float

    @classmethod
    def from_fit(cls, index: NDArray[np.intp], fit: LineAlong) -> Line:
        """The line of a fit (:func:`fit_line`) through the points ``index``."""
        return cls(
            index, np.array([fit.cy, fit.cz]), np.array([fit.dy, fit.dz]), fit.along, fit.rms
        )

    def flipped(self) -> Line:
        """The same line, its direction (and the coordinates along it) reversed."""
        return Line(self.index, self.centroid, -self.direction, -self.t, self.rms)

    @functools.cached_property
    def normal(self) -> FloatArray:
        return np.array([-self.direction[1], self.direction[0]])

    @property
    def count(self) -> int:
        return len(self.index)

    @property
    def extent(self) -> float:
        return float(self.t[-1] - self.t[0]) if len(self.t) else 0.0

    def point(self, t: float) -> FloatArray:
        return self.centroid + t * self.direction

    @functools.cached_property
    def scalars(self) -> tuple[float, float, float, float, float, float]:
        """Centroid (y, z), direction (y, z) and the first and last inliers' coordinates
        along the line, as floats (scalar tests without numpy's per-call overhead)."""
        (cy, cz), (dy, dz) = self.centroid.tolist(), self.direction.tolist()
        t0, t1 = float(self.t[0]), float(self.t[-1])  # IndexError on no inliers, as before
        return cy, cz, dy, dz, t0, t1

    @functools.cached_property
    def _steps(self) -> tuple[float, float]:
        k = min(10, len(self.t) - 1)
        if k < 1:
            return 0.0, 0.0
        t = self.t
        return float(abs(t[k] - t[0])) / k, float(abs(t[-1] - t[-1 - k])) / k

    def step(self, at_end: bool) -> float:
        """Mean spacing of the last (``at_end``) or first ten inliers along the line."""
        return self._steps[1 if at_end else 0]

    def end(self, at_end: bool) -> FloatArray:
        """The line's end half a spacing beyond its last (first) inlier."""
        half = 0.5 * self.step(at_end)
        return self.point(float(self.t[-1] + half if at_end else self.t[0] - half))


# ----------------------------------------------------------------- total least squares
@numba.njit(**KERNEL)
def principal_angle(syy: float, szz: float, syz: float) -> float:
    """Angle (rad) of the principal axis of centred second moments: the direction of the
    total-least-squares line (up to its sign)."""
    return 0.5 * math.atan2(2.0 * syz, syy - szz)


@numba.njit(**KERNEL)
def fit_points(p: FloatArray, idx: IntArray, n: int) -> LineFit:
    """Total-least-squares line through ``p[idx[:n]]``: centroid, unit direction (from the
    first point towards the last), rms residual."""
    cy = 0.0
    cz = 0.0
    for k in range(n):
        cy += p[idx[k], 0]
        cz += p[idx[k], 1]
    cy /= n
    cz /= n
    syy = 0.0
    szz = 0.0
    syz = 0.0
    for k in range(n):
        dy, dz = p[idx[k], 0] - cy, p[idx[k], 1] - cz
        syy += dy * dy
        szz += dz * dz
        syz += dy * dz
    theta = principal_angle(syy, szz, syz)
    uy, uz = math.cos(theta), math.sin(theta)
    a, b = idx[0], idx[n - 1]
    if uy * (p[b, 0] - p[a, 0]) + uz * (p[b, 1] - p[a, 1]) < 0.0:
        uy, uz = -uy, -uz
    rr = 0.0
    for k in range(n):
        r = -(p[idx[k], 0] - cy) * uz + (p[idx[k], 1] - cz) * uy
        rr += r * r
    return LineFit(cy, cz, uy, uz, math.sqrt(rr / n))


@numba.njit(**KERNEL)
def fit_line(p: FloatArray, idx: IntArray) -> LineAlong:
    """Total-least-squares line through ``p[idx]`` (at least one point): :func:`fit_points`
    and the points' coordinates along the line."""
    n = idx.shape[0]
    cy, cz, uy, uz, rms = fit_points(p, idx, n)
    t = np.empty(n)
    for k in range(n):
        t[k] = (p[idx[k], 0] - cy) * uy + (p[idx[k], 1] - cz) * uz
    return LineAlong(cy, cz, uy, uz, rms, t)


@numba.njit(**KERNEL)
def fit_spans(p: FloatArray, lo: int, hi: int, lo2: int, hi2: int) -> LineThrough:
    """Total-least-squares line through ``p[lo:hi]`` and ``p[lo2:hi2]``: centroid and unit
    direction (its sign as the principal angle gives it)."""
    n = (hi - lo) + (hi2 - lo2)
    cy = 0.0
    cz = 0.0
    for r in ((lo, hi), (lo2, hi2)):
        for i in range(r[0], r[1]):
            cy += p[i, 0]
            cz += p[i, 1]
    cy /= n
    cz /= n
    syy = 0.0
    szz = 0.0
    syz = 0.0
    for r in ((lo, hi), (lo2, hi2)):
        for i in range(r[0], r[1]):
            dy, dz = p[i, 0] - cy, p[i, 1] - cz
            syy += dy * dy
            szz += dz * dz
            syz += dy * dz
    theta = principal_angle(syy, szz, syz)
    return LineThrough(cy, cz, math.cos(theta), math.sin(theta))


@numba.njit(**KERNEL)
def fit_range(p: FloatArray, lo: int, hi: int) -> LineThrough:
    """Total-least-squares line through ``p[lo:hi]``: centroid and unit direction (from the
    first point towards the last)."""
    cy, cz, uy, uz = fit_spans(p, lo, hi, hi, hi)
    if uy * (p[hi - 1, 0] - p[lo, 0]) + uz * (p[hi - 1, 1] - p[lo, 1]) < 0.0:
        uy, uz = -uy, -uz
    return LineThrough(cy, cz, uy, uz)


# ----------------------------------------------------------------- corners
#: Lines within this angle (rad) of each other meet in no corner.
CORNER_MIN_RAD = math.radians(20.0)


class Crossing(NamedTuple):
    """Where two lines cross (``y``, ``z``), when they meet in a corner (``found``)."""

    found: bool
    y: float
    z: float


@numba.njit(**KERNEL)
def corner_crossing(line: LineThrough, other: LineThrough, cos_min: float) -> Crossing:
    """The crossing of two lines that meet in a corner: their directions more than
    ``acos(cos_min)`` apart (and not parallel); else not found."""
    cy, cz, dy, dz = line
    ocy, ocz, ody, odz = other
    if abs(dy * ody + dz * odz) > cos_min:
        return Crossing(False, 0.0, 0.0)  # too near parallel: no corner
    det = dy * odz - dz * ody
    if abs(det) < 1e-9:
        return Crossing(False, 0.0, 0.0)
    s = ((ocy - cy) * odz - (ocz - cz) * ody) / det
    return Crossing(True, cy + s * dy, cz + s * dz)


@numba.njit(**KERNEL)
def end_distance(line: LineThrough, t_first: float, t_last: float, y: float, z: float) -> float:
    """Distance of (y, z) from the nearer of a line's end inliers (at ``t_first`` and
    ``t_last`` along it): whether a corner found on it lies at one of its ends."""
    cy, cz, dy, dz = line
    near = math.hypot(cy + t_first * dy - y, cz + t_first * dz - z)
    far = math.hypot(cy + t_last * dy - y, cz + t_last * dz - z)
    return far if far < near else near


@numba.njit(**KERNEL)
def holds(
    anchor: LineThrough,
    line: LineThrough,
    t_first: float,
    t_last: float,
    cos_max: float,
    tol: float,
) -> bool:
    """Whether ``anchor`` holds ``line`` in its collinear group: their directions within
    ``acos(cos_max)`` and both of ``line``'s end inliers (at ``t_first``, ``t_last`` along it)
    within ``tol`` of ``anchor`` (collinear_members' test, as the plates' and the V's
    extractors group their pieces)."""
    cy, cz, dy, dz = line
    e0y, e0z = cy + t_first * dy, cz + t_first * dz
    e1y, e1z = cy + t_last * dy, cz + t_last * dz
    ay, az, ady, adz = anchor
    return (
        abs(ady * dy + adz * dz) >= cos_max
        and abs((e0y - ay) * -adz + (e0z - az) * ady) <= tol
        and abs((e1y - ay) * -adz + (e1z - az) * ady) <= tol
    )


class TipCorner(NamedTuple):
    """A corner found at a line's end (:func:`corner_near`): found, where (y, z), and its
    distance from the line's end."""

    found: bool
    y: float
    z: float
    d: float


@numba.njit(**KERNEL)
def corner_near(
    line: LineThrough, tip_y: float, tip_z: float, other: LineThrough, t_first: float,
    t_last: float, cos_min: float, reach: float, best_d: float, near_max: float,
) -> TipCorner:  # fmt: skip
    """The corner ``line``'s end (its tip at ``tip_y``, ``tip_z``) makes with ``other``:
    their :func:`corner_crossing` when it lies within ``reach`` of the tip, nearer than
    ``best_d`` (a corner found before), and within ``near_max`` of one of ``other``'s end
    inliers (at ``t_first``, ``t_last`` along it: the corner lies at its end); else not
    found. The corner search of the plates' and the V's extractors."""
    hit, xy, xz = corner_crossing(line, other, cos_min)
    if not hit:
        return TipCorner(False, 0.0, 0.0, 0.0)
    d = math.hypot(xy - tip_y, xz - tip_z)
    if d > reach or d >= best_d:
        return TipCorner(False, 0.0, 0.0, 0.0)
    if end_distance(other, t_first, t_last, xy, xz) <= near_max:
        return TipCorner(True, xy, xz, d)
    return TipCorner(False, 0.0, 0.0, 0.0)
