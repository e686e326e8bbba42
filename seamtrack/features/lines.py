"""Split-and-merge line segmentation of stripe profiles: the front end of the extractors.

:func:`segment_profile` drops isolated outliers against a 5-point running median, estimates the
noise from second differences, cuts the profile at jumps, splits each run by Douglas-Peucker at
a noise-scaled tolerance, merges neighbours that fit one line, and refits each piece by total
least squares on its inliers. :func:`collinear_groups` and :func:`intersect` are the geometry
the family extractors build on, and ``ExtractorBase`` their shared parameters and never-raise
wrapper (the extractors themselves live in :mod:`seamtrack.features.extractors` and
:mod:`seamtrack.features.plates.extractor`).

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from seamtrack.features._segmentation import (
    NO_PIECE,
    SEGMENTED,
    TOO_MANY_PIECES,
    PieceTable,
    buffer_layout,
    segment,
)
from seamtrack.features.arrays import FloatArray
from seamtrack.features.line_geometry import Line, fit_line
from seamtrack.features.refusal import Refusal
from seamtrack.features.robust import (
    CONSTANT,
    DEFAULT_RESOLUTION_MM,
    TOO_FEW_POINTS,
    front_params,
    profile_arrays,
)
from seamtrack.sensing.profiles import Profile

#: A run's end piece is split at a kink of at least this much (rad): a root face at a slant.
_MIN_KINK = math.radians(5.0)

#: The buffers' layout and the front end's settings, built once per set of values (named
#: tuples: immutable, shared): they cost about a microsecond a profile to build.
_layout = functools.lru_cache(maxsize=64)(buffer_layout)
_front_params = functools.lru_cache(maxsize=64)(front_params)


def _fit(points: FloatArray, index: NDArray[np.intp]) -> Line:
    """Total-least-squares line through ``points[index]`` (column order kept); compiled
    (:func:`seamtrack.features.line_geometry.fit_line`): numpy's per-call overhead on a few hundred
    points was most of its cost."""
    if len(index) == 0:
        raise ValueError("no points to fit a line to")
    return Line.from_fit(index, fit_line(points, np.asarray(index, dtype=np.int64)))


@dataclass
class Segments:
    """What :func:`segment_profile` found: kept points, noise and straight pieces."""

    points: FloatArray  # (m, 2) kept points, column order
    sigma: float  # noise estimate (mm)
    tol: float  # split / inlier tolerance (mm)
    spacing: float  # median distance between neighbouring points (mm)
    #: The straight pieces; None: built from ``table`` when first asked for (:attr:`lines`).
    pieces: list[Line] | None
    #: (m,) True for the points of detours (spikes, reflections: in no piece).
    stray: NDArray[np.bool_] = field(default_factory=lambda: np.zeros(0, dtype=bool))
    #: (m,) each kept point's column in the profile.
    columns: NDArray[np.intp] = field(default_factory=lambda: np.zeros(0, dtype=np.intp))
    #: Bounds of the runs between jumps: ``points[runs[k]:runs[k + 1]]``.
    runs: NDArray[np.intp] = field(default_factory=lambda: np.zeros(0, dtype=np.intp))
    #: The range step of the profile's units (mm; 0: not quantized) and the resolution used.
    quantum: float = 0.0
    resolution: float = DEFAULT_RESOLUTION_MM
    #: The pieces as :func:`segment_profile`'s compiled call left them, for the compiled joint
    #: models (:class:`~seamtrack.features._segmentation.PieceTable`: ``index, along, fits,
    #: bounds``). None: build them from ``lines``.
    table: PieceTable | None = None

    @property
    def lines(self) -> list[Line]:
        """The straight pieces, in column order (built on first use: the compiled joint models
        read ``table`` and never need most of them)."""
        if self.pieces is None:
            assert self.table is not None
            self.pieces = [self.line(j) for j in range(self.n_lines)]
        return self.pieces

    @property
    def n_lines(self) -> int:
        return len(self.pieces) if self.pieces is not None else len(self.table.bounds) - 1  # type: ignore[union-attr]

    def line(self, j: int) -> Line:
        """Piece ``j`` (without building the others)."""
        if self.pieces is not None:
            return self.pieces[j]
        assert self.table is not None
        index, along, fits, bounds = self.table
        a, b = int(bounds[j]), int(bounds[j + 1])
        cy, cz, uy, uz, rms, t0, t1 = fits[j].tolist()
        line = Line(index[a:b], fits[j, 0:2], fits[j, 2:4], along[a:b], rms)
        line.__dict__["scalars"] = (cy, cz, uy, uz, t0, t1)  # the cached property, as floats
        return line


def segment_profile(
    profile: Profile,
    *,
    min_tol_mm: float | None = None,
    resolution_mm: float | None = None,
    sigma_factor: float = 5.0,
    min_points: int = 8,
    max_lines: int = 64,
    max_detour_mm: float = 3.0,
) -> Segments | Refusal:
    """Split-and-merge a profile into straight pieces, or say why not (a :class:`Refusal`).

    Parameters
    ----------
    profile : Profile
    min_tol_mm : float, optional
        Floor of the split tolerance (covers pixel quantization); default
        :data:`TOL_RESOLUTIONS` resolutions.
    resolution_mm : float, optional
        The sensor's range resolution; default the profile's range step when its ranges are
        quantized (:func:`~seamtrack.features.robust.range_quantum`), else
        :data:`DEFAULT_RESOLUTION_MM`.
    sigma_factor : float
        Split tolerance = max(floor, sigma_factor * estimated noise).
    min_points : int
        Pieces with fewer inliers are dropped.
    max_lines : int
        More pieces than this means there is no line structure: give up.
    max_detour_mm : float
        Widest detour (spike, reflection) the surface is followed across (mm, lateral).
    """
    arrays = profile_arrays(profile)
    if isinstance(arrays, Refusal):
        return arrays
    pts, valid = arrays
    n = len(pts)
    max_lines = int(max_lines)
    # The compiled call writes into these (see :func:`seamtrack.features._segmentation.segment`).
    at = _layout(n, max_lines)
    floats = np.empty(at.floats)
    ints = np.empty(at.ints, dtype=np.intp)
    stray = np.empty(n, dtype=np.bool_)
    found = segment(
        pts,
        valid,
        _front_params(min_points, resolution_mm, min_tol_mm, sigma_factor, max_detour_mm),
        max_lines,
        _MIN_KINK,
        floats,
        ints,
        stray,
    )
    if found.code != SEGMENTED:
        return Refusal(_WHY[found.code].format(found.kept))
    m, k = found.kept, found.n_pieces
    bounds = ints[at.offsets : at.offsets + k + 1]
    fits = floats[at.fits : at.fits + 7 * k].reshape(k, 7)
    end = int(bounds[-1])
    return Segments(
        floats[at.points : at.points + 2 * m].reshape(m, 2),
        found.sigma,
        found.tol,
        found.spacing,
        None,
        stray[:m],
        ints[at.columns : at.columns + m],
        ints[at.runs : at.runs + found.n_runs],
        found.quantum,
        found.resolution,
        PieceTable(
            ints[at.inliers : at.inliers + end], floats[at.along : at.along + end], fits, bounds
        ),
    )


#: Why :func:`segment_profile` found no pieces, by the compiled call's code.
_WHY = {
    TOO_FEW_POINTS: "too few valid points ({})",
    CONSTANT: "the valid points do not spread out (constant profile)",
    TOO_MANY_PIECES: "no straight pieces (too noisy or curved)",
    NO_PIECE: "no straight pieces with enough points",
}


def collinear_members(
    seg: Segments, lines: list[Line], max_angle_deg: float = 30.0
) -> list[list[int]]:
    """Positions in ``lines`` grouped by the straight line they lie on, largest group first.

    Pieces are taken from the best supported down; each joins the largest earlier group
    whose anchor (its best supported piece) holds both the piece's ends within the
    tolerance (directions within ``max_angle_deg``), so a short piece at a corner cannot
    bridge two lines, and a short stub cut off a plate by an interruption joins the plate.
    """
    order = sorted(range(len(lines)), key=lambda i: -lines[i].count)
    # (centroid, direction, normal) of each group's anchor, as floats: these are a handful
    # of tests on scalars, where numpy's per-call overhead would dominate.
    anchors: list[tuple[float, float, float, float]] = []
    members: list[list[int]] = []
    cos_max = math.cos(math.radians(max_angle_deg))
    tol = seg.tol
    for i in order:
        cy, cz, dy, dz, t0, t1 = lines[i].scalars
        ends = ((cy + t0 * dy, cz + t0 * dz), (cy + t1 * dy, cz + t1 * dz))
        for k, (ay, az, ady, adz) in enumerate(anchors):
            if abs(ady * dy + adz * dz) >= cos_max and all(
                abs((ey - ay) * -adz + (ez - az) * ady) <= tol for ey, ez in ends
            ):
                members[k].append(i)
                break
        else:
            anchors.append((cy, cz, dy, dz))
            members.append([i])
    return members


def collinear_groups(seg: Segments, max_angle_deg: float = 30.0) -> list[Line]:
    """Join pieces that lie on one line, across gaps and interruptions (refit on the union);
    see :func:`collinear_members`."""
    return [
        seg.lines[m[0]]
        if len(m) == 1
        else _fit(seg.points, np.sort(np.concatenate([seg.lines[i].index for i in m])))
        for m in collinear_members(seg, seg.lines, max_angle_deg)
    ]


def intersect(a: Line, b: Line) -> FloatArray | None:
    """(2,) crossing of two lines, or None when (nearly) parallel."""
    (ay, az), (ady, adz) = a.centroid.tolist(), a.direction.tolist()
    (by, bz), (bdy, bdz) = b.centroid.tolist(), b.direction.tolist()
    d = ady * bdz - adz * bdy
    if abs(d) < 1e-9:
        return None
    s = ((by - ay) * bdz - (bz - az) * bdy) / d
    return np.array([ay + s * ady, az + s * adz])


# ----------------------------------------------------------------- the extractors' base
#: What bad data (NaN, degenerate fits, empty selections) can raise inside an extractor: caught
#: and turned into a falsy ``Feature.failed``.
DATA_ERRORS = (
    ValueError,
    IndexError,
    ZeroDivisionError,
    FloatingPointError,
    np.linalg.LinAlgError,
    AttributeError,
    TypeError,
)


#: A gap's wall or a lap's edge face stands at least this steep on the plates (deg). A false
#: reflection is a stray line tilted by at most 45 deg in the laser plane: up to 60 deg on a
#: plate rolled by 15 deg, so it is never taken for a wall.
WALL_DEG = 65.0
