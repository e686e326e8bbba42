"""A hand-written baseline for :class:`~seamtrack.gym.env.SeamTrackEnv`: a PD law on the seam
that the profile shows, remembered until the torch gets there.

Each frame, the deepest valid point of the profile (the largest range ``z_L``: the root of a
groove seen from above) is taken for the seam. Its place relative to the torch follows from the
sensor's fixed mount on a gantry (``T_world_sensor`` is the torch's position plus a constant
offset and rotation): so far ahead along the nominal path, so far across and up. The seam's
offset from the nominal path is stored against the arc length at which it lies, and the policy
steers the correction towards the stored offset at the torch's aim point (``lead_mm`` ahead of
it): ``action = kp * e + kd * (e - e_previous)``, with ``e`` the stored offset less the
correction held.
"""

from __future__ import annotations

import bisect
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.gym.env import SeamTrackEnv, split_observation


class ProfilePD:
    """A PD policy on the seam's root found in the profile (a baseline, not learned).

    Parameters
    ----------
    env : SeamTrackEnv (or a wrapper of one)
        The environment it steers (its sensor mount and nominal path set the geometry).
    kp, kd : float
        Proportional and derivative gains, per frame.
    """

    def __init__(self, env: Any, kp: float = 0.5, kd: float = 0.1) -> None:
        base: SeamTrackEnv = env.unwrapped
        parts = base.parts
        robot = parts.robot
        state = robot.state_at(robot.q_from_world(parts.tcp_start_world))
        T_world_sensor = robot.sensor_pose(state)
        #: Sensor axes y_L, z_L in the world, and the sensor origin relative to the torch tip.
        self.axes = T_world_sensor[:3, 1:3]
        self.origin = T_world_sensor[:3, 3] - np.asarray(parts.tcp_start_world, dtype=float)
        self.nominal = base.nominal
        self.rays = base.rays
        self.lead_mm = base.lead_mm
        self.bound = base.max_correction_mm
        self.kp, self.kd = kp, kd
        self.reset()

    def reset(self) -> None:
        """Forget the seam seen so far (call at each episode's start)."""
        self._s: list[float] = []
        self._offsets: list[NDArray[np.float64]] = []
        self._previous = np.zeros(2)

    def __call__(self, observation: NDArray[Any]) -> NDArray[np.float32]:
        parts = split_observation(observation, self.rays)
        torch = parts["torch"].astype(np.float64)
        s_torch = float(torch[8]) * self.nominal.length_mm
        correction = torch[5:7]
        _, tangent, lateral, normal = self.nominal.frame(s_torch)
        valid = parts["valid"]
        if valid.any():
            points = parts["profile"][valid].astype(np.float64)
            y, z = points[int(np.argmax(points[:, 1]))]
            seam = self.origin + self.axes @ np.array((y, z))  # relative to the torch tip
            s_seam = s_torch + float(seam.dot(tangent))
            offset = torch[0:2] + np.array((seam.dot(lateral), seam.dot(normal)))
            if not self._s or s_seam > self._s[-1]:
                self._s.append(s_seam)
                self._offsets.append(offset)
        if not self._s:
            return np.zeros(2, dtype=np.float32)
        wanted = self._offset_at(s_torch + self.lead_mm)
        error = wanted - correction
        action = self.kp * error + self.kd * (error - self._previous)
        self._previous = error
        return np.clip(action, -self.bound, self.bound).astype(np.float32)

    def _offset_at(self, s_mm: float) -> NDArray[np.float64]:
        """The stored seam offset at arc length ``s_mm`` (linear between frames; the nearest
        stored one outside them)."""
        s = self._s
        i = bisect.bisect_left(s, s_mm)
        if i == 0:
            return self._offsets[0]
        if i == len(s):
            return self._offsets[-1]
        w = (s_mm - s[i - 1]) / (s[i] - s[i - 1])
        return (1.0 - w) * self._offsets[i - 1] + w * self._offsets[i]
