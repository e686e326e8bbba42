"""SE(3) helpers on (4, 4) arrays.

Convention (written down once): ``T_a_b`` is the pose of frame *b* in frame *a*, so
``p_a = T_a_b @ p_b`` and chains cancel inner indices::

    T_world_sensor = T_world_base @ T_base_tcp @ T_tcp_sensor

Angles are radians; the ``*_deg`` helpers exist only for the edges (scene files, CLI).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.spatial.transform import Rotation

Pose = NDArray[np.float64]


def make(rotation: ArrayLike | None = None, translation: ArrayLike | None = None) -> Pose:
    """Pose from a (3, 3) rotation matrix and a (3,) translation (mm)."""
    T = np.eye(4)
    if rotation is not None:
        T[:3, :3] = np.asarray(rotation, dtype=np.float64)
    if translation is not None:
        T[:3, 3] = np.asarray(translation, dtype=np.float64)
    return T


def from_xyz_rpy(translation_mm: ArrayLike, rpy_rad: ArrayLike) -> Pose:
    """Pose from a translation and extrinsic x-y-z (roll, pitch, yaw) angles in radians."""
    rotation = Rotation.from_euler("xyz", np.asarray(rpy_rad, dtype=np.float64)).as_matrix()
    return make(rotation, translation_mm)


def from_xyz_rpy_deg(translation_mm: ArrayLike, rpy_deg: ArrayLike) -> Pose:
    """:func:`from_xyz_rpy` with angles in degrees (scene files speak degrees)."""
    return from_xyz_rpy(translation_mm, np.radians(np.asarray(rpy_deg, dtype=np.float64)))


def invert(T_a_b: ArrayLike) -> Pose:
    """``T_b_a`` from ``T_a_b`` (exact for rigid transforms, no matrix inverse)."""
    T = np.asarray(T_a_b, dtype=np.float64)
    R = T[:3, :3]
    out = np.eye(4)
    out[:3, :3] = R.T
    out[:3, 3] = -R.T @ T[:3, 3]
    return out


def compose(*poses: ArrayLike) -> Pose:
    """``T_a_b @ T_b_c @ ...``, left to right."""
    out = np.eye(4)
    for T in poses:
        out = out @ np.asarray(T, dtype=np.float64)
    return out


def apply(T_a_b: ArrayLike, points_b: ArrayLike) -> NDArray[np.float64]:
    """Map points from frame b to frame a.

    Parameters
    ----------
    T_a_b : (4, 4) float
    points_b : (n, 3) or (3,) float

    Returns
    -------
    points_a : same shape as ``points_b``
    """
    T = np.asarray(T_a_b, dtype=np.float64)
    p = np.asarray(points_b, dtype=np.float64)
    return p @ np.ascontiguousarray(T[:3, :3].T) + T[:3, 3]


def apply_vectors(T_a_b: ArrayLike, vectors_b: ArrayLike) -> NDArray[np.float64]:
    """Rotate direction vectors ((n, 3) or (3,)) from frame b to frame a."""
    T = np.asarray(T_a_b, dtype=np.float64)
    return np.asarray(vectors_b, dtype=np.float64) @ np.ascontiguousarray(T[:3, :3].T)


def look_rotation(z_axis: Sequence[float], x_axis: Sequence[float]) -> NDArray[np.float64]:
    """Rotation whose z column is ``z_axis`` and whose x column is ``x_axis`` made orthogonal.

    Raises
    ------
    ValueError
        When the two axes are parallel.
    """
    z = np.asarray(z_axis, dtype=np.float64)
    z = z / np.linalg.norm(z)
    x = np.asarray(x_axis, dtype=np.float64)
    x = x - (x @ z) * z
    norm = np.linalg.norm(x)
    if norm < 1e-12:
        raise ValueError("look_rotation: x_axis is parallel to z_axis")
    x = x / norm
    y = np.cross(z, x)
    return np.column_stack([x, y, z])
