"""Image-mode profiles as labelled real-data sets: the label is the seam's crossing of the laser
plane (analytic geometry), and a written set reads back through the real-data bench's loader."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from seamtrack.bench.camera_sets import ImageSet, seam_in_laser_plane
from seamtrack.bench.extractors import load_real_set


def _sensor_looking_down(x_mm: float, height_mm: float) -> np.ndarray:
    """Laser frame at (x, 0, height): x_L along world x, z_L straight down, so y_L = -world y."""
    T = np.eye(4)
    T[:3, :3] = np.column_stack([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])
    T[:3, 3] = [x_mm, 0.0, height_mm]
    return T


def test_label_is_where_a_straight_seam_crosses_the_laser_plane() -> None:
    seam = np.array([[0.0, 1.5, 0.0], [7.0, 1.5, 0.0], [20.0, 1.5, 0.0]])
    label = seam_in_laser_plane(seam, _sensor_looking_down(10.0, 100.0))
    np.testing.assert_allclose(label, [-1.5, 100.0], atol=1e-12)


def test_label_interpolates_a_sloping_seam_and_takes_the_crossing_nearest_the_emitter() -> None:
    # z rises 1 mm per 10 mm of x: at x = 12 the seam is 1.2 mm up, 98.8 mm from the emitter.
    sloping = np.array([[0.0, -2.0, 0.0], [30.0, 1.0, 3.0]])
    np.testing.assert_allclose(
        seam_in_laser_plane(sloping, _sensor_looking_down(12.0, 100.0)), [0.8, 98.8], atol=1e-12
    )
    # A seam that comes back through the plane farther away: the near crossing is the label.
    hairpin = np.array([[0.0, 0.0, 10.0], [20.0, 0.0, 10.0], [20.0, 0.0, 0.0], [0.0, 0.0, 0.0]])
    np.testing.assert_allclose(
        seam_in_laser_plane(hairpin, _sensor_looking_down(5.0, 100.0)), [0.0, 90.0], atol=1e-12
    )


def test_a_seam_that_misses_the_plane_has_no_label() -> None:
    seam = np.array([[20.0, 0.0, 0.0], [30.0, 0.0, 0.0]])
    assert np.isnan(seam_in_laser_plane(seam, _sensor_looking_down(10.0, 100.0))).all()


def test_a_written_set_reads_back_through_the_real_data_loader(tmp_path) -> None:
    seam = np.array([[0.0, 0.0, 0.0], [50.0, 0.0, 0.0]])
    s = ImageSet("square-butt", "square-butt", "bright aluminium", "square-butt", (0.0, 10.0))
    y = np.linspace(-5.0, 5.0, 11)
    for k in range(3):
        points = np.column_stack([y, np.full_like(y, 90.0 + k)])
        valid = np.ones(len(y), dtype=bool)
        valid[k] = False
        s.add(SimpleNamespace(points_laser=points, valid=valid), seam,
              _sensor_looking_down(10.0 + k, 100.0))  # fmt: skip
    folder = s.write(tmp_path, {"camera": "test"})
    assert folder.name == "square-butt-bright-aluminium"
    back = load_real_set(folder)
    assert back.joint == "square-butt" and back.meta["material"] == "bright aluminium"
    assert back.meta["offset_mm"] == [0.0, 10.0] and back.meta["camera"] == "test"
    assert len(back.profiles) == 3
    for k, profile in enumerate(back.profiles):
        assert not profile.valid[k] and profile.valid.sum() == len(y) - 1
        np.testing.assert_allclose(profile.valid_points[:, 1], 90.0 + k)
    # The seam lies 100 mm below each pose; the scene's torch offset (10 mm deeper) comes off.
    assert back.labels is not None
    np.testing.assert_allclose(back.labels, [[0.0, 90.0]] * 3, atol=1e-9)


@pytest.mark.parametrize("offset", [(0.0, 0.0), (0.5, -2.0)])
def test_the_label_is_the_crossing_minus_the_scenes_torch_offset(offset) -> None:
    seam = np.array([[0.0, 2.0, 0.0], [50.0, 2.0, 0.0]])
    s = ImageSet("lap", "lap", "mill-scale steel", "lap", offset)
    s.add(SimpleNamespace(points_laser=np.zeros((4, 2)), valid=np.ones(4, dtype=bool)), seam,
          _sensor_looking_down(25.0, 80.0))  # fmt: skip
    np.testing.assert_allclose(s.labels[0], np.array([-2.0, 80.0]) - offset, atol=1e-12)
