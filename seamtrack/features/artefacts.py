"""Synthetic profiles with the artefacts of a real laser line sensor, and their ground truth.

:func:`real_sensor_profile` draws a joint with
:func:`seamtrack.features.synthetic.synthetic_profile` on an unquantized sensor and adds what
real scans show and the synthetic imperfections do not:

* integer range units: every range z_L rounded to a multiple of ``range_unit_mm`` (after
  Gaussian noise of ``noise_units`` units), the point kept on its ray;
* clustered dropouts: runs of lost columns (run lengths geometric), most of them on the groove's
  flanks (``dropout_groove`` of the columns between the groove's edges, ``dropout_plate``
  elsewhere; runs ``dropout_mean_run_mm`` wide on average), and a block of columns at one
  end that is never lit (``dead_fraction``);
* specular spikes and multipath streaks inside the groove: ``spike_runs`` runs per profile on
  average (Poisson), each ``spike_mean_run_mm`` wide on average (geometric), its points
  moved along their rays behind the surface (share ``spike_behind``) or in front of it, by a
  log-normal distance (median and 90th percentile below), drifting linearly along the run.

The defaults are measured on the public LDS V-groove scans (200 profiles of 2048 points, range
unit assumed 0.05 mm; docs/extractors.md, "Real data"): 10.7 % of the columns within 4 mm of
the seam lost against 0.2 % elsewhere, dropout runs 3.4 columns (0.034 mm) wide on average;
a quarter of the points inside the groove more than 0.5 mm off the V, in 14 runs per profile
(median 7, mean 12 columns: 0.12 mm at the 0.01 mm pitch), 44 % behind the surface (median
2.4 mm, 90th percentile 15 mm) and 56 % in front (median 1.9 mm, 90th percentile 5.4 mm);
plate scatter 0.45 units; the last 6 % of the columns dark. Plate tilt (8-11 deg there) is
the caller's ``roll_deg``. Every draw comes from the ``rng`` passed in; the ground truth is
the joint's (artefacts never move the seam).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from seamtrack.features.synthetic import (
    GroundTruth,
    Imperfections,
    ray_angles,
    synthetic_profile,
)
from seamtrack.sensing.profiles import Profile, Reason
from seamtrack.sensing.sensor import LaserLineSensor, preset

#: Half width (mm) of the region around a seam point counted as the groove when the joint has
#: no groove edges (a fillet's corner, a lap's step).
_GROOVE_HALF_MM = 4.0


@dataclass(frozen=True)
class SensorArtefacts:
    """Artefacts of a real laser line sensor (defaults: the LDS V-groove scans)."""

    range_unit_mm: float = 0.05
    noise_units: float = 0.45
    dropout_groove: float = 0.107
    dropout_plate: float = 0.002
    dropout_mean_run_mm: float = 0.034
    dead_fraction: float = 0.0625
    spike_runs: float = 14.0
    spike_mean_run_mm: float = 0.12
    spike_behind: float = 0.44
    spike_behind_median_mm: float = 2.35
    spike_behind_p90_mm: float = 15.4
    spike_front_median_mm: float = 1.86
    spike_front_p90_mm: float = 5.43


def _lognormal(rng: np.random.Generator, median: float, p90: float, n: int) -> np.ndarray:
    sigma = math.log(p90 / median) / 1.2815515655446004
    return np.asarray(rng.lognormal(math.log(median), sigma, n))


def _runs(rng: np.random.Generator, cols: np.ndarray, share: float, mean_run: float) -> np.ndarray:
    """Columns of ``cols`` (sorted) lost in runs of geometric length until ``share`` of
    them are lost."""
    lost = np.zeros(len(cols), dtype=bool)
    target = int(round(share * len(cols)))
    for _ in range(10 * len(cols) + 10):
        if lost.sum() >= target or not len(cols):
            break
        start = int(rng.integers(0, len(cols)))
        length = int(rng.geometric(1.0 / max(mean_run, 1.0)))
        lost[start : start + length] = True
    return np.asarray(cols[lost])


def real_sensor_profile(
    joint: str,
    rng: np.random.Generator,
    *,
    artefacts: SensorArtefacts = SensorArtefacts(),
    sensor: LaserLineSensor | None = None,
    rays: int = 2048,
    **pose_and_joint: Any,
) -> tuple[Profile, GroundTruth]:
    """A profile of ``joint`` as a real sensor with ``artefacts`` would give it.

    Parameters
    ----------
    joint : str
        A joint of :data:`seamtrack.features.synthetic.JOINTS` (``"block"``: a raised block).
    rng : numpy.random.Generator
        Every random draw.
    artefacts : SensorArtefacts
    sensor : LaserLineSensor, optional
        Field of view and geometry (default: the paper's, unquantized: the range unit
        quantizes instead).
    rays : int
        Columns (the LDS: 2048).
    **pose_and_joint
        The pose (``pitch_deg``, ``roll_deg``, ``lateral_offset_mm``, ``standoff_mm``,
        ``section``) and the joint's parameters, as for
        :func:`~seamtrack.features.synthetic.synthetic_profile` (and its defaults).
    """
    base = dataclasses.replace(preset("paper"), quantize=False) if sensor is None else sensor
    profile, truth = synthetic_profile(
        joint,
        base,
        rng=None,
        imperfections=Imperfections(),
        rays=rays,
        **pose_and_joint,
    )
    a = artefacts
    assert profile.reason is not None
    reason = profile.reason.copy()
    phi = ray_angles(base, rays)
    pts = profile.points_laser
    r = np.hypot(pts[:, 0], pts[:, 1])  # range along the ray (NaN where nothing was seen)
    lit = np.flatnonzero(reason == Reason.VALID)
    # Runs are as wide in mm at any pitch: in columns, at this profile's mean spacing.
    pitch = float(np.nanmedian(np.abs(np.diff(pts[lit, 0])))) if len(lit) > 1 else 1.0
    # The groove: between its edges, else around the seam point.
    y = pts[:, 0]
    if len(truth.edges_laser) >= 2:
        lo, hi = float(truth.edges_laser[:, 0].min()), float(truth.edges_laser[:, 0].max())
    elif truth.has_seam:
        lo = float(truth.seam_laser[0]) - _GROOVE_HALF_MM
        hi = float(truth.seam_laser[0]) + _GROOVE_HALF_MM
    else:
        lo = hi = math.nan
    in_groove = lit[(y[lit] >= lo) & (y[lit] <= hi)] if math.isfinite(lo) else lit[:0]
    on_plate = np.setdiff1d(lit, in_groove)
    # Specular spikes and streaks in the groove: moved along their rays.
    n_runs = int(rng.poisson(a.spike_runs)) if len(in_groove) else 0
    for _ in range(n_runs):
        start = int(rng.integers(0, len(in_groove)))
        length = int(rng.geometric(1.0 / max(a.spike_mean_run_mm / pitch, 1.0)))
        cols = in_groove[start : start + length]
        behind = bool(rng.random() < a.spike_behind)
        if behind:
            d = _lognormal(rng, a.spike_behind_median_mm, a.spike_behind_p90_mm, 2)
        else:
            d = -_lognormal(rng, a.spike_front_median_mm, a.spike_front_p90_mm, 2)
        r[cols] = np.maximum(r[cols] + np.linspace(d[0], d[1], len(cols)), 1.0)
    # Noise and integer range units (in z_L, the sensor's range axis).
    z = r[lit] * np.cos(phi[lit]) + rng.normal(0.0, a.noise_units * a.range_unit_mm, len(lit))
    r[lit] = np.round(z / a.range_unit_mm) * a.range_unit_mm / np.cos(phi[lit])
    # Dropouts, clustered, mostly in the groove; a dark block of columns at one end.
    mean_run = a.dropout_mean_run_mm / pitch
    reason[_runs(rng, in_groove, a.dropout_groove, mean_run)] = Reason.DROPOUT
    reason[_runs(rng, on_plate, a.dropout_plate, mean_run)] = Reason.DROPOUT
    dead = int(round(a.dead_fraction * rays))
    if dead:
        reason[rays - dead :] = np.where(
            reason[rays - dead :] == Reason.VALID, Reason.DROPOUT, reason[rays - dead :]
        )
    valid = reason == Reason.VALID
    out = np.where(valid[:, None], np.column_stack([r * np.sin(phi), r * np.cos(phi)]), np.nan)
    return Profile(out, valid=valid, reason=reason, T_world_sensor=profile.T_world_sensor), truth
