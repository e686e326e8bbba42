"""Where the sensor sits on the torch: from the scene's mount angles, or from the seam itself.

The scene's ``sensor.mount_rotation_deg`` keeps the classic mount: laser pointing down (-Z),
baseline along base +X, turned by x-y-z angles in the laser frame. Left unset on a scene whose
seam comes from a workpiece, the mount comes from the seam's torch frame at its start instead:

- the laser plane is normal to the seam's tangent there, the camera ahead along it (the sensor
  looks ahead along the seam, whichever way the seam runs: a 3-axis robot keeps that mount);
- the laser points along the torch direction (the bisector of the two faces' outward normals),
  so it comes in from the open side of the joint and its stripe crosses both faces of the seam
  that was chosen, not those of a neighbour; a lap joint is seen square to its sheets (along
  the normal of the sheet that goes on), as a lap extractor expects;
- if something stands in the way of the laser fan or the camera (the next upright of a comb, a
  web beside a lap, a gusset where the seam ends), the camera is turned round to look back from
  the torch's side, or the laser is turned about the seam, towards one face or the other, by
  the smallest angle (5 deg steps, up to 40 deg) that clears them all along the seam.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.geometry import frames
from seamtrack.geometry.seam import Seam

FloatArray = NDArray[np.float64]

#: Turns of the laser about the seam tried when the torch direction is blocked (deg).
TURNS_DEG = (0, 5, -5, 10, -10, 15, -15, 20, -20, 25, -25, 30, -30, 35, -35, 40, -40)
#: Points along the seam whose line of sight is checked.
SIGHT_SAMPLES = 9
#: The sight is checked for torch positions whose laser meets the seam this far short of its end.
END_MARGIN_MM = 1.0
#: How far off the seam, along its torch direction, the camera's sight is tested (mm).
SIGHT_OFFSET_MM = 0.05
#: Rays across the laser fan checked at each of them.
FAN_SAMPLES = 21
#: A fan ray that meets the part nearer than this fraction of the range is blocked.
NEAR_FRACTION = 0.6


@dataclass(frozen=True)
class Mount:
    """The sensor on the torch.

    Attributes
    ----------
    T_tcp_sensor : (4, 4) float
    from_seam : bool
        Set up from the seam's torch frame (else from the scene's mount angles).
    turn_rad : float
        The turn about the seam that the line of sight needed (0: the torch direction was free).
    blocked : bool
        No turn tried cleared the line of sight (the torch direction is kept).
    camera_ahead : bool
        The camera sits ahead of the laser along the seam (else between laser and torch).
    """

    T_tcp_sensor: FloatArray
    from_seam: bool = False
    turn_rad: float = 0.0
    blocked: bool = False
    camera_ahead: bool = True

    def describe(self) -> str:
        """One line for ``seamtrack check``."""
        if not self.from_seam:
            return "sensor.mount_rotation_deg"
        if self.blocked:
            return "from the seam; the line of sight is blocked at every turn tried"
        where = "" if self.camera_ahead else ", camera looking back"
        return f"from the seam, turned {math.degrees(self.turn_rad):+.0f} deg about it{where}"


def angles_mount(
    mount_rotation_deg: tuple[float, float, float], look_ahead_mm: float, distance_mm: float
) -> Mount:
    """The classic mount: laser down, baseline along +X, turned by the given angles."""
    R_down = frames.look_rotation([0.0, 0.0, -1.0], [1.0, 0.0, 0.0])
    R = R_down @ frames.from_xyz_rpy_deg([0.0, 0.0, 0.0], mount_rotation_deg)[:3, :3]
    emitter = np.array([look_ahead_mm, 0.0, 0.0]) - distance_mm * R[:, 2]
    return Mount(frames.make(R, emitter))


def seam_mount(
    seam: Seam,
    look_ahead_mm: float,
    distance_mm: float,
    baseline_mm: float,
    half_fan_rad: float,
    caster: Any = None,
    view: FloatArray | None = None,
) -> Mount:
    """The mount from the seam's torch frame at its start (see the module docstring).

    Parameters
    ----------
    seam : Seam
        World frame, with torch normals.
    look_ahead_mm, distance_mm : float
        How far ahead of the torch along the seam the laser meets it, and the emitter's
        distance from there along the laser.
    baseline_mm : float
        Emitter-to-camera distance along x_L.
    half_fan_rad : float
        Half the laser fan's opening angle.
    caster : RayCaster, optional
        The part as the sensor sees it: the fan and the camera's line of sight are checked
        against it (None: no check).
    view : (3,) float, optional
        The direction to look from, world frame (default: the torch normal at the start). A lap
        joint is seen square to its sheets.
    """
    tangent = seam.tangent_at([0.0])[0]
    normal = seam.normals[0] if view is None else np.asarray(view, dtype=np.float64)
    normal = normal - (normal @ tangent) * tangent
    normal /= np.linalg.norm(normal)
    side = np.cross(tangent, normal)
    length = seam.length_mm
    # Torch positions whose laser still meets the seam (short of its end, where it may stop
    # against a wall that no sensor looks past).
    last = max(0.0, length - look_ahead_mm - END_MARGIN_MM)
    s = np.linspace(0.0, last, SIGHT_SAMPLES)
    tcps = seam.interpolate(s)
    ahead = seam.interpolate(np.minimum(s + look_ahead_mm, length))
    # Test the sight from just off the seam, into the open side: a point on the corner itself
    # lies in both faces' planes, and a camera ahead along the seam would graze them.
    ahead = ahead + SIGHT_OFFSET_MM * seam.normals[seam.closest(ahead).segment]
    first: Mount | None = None
    for turn_deg in TURNS_DEG:
        turn = math.radians(turn_deg)
        laser = -(math.cos(turn) * normal + math.sin(turn) * side)
        emitter = look_ahead_mm * tangent - distance_mm * laser
        # The camera ahead of the laser, or (when something ahead hides the stripe from it)
        # turned round to look back at it from the torch's side.
        for camera_ahead in (True, False):
            R = frames.look_rotation(laser, tangent if camera_ahead else -tangent)
            mount = Mount(frames.make(R, emitter), True, turn, camera_ahead=camera_ahead)
            if caster is None:
                return mount
            first = first or mount
            if _clear(caster, R, emitter, tcps, ahead, distance_mm, baseline_mm, half_fan_rad):
                return mount
    assert first is not None
    return Mount(first.T_tcp_sensor, True, 0.0, blocked=True)


def _clear(
    caster: Any,
    R: FloatArray,
    emitter: FloatArray,
    tcps: FloatArray,
    ahead: FloatArray,
    distance_mm: float,
    baseline_mm: float,
    half_fan_rad: float,
) -> bool:
    """Whether, with the torch at each of ``tcps``, no fan ray meets the part in the near half
    of its range and the camera sees the seam point ahead."""
    angles = np.linspace(-half_fan_rad, half_fan_rad, FAN_SAMPLES)
    fan = np.cos(angles)[:, None] * R[:, 2] + np.sin(angles)[:, None] * R[:, 1]
    camera = emitter + baseline_mm * R[:, 0]
    for tcp, point in zip(tcps, ahead, strict=True):
        hits = caster.first_hit(tcp + emitter, fan, refine=False)
        if np.any(hits.hit & (hits.distance_mm < NEAR_FRACTION * distance_mm)):
            return False
        if np.any(caster.line_of_sight_blocked(point[None], tcp + camera)):
            return False
    return True
