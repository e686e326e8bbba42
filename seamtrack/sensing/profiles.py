"""Stripe profiles and seam-point results: the types every sensing path and extractor share.

A :class:`Profile` is what the sensor's camera gives after triangulation: points (y_L, z_L) in
the laser plane, one per sensor column, with a validity mask and a reason code per point. A
:class:`Feature` is what an extractor (or the seam-mode model) finds in it: the seam point, or a
falsy failure with a reason.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from enum import IntEnum

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.geometry.frames import apply

FloatArray = NDArray[np.float64]


class Reason(IntEnum):
    """Why a stripe point is (in)valid; stored per point as uint8."""

    VALID = 0
    MISS = 1  # the laser ray hit nothing
    OCCLUDED = 2  # the camera cannot see the lit point
    OUT_OF_RANGE = 3  # outside the depth of field or the trapezoidal field of view
    INCIDENCE = 4  # lit at a grazing angle beyond the sensor's limit: too dim
    DROPOUT = 5  # lost to the noise model (dropout, speckle), or no peak in an image column
    SPIKE = 6  # an isolated point off its neighbours (a specular spike): left out by extractors
    REFLECTION = 7  # a run off the line the surface continues on across it (multipath streak)


_VALID = int(Reason.VALID)
_MISS = int(Reason.MISS)


@dataclass(frozen=True, eq=False)
class Profile:
    """One stripe profile in the laser frame.

    Parameters
    ----------
    points_laser : (n, 2) float
        (y_L, z_L) in mm; invalid points may hold NaN.
    valid : (n,) bool, optional
        Default: the points that are finite.
    reason : (n,) uint8, optional
        :class:`Reason` codes; default VALID where valid, MISS elsewhere.
    T_world_sensor : (4, 4) float, optional
        Pose of the laser frame at capture; needed for :attr:`points_world`.
    t_s : float
        Capture time (NaN when unknown).
    """

    points_laser: FloatArray
    valid: NDArray[np.bool_] | None = None
    reason: NDArray[np.uint8] | None = None
    T_world_sensor: FloatArray | None = None
    t_s: float = float("nan")

    def __post_init__(self) -> None:
        pts = np.asarray(self.points_laser, dtype=np.float64)
        if pts.size == 0:
            pts = pts.reshape(0, 2)
        if pts.ndim != 2 or pts.shape[1] != 2:
            raise ValueError(f"points_laser must have shape (n, 2), got {pts.shape}")
        # Per-column finiteness and plain integer codes: this runs once per sensor frame, and
        # isfinite(...).all(axis=1) or comparisons against the IntEnum cost several times more.
        finite = np.isfinite(pts[:, 0]) & np.isfinite(pts[:, 1])
        valid = finite if self.valid is None else np.asarray(self.valid, dtype=bool) & finite
        if valid.shape != (len(pts),):
            raise ValueError(f"valid must have shape ({len(pts)},), got {valid.shape}")
        if self.reason is None:
            reason = np.where(valid, _VALID, _MISS).astype(np.uint8)
        else:
            reason = np.array(self.reason, dtype=np.uint8)
            reason[~valid & (reason == _VALID)] = _MISS
            reason[valid] = _VALID
        object.__setattr__(self, "points_laser", pts)
        object.__setattr__(self, "valid", valid)
        object.__setattr__(self, "reason", reason)
        if self.T_world_sensor is not None:
            object.__setattr__(
                self, "T_world_sensor", np.asarray(self.T_world_sensor, dtype=np.float64)
            )

    @classmethod
    def _trusted(
        cls,
        points_laser: FloatArray,
        reason: NDArray[np.uint8],
        T_world_sensor: FloatArray | None,
        t_s: float,
    ) -> Profile:
        """A profile from arrays the caller guarantees: (n, 2) float64 points, uint8 reasons
        with valid points exactly where the reason is VALID (and only finite ones there). The
        ray caster builds one per sensor frame; this skips the checks of ``__init__``."""
        profile = object.__new__(cls)
        object.__setattr__(profile, "points_laser", points_laser)
        object.__setattr__(profile, "valid", reason == _VALID)
        object.__setattr__(profile, "reason", reason)
        object.__setattr__(profile, "T_world_sensor", T_world_sensor)
        object.__setattr__(profile, "t_s", t_s)
        return profile

    def __len__(self) -> int:
        return len(self.points_laser)

    @property
    def valid_points(self) -> FloatArray:
        """(m, 2) the valid points only, in column order."""
        assert self.valid is not None
        return self.points_laser[self.valid]

    @property
    def points_world(self) -> FloatArray:
        """(n, 3) the points in the world frame (needs ``T_world_sensor``)."""
        if self.T_world_sensor is None:
            raise ValueError("this profile has no pose (T_world_sensor)")
        return laser_to_world(self.T_world_sensor, self.points_laser)


def laser_to_world(T_world_sensor: ArrayLike, points_laser: ArrayLike) -> FloatArray:
    """(n, 2) or (2,) (y_L, z_L) laser-plane points to (n, 3) or (3,) world points."""
    p = np.asarray(points_laser, dtype=np.float64)
    p3 = np.concatenate([np.zeros(p.shape[:-1] + (1,)), p], axis=-1)
    return apply(T_world_sensor, p3)


_EMPTY2 = np.empty((0, 2))


#: How far from the expected seam point a candidate may lie and still be preferred (mm), across
#: the seam (y_L) and in range (z_L): a path extrapolated straight misses a turning seam
#: sideways (a mitre's 80 deg turn: 0.9 mm, 10 mm ahead of the torch), while the root's depth
#: changes little from one frame to the next (a false V's apex lies 0.5 mm or more deeper).
HINT_TOLERANCE_MM = (1.5, 0.4)


@dataclass(frozen=True)
class SeamHint:
    """A prior on the seam in a frame, from the tracker's path: where the seam is expected in
    the laser plane (``point_laser``: y_L, z_L; mm), the direction it is heading (``direction``:
    a unit vector in the sensor frame, x_S across the laser plane) and how far from the
    expected point a candidate may lie across the seam and in range and still be preferred
    (``tolerance_mm``: y_L, z_L; an ellipse about the point).

    An extractor that takes a ``hint`` keyword (``extractor(profile, hint=...)``) may use it to
    choose among candidates (the V that continues the seam where the laser plane crosses two
    grooves at a mitred corner); it never makes a seam point that the profile does not show.
    """

    point_laser: tuple[float, float]
    direction: tuple[float, float, float] = (1.0, 0.0, 0.0)
    tolerance_mm: tuple[float, float] = HINT_TOLERANCE_MM


def hint_from_path(
    T_world_sensor: ArrayLike,
    point_world: ArrayLike,
    direction_world: ArrayLike,
    tolerance_mm: tuple[float, float] = HINT_TOLERANCE_MM,
) -> SeamHint | None:
    """The :class:`SeamHint` of a path through ``point_world`` heading ``direction_world``
    (world frame): where the straight line crosses the laser plane (x_S = 0), or None when
    it runs along the plane."""
    T = np.asarray(T_world_sensor, dtype=np.float64)
    R, t = T[:3, :3], T[:3, 3]
    p = R.T @ (np.asarray(point_world, dtype=np.float64) - t)
    d = R.T @ np.asarray(direction_world, dtype=np.float64)
    norm = float(np.linalg.norm(d))
    if not norm > 1e-12 or abs(d[0]) < 1e-6 * norm:
        return None
    d = d / norm
    at = p - (p[0] / d[0]) * d
    if not np.isfinite(at).all():
        return None
    sign = 1.0 if d[0] > 0 else -1.0
    return SeamHint(
        (float(at[1]), float(at[2])),
        (float(sign * d[0]), float(sign * d[1]), float(sign * d[2])),
        (float(tolerance_mm[0]), float(tolerance_mm[1])),
    )


@dataclass(frozen=True, eq=False)
class Feature:
    """A seam point found in a profile, or a falsy failure with a reason.

    Attributes
    ----------
    point_laser : (2,) float
        (y_L, z_L) of the seam point; empty when not found.
    point_world : (3,) float
        The same in the world frame, when the profile had a pose; else empty.
    confidence : float
        In [0, 1]; 0 for a failure.
    edges_laser : (k, 2) float
        Groove edges (or other feature points), may be empty.
    gap_mm : float
        Root gap width, NaN when not measured.
    joint : str
        Joint type the extractor assumed.
    reason : str
        Why nothing was found ("" when found).
    stripe_points : int
        Valid points in the profile of a frame without a seam point, when the scan counted
        them (0: the stripe is off the part, or hidden whole); -1 when not counted.
    area_mm2 : float
        A groove's remaining cross-section (mm^2) between its fill surface and the line joining
        its top corners (the ``groove`` extractor's); NaN when not measured.
    """

    point_laser: FloatArray = field(default_factory=lambda: np.empty(0))
    point_world: FloatArray = field(default_factory=lambda: np.empty(0))
    confidence: float = 1.0
    edges_laser: FloatArray = field(default_factory=lambda: _EMPTY2.copy())
    gap_mm: float = float("nan")
    joint: str = ""
    reason: str = ""
    stripe_points: int = -1
    area_mm2: float = float("nan")

    def __bool__(self) -> bool:
        return self.point_laser.shape == (2,) and not self.reason

    @classmethod
    def failed(cls, reason: str, joint: str = "") -> Feature:
        """A falsy result that says why."""
        return cls(confidence=0.0, joint=joint, reason=reason)

    @classmethod
    def found(
        cls,
        point_laser: ArrayLike,
        T_world_sensor: ArrayLike | None = None,
        **kwargs: object,
    ) -> Feature:
        """A seam point; its world position follows from the pose when one is given."""
        p = np.asarray(point_laser, dtype=np.float64).reshape(2)
        if T_world_sensor is None:
            world = np.empty(0)
        else:  # laser_to_world on floats: one point, called once per frame
            y, z = p.tolist()
            (_, ay, az, ax), (_, by, bz, bx), (_, cy, cz, cx) = np.asarray(
                T_world_sensor, dtype=np.float64
            )[:3].tolist()
            world = np.array((y * ay + z * az + ax, y * by + z * bz + bx, y * cy + z * cz + cx))
        return cls(point_laser=p, point_world=world, **kwargs)  # type: ignore[arg-type]
