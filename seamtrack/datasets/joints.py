"""Joint cross-sections built analytically, with their seam point and named feature points.

A section lives in the *seam frame* {S} of one sample: x_S along the seam, y_S lateral, z_S into
the part (away from the sensor), origin at the seam point. Every surface is the section's
polyline extruded along x_S, so a laser ray's first hit is the first crossing of its (y, z)
projection with the polyline (:mod:`seamtrack.datasets.kernel`). The shapes and seam points are
those of :func:`seamtrack.features.synthetic.joint_section` (a test holds them equal), shifted
so that the seam point is the origin; this module adds the feature points and builds the
vertices without numpy's per-call overhead (it runs once per sample).

Feature points, by family (NaN rows pad to :data:`MAX_FEATURES`):

* ``square-butt``: the plates' top edges (left, right) and bottom edges seen through the gap.
* ``v-groove``: the top edges of the bevels, the root corners (where bevel meets root face, the
  seam point is their midpoint) and the root's bottom edges.
* ``fillet``: the corner; ``outside-corner``: the apex.
* ``lap``: the top sheet's upper and lower edges, and the root (the seam point) below them.
* ``flat``: none, and no seam point.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
from numpy.typing import NDArray

#: Half length of the "infinite" plates, mm (as in the synthetic profiles).
FAR_MM = 1000.0
#: Length of the fillet and outside-corner faces, mm (as in the synthetic profiles).
FACE_MM = 60.0
#: A tack's mound is drawn with this many straight pieces (a 6 mm wide, 0.5 mm high mound is
#: then within 0.001 mm of its arc: far below a pixel).
TACK_PIECES = 24

FEATURES: dict[str, tuple[str, ...]] = {
    "square-butt": ("left_edge", "right_edge", "left_bottom", "right_bottom"),
    "v-groove": (
        "left_edge", "right_edge", "left_root_corner", "right_root_corner", "left_root_bottom",
        "right_root_bottom",
    ),
    "fillet": ("corner",),
    "lap": ("top_sheet_upper_edge", "top_sheet_lower_edge", "root"),
    "outside-corner": ("apex",),
    "flat": (),
}  # fmt: skip
MAX_FEATURES = max(len(v) for v in FEATURES.values())


def section(
    family: str,
    *,
    thickness_mm: float,
    groove_angle_rad: float,
    root_face_mm: float,
    gap_mm: float,
    misalignment_mm: float,
    web_angle_rad: float,
    corner_angle_rad: float,
) -> tuple[list[list[tuple[float, float]]], tuple[float, float] | None, list[tuple[float, float]]]:
    """The cross-section of one joint, in the joint's own coordinates (top surface at z = 0).

    Parameters not used by ``family`` are ignored. Lap joints take ``thickness_mm`` as the top
    sheet's thickness and ``gap_mm`` as the gap between the sheets.

    Returns
    -------
    polylines : list of lists of (y, z)
        The visible surfaces, each a chain of vertices.
    seam : (y, z) or None
        The seam point (None for ``flat``).
    features : list of (y, z)
        In the order of :data:`FEATURES` ``[family]``.
    """
    L = FAR_MM
    t, g, m = thickness_mm, gap_mm, misalignment_mm
    if family == "flat":
        return [[(-L, 0.0), (L, 0.0)]], None, []
    if family == "square-butt":
        left = [(-L, 0.0), (-g / 2, 0.0), (-g / 2, t)]
        right = [(g / 2, t + m), (g / 2, m), (L, m)]
        features = [(-g / 2, 0.0), (g / 2, m), (-g / 2, t), (g / 2, t + m)]
        return [left, right], (0.0, m / 2), features
    if family == "v-groove":
        r = root_face_mm
        w2 = g / 2 + (t - r) * math.tan(groove_angle_rad / 2)
        left = [(-L, 0.0), (-w2, 0.0), (-g / 2, t - r), (-g / 2, t)]
        right = [(g / 2, t + m), (g / 2, t - r + m), (w2, m), (L, m)]
        features = [(-w2, 0.0), (w2, m), (-g / 2, t - r), (g / 2, t - r + m), (-g / 2, t),
                    (g / 2, t + m)]  # fmt: skip
        return [left, right], (0.0, t - r + m / 2), features
    if family in ("fillet", "outside-corner"):
        half = (web_angle_rad if family == "fillet" else corner_angle_rad) / 2
        sign = -1.0 if family == "fillet" else 1.0  # fillet faces rise towards the sensor
        dy, dz = FACE_MM * math.sin(half), sign * FACE_MM * math.cos(half)
        return [[(-dy, dz), (0.0, 0.0), (dy, dz)]], (0.0, 0.0), [(0.0, 0.0)]
    if family == "lap":
        lower = [(-L, 0.0), (L, 0.0)]
        top = [(L, -g), (0.0, -g), (0.0, -g - t), (L, -g - t)]
        return [lower, top], (0.0, 0.0), [(0.0, -g - t), (0.0, -g), (0.0, 0.0)]
    raise ValueError(f"unknown joint family {family!r}")


def tack_mound(
    seam: tuple[float, float], height_mm: float, width_mm: float
) -> list[tuple[float, float]]:
    """A tack weld over the seam: the circular arc from ``seam -+ width/2`` through the crown
    ``height_mm`` in front of the seam point (towards the sensor), as a vertex chain."""
    half = width_mm / 2
    # Circle through (-half, 0), (0, -h), (half, 0) relative to the seam point: centre on the
    # z axis at depth c with c^2 + half^2 = (c + h)^2.
    c = (half * half - height_mm * height_mm) / (2 * height_mm)
    radius = c + height_mm
    start = math.atan2(-c, -half)  # angle of (-half, -c) seen from the centre (0, c)
    stop = math.atan2(-c, half)
    sweep = (stop - start) % (2 * math.pi)
    if (-math.pi / 2 - start) % (2 * math.pi) > sweep:  # go the way round through the crown
        sweep -= 2 * math.pi
    y0, z0 = seam
    out = []
    for i in range(TACK_PIECES + 1):
        a = start + sweep * i / TACK_PIECES
        out.append((y0 + radius * math.cos(a), z0 + c + radius * math.sin(a)))
    return out


def segments(polylines: list[list[tuple[float, float]]], shift: tuple[float, float]) -> NDArray:
    """(k, 4) float segments ``(y0, z0, y1, z1)`` of the polylines moved by ``-shift``; pieces
    of zero length (a zero root face) are dropped."""
    flat: list[tuple[float, float, float, float]] = []
    sy, sz = shift
    for chain in polylines:
        for (y0, z0), (y1, z1) in itertools.pairwise(chain):
            if y0 != y1 or z0 != z1:
                flat.append((y0 - sy, z0 - sz, y1 - sy, z1 - sz))
    return np.array(flat, dtype=np.float64)


def extruded_mesh(segs: NDArray, half_length_mm: float = FAR_MM) -> tuple[NDArray, NDArray]:
    """The section's segments ``(y0, z0, y1, z1)`` (k, 4) extruded along x_S over
    ``[-half_length_mm, half_length_mm]``: vertices (4k, 3) float and faces (2k, 3) int, two
    triangles a segment (the surface that :mod:`seamtrack.datasets.kernel` intersects)."""
    s = np.asarray(segs, dtype=np.float64)
    k = len(s)
    x = np.array([-half_length_mm, half_length_mm, half_length_mm, -half_length_mm])
    yz = s[:, [0, 1, 0, 1, 2, 3, 2, 3]].reshape(k, 4, 2)  # corners: (a, a, b, b)
    vertices = np.concatenate([np.broadcast_to(x[None, :, None], (k, 4, 1)), yz], axis=2)
    base = 4 * np.arange(k)[:, None]
    faces = np.concatenate([base + [0, 1, 2], base + [0, 2, 3]], axis=1).reshape(2 * k, 3)
    return vertices.reshape(4 * k, 3), faces
