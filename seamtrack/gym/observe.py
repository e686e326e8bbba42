"""The environment's flat observation, filled in one compiled call (see
:class:`~seamtrack.gym.env.SeamTrackEnv` for its layout)."""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.jit import KERNEL


@numba.njit(**KERNEL)
def fill_observation(
    points_laser: NDArray[np.float64], valid: NDArray[np.bool_], torch: NDArray[np.float64],
    limit: float, out: NDArray[np.float32],
) -> None:  # fmt: skip
    """``out`` (3 n + 9,) float32: the profile's (y_L, z_L) points (``points_laser`` (n, 2),
    0 where not ``valid``), their validity (1.0 or 0.0), then ``torch`` (9,), each rounded to
    float32 and then kept within +- ``limit`` (as ``np.clip`` of the float32 array)."""
    n = len(valid)
    hi = np.float32(limit)
    lo = -hi
    for j in range(n):
        if valid[j]:
            for c in range(2):
                value = np.float32(points_laser[j, c])
                out[2 * j + c] = min(max(value, lo), hi)
            out[2 * n + j] = 1.0
        else:
            out[2 * j] = 0.0
            out[2 * j + 1] = 0.0
            out[2 * n + j] = 0.0
    for k in range(len(torch)):
        value = np.float32(torch[k])
        out[3 * n + k] = min(max(value, lo), hi)
