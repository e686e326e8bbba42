"""Compiled pieces of the two-line models (two plates, a corner's two faces): the named
tables the two-plate kernels pass, where a line ends, and the share of a profile two lines
explain.

Lines are passed as :class:`~seamtrack.features.line_geometry.LineThrough` (centroid and unit
direction, as floats); the profile's
pieces as :class:`PieceLines`, one array per field (piece ``j``'s line is ``pieces.cy[j]``,
...). The arithmetic is that of the numpy formulation of :mod:`seamtrack.features.lines` and
:mod:`seamtrack.features.base` (the same formulas, medians as numpy takes them), so results
agree to rounding. Every kernel returns one value or a named tuple.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray, IntArray
from seamtrack.features.counts import explained_share
from seamtrack.features.line_geometry import CORNER_MIN_RAD, LineThrough, Point, corner_near
from seamtrack.jit import KERNEL


class PieceLines(NamedTuple):
    """The lines of a profile's pieces, a column per field (piece ``j``: ``cy[j]``, ...)."""

    cy: FloatArray
    cz: FloatArray
    dy: FloatArray
    dz: FloatArray


class PieceSpans(NamedTuple):
    """Where each piece's inliers lie along its line: their number (``n_inliers``), the
    first's and the last's coordinates, and the mean spacing of the first and of the last
    ten (:meth:`~seamtrack.features.line_geometry.Line.step`)."""

    n_inliers: IntArray
    t_first: FloatArray
    t_last: FloatArray
    step_first: FloatArray
    step_last: FloatArray


class Steps(NamedTuple):
    """Mean spacing along a line of the first and of the last ten coordinates."""

    first: float
    last: float


class RunEnd(NamedTuple):
    """A run at one of its ends: its line, the end inlier's coordinate along it and the
    step there."""

    line: LineThrough
    t: float
    step: float


@numba.njit(**KERNEL, error_model="numpy")
def piece_line(pieces: PieceLines, j: int) -> LineThrough:
    """Piece ``j``'s line."""
    return LineThrough(pieces.cy[j], pieces.cz[j], pieces.dy[j], pieces.dz[j])


@numba.njit(**KERNEL, error_model="numpy")
def towards(line: LineThrough, y: float, z: float) -> float:
    """Signed distance of (y, z) from ``line``, positive on the sensor's side (the origin)."""
    h = (y - line.cy) * -line.dz + (z - line.cz) * line.dy
    return h if line.cy * -line.dz + line.cz * line.dy < 0 else -h


@numba.njit(**KERNEL, error_model="numpy")
def angle(ady: float, adz: float, bdy: float, bdz: float) -> float:
    """Unsigned angle between two directions (rad, in [0, pi/2])."""
    return math.acos(min(1.0, abs(ady * bdy + adz * bdz)))


