"""Where the fixed laser plane crosses a mitred V-groove corner, the stripe shows a false V
(one wall bent in two). The lower part of the bent wall runs from one lower end of the V to the
other: no gap shows there, so the v-groove extractor, without a prior, reports the intersection
of the two walls it paired, with halved confidence. With the tracker's hint (where its path
expects the seam) it takes the V that continues the seam."""

from __future__ import annotations

import numpy as np
import pytest

from seamtrack.sensing.profiles import hint_from_path
from seamtrack.simulation.assemble import build_parts
from seamtrack.simulation.scene import load_scene


@pytest.fixture(scope="module")
def corner():
    return build_parts(load_scene("v-groove-corner"))


@pytest.fixture(scope="module")
def corner_any_share():
    """The corner with the arm scene's extractor (``min_explained = 0``): the true V at the
    mitre leaves the other leg's wall unexplained."""
    return build_parts(
        load_scene("v-groove-corner", overrides={"extractor.params": {"min_explained": 0.0}})
    )


def _leg_hint(parts, T):
    """What a tracker on the first leg expects: its path (the CAD seam 30-45 mm, a straight
    leg) carried straight on to the laser plane."""
    a, b = parts.seam.interpolate([30.0, 45.0])
    return hint_from_path(T, b, b - a)


def _scan(parts, s_mm, hinted=False):
    tcp = parts.seam.interpolate([s_mm])[0]
    T = parts.robot.T_world_sensor(parts.robot.q_from_world(tcp))
    _, feature = parts.scan(T, 0.0, _leg_hint(parts, T) if hinted else None)
    error = float(parts.seam.closest(feature.point_world).distance_mm[0]) if feature else None
    return feature, error


#: Where the plane 10 mm ahead crosses the corner (s = 50.1-50.9 mm).
AT_THE_CORNER = np.arange(50.1, 50.95, 0.1)


def test_the_false_v_at_the_mitred_corner_is_flagged(corner):
    """Today's handling of the ambiguity: no gap is measured and the confidence drops from
    0.71-0.76 (a true V next to the corner) to below 0.4, so a tracker can discount it."""
    for s in AT_THE_CORNER:
        feature, _ = _scan(corner, s)
        assert feature and np.isnan(feature.gap_mm)
        assert feature.confidence < 0.4


def test_without_a_hint_a_point_off_the_seam_is_flagged(corner_any_share):
    """Without a prior the false V's apex may sink below the root as the plane moves into the
    mitre (today up to 0.7 mm off the seam at its far end); what must hold is that a point
    farther than the suite's 'detected' radius (0.5 mm) from the CAD seam never comes with
    the confidence of a true V (0.71-0.76 next to the corner): it stays below 0.4, so a
    tracker can discount it. An extractor that finds the true V here passes too."""
    for s in AT_THE_CORNER:
        feature, error = _scan(corner_any_share, s)
        if feature and error is not None and error > 0.5:
            assert feature.confidence < 0.4, f"{error:.3f} mm off at s = {s:.1f} mm"


def test_with_the_trackers_hint_the_seam_point_lies_on_the_seam(corner_any_share):
    """At every pose across the corner, with the hint of a tracker that followed the first leg,
    a seam point is found within 0.5 mm of the CAD seam (the suite's 'detected' radius,
    tests/test_extractors_robust.py)."""
    for s in AT_THE_CORNER:
        feature, error = _scan(corner_any_share, s, hinted=True)
        assert feature and error is not None
        assert error <= 0.5, f"{error:.3f} mm off the seam at s = {s:.1f} mm"


@pytest.mark.parametrize("s_mm", [30.0, 49.5, 50.0, 51.0, 55.0, 80.0])
def test_true_v_next_to_the_corner_keeps_its_confidence(corner, s_mm):
    feature, error = _scan(corner, s_mm)
    assert feature and error < 0.01
    assert feature.confidence > 0.55
