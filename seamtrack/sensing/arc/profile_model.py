"""The arc in profile mode: a statistical model of what the arc does to a stripe profile, cheap
enough for mesh-mode runs that form no image (issue 38 item 2).

The image model (:mod:`seamtrack.sensing.arc.image`) draws the arc's light into the camera's
image; a peak detector that keeps each column's strongest peak then reports, in some columns,
the arc's light instead of the laser's. Measured on ``v-groove-arc`` (the calibration,
:func:`seamtrack.bench.arc.calibrate`), two things happen to a profile:

1. **The blob near the arc.** Where a stripe point lies within a distance R of the arc's root,
   the plate the arc lights and heats, the weld pool and the fume's veil outshine the laser: the
   column's peak moves off the stripe. The point is lost with the probability

       p_lost(d) = 1 / (1 + exp((d - R(I)) / s)),   R(I) = R_ref (I / I_ref) ** gamma,

   where ``d`` is the stripe point's distance from the arc (mm; the look-ahead sets its least
   value), ``I`` the current. The edge is drawn once a frame (R(I) plus s times a logistic
   variate), so the lost points form one region, as the blob does in the image. A lost point
   becomes a false point (the peak the detector chose) with the probability
   ``blob_false_fraction``, else a drop-out (``Reason.DROPOUT``). The false points lie on one
   line across the stripe, ``blob_offset_mm`` (+- ``blob_offset_sd_mm`` from frame to frame)
   from the arc's range z_L: the detector finds the blob's centre on the same chip row in
   every column it wins, and the sensor triangulates that row as if it lay in the laser plane.
2. **Isolated false points.** A glowing droplet streaks across the image and wins a column
   or a few (and the blob leaves a stray column beyond its edge): a run of false points
   ``streak_run_mm`` long along the stripe at a random range in the stripe's depth, at a
   random slope. Runs start at each stripe point with the probability

       p_streak(d) = S_ref (rate(I) / rate(I_ref)) (d_ref / d) ** 2,

   ``rate`` the image model's droplet rate (:func:`seamtrack.sensing.arc.spatter.
   spatter_rate_hz`; constant for TIG, which throws none) and the inverse square the density
   of droplets a point source throws (assumed; the calibration fits S_ref only).

The model stands for a camera: the one a scene's ``countermeasures`` switch gives (its filter,
exposure control and peak rejection, :mod:`seamtrack.simulation.countermeasures`), so each
switch has its parameters (:data:`PROFILE_ARC_BY_SWITCH`; :data:`PROFILE_ARC` those of
``"default"``). Under ``"none"`` (no filter, the multiple exposure) the blob reaches 15-26 mm
at 250 A; under ``"default"`` (10 nm band-pass, fixed exposure, rejection) MAG spray's reaches
5 mm (11 mm at 350 A), so a 10 mm look-ahead keeps the root up to 300 A. The peak detector keeps
a column's strongest surviving peak, so the arc rarely empties a column: nearly every lost
point is a false point (``blob_false_fraction`` ~ 1), except short-circuit MAG under
``"default"``, whose few lost points near the arc are drop-outs.

Every draw comes from the run's seeded :class:`numpy.random.Generator`; the model is a few
vectorised numpy operations on the profile's points, no image and no ray. Its parameters
are measured from the image model, not assumed: their provenance is written next to them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seamtrack.errors import SeamtrackError
from seamtrack.sensing.arc.spatter import SPATTER, spatter_rate_hz
from seamtrack.sensing.profiles import Reason

FloatArray = NDArray[np.float64]

#: The current the parameters are given at (A).
CURRENT_REF_A = 250.0
#: The distance the spatter's streak probability is given at (mm).
DISTANCE_REF_MM = 30.0
#: The most streak runs one profile may draw (each a few numbers; memory stays small).
MAX_STREAKS = 100_000
#: The least look-ahead with the arc on (mm): the laser line must lie outside the gas nozzle,
#: whose outer diameter on MAG torches is about 16-20 mm (assumed; a radius of 8 mm). A
#: stripe under the nozzle is hidden from the camera, and the arc model does not hold there.
MIN_LOOK_AHEAD_MM = 8.0


@dataclass(frozen=True)
class ProfileArcParams:
    """One process's profile-mode arc model (see the module docstring): ``blob_radius_mm``
    R_ref at :data:`CURRENT_REF_A`, ``blob_radius_exponent`` gamma, ``blob_edge_mm`` s,
    ``blob_false_fraction`` the share of lost points that become false points,
    ``blob_offset_mm`` and ``blob_offset_sd_mm`` the false points' range from the arc's
    (z_L, mm),
    ``streak_probability`` S_ref per stripe point at :data:`DISTANCE_REF_MM` and
    :data:`CURRENT_REF_A`, ``streak_run_mm`` a streak's length along the stripe (y_L)."""

    blob_radius_mm: float
    blob_radius_exponent: float
    blob_edge_mm: float
    blob_false_fraction: float
    blob_offset_mm: float
    blob_offset_sd_mm: float
    streak_probability: float
    streak_run_mm: float