@numba.njit(**KERNEL, error_model="numpy")
def median(v: FloatArray) -> float:
    """numpy's median (mean of the two middle values of an even count; NaN propagates). A
    Shell sort of a copy: small code (numba's sort made the kernels slow to compile) and
    fast enough on the few hundred values of a hole."""
    n = v.shape[0]
    for x in v:
        if math.isnan(x):
            return math.nan
    s = v.copy()
    gap = 1
    while gap < n // 3:
        gap = 3 * gap + 1
    while gap > 0:
        for i in range(gap, n):
            x = s[i]
            j = i
            while j >= gap and s[j - gap] > x:
                s[j] = s[j - gap]
                j -= gap
            s[j] = x
        gap //= 3
    if n % 2:
        return s[n // 2]
    return (s[n // 2 - 1] + s[n // 2]) / 2.0


@numba.njit(**KERNEL, error_model="numpy")
def kept(keep: NDArray[np.bool_]) -> IntArray:
    """Positions of the True flags (``np.flatnonzero``)."""
    n = 0
    for x in keep:
        if x:
            n += 1
    k = np.empty(n, dtype=np.int64)
    n = 0
    for i in range(keep.shape[0]):
        if keep[i]:
            k[n] = i
            n += 1
    return k


@numba.njit(**KERNEL, error_model="numpy")
def steps(t: FloatArray) -> Steps:
    """Mean spacing of the first and of the last ten coordinates
    (:meth:`~seamtrack.features.line_geometry.Line.step`)."""
    n = t.shape[0]
    k = min(10, n - 1)
    if k < 1:
        return Steps(0.0, 0.0)
    return Steps(abs(t[k] - t[0]) / k, abs(t[n - 1] - t[n - 1 - k]) / k)


@numba.njit(**KERNEL, error_model="numpy")
def line_end(
    line: LineThrough,
    end: RunEnd,
    at_end: bool,
    skip: int,
    pieces: PieceLines,
    spans: PieceSpans,
    min_points: int,
    spacing: float,
    tol: float,
) -> Point:
    """Where a run's ``line`` ends at ``end`` (its last inlier when ``at_end``, else its
    first): the corner search of :func:`seamtrack.features.vgroove._v_search.corner_with` with the
    pieces of ``min_points`` as the others, ``skip`` the run's own piece or -1. Its crossing with a
    piece meeting it there (a visible corner), else half a step beyond the end inlier."""
    cy, cz, dy, dz = line
    tip_y, tip_z = cy + end.t * dy, cz + end.t * dz
    reach = 3.0 * (spacing if spacing > end.step else end.step) + tol
    cos_min = math.cos(CORNER_MIN_RAD)
    found = False
    best_y = best_z = 0.0
    best_d = math.inf
    for j in range(pieces.cy.shape[0]):
        if spans.n_inliers[j] < min_points or j == skip:
            continue
        wide = spans.step_last[j]
        wide = spans.step_first[j] if spans.step_first[j] > wide else wide
        wide = spacing if spacing > wide else wide
        c = corner_near(
            line, tip_y, tip_z, piece_line(pieces, j), spans.t_first[j], spans.t_last[j],
            cos_min, reach, best_d, 3.0 * wide + tol,
        )  # fmt: skip
        if c.found:
            found, best_y, best_z, best_d = True, c.y, c.z, c.d
    if found:
        return Point(best_y, best_z)
    t = end.t + 0.5 * end.step if at_end else end.t - 0.5 * end.step
    return Point(cy + t * dy, cz + t * dz)


@numba.njit(**KERNEL, error_model="numpy")
def two_lines_share(
    points: FloatArray,
    stray: NDArray[np.bool_],
    lo: int,
    hi: int,
    a: LineThrough | tuple[float, float, float, float],
    b: LineThrough | tuple[float, float, float, float],
    band: float,
) -> float:
    """Share of the surface points (``stray`` left out when it flags each point) within
    ``band`` of their line when line ``a`` runs from the profile's start to kept point
    ``lo`` and line ``b`` from ``hi`` to its end, what lies between them left out:
    :func:`seamtrack.features.base.explained` of a two-plate or two-face model
    (:func:`seamtrack.features.counts.explained_share`). The lines: :class:`LineThrough` or, from
    Python, plain tuples of its fields (numba types a named tuple argument in Python on every
    call, some microseconds; a plain one at once)."""
    a, b = LineThrough(*a), LineThrough(*b)
    m = points.shape[0]
    zones = np.empty((3, 3), dtype=np.int64)
    zones[0, 0], zones[0, 1], zones[0, 2] = 0, lo, 1
    zones[1, 0], zones[1, 1], zones[1, 2] = lo, hi, 0
    zones[2, 0], zones[2, 1], zones[2, 2] = max(hi, lo), m, 1
    fits = np.zeros((3, 1, 4))
    fits[0, 0, 0], fits[0, 0, 1], fits[0, 0, 2], fits[0, 0, 3] = a.cy, a.cz, -a.dz, a.dy
    fits[2, 0, 0], fits[2, 0, 1], fits[2, 0, 2], fits[2, 0, 3] = b.cy, b.cz, -b.dz, b.dy
    surface = ~stray if stray.shape[0] == m else np.ones(m, dtype=np.bool_)
    return explained_share(points, surface, zones, fits, band)
