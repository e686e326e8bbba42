"""SE(3) helpers: round trips on seeded random poses."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from seamtrack.geometry import frames


def random_pose(rng: np.random.Generator) -> np.ndarray:
    return frames.make(Rotation.random(random_state=rng).as_matrix(), rng.normal(0, 100, 3))


@pytest.mark.parametrize("seed", range(5))
def test_invert_round_trip_and_chain(seed: int) -> None:
    rng = np.random.default_rng(seed)
    T_a_b, T_b_c = random_pose(rng), random_pose(rng)
    assert np.allclose(frames.invert(frames.invert(T_a_b)), T_a_b, atol=1e-12)
    assert np.allclose(frames.compose(T_a_b, frames.invert(T_a_b)), np.eye(4), atol=1e-12)
    p_c = rng.normal(size=(7, 3))
    # p_a = T_a_b T_b_c p_c: chains cancel inner indices.
    expected = frames.apply(T_a_b, frames.apply(T_b_c, p_c))
    assert np.allclose(frames.apply(frames.compose(T_a_b, T_b_c), p_c), expected, atol=1e-9)


def test_look_rotation_axes() -> None:
    R = frames.look_rotation([0, 0, -1], [1, 0, 0])
    assert np.allclose(R[:, 2], [0, 0, -1]) and np.allclose(R[:, 0], [1, 0, 0])
    assert np.linalg.det(R) == pytest.approx(1.0)
    with pytest.raises(ValueError):
        frames.look_rotation([0, 0, 1], [0, 0, 2])


def test_rpy_deg_matches_scipy() -> None:
    T = frames.from_xyz_rpy_deg([1, 2, 3], [10, 20, 30])
    R = Rotation.from_euler("xyz", [10, 20, 30], degrees=True).as_matrix()
    assert np.allclose(T[:3, :3], R) and np.allclose(T[:3, 3], [1, 2, 3])
