"""The square butt in image mode: the camera renders the gap's edges where the geometry puts
them. The backing strip seen through the 1 mm gap is lit and seen over exactly the gap's width
(the plate edges are walls 10 mm deep: a laser or camera ray reaching the backing farther out
grazes a wall), so the stripe on it spans 1.0 mm, centred on the seam, to within one column.
(That this strip measures 1.0 mm is what trips the square-butt extractor's ``min_plate_mm``:
README, "Camera images".)"""

from __future__ import annotations

import numpy as np
import pytest

from seamtrack.bench.camera_sets import seam_in_laser_plane
from seamtrack.sensing.materials import material
from seamtrack.simulation.assemble import build_parts
from seamtrack.simulation.scene import load_scene

pytestmark = [pytest.mark.cad, pytest.mark.embree]

GAP_MM = 1.0  # the square-butt scene's root_gap_mm


@pytest.mark.parametrize("ideal", [True, False])
def test_the_backing_seen_through_the_gap_spans_the_gap(ideal: bool) -> None:
    scene = load_scene("square-butt", {
        "sensor.source": "image", "sensor.mode": "mesh", "workpiece.material": "mill-scale steel",
        "sensor.camera.rows": 512, "sensor.camera.columns": 1024, "sensor.camera.ideal": ideal,
        "sensor.camera.exposure": 0.1 / material("mill-scale steel").diffuse_albedo,
        "sensor.camera.threshold": 0.02,
        "workpiece.params.seam_length_mm": 30.0,
    })  # fmt: skip
    parts = build_parts(scene)
    assert parts.scan is not None
    tcp = parts.seam.interpolate(np.array([10.0]))[0]
    T = parts.robot.T_world_sensor(parts.robot.q_from_world(tcp))
    profile, _ = parts.scan(T, 0.0)
    seam_y, root_z = seam_in_laser_plane(parts.seam.points, T)
    p = profile.valid_points
    backing = p[np.abs(p[:, 1] - root_z) < 1.0]  # the backing lies at the root, 10 mm deep
    spacing = float(np.median(np.diff(backing[:, 0])))
    assert 0.01 < spacing < 0.05  # 1024 columns over the paper sensor's field at that range
    lo, hi = float(backing[:, 0].min()), float(backing[:, 0].max())
    assert hi - lo == pytest.approx(GAP_MM, abs=spacing)
    assert 0.5 * (lo + hi) == pytest.approx(seam_y, abs=spacing)


def _butt_with_backing(backing_width_mm: float) -> np.ndarray:
    """A square butt seen square on: plates at z = 100 mm either side of a 1 mm gap centred at
    y = 0, and the backing 10 mm behind seen through it over ``backing_width_mm``; 0.02 mm pitch."""
    y = np.arange(-10.0, 10.0, 0.02)
    z = np.full_like(y, 100.0)
    z[np.abs(y) < 0.5 * backing_width_mm] = 110.0
    keep = (np.abs(y) >= 0.5) | (np.abs(y) < 0.5 * backing_width_mm)
    return np.column_stack([y, z])[keep]


@pytest.mark.parametrize("width", [0.6, 0.98, 1.2])
def test_a_backing_as_wide_as_the_plate_minimum_is_no_third_plate(width: float) -> None:
    """What a camera sees of the backing through the gap spans the gap (the test above), as
    wide as the extractor's smallest plate (1 mm): 10 mm behind both plates it is no plate, so
    the two plates stay neighbours and the gap between them is the joint. With the backing
    test off (``min_bottom_mm`` beyond its depth), a backing over 1 mm reads as a third plate
    and no gap is found: the failure the image-mode bench showed."""
    from seamtrack.features.extractors import extractor
    from seamtrack.sensing.profiles import Profile

    profile = Profile(_butt_with_backing(width))
    feature = extractor("square-butt")(profile)
    assert feature, feature.reason
    assert abs(feature.point_laser[0]) < 0.05 and abs(feature.point_laser[1] - 100.0) < 0.05
    if width > 1.0:
        assert not extractor("square-butt", min_bottom_mm=50.0)(profile)
