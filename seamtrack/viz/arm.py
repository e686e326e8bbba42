"""An articulated arm drawn in PyVista from its kinematics: one set of meshes per joint frame.

The arms' URDFs carry kinematics only (no ``<visual>`` meshes), so each link is drawn from the
joint frames Pinocchio computes: a motor (a cylinder along the joint's axis at its origin) and
the link to the next joint's origin (tubes along the fixed offset's z, x and y components in
turn, so that a KR 16's column rises and then reaches forward, as the real arm's does), then
the flange (a disc) and the torch from the flange to the torch tip (TCP).

A link's meshes are built once in its joint's frame, where they never change: the offset from
a joint to the next joint's origin is a fixed placement of the model (``model.jointPlacements``)
and a revolute joint only turns about its own origin. Moving the arm sets each actor's
``user_matrix`` to its joint's world pose ``T_world_base @ oMi`` (mm); nothing is re-meshed.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.control.arm import ArticulatedRobot
from seamtrack.control.kinematics import M_PER_MM, import_pinocchio, joint_axis

FloatArray = NDArray[np.float64]

_LINK_COLOR = "#e07b00"  # an arc-welding arm's orange
_MOTOR_COLOR = "#5a5a5a"
_FLANGE_COLOR = "#303030"
_TORCH_COLOR = "#c08000"
_BASE_COLOR = "#404040"

#: Offsets shorter than this (mm) are not drawn (coincident joint origins, a spherical wrist).
_MIN_SEGMENT_MM = 1.0


@dataclass(frozen=True, eq=False)
class ArmSegments:
    """The arm's drawn geometry, in each mesh's own joint frame (mm).

    Attributes
    ----------
    joint : (k,) int
        Pinocchio joint id whose frame each piece is drawn in (0: the base).
    points : list of (m, 3) float
        Each piece's polyline (a link's path from its joint's origin to the next origin, the
        torch from the flange to the TCP), in that joint's frame.
    kind : list of str
        ``"link"``, ``"torch"``.
    """

    joint: tuple[int, ...]
    points: tuple[FloatArray, ...]
    kind: tuple[str, ...]


def arm_segments(robot: ArticulatedRobot) -> ArmSegments:
    """The link paths and the torch of an arm, each in its parent joint's frame (mm)."""
    kin = robot.kinematics
    model = kin.model
    joints: list[int] = []
    points: list[FloatArray] = []
    kinds: list[str] = []
    for child in range(2, model.njoints):
        offset = np.asarray(model.jointPlacements[child].translation) / M_PER_MM
        joints.append(int(model.parents[child]))
        points.append(_elbow_path(offset))
        kinds.append("link")
    flange = model.frames[kin.frame_id]
    tcp = model.frames[kin.tcp_id]
    parent = int(flange.parentJoint)
    offset = np.asarray(flange.placement.translation) / M_PER_MM
    joints.append(parent)
    points.append(_elbow_path(offset))
    kinds.append("link")
    joints.append(int(tcp.parentJoint))
    tip = np.asarray(tcp.placement.translation) / M_PER_MM
    points.append(np.vstack([offset, tip]))
    kinds.append("torch")
    return ArmSegments(tuple(joints), tuple(points), tuple(kinds))


def _elbow_path(offset: FloatArray) -> FloatArray:
    """(m, 3) from the origin to ``offset`` along its z, then x, then y components."""
    path = [np.zeros(3)]
    for axis in (2, 0, 1):
        if abs(offset[axis]) >= _MIN_SEGMENT_MM:
            step = path[-1].copy()
            step[axis] = offset[axis]
            path.append(step)
    if len(path) == 1 or not np.allclose(path[-1], offset):
        path.append(np.asarray(offset, dtype=np.float64))
    return np.vstack(path)


