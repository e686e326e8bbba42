"""The V-groove extractor against the groove's included angle on real-sensor artefact profiles
(seamtrack.bench.extractors_angles): the sweep's structure, the claim inside CLAIMED_DEG, and
the causes of the misses outside it."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from seamtrack.bench.extractors_angles import (
    ANGLES_DEG,
    CLAIMED_DEG,
    COLUMNS,
    DETECTED_MM,
    RANGE_UNITS_MM,
    angle_sweep,
    angle_table,
)

N = 20


@pytest.fixture(scope="module")
def sweep():
    return angle_sweep(N, seed=7)


def test_the_sweep_has_one_row_per_angle_and_range_unit(sweep):
    assert [(r["range_unit_mm"], r["angle_deg"]) for r in sweep] == list(
        itertools.product(RANGE_UNITS_MM, map(float, ANGLES_DEG))
    )
    assert ANGLES_DEG[0] <= 30 and ANGLES_DEG[-1] >= 150  # the 30-150 deg
    for r in sweep:
        assert tuple(r) == COLUMNS and r["n"] == N
        assert 0.0 <= r["wrong_rate"] <= 1.0 - r["detection_rate"] + 1e-12
        assert sum(r["refusals"].values()) == round(
            N * (1.0 - r["detection_rate"] - r["wrong_rate"])
        )
        # The groove fits the field of view: no deeper than drawn, its opening <= 12 mm.
        half = np.radians(r["angle_deg"]) / 2
        assert r["depth_mm"] <= 7.0 and 2 * r["depth_mm"] * np.tan(half) <= 12.0 + 1e-2
    table = angle_table(sweep)
    assert table.count("\n") == len(sweep) + 2 and "(outside claim)" in table


def test_inside_the_claimed_angles_90_percent_detected_p95_under_half_a_mm(sweep):
    """Pooled over the claimed cells (27 x 20 profiles) the claim itself; per cell at least
    15 of 20. Margin: at the full bench's rates (>= 0.95 per cell) 6 or more misses of 20
    happen with probability 3e-4 per cell (binomial), about 1 % over the 27 cells, so another
    seed passes too while a cell that really falls to the 150 deg cells' ~0.6 fails."""
    lo, hi = CLAIMED_DEG
    inside = [r for r in sweep if lo <= r["angle_deg"] <= hi]
    assert len(inside) == 3 * len([a for a in ANGLES_DEG if lo <= a <= hi])
    for r in inside:
        assert r["detection_rate"] >= 0.75, r
    assert np.mean([r["detection_rate"] for r in inside]) >= 0.9
    # p95 over the pooled found points: within DETECTED_MM when < 5 % of them are wrong.
    wrong = sum(r["wrong_rate"] * r["n"] for r in inside)
    found = sum((r["wrong_rate"] + r["detection_rate"]) * r["n"] for r in inside)
    assert wrong / found < 0.05
    assert max(r["median_error_mm"] for r in inside) <= DETECTED_MM


def test_outside_the_claim_the_misses_have_the_documented_causes():
    """At 150 deg the measured included angle scatters about the true one and half of it
    falls past the acceptance window's 150 deg: the same profiles with the window widened to
    170 deg are found. At 30 deg one bevel is out of the laser's sight (incidence) once the
    plates tilt past a few degrees: no extractor can find a V there, and this one finds no
    more than the profiles that show both bevels."""
    kw = {"angles_deg": (150.0,), "units_mm": (0.05,), "seed": 3}
    narrow = angle_sweep(40, **kw)[0]
    wide = angle_sweep(40, **kw, max_angle_deg=170.0)[0]
    assert narrow["detection_rate"] < 0.9 <= wide["detection_rate"]
    assert max(narrow["refusals"], key=narrow["refusals"].get) == (
        "no pair of lines forms the joint"
    )
    low = angle_sweep(40, angles_deg=(30.0,), units_mm=(0.01,), seed=3)[0]
    assert low["both_flanks_rate"] < 0.9
    assert low["detection_rate"] <= low["both_flanks_rate"] + 1e-12
