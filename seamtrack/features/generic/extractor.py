"""The generic (slope / curvature) extractor: no segmentation, no joint model.

Its steps, each one compiled call of :mod:`seamtrack.features.generic._slope_turns`: clean the
profile's points up (valid, bounded, isolated outliers against a running median of 5 left
out; :func:`~seamtrack.features.generic._slope_turns.clean_points`), the turn between sliding
windows' directions (:func:`~seamtrack.features.generic._slope_turns.window_turns`), and where the
sharpest turn lies, the crossing of two local fits
(:func:`~seamtrack.features.generic._slope_turns.corner_point`). Registered in
:mod:`seamtrack.features.extractors` as ``"generic"``.

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from seamtrack.features.arrays import FloatArray
from seamtrack.features.generic._slope_turns import (
    NO_SPREAD,
    TOO_FEW,
    clean_points,
    corner_point,
    window_turns,
)
from seamtrack.features.lines import DATA_ERRORS
from seamtrack.features.robust import MAX_ABS_MM
from seamtrack.sensing.profiles import Feature, Profile


@dataclass(frozen=True)
class GenericExtractor:
    """Slope / curvature: the sharpest concave turn of the profile (sliding-window slopes),
    refined by intersecting two local line fits; else the widest interior gap or step; else
    the sharpest convex turn. No segmentation, no joint model: the fastest built-in."""

    name: str = "generic"
    window_mm: float = 1.0
    min_turn_deg: float = 25.0
    min_jump_mm: float = 0.3
    min_points: int = 8

    def __call__(self, profile: Profile) -> Feature:
        try:
            with np.errstate(all="ignore"):
                return self._extract(profile)
        except DATA_ERRORS as exc:  # never raise on data
            return Feature.failed(f"generic: unusable profile ({exc})", joint=self.name)

    def _extract(self, profile: Profile) -> Feature:
        points = np.ascontiguousarray(profile.points_laser, dtype=np.float64).reshape(-1, 2)
        valid = np.asarray(profile.valid, dtype=bool).reshape(-1)
        if valid.shape != (len(points),):
            return Feature.failed("valid does not match the points", joint=self.name)
        cleaned = clean_points(points, valid, MAX_ABS_MM, 4 * self.min_points)
        p, spacing, sigma = cleaned.kept, cleaned.spacing, cleaned.sigma
        if cleaned.status == TOO_FEW:
            return Feature.failed(f"too few valid points ({len(p)})", joint=self.name)
        if cleaned.status == NO_SPREAD:
            return Feature.failed("the valid points do not spread out", joint=self.name)
        m = len(p)
        k = min(max(round(max(self.window_mm, 20 * sigma) / spacing), 4), max(4, m // 4))
        if m < 2 * k + 2:
            return Feature.failed("too few points for the slope window", joint=self.name)
        jump_mm = max(6 * spacing, 8 * sigma, 0.1)
        # Total-least-squares direction of each k-point window (from window sums), and the
        # turn between windows k apart where no jump lies between them.
        turns = window_turns(p, k, jump_mm)
        gaps, turn = turns.gaps, turns.turn
        min_turn = math.radians(self.min_turn_deg)
        i = int(np.argmin(turn))
        if turn[i] <= -min_turn:
            return self._corner(profile, p, i + k, k, -float(turn[i]))
        interior = np.flatnonzero(gaps > max(self.min_jump_mm, jump_mm))
        if interior.size:
            j = int(interior[np.argmax(gaps[interior])])
            a, b = p[j], p[j + 1]
            dy, dz = abs(b[0] - a[0]), abs(b[1] - a[1])
            if dz > 2 * dy:  # a step: the corner at the foot of the higher side
                hi, lo = (a, b) if a[1] < b[1] else (b, a)
                seam = np.array([hi[0], lo[1]])
            else:
                seam = 0.5 * (a + b)
            return Feature.found(
                seam,
                profile.T_world_sensor,
                joint=self.name,
                confidence=0.5,
                edges_laser=np.array([a, b]),
                gap_mm=float(dy),
            )
        i = int(np.argmax(turn))
        if turn[i] >= min_turn:
            return self._corner(profile, p, i + k, k, float(turn[i]))
        return Feature.failed("no turn, gap or step in the profile", joint=self.name)

    def _corner(self, profile: Profile, p: FloatArray, c: int, k: int, turn: float) -> Feature:
        corner = corner_point(p, c, k)
        if math.isnan(corner.y):  # a side has fewer than 3 points
            return Feature.failed("the corner is too near the profile's end", joint=self.name)
        conf = float(np.clip(turn / math.radians(90), 0.0, 1.0))
        return Feature.found(
            np.array([corner.y, corner.z]), profile.T_world_sensor, joint=self.name,
            confidence=conf,
        )  # fmt: skip
