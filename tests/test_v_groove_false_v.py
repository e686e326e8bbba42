"""Where the fixed laser plane crosses a mitred V-groove corner, the stripe shows a false V
(one wall bent in two). The lower part of the bent wall runs from one lower end of the V to the
other: no gap shows there, so the v-groove extractor reports the intersection of the two walls
it paired, with halved confidence."""

from __future__ import annotations

import numpy as np
import pytest

from seamtrack.simulation.assemble import build_parts
from seamtrack.simulation.scene import load_scene


@pytest.fixture(scope="module")
def corner():
    return build_parts(load_scene("v-groove-corner"))


def _scan(parts, s_mm):
    tcp = parts.seam.interpolate([s_mm])[0]
    T = parts.robot.T_world_sensor(parts.robot.q_from_world(tcp))
    _, feature = parts.scan(T, 0.0)
    error = float(parts.seam.closest(feature.point_world).distance_mm[0]) if feature else None
    return feature, error


def test_false_v_at_the_mitred_corner_has_halved_confidence(corner):
    """At 50.1-50.9 mm (the plane 10 mm ahead crosses the corner) the point lies 0.08-0.75 mm
    off the seam (the midpoint of the lower ends was 0.23-2.2 mm off); its confidence drops
    from 0.71-0.76 to below 0.4."""
    errors = []
    for s in np.arange(50.1, 50.95, 0.1):
        feature, error = _scan(corner, s)
        assert feature and np.isnan(feature.gap_mm)
        assert feature.confidence < 0.4
        errors.append(error)
    assert 0.05 < min(errors) and max(errors) < 0.8


@pytest.mark.parametrize("s_mm", [30.0, 49.5, 50.0, 51.0, 55.0, 80.0])
def test_true_v_next_to_the_corner_keeps_its_confidence(corner, s_mm):
    feature, error = _scan(corner, s_mm)
    assert feature and error < 0.01
    assert feature.confidence > 0.55
