"""The torch's orientation relative to the seam frame: work and travel angles.

Seam frame at a seam point: ``t`` the unit tangent (direction of travel), ``n`` the unit torch
normal (for a CAD seam the bisector of the two faces' outward normals, away from the material),
and the lateral axis ``l = t x n``. The torch axis ``a`` is the unit vector from the torch tip up
the torch (the tool frame's +z: the gantry's torch is world +Z).

The angles are the projected ones of welding practice (AWS A3.0 "work angle", "travel angle"):

* **travel angle** ``atan2(-a.t, a.n)``: in the plane of ``t`` and ``n``; positive is *push*
  (the torch points ahead, in the direction of travel), negative *drag*;
* **work angle** ``atan2(a.l, a.n)``: in the plane of ``l`` and ``n``, a tilt about the seam.

Both are 0 for a torch along the torch normal. Radians throughout; degrees only at the edges.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

FloatArray = NDArray[np.float64]


def torch_axis(
    tangent: ArrayLike, normal: ArrayLike, work_rad: float = 0.0, travel_rad: float = 0.0
) -> FloatArray:
    """Unit torch axes with the given work and travel angles.

    Parameters
    ----------
    tangent, normal : (3,) or (n, 3) float
        Seam frame (unit, orthogonal).
    work_rad, travel_rad : float
        Angles in (-pi/2, pi/2).

    Returns
    -------
    axis : same shape as ``tangent``
    """
    t = np.asarray(tangent, dtype=np.float64)
    n = np.asarray(normal, dtype=np.float64)
    lateral = np.cross(t, n)
    a = n - np.tan(travel_rad) * t + np.tan(work_rad) * lateral
    return a / np.linalg.norm(a, axis=-1, keepdims=True)


def torch_angles(axis: ArrayLike, tangent: ArrayLike, normal: ArrayLike) -> FloatArray:
    """Work and travel angles of torch axes in seam frames.

    Parameters
    ----------
    axis, tangent, normal : (n, 3) float
        Unit torch axes and the seam frames they are measured in.

    Returns
    -------
    angles : (n, 2) float
        ``[:, 0]`` work angle, ``[:, 1]`` travel angle, rad.
    """
    a = np.atleast_2d(np.asarray(axis, dtype=np.float64))
    t = np.atleast_2d(np.asarray(tangent, dtype=np.float64))
    n = np.atleast_2d(np.asarray(normal, dtype=np.float64))
    lateral = np.cross(t, n)
    a_n = np.sum(a * n, axis=1)
    work = np.arctan2(np.sum(a * lateral, axis=1), a_n)
    travel = np.arctan2(-np.sum(a * t, axis=1), a_n)
    return np.column_stack([work, travel])
