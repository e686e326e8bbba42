"""Independent oracles for the arm tests: Universal Robots' published UR10e DH table and the
standard DH link transform (written here, not taken from Pinocchio or our URDF)."""

from __future__ import annotations

import math

import numpy as np

#: Universal Robots' published UR10e DH table (d, a, alpha; mm, rad).
UR10E_DH = [
    (180.7, 0.0, math.pi / 2),
    (0.0, -612.7, 0.0),
    (0.0, -571.55, 0.0),
    (174.15, 0.0, math.pi / 2),
    (119.85, 0.0, -math.pi / 2),
    (116.55, 0.0, 0.0),
]


def dh(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """Standard DH link transform."""
    ct, st_, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [[ct, -st_ * ca, st_ * sa, a * ct], [st_, ct * ca, -ct * sa, a * st_], [0, sa, ca, d],
         [0, 0, 0, 1.0]]
    )  # fmt: skip
