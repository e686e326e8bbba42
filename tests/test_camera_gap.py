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