#: Measured from the image model on v-groove-arc (paper preset, 512 x 1024 camera, mill-scale
#: steel) under the countermeasures ``"default"``, the camera a scene's switch gives: the 10 nm
#: Gaussian band-pass at 660 nm, one fixed exposure, blob and streak rejection in the peak
#: detector. 8 frames at each look-ahead of 10, 12.5, 15, 20, 30 and 50 mm and each current of
#: 100, 200, 300 and 350 A, against the ideal camera's stripe without the arc; fitted by maximum
#: likelihood (seamtrack.bench.arc.calibrate; ``python -m seamtrack.bench.arc --calibrate
#: --countermeasures default`` prints these values, in 712 s for the three processes at a
#: 1-minute load of 6.7, 2026-12-05; TIG again with the fit's bound on gamma, ``--process
#: tig``, 43 s: unbounded, gamma came out -0.016, a blob that shrinks as the current rises).
#: Measured beside them: the camera's own loss without the arc, 0.62 % of the columns; 329, 153
#: and 43 isolated false points counted (mag-short, mag-spray, tig). The fixed exposure keeps
#: the root up close: MAG spray's blob reaches 4.9 mm at 250 A (7.6 mm at 300 A, 11 mm at
#: 350 A, so of the bench's currents only 350 A loses part of the stripe at 10 mm), TIG's
#: 9.9 mm at every current; short-circuit MAG has no blob, the fit's R below zero with a 4.9 mm
#: edge is a thin tail: a point 10 mm from the arc is dropped with a chance of 1-3 %.
PROFILE_ARC: dict[str, ProfileArcParams] = {
    "mag-short": ProfileArcParams(-7.964, -0.375, 4.892, 0.0, 0.0, 0.0, 7.93e-4, 0.08),
    "mag-spray": ProfileArcParams(4.929, 2.406, 0.111, 0.997, -0.09, 2.2, 3.3e-4, 0.03),
    "tig": ProfileArcParams(9.895, 0.0, 0.054, 0.936, -21.18, 0.98, 8.96e-5, 0.02),
}
#: The same under the countermeasures ``"none"``: no filter (the chip's own 400-1100 nm), the
#: camera's multiple exposure, no rejection (``python -m seamtrack.bench.arc --calibrate
#: --countermeasures none``, same grid and frames, 294 s at a 1-minute load of 3.7,
#: 2026-12-05; 199, 4 and 336 isolated false points counted). Through 700 nm of band the arc
#: outshines the stripe far out: MAG spray's blob reaches 26 mm at 250 A (16 mm at 100 A,
#: 31 mm at 350 A), its false points 13-15 mm nearer the sensor than the arc (+- 5 mm).
PROFILE_ARC_NONE: dict[str, ProfileArcParams] = {
    "mag-short": ProfileArcParams(18.669, 0.385, 1.467, 1.0, -14.55, 5.12, 4.05e-3, 0.06),
    "mag-spray": ProfileArcParams(26.076, 0.51, 3.694, 1.0, -13.26, 4.56, 3.25e-4, 0.15),
    "tig": ProfileArcParams(14.969, 0.212, 0.886, 1.0, -17.13, 2.04, 2.1e-3, 0.11),
}
#: The parameters per countermeasures switch (``ArcProfileModel.countermeasures``).
PROFILE_ARC_BY_SWITCH: dict[str, dict[str, ProfileArcParams]] = {
    "default": PROFILE_ARC,
    "none": PROFILE_ARC_NONE,
}


def _check_current(current_a: float) -> float:
    if not (isinstance(current_a, int | float) and math.isfinite(current_a) and current_a > 0):
        raise SeamtrackError(f"{current_a!r} A", field="arc.current_a",
                             fix="give the welding current in A, > 0 (e.g. 250)")  # fmt: skip
    return float(current_a)


