"""The V-groove extractor: two bevels opening towards the sensor, and what lies between their
lower ends (a root gap, a stray line over a root corner, or no gap at all).

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.features.base import ExtractorBase
from seamtrack.features.expect import Expect
from seamtrack.features.lines import Segments
from seamtrack.features.vgroove._v_groove_model import (
    GROOVE,
    NO_PLATE,
    NO_V,
    SIDE_ALONG_PLATE,
    WIDE_ROOT,
    GrooveParams,
    VGrooveResult,
    v_groove,
)
from seamtrack.features.vgroove._v_search import pieces_of
from seamtrack.jit import KERNEL
from seamtrack.sensing.profiles import Feature, Profile, SeamHint

#: Why a V is no groove, by the code of :func:`seamtrack.features.vgroove._v_groove_model.v_groove`.
_REFUSALS = {
    NO_V: "no pair of lines forms the joint",
    NO_PLATE: "not a v-groove: no plate beside the bevels (two faces alone: a fillet?)",
    SIDE_ALONG_PLATE: (
        "not a v-groove: a side of the V runs along a plate (a step or a block's foot)"
    ),
    WIDE_ROOT: (
        "not a v-groove: {:.0f} % of the profile lies between the bevels' lower ends "
        "(a raised block between two plates?)"
    ),
}


def _fill_above(seg: Segments, groove: VGrooveResult) -> float | None:
    """How far (mm) the surface over the seam lies above it, when a fill covers it: the median
    of the points within half a millimetre of the seam across the groove (along the line
    joining the top edges) lies more than max(1.5 mm, a tenth of the seam's depth) above the
    seam, and the surface lies at that depth a quarter of the groove's width there to either
    side as well; else None (an empty V, a root gap, a tack weld, a reflection streak)."""
    n = len(seg.points)
    stray = seg.stray if len(seg.stray) == n else np.zeros(n, dtype=np.bool_)
    above = _fill_height(
        seg.points, stray, groove.top_left_y, groove.top_left_z, groove.top_right_y,
        groove.top_right_z, groove.seam_y, groove.seam_z,
    )  # fmt: skip
    return None if math.isnan(above) else above


@numba.njit(**KERNEL)
def _fill_height(
    points: NDArray[np.float64], stray: NDArray[np.bool_], left_y: float, left_z: float,
    right_y: float, right_z: float, seam_y: float, seam_z: float,
) -> float:  # fmt: skip
    """:func:`_fill_above`'s test, compiled (it runs on every V found): the height, or NaN."""
    length = math.hypot(right_y - left_y, right_z - left_z)
    if not (length > 0.0 and math.isfinite(length)):
        return math.nan
    uy, uz = (right_y - left_y) / length, (right_z - left_z) / length
    vy, vz = -uz, uy
    if vz < 0.0:
        vy, vz = -vy, -vz  # into the groove
    depth = (seam_y - left_y) * vy + (seam_z - left_z) * vz
    n = points.shape[0]
    over = np.empty(n)
    k = 0
    for i in range(n):
        if not stray[i]:
            if abs((points[i, 0] - seam_y) * uy + (points[i, 1] - seam_z) * uz) <= 0.5:
                over[k] = (points[i, 0] - left_y) * vy + (points[i, 1] - left_z) * vz
                k += 1
    if k < 8:
        return math.nan
    middle = np.median(over[:k])
    if np.median(np.abs(over[:k] - middle)) > 0.3:
        return math.nan  # no one surface over the seam (spikes, streaks)
    above = depth - middle
    if not above > max(1.5, 0.1 * depth):
        return math.nan
    # A fill spans the groove: the surface lies at that depth a quarter of the groove's width
    # at that depth to either side too (a reflection streak or a tack does not).
    level = depth - above
    width = length * max(0.0, 1.0 - level / depth) if depth > 0.0 else 0.0
    near_level = max(1.0, 0.25 * above)
    for side in (-1.0, 1.0):
        count = 0
        for i in range(n):
            if not stray[i]:
                qu = (points[i, 0] - seam_y) * uy + (points[i, 1] - seam_z) * uz
                qd = (points[i, 0] - left_y) * vy + (points[i, 1] - left_z) * vz
                if abs(qu - side * 0.25 * width) <= 0.3 and abs(qd - level) <= near_level:
                    count += 1
        if count < 3:
            return math.nan
    return above


@dataclass(frozen=True)
class VGrooveExtractor(ExtractorBase):
    """V-groove: two bevels opening towards the sensor, a plate beside at least one of them.
    Seam: the root centre, midpoint of the bevels' lower ends, when a root gap shows between
    them (the ends level, the V's tip below them empty, the columns between them open);
    else the bevels' intersection (confidence halved unless they meet: the bottom is cut up
    by spikes and dropouts, or filled). Edges: the top edges. It accepts a measured opening of
    ``min_angle_deg``-``max_angle_deg`` (20-150 deg) and is claimed for V's of 40-145 deg
    (>= 90 % found, p95 <= 0.5 mm on real-sensor artefacts: the extractor bench's angle sweep).

    Where a stray line (a false reflection) covers a bevel's root end, the end is hidden:
    it is put at the depth of the other root end below the plates (both root corners lie
    at one depth under their plate: thickness minus root face), within the covered
    stretch (confidence halved). Confidence is halved too when a surface that is no wall
    joins the two root ends: there is no gap between them (a false V where the laser plane
    crosses a mitred corner, a tack weld over the root).

    With a ``hint`` (:class:`~seamtrack.sensing.profiles.SeamHint`, the tracker's expected seam
    point), of the V's the profile shows the one whose apex lies nearest the expected point
    within ``hint.tolerance_mm`` is taken (the V that continues the seam, not the false V where
    the laser plane crosses both grooves of a mitred corner: its apex lies deeper than the
    root); when none lies within the tolerance, the best-supported V, as without a hint.

    Refused too when a fill covers the seam (the surface across the groove's middle lies
    more than max(1.5 mm, a tenth of the depth) above the bevels' meeting point: beads in the
    groove; the groove extractor reads those).

    Refused with a reason when the profile shows no groove (two
    faces alone, a side along the other's plate, a wide root, or less than
    ``min_explained`` of the profile on the model's lines) or when ``expect`` says the
    included angle, the depth below the plates or the gap is implausible.

    The model runs compiled, in one call
    (:func:`seamtrack.features.vgroove._v_groove_model.v_groove`): the Python formulation spent ten
    times the arithmetic's cost on numpy calls on 2-vectors. Its steps: segment the profile
    (``ExtractorBase.segments``), run the groove's model on the pieces, refuse what it refuses or
    what ``expect`` finds implausible, else the seam point.
    """

    name: str = "v-groove"
    min_angle_deg: float = 20.0
    max_angle_deg: float = 150.0
    max_gap_mm: float = 6.0
    min_gap_mm: float = 0.05

    def _extract(
        self, profile: Profile, seg: Segments, hint: SeamHint | None = None
    ) -> Feature | tuple[Feature, float]:
        if not seg.n_lines:
            return Feature.failed(_REFUSALS[NO_V], joint=self.name)
        lo, hi = self._angles(self.min_angle_deg, self.max_angle_deg)
        expect = self.expect if isinstance(self.expect, Expect) else None
        search = self.search_params(False, lo, hi, self.max_gap_mm)  # the bevels reach the root
        if hint is not None:  # prefer the V nearest the expected seam point, within the gate
            hy, hz = hint.point_laser
            ty, tz = hint.tolerance_mm
            search = search._replace(
                hint_y=float(hy), hint_z=float(hz), tol_y=float(ty), tol_z=float(tz)
            )
        params = GrooveParams(
            search=search,
            min_gap=float(self.min_gap_mm),
            gapless=bool(expect is not None and expect.gapless),
        )
        groove = v_groove(
            np.ascontiguousarray(seg.points, dtype=np.float64),
            np.asarray(seg.stray, dtype=np.bool_),
            np.asarray(seg.columns, dtype=np.int64),
            np.asarray(seg.runs, dtype=np.int64),
            float(seg.tol),
            float(seg.sigma),
            float(seg.spacing),
            pieces_of(seg),
            params,
        )
        if groove.code != GROOVE:
            why = _REFUSALS[groove.code].format(groove.root_share)
            return Feature.failed(why, joint=self.name)
        wrong = self._implausible(angle=groove.angle, depth=groove.depth, gap=groove.gap)
        if wrong is not None:
            return wrong
        fill = _fill_above(seg, groove)
        if fill is not None:
            return Feature.failed(
                f"not a v-groove: a surface lies {fill:.1f} mm above the bevels' meeting point "
                "across the groove's middle (a filled groove: use the groove extractor)",
                joint=self.name,
            )
        feature = self._found(
            profile,
            np.array([groove.seam_y, groove.seam_z]),
            confidence=groove.confidence,
            edges_laser=np.array(
                [[groove.top_left_y, groove.top_left_z], [groove.top_right_y, groove.top_right_z]]
            ),
            gap_mm=groove.gap,
        )
        return feature, groove.explained

    def _extract_hinted(
        self, profile: Profile, seg: Segments, hint: SeamHint
    ) -> Feature | tuple[Feature, float]:
        return self._extract(profile, seg, hint)
