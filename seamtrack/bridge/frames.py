"""Every sensor frame of a run, seen from outside the loop: profile, pose, feature, TF chain.

:func:`observe` wraps a run's :class:`~seamtrack.simulation.assemble.Parts` so that each call
of its ``sense`` (once per sensor frame, from :func:`seamtrack.simulation.loop.run`) also
hands a :class:`Frame` to a callback; the loop is unchanged, and so are its numbers (the
wrapper calls the same scan with the same arguments, in the same order). In mesh mode the
frame holds the stripe profile the extractor saw; in seam mode (no stripe) the "profile" is the
single seam point (NaN with a reason when the laser plane misses the seam).

:func:`frame_chain` gives the robot's frames at a sensor pose as TF links: world -> base ->
tcp -> sensor, and on an arm world -> base -> flange -> tcp -> sensor (frame ids:
:data:`seamtrack.bridge.messages.FRAMES`).

This module imports no ROS library: the lockstep bridge, the recorder and the Gymnasium
environment share it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.geometry.frames import invert
from seamtrack.sensing.profiles import Feature, Profile, Reason, SeamHint
from seamtrack.sensing.scan import laser_plane_crossings
from seamtrack.simulation.assemble import Parts

FloatArray = NDArray[np.float64]

#: Frame ids of the chain (the same strings as seamtrack.bridge.messages.FRAMES).
WORLD, BASE, FLANGE, TCP, SENSOR = "world", "base", "flange", "tcp", "sensor"


@dataclass(frozen=True, eq=False)
class Frame:
    """One sensor frame of a run.

    Attributes
    ----------
    index : int
        0 for the run's first frame.
    t_s : float
        Capture time (simulated).
    T_world_sensor : (4, 4) float
        The sensor's pose at capture (mm).
    profile : Profile
        Mesh mode: the stripe profile; seam mode: the seam point alone (one point).
    feature : Feature
        What the extractor (or the seam-mode model) found.
    image : StripeImage or None
        Image mode: the camera image the profile was measured from.
    """

    index: int
    t_s: float
    T_world_sensor: FloatArray
    profile: Profile
    feature: Feature
    image: Any = None


def seam_profile(feature: Feature, T_world_sensor: FloatArray, t_s: float) -> Profile:
    """Seam mode's "profile": the seam point as a one-point profile; without one, a NaN point
    with a reason (OUT_OF_RANGE: the crossing is outside the field of view; else MISS)."""
    if feature:
        return Profile(feature.point_laser.reshape(1, 2), T_world_sensor=T_world_sensor, t_s=t_s)
    code = Reason.OUT_OF_RANGE if "field of view" in feature.reason else Reason.MISS
    return Profile(
        np.full((1, 2), np.nan),
        reason=np.array([code], dtype=np.uint8),
        T_world_sensor=T_world_sensor,
        t_s=t_s,
    )


def observe(parts: Parts, on_frame: Callable[[Frame], object]) -> Parts:
    """``parts`` whose ``sense`` also calls ``on_frame(frame)`` for every sensor frame.

    Mesh mode calls the parts' ``scan`` (the profile and the feature, as ``sense`` does);
    image mode adds the camera image the scan rendered (``parts.last_image``). The returned
    parts are a :func:`dataclasses.replace` of ``parts``: run them with
    :func:`seamtrack.simulation.loop.run` as usual. ``scan`` itself is left unwrapped (a
    caller of ``scan`` sees no frames).
    """
    count = [0]
    scan = parts.scan
    sense = parts.sense
    last_image = getattr(parts, "last_image", None)

    def observed(T_world_sensor: FloatArray, t_s: float, hint: SeamHint | None = None) -> Feature:
        image = None
        if scan is not None:
            profile, feature = scan(T_world_sensor, t_s, hint)
            if last_image is not None:
                image = last_image()
        else:
            feature = (
                sense(T_world_sensor, t_s, hint) if hint is not None else sense(T_world_sensor, t_s)
            )
            profile = seam_profile(feature, T_world_sensor, t_s)
        frame = Frame(count[0], t_s, np.array(T_world_sensor, dtype=float), profile, feature, image)
        count[0] += 1
        on_frame(frame)
        return feature

    return dataclasses.replace(parts, sense=observed)


class FrameLog:
    """A callback for :func:`observe` that keeps every frame (``log.frames``)."""

    def __init__(self) -> None:
        self.frames: list[Frame] = []

    def __call__(self, frame: Frame) -> None:
        self.frames.append(frame)


def true_seam_point(seam: Any, sensor: Any, T_world_sensor: FloatArray) -> FloatArray | None:
    """Where the laser plane crosses the true seam inside the sensor's field of view, as
    (y_L, z_L) mm (the crossing nearest the stripe's centre when there are several), or None:
    the label of a frame."""
    crossings = laser_plane_crossings(seam, T_world_sensor)
    if not len(crossings):
        return None
    inside = np.flatnonzero(sensor.in_field_of_view(crossings[:, 0], crossings[:, 1]))
    if not len(inside):
        return None
    return np.asarray(crossings[inside[np.argmin(np.abs(crossings[inside, 0]))]], dtype=float)


def frame_chain(robot: Any, T_world_sensor: FloatArray) -> list[tuple[str, str, FloatArray]]:
    """The robot's frames at a sensor pose, as (parent, child, T_parent_child) links in mm.

    world -> base (``robot.T_world_base``), base -> tcp (from the sensor pose and the fixed
    ``robot.T_tcp_sensor``), tcp -> sensor; an arm (a robot with ``kinematics``) puts its
    flange between base and tcp (``kinematics.T_flange_tcp``: the torch on the flange).
    """
    T_world_base = np.asarray(robot.T_world_base, dtype=float)
    T_tcp_sensor = np.asarray(robot.T_tcp_sensor, dtype=float)
    T_world_tcp = np.asarray(T_world_sensor, dtype=float) @ invert(T_tcp_sensor)
    T_base_tcp = invert(T_world_base) @ T_world_tcp
    chain = [(WORLD, BASE, T_world_base)]
    kinematics = getattr(robot, "kinematics", None)
    if kinematics is not None:
        T_flange_tcp = np.asarray(kinematics.T_flange_tcp, dtype=float)
        chain.append((BASE, FLANGE, T_base_tcp @ invert(T_flange_tcp)))
        chain.append((FLANGE, TCP, T_flange_tcp))
    else:
        chain.append((BASE, TCP, T_base_tcp))
    chain.append((TCP, SENSOR, T_tcp_sensor))
    return chain
