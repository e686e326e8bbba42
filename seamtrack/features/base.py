"""The built-in family extractors' base class: shared parameters, the never-raise wrapper,
line groups and the V (or ridge) search.

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.features.lines import (
    DATA_ERRORS,
    Line,
    Segments,
    collinear_groups,
    intersect,
    segment_profile,
)
from seamtrack.sensing.profiles import Feature, Profile

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class _Base:
    """Shared parameters and the never-raise wrapper of the built-in extractors."""

    name: str = "base"
    min_tol_mm: float | None = None
    resolution_mm: float | None = None
    min_points: int = 8
    min_arm_mm: float = 0.5

    def __call__(self, profile: Profile) -> Feature:
        try:
            with np.errstate(all="ignore"):
                seg = segment_profile(
                    profile,
                    min_tol_mm=self.min_tol_mm,
                    resolution_mm=self.resolution_mm,
                    min_points=self.min_points,
                )
                if isinstance(seg, str):
                    return Feature.failed(seg, joint=self.name)
                return self._extract(profile, seg)
        except DATA_ERRORS as exc:  # never raise on data
            return Feature.failed(f"{self.name}: unusable profile ({exc})", joint=self.name)

    def _extract(self, profile: Profile, seg: Segments) -> Feature:
        raise NotImplementedError

    def _found(self, profile: Profile, point: FloatArray, **kw: Any) -> Feature:
        return Feature.found(point, profile.T_world_sensor, joint=self.name, **kw)

    def _groups(self, seg: Segments) -> list[Line]:
        """Collinear groups supported enough to be an arm or a plate."""
        return [
            g
            for g in collinear_groups(seg)
            if g.count >= self.min_points and g.extent >= self.min_arm_mm
        ]

    def _arms(
        self,
        seg: Segments,
        opening_down: bool,
        min_deg: float,
        max_deg: float,
        max_reach_mm: float,
        groups: list[Line] | None = None,
    ) -> tuple[Line, Line, FloatArray, float] | str:
        """The best pair of lines forming a V (opening towards the sensor, -z) or a ridge
        (``opening_down``: the arms fall away from the sensor): (left, right, apex, score)."""
        if groups is None:
            groups = self._groups(seg)
        sign = 1.0 if opening_down else -1.0
        best: tuple[Line, Line, FloatArray, float] | None = None
        surface = seg.points[~seg.stray] if seg.stray.shape == (len(seg.points),) else seg.points
        band = 2.0 * seg.tol
        for i, a in enumerate(groups):
            for b in groups[i + 1 :]:
                x = intersect(a, b)
                if x is None:
                    continue
                arms = []
                for g in (a, b):
                    v = g.centroid - x
                    v = v / max(float(np.hypot(*v)), 1e-300)
                    near = float(np.min((seg.points[g.index] - x) @ v))
                    arms.append((v, near, g))
                (va, na, ga), (vb, nb, gb) = sorted(arms, key=lambda arm: float(arm[0][0]))
                included = math.degrees(math.acos(float(np.clip(va @ vb, -1, 1))))
                bis = va + vb
                ok = (
                    va[0] < 0 < vb[0]
                    and sign * va[1] > 0
                    and sign * vb[1] > 0
                    and min_deg <= included <= max_deg
                    and sign * bis[1] > 0.7 * float(np.hypot(*bis))  # bisector within 45 deg
                    and -seg.tol <= min(na, nb)
                    and max(na, nb) <= max_reach_mm
                )
                if not ok:
                    continue
                # Support: the surface points on either arm's line, on its side of the apex
                # (fragments of a bevel cut up by spikes count, whatever piece they are in).
                score = 0.0
                for v, g in ((va, ga), (vb, gb)):
                    d = surface - x
                    on_line = np.abs(d @ g.normal) <= band
                    score += float(np.count_nonzero(on_line & (d @ v >= -seg.tol)))
                if best is None or score > best[3]:
                    best = (ga, gb, x, score)
        return best if best is not None else "no pair of lines forms the joint"


def _confidence(arms: list[Line], seg: Segments) -> float:
    """Share of the kept points explained by the feature's lines, scaled by their fit."""
    explained = sum(a.count for a in arms) / max(len(seg.points), 1)
    fit = max(0.0, 1.0 - max(a.rms for a in arms) / seg.tol)
    return float(np.clip(0.5 * explained + 0.5 * fit, 0.0, 1.0))
