"""A found seam point's world position (computed on floats, once per frame) against the
homogeneous transform of the laser-plane point (0, y_L, z_L)."""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

from seamtrack.sensing.profiles import Feature


def test_found_point_is_the_pose_applied_to_the_laser_plane_point() -> None:
    rng = np.random.default_rng(23)
    for _ in range(200):
        T = np.eye(4)
        T[:3, :3] = Rotation.random(random_state=int(rng.integers(2**31))).as_matrix()
        T[:3, 3] = rng.normal(size=3) * 500.0
        y, z = rng.normal(size=2) * 50.0
        expected = (T @ np.array([0.0, y, z, 1.0]))[:3]
        feature = Feature.found([y, z], T)
        np.testing.assert_allclose(feature.point_world, expected, rtol=0, atol=1e-11)
        assert feature.point_laser.tolist() == [y, z]
    assert Feature.found([1.0, 2.0]).point_world.shape == (0,)  # no pose, no world point
