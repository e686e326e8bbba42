"""Compiled counts of the family extractors' joint models: the share of a profile a model's
lines explain (:func:`seamtrack.features.base.explained`) and an arm's support in the V search
(:meth:`seamtrack.features.base.ExtractorBase._arms`). One pass over the kept points each, where the
numpy formulation made a dozen small array operations per zone or group."""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray, IntArray
from seamtrack.features.line_geometry import LineThrough
from seamtrack.jit import KERNEL

#: The columns of :func:`explained_share`'s zones: first and past-the-end kept point, lines.
ZONE_LO, ZONE_HI, ZONE_LINES = range(3)
#: The columns of its lines: a point of the line (its centroid y, z) and its unit normal.
LINE_CY, LINE_CZ, LINE_NY, LINE_NZ = range(4)


@numba.njit(**KERNEL)
def explained_share(
    p: FloatArray,
    surface: NDArray[np.bool_],
    zones: IntArray,
    lines: FloatArray,
    band: float,
) -> float:
    """Share of the surface points within ``band`` of a line of their zone
    (:func:`seamtrack.features.base.explained`): zone ``k`` spans
    ``p[zones[k, ZONE_LO]:zones[k, ZONE_HI]]`` with ``zones[k, ZONE_LINES]`` lines
    (``lines[k, j]``: centroid y, z, normal y, z, columns ``LINE_*``); a zone without a line
    is left out of the count; points in no zone count as unexplained."""
    m = p.shape[0]
    counted = surface.copy()
    ok = np.zeros(m, dtype=np.bool_)
    for k in range(zones.shape[0]):
        lo, hi = max(zones[k, ZONE_LO], 0), min(zones[k, ZONE_HI], m)
        if hi <= lo:
            continue
        if zones[k, ZONE_LINES] == 0:
            counted[lo:hi] = False
            continue
        for j in range(zones[k, ZONE_LINES]):
            line = lines[k, j]
            cy, cz, ny, nz = line[LINE_CY], line[LINE_CZ], line[LINE_NY], line[LINE_NZ]
            for i in range(lo, hi):
                if abs((p[i, 0] - cy) * ny + (p[i, 1] - cz) * nz) <= band:
                    ok[i] = True
    total = 0
    good = 0
    for i in range(m):
        if counted[i]:
            total += 1
            if ok[i]:
                good += 1
    return good / total if total else 0.0


@numba.njit(**KERNEL)
def support(
    p: FloatArray, surface: NDArray[np.bool_], line: LineThrough, band: float, x_u: float,
    sign: float, tol: float,
) -> int:  # fmt: skip
    """Surface points within ``band`` of ``line`` on one side of the point whose projection
    on its direction is ``x_u`` (``sign``: which side; a tolerance past it counts): an arm's
    support (:meth:`seamtrack.features.base.ExtractorBase._arms`)."""
    cy, cz, uy, uz = line
    n = 0
    for i in range(p.shape[0]):
        if surface[i]:
            dy, dz = p[i, 0] - cy, p[i, 1] - cz
            if abs(dy * -uz + dz * uy) <= band:
                if sign * ((p[i, 0] * uy + p[i, 1] * uz) - x_u) >= -tol:
                    n += 1
    return n
