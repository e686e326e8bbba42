"""The V-groove extractor: two bevels opening towards the sensor, and what lies between their
lower ends (a root gap, a stray line over a root corner, or no gap at all).

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seamtrack.features.base import _Base
from seamtrack.features.expect import Expect
from seamtrack.features.lines import Segments
from seamtrack.features.vkernels import pieces_of
from seamtrack.features.vmodel import vgroove
from seamtrack.sensing.profiles import Feature, Profile

FloatArray = NDArray[np.float64]
#: Why a V is no groove, by the code of :func:`seamtrack.features.vmodel.vgroove`.
_REFUSALS = {
    1: "no pair of lines forms the joint",
    2: "not a v-groove: no plate beside the bevels (two faces alone: a fillet?)",
    3: "not a v-groove: a side of the V runs along a plate (a step or a block's foot)",
}


@dataclass(frozen=True)
class VGrooveExtractor(_Base):
    """V-groove: two bevels opening towards the sensor, a plate beside at least one of them.
    Seam: the root centre, midpoint of the bevels' lower ends, when a root gap shows between
    them (the ends level, the V's tip below them empty, the columns between them open);
    else the bevels' intersection (confidence halved unless they meet: the bottom is cut up
    by spikes and dropouts, or filled). Edges: the top edges.

    Where a stray line (a false reflection) covers a bevel's root end, the end is hidden:
    it is put at the depth of the other root end below the plates (both root corners lie
    at one depth under their plate: thickness minus root face), within the covered
    stretch (confidence halved). Confidence is halved too when a surface that is no wall
    joins the two root ends: there is no gap between them (a false V where the laser plane
    crosses a mitred corner, a tack weld over the root).

    Refused with a reason when the profile shows no groove (two
    faces alone, a side along the other's plate, a wide root, or less than
    ``min_explained`` of the profile on the model's lines) or when ``expect`` says the
    included angle, the depth below the plates or the gap is implausible.

    The model runs compiled, in one call (:func:`seamtrack.features.vmodel.vgroove`): the
    Python formulation spent ten times the arithmetic's cost on numpy calls on 2-vectors.
    """

    name: str = "v-groove"
    min_angle_deg: float = 20.0
    max_angle_deg: float = 150.0
    max_gap_mm: float = 6.0
    min_gap_mm: float = 0.05

    def _extract(self, profile: Profile, seg: Segments) -> Feature | tuple[Feature, float]:
        if not seg.n_lines:
            return Feature.failed(_REFUSALS[1], joint=self.name)
        lo, hi = self._angles(self.min_angle_deg, self.max_angle_deg)
        expect = self.expect if isinstance(self.expect, Expect) else None
        params = np.array(
            [
                self.min_points,
                self.min_arm_mm,
                lo,
                hi,
                self.max_gap_mm,
                self.min_gap_mm,
                self.arms_from_pieces,
                expect is not None and expect.gapless,
            ],
            dtype=np.float64,
        )
        out = vgroove(
            np.ascontiguousarray(seg.points, dtype=np.float64),
            np.asarray(seg.stray, dtype=np.bool_),
            np.asarray(seg.columns, dtype=np.int64),
            np.asarray(seg.runs, dtype=np.int64),
            float(seg.tol),
            float(seg.sigma),
            float(seg.spacing),
            *pieces_of(seg),
            params,
        )
        code = int(out[0])
        if code == 4:
            return Feature.failed(
                f"not a v-groove: {out[12]:.0f} % of the profile lies between the bevels' "
                "lower ends (a raised block between two plates?)",
                joint=self.name,
            )
        if code:
            return Feature.failed(_REFUSALS[code], joint=self.name)
        gap = float(out[4])
        wrong = self._implausible(angle=float(out[10]), depth=float(out[11]), gap=gap)
        if wrong is not None:
            return wrong
        feature = self._found(
            profile,
            out[1:3].copy(),
            confidence=float(out[3]),
            edges_laser=out[5:9].reshape(2, 2),
            gap_mm=gap,
        )
        return feature, float(out[9])