def joint_poses_world(robot: ArticulatedRobot, q: ArrayLike, data: Any = None) -> FloatArray:
    """(njoints, 4, 4) world pose of every joint frame (index 0: the base), mm.

    Parameters
    ----------
    robot : ArticulatedRobot
    q : (n,) float
        Joint positions, rad.
    """
    pin = import_pinocchio()
    kin = robot.kinematics
    data = kin.new_data() if data is None else data
    pin.forwardKinematics(kin.model, data, np.asarray(q, dtype=np.float64))
    out = np.empty((kin.model.njoints, 4, 4))
    for j in range(kin.model.njoints):
        T = data.oMi[j].homogeneous
        T[:3, 3] /= M_PER_MM
        out[j] = robot.T_world_base @ T
    return out


def _size_mm(robot: ArticulatedRobot) -> float:
    """A radius for the motors that scales with the arm (about 70 mm on a UR10e)."""
    segments = arm_segments(robot)
    length = sum(
        float(np.linalg.norm(np.diff(p, axis=0), axis=1).sum())
        for p, kind in zip(segments.points, segments.kind, strict=True)
        if kind == "link"
    )
    return max(0.035 * length, 5.0)


class ArmActors:
    """The arm's actors in a plotter; :meth:`move` poses them at joint positions."""

    def __init__(self, plotter: Any, robot: ArticulatedRobot, q: ArrayLike) -> None:
        pv = _pyvista_module()
        self.robot = robot
        self._data = robot.kinematics.new_data()
        model = robot.kinematics.model
        radius = _size_mm(robot)
        n = model.njoints - 1
        self.segments = arm_segments(robot)
        #: (actor, joint id) pairs: each actor's user matrix is its joint's world pose.
        self.actors: list[tuple[Any, int]] = []
        base = pv.Cylinder(
            center=(0.0, 0.0, -0.6 * radius), direction=(0, 0, 1), radius=1.4 * radius,
            height=1.2 * radius, resolution=32,
        )  # fmt: skip
        self._add(plotter, base, 0, "arm-base", _BASE_COLOR)
        for j in range(1, model.njoints):
            r = radius * (1.0 - 0.45 * (j - 1) / max(n - 1, 1))
            axis = joint_axis(model.joints[j])
            motor = pv.Cylinder(
                center=(0.0, 0.0, 0.0), direction=tuple(axis), radius=r, height=2.2 * r,
                resolution=32,
            )  # fmt: skip
            self._add(plotter, motor, j, f"arm-motor-{j}", _MOTOR_COLOR)
        for k, (j, points, kind) in enumerate(
            zip(self.segments.joint, self.segments.points, self.segments.kind, strict=True)
        ):
            r = radius * (1.0 - 0.45 * (max(j, 1) - 1) / max(n - 1, 1))
            if kind == "torch":
                tube = pv.lines_from_points(points).tube(radius=0.12 * radius, n_sides=16)
                self._add(plotter, tube, j, "arm-torch", _TORCH_COLOR)
                flange = pv.Cylinder(
                    center=tuple(points[0]), direction=tuple(points[1] - points[0]),
                    radius=0.7 * r, height=0.25 * r, resolution=32,
                )  # fmt: skip
                self._add(plotter, flange, j, "arm-flange", _FLANGE_COLOR)
            else:
                tube = pv.lines_from_points(points).tube(radius=0.7 * r, n_sides=24, capping=True)
                self._add(plotter, tube, j, f"arm-link-{k}", _LINK_COLOR)
        self.move(q)

    def _add(self, plotter: Any, mesh: Any, joint: int, name: str, color: str) -> None:
        actor = plotter.add_mesh(mesh, color=color, name=name, smooth_shading=True)
        self.actors.append((actor, joint))

    def move(self, q: ArrayLike) -> FloatArray:
        """Pose the arm at joint positions q (rad); returns the joints' world poses."""
        poses = joint_poses_world(self.robot, q, self._data)
        for actor, joint in self.actors:
            actor.user_matrix = poses[joint]
        return poses


def _pyvista_module() -> Any:
    try:
        import pyvista as pv
    except ImportError as exc:
        raise ImportError("seamtrack's 3D views need PyVista: pip install pyvista") from exc
    return pv
