"""The tool's orientation along a seam, as a robot program states it.

Seam tracking corrects the torch's *position* from what the sensor measures; its *orientation*
comes from the robot program, here the nominal seam (the scene's seam, or the CAD seam edge
with its face bisectors): at arc length s the torch axis makes the scene's work and travel
angles with the seam frame (tangent, torch normal: :mod:`seamtrack.geometry.torch`), and the
tool is turned about that axis so that its x axis, along which the sensor looks ahead, points
at the seam point ``look_ahead_mm`` further along the seam. Then the laser line crosses the
seam near the centre of its field of view on curves and round corners, which a tool that
never turns (the paper's gantry) cannot do.

A closed seam (a pipe's girth) wraps around: the heading near its end points at its start.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.geometry.seam import Seam
from seamtrack.geometry.torch import torch_axis
from seamtrack.jit import KERNEL

FloatArray = NDArray[np.float64]

#: A seam whose ends are closer than this (mm) is closed (a girth seam).
CLOSED_TOL_MM = 1e-3

#: Half the arc length (mm) over which the program's rate of turning is differenced.
TURN_RATE_STEP_MM = 0.5


@numba.njit(**KERNEL)
def _point_at(s: float, knots: FloatArray, points: FloatArray, length: float) -> FloatArray:
    """:meth:`Seam.interpolate` at one arc length."""
    x = min(max(s, 0.0), length)
    out = np.empty(3)
    for k in range(3):
        out[k] = np.interp(x, knots, points[:, k])
    return out


@numba.njit(**KERNEL)
def _rotation_at(
    s: float, points: FloatArray, knots: FloatArray, seg_len: FloatArray, normals: FloatArray,
    par: FloatArray,
) -> FloatArray:  # fmt: skip
    """:meth:`ToolProgram.rotations` at one arc length, compiled (the same formulas; equal
    to rounding). ``par``: tan(travel), tan(work), look-ahead, closed (0/1), length."""
    tan_travel, tan_work, look, closed, length = par[0], par[1], par[2], par[3] > 0, par[4]
    x = min(max(s, 0.0), length)
    last = len(knots) - 2
    seg = min(max(int(np.searchsorted(knots, x, side="right")) - 1, 0), last)
    w = (x - knots[seg]) / seg_len[seg]
    a, b = points[seg], points[seg + 1]
    t = (b - a) / seg_len[seg]
    n = (1 - w) * normals[seg] + w * normals[seg + 1]
    n = n - (n @ t) * t
    n = n / math.sqrt(n @ n)
    point = a + w * (b - a)
    lateral = np.cross(t, n)
    axis = n - tan_travel * t + tan_work * lateral
    axis = axis / math.sqrt(axis @ axis)
    ahead = s + look
    if closed:
        p_ahead = _point_at(ahead % length, knots, points, length)
    else:
        end = points[last + 1] - points[last]
        end = end / math.sqrt(end @ end)
        p_ahead = _point_at(min(ahead, length), knots, points, length)
        p_ahead = p_ahead + max(ahead - length, 0.0) * end
    heading = p_ahead - point
    heading = heading - (heading @ axis) * axis
    norm = math.sqrt(heading @ heading)
    if not norm > 1e-9:  # the chord along the torch axis (never on a real seam): the tangent
        heading = t - (t @ axis) * axis
        norm = math.sqrt(heading @ heading)
    heading = heading / norm
    out = np.empty((3, 3))
    out[:, 0], out[:, 1], out[:, 2] = heading, np.cross(axis, heading), axis
    return out


@numba.njit(**KERNEL)
def _rotation_vector(R: FloatArray) -> FloatArray:
    """(3,) axis times angle (rad) of a rotation matrix (angle below pi)."""
    v = 0.5 * np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    angle = math.acos(min(max(0.5 * (R[0, 0] + R[1, 1] + R[2, 2] - 1.0), -1.0), 1.0))
    if angle < 1e-8:
        return v
    return v * (angle / math.sin(angle))


@numba.njit(**KERNEL)
def turning_at(
    s: float, speed: float, points: FloatArray, knots: FloatArray, seg_len: FloatArray,
    normals: FloatArray, par: FloatArray,
) -> tuple[FloatArray, FloatArray]:  # fmt: skip
    """The tool rotation at arc length s and its angular velocity at ``speed`` (the central
    difference of :meth:`ToolProgram.angular_velocity`), compiled."""
    R = _rotation_at(s, points, knots, seg_len, normals, par)
    lo = max(s - TURN_RATE_STEP_MM, 0.0)
    hi = min(s + TURN_RATE_STEP_MM, par[4])
    if hi <= lo:
        return R, np.zeros(3)
    R_lo = _rotation_at(lo, points, knots, seg_len, normals, par)
    R_hi = _rotation_at(hi, points, knots, seg_len, normals, par)
    return R, _rotation_vector(R_hi @ np.ascontiguousarray(R_lo.T)) * (speed / (hi - lo))


def is_closed(seam: Seam) -> bool:
    """True when the seam ends where it starts."""
    return bool(np.linalg.norm(seam.points[-1] - seam.points[0]) <= CLOSED_TOL_MM)


@dataclass(frozen=True, eq=False)
class ToolProgram:
    """Tool orientations along a nominal seam.

    Parameters
    ----------
    seam : Seam
        The nominal seam, world frame.
    work_rad, travel_rad : float
        Torch angles relative to the seam frame.
    look_ahead_mm : float
        How far ahead along the seam the tool's x axis points.
    """

    seam: Seam
    work_rad: float = 0.0
    travel_rad: float = 0.0
    look_ahead_mm: float = 10.0
    #: The seam's arrays and the parameters of the compiled :func:`turning_at`.
    _arrays: tuple[FloatArray, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        seam = self.seam
        par = np.array(
            [math.tan(self.travel_rad), math.tan(self.work_rad), self.look_ahead_mm,
             1.0 if is_closed(seam) else 0.0, seam.length_mm],
        )  # fmt: skip
        arrays = tuple(
            np.ascontiguousarray(a, dtype=np.float64)
            for a in (seam.points, seam.arc_length_mm, seam.segment_lengths_mm, seam.normals)
        )
        object.__setattr__(self, "_arrays", (*arrays, par))

    @property
    def closed(self) -> bool:
        return is_closed(self.seam)

    def frame(self, arc_length_mm: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """Seam points, unit tangents and unit torch normals at arc lengths.

        The normal is interpolated linearly between the seam points' normals and made
        orthogonal to the segment's tangent.

        Returns
        -------
        points, tangents, normals : (m, 3) float
        """
        seam = self.seam
        s = np.clip(np.atleast_1d(np.asarray(arc_length_mm, dtype=np.float64)), 0, seam.length_mm)
        knots = seam.arc_length_mm
        seg = np.clip(np.searchsorted(knots, s, side="right") - 1, 0, len(knots) - 2)
        w = ((s - knots[seg]) / seam.segment_lengths_mm[seg])[:, None]
        a, b = seam.points[seg], seam.points[seg + 1]
        tangent = (b - a) / seam.segment_lengths_mm[seg][:, None]
        normal = (1 - w) * seam.normals[seg] + w * seam.normals[seg + 1]
        normal -= np.sum(normal * tangent, axis=1, keepdims=True) * tangent
        normal /= np.linalg.norm(normal, axis=1, keepdims=True)
        return a + w * (b - a), tangent, normal

    def ahead(self, arc_length_mm: ArrayLike) -> FloatArray:
        """(m, 3) the seam points ``look_ahead_mm`` further on (wrapping on a closed seam;
        past an open seam's end, extended along its last segment)."""
        seam = self.seam
        s = np.atleast_1d(np.asarray(arc_length_mm, dtype=np.float64)) + self.look_ahead_mm
        length = seam.length_mm
        if self.closed:
            return seam.interpolate(np.mod(s, length))
        over = np.maximum(s - length, 0.0)[:, None]
        end_dir = seam.tangent_at([length])[0]
        return seam.interpolate(np.minimum(s, length)) + over * end_dir

    def rotations(self, arc_length_mm: ArrayLike) -> FloatArray:
        """(m, 3, 3) tool rotations ``R_world_tcp`` at arc lengths (z the torch axis, x towards
        the seam ahead)."""
        points, tangent, normal = self.frame(arc_length_mm)
        axis = torch_axis(tangent, normal, self.work_rad, self.travel_rad)
        heading = self.ahead(arc_length_mm) - points
        heading -= np.sum(heading * axis, axis=1, keepdims=True) * axis
        norm = np.linalg.norm(heading, axis=1, keepdims=True)
        # Where the chord runs along the torch axis (never on a real seam), use the tangent.
        fallback = tangent - np.sum(tangent * axis, axis=1, keepdims=True) * axis
        heading = np.where(norm > 1e-9, heading, fallback)
        heading /= np.linalg.norm(heading, axis=1, keepdims=True)
        return np.stack([heading, np.cross(axis, heading), axis], axis=2)

    def angular_velocity(self, arc_length_mm: float, speed_mm_s: float) -> FloatArray:
        """(3,) world angular velocity (rad/s) of the tool moving along the program at a speed:
        ``omega = (dR/ds R^T)^vee v``, by a central difference over +-0.5 mm.

        This is the orientation's feed-forward: a tool that must keep turning (a saddle, a
        girth) turns at this rate without waiting for an orientation error to build up.
        """
        return self._turning(arc_length_mm, speed_mm_s)[1]

    def _turning(self, s: float, speed_mm_s: float) -> tuple[FloatArray, FloatArray]:
        """The rotation at s and the angular velocity there (compiled: :func:`turning_at`,
        :meth:`rotations`' formulas)."""
        return turning_at(float(s), float(speed_mm_s), *self._arrays)

    def turning_near(
        self, point: ArrayLike, hint_mm: float, speed_mm_s: float
    ) -> tuple[FloatArray, FloatArray, float]:
        """Tool rotation and angular velocity (at ``speed_mm_s`` along the seam) at the seam
        point closest to ``point`` near the arc length hint, and that arc length."""
        s = self.seam.closest_near(point, hint_mm)
        R, omega = self._turning(s, speed_mm_s)
        return R, omega, s

    def rotation_near(self, point: ArrayLike, hint_mm: float) -> tuple[FloatArray, float]:
        """Tool rotation at the seam point closest to ``point`` near the arc length hint
        (a torch moving along the seam), and that arc length."""
        s = self.seam.closest_near(point, hint_mm)
        return self.rotations([s])[0], s