@dataclass(frozen=True)
class ArcProfileModel:
    """The profile-mode arc of one scene: ``process``, ``current_a`` and the parameters
    (default those of the process measured under the scene's ``countermeasures`` switch,
    :data:`PROFILE_ARC_BY_SWITCH`: the camera, filter, exposure and peak rejection the switch
    gives)."""

    process: str
    current_a: float
    params: ProfileArcParams | None = None
    countermeasures: str = "default"

    def __post_init__(self) -> None:
        if self.countermeasures not in PROFILE_ARC_BY_SWITCH:
            switches = ", ".join(sorted(PROFILE_ARC_BY_SWITCH))
            raise SeamtrackError(f"{self.countermeasures!r} is not a countermeasures switch",
                                 field="countermeasures", fix=f"one of {switches}")  # fmt: skip
        if self.process not in PROFILE_ARC and self.params is None:
            raise SeamtrackError(f"{self.process!r} is not a process", field="arc.process",
                                 fix=f"one of {', '.join(sorted(PROFILE_ARC))}")  # fmt: skip
        _check_current(self.current_a)

    @property
    def p(self) -> ProfileArcParams:
        """The parameters in use."""
        if self.params is not None:
            return self.params
        return PROFILE_ARC_BY_SWITCH[self.countermeasures][self.process]

    def blob_radius_mm(self) -> float:
        """R(I): the distance from the arc within which the blob takes the stripe (mm)."""
        p = self.p
        return float(p.blob_radius_mm * (self.current_a / CURRENT_REF_A) ** p.blob_radius_exponent)

    def loss_probability(self, distance_mm: FloatArray) -> FloatArray:
        """p_lost(d) (n,): the chance the blob takes a stripe point ``distance_mm`` (n,) from
        the arc."""
        d = np.asarray(distance_mm, dtype=np.float64)
        edge = max(self.p.blob_edge_mm, 1e-9)
        return np.asarray(0.5 * (1.0 - np.tanh(0.5 * (d - self.blob_radius_mm()) / edge)))

    def streak_probability(self, distance_mm: FloatArray) -> FloatArray:
        """p_streak(d) (n,): the chance a spatter streak's run starts at a stripe point."""
        d = np.maximum(np.asarray(distance_mm, dtype=np.float64), 1e-3)
        rate = 1.0
        if self.process in SPATTER and SPATTER[self.process].rate_hz > 0:
            rate = spatter_rate_hz(self.process, self.current_a) / spatter_rate_hz(
                self.process, CURRENT_REF_A
            )
        return np.asarray(self.p.streak_probability * rate * (DISTANCE_REF_MM / d) ** 2)

    def apply(
        self,
        points: FloatArray,
        reason: NDArray[np.uint8],
        arc_laser: FloatArray,
        rng: np.random.Generator,
    ) -> tuple[FloatArray, NDArray[np.uint8]]:
        """The arc on a profile: ``points`` (n, 2) (y_L, z_L) and ``reason`` (n,) codes, the
        arc's root ``arc_laser`` (3,) in the laser frame (x_L, y_L, z_L); returns new
        (points, reason). Only valid points are touched; a lost point becomes a false point
        or a drop-out, a streak's points become false points."""
        points = np.array(points, dtype=np.float64, copy=True)
        reason = np.array(reason, dtype=np.uint8, copy=True)
        idx = np.flatnonzero(reason == Reason.VALID)
        if len(idx) == 0:
            return points, reason
        a = np.asarray(arc_laser, dtype=np.float64)
        y, z = points[idx, 0], points[idx, 1]
        d = np.sqrt(a[0] ** 2 + (y - a[1]) ** 2 + (z - a[2]) ** 2)
        self._blob(points, reason, idx, d, float(a[2]), rng)
        self._streaks(points, reason, idx, d, rng)
        return points, reason

    def _blob(self, points: FloatArray, reason: NDArray[np.uint8], idx: NDArray[np.intp],
              d: FloatArray, arc_z: float, rng: np.random.Generator) -> None:  # fmt: skip
        """The blob takes every point nearer the arc than this frame's edge, R(I) + s L with L
        drawn once from the logistic distribution (so each point is lost with p_lost(d), and
        the lost points are one contiguous region, as in the image); its false points lie on
        one line at the arc's range plus this frame's offset."""
        p = self.p
        u = float(np.clip(rng.random(), 1e-12, 1.0 - 1e-12))
        edge = self.blob_radius_mm() + p.blob_edge_mm * (math.log(u) - math.log1p(-u))
        lost = d < edge
        false = lost & (rng.random(len(idx)) < p.blob_false_fraction)
        offset = p.blob_offset_mm + p.blob_offset_sd_mm * float(rng.standard_normal())
        points[idx[false], 1] = arc_z + offset
        reason[idx[lost & ~false]] = Reason.DROPOUT

    def _streaks(self, points: FloatArray, reason: NDArray[np.uint8], idx: NDArray[np.intp],
                 d: FloatArray, rng: np.random.Generator) -> None:  # fmt: skip
        prob = self.streak_probability(d)
        expected = float(prob.sum())
        if not math.isfinite(expected) or expected > MAX_STREAKS / 2:
            raise SeamtrackError(
                f"the spatter puts about {expected:.3g} streaks on one profile",
                field="arc.spatter_rate_hz",
                fix=f"give a streak probability that puts fewer than {MAX_STREAKS // 2} on it",
            )
        starts = np.flatnonzero(rng.random(len(idx)) < np.minimum(prob, 1.0))
        if len(starts) == 0:
            return
        y = points[idx, 0]
        valid_z = points[idx, 1]
        z_lo, z_hi = float(valid_z.min()), float(valid_z.max())
        depth = max(z_hi - z_lo, 1.0)
        centre_z = rng.uniform(z_lo - 0.5 * depth, z_hi + 0.5 * depth, len(starts))
        slope = np.tan(rng.uniform(-0.4 * math.pi, 0.4 * math.pi, len(starts)))
        run = self.p.streak_run_mm
        for k, start in enumerate(starts):  # few per profile: a loop over streaks, not points
            ys = y[start]
            hit = (y >= ys) & (y < ys + run)
            points[idx[hit], 1] = centre_z[k] + slope[k] * (y[hit] - ys)
            reason[idx[hit]] = Reason.VALID
