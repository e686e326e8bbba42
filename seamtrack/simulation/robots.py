"""The scene's robot: the paper's Cartesian gantry or an articulated arm, the tool and the sensor
mount, the servo, and (for an arm) the plan that proves the seam reachable before the run.

Scene keys: ``robot.model`` (``"cartesian"`` or a name of
:data:`~seamtrack.control.kinematics.ARM_MODELS`), ``robot.urdf`` (any serial arm),
``robot.servo_gain_1_s`` (K_v; absent: ideal axes), ``robot.interpolation_period_s``,
``[robot.tool]`` (``T_flange_tcp``, optionally ``T_tcp_sensor``) and ``[torch]`` (work and
travel angles).
"""

from __future__ import annotations

import dataclasses
import difflib
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.control.orientation import ToolProgram
from seamtrack.control.robot import CartesianRobot
from seamtrack.control.servo import MAX_GAIN_PERIOD, Servo
from seamtrack.errors import ReachError, SceneError
from seamtrack.geometry import frames
from seamtrack.geometry.seam import Seam
from seamtrack.sensing.sensor import LaserLineSensor
from seamtrack.simulation.config import Scene, SceneConfig
from seamtrack.simulation.mount import Mount, angles_mount, seam_mount

FloatArray = NDArray[np.float64]

#: The plan checks a pose at least every this many mm along the seam.
PLAN_STEP_MM = 1.0


def is_arm(c: SceneConfig) -> bool:
    """True when the scene's robot is an articulated arm (a named model or a URDF)."""
    return c.robot.urdf is not None or c.robot.model != "cartesian"


def check_robot(c: SceneConfig) -> None:
    """The robot keys that the schema alone cannot check (before anything is built)."""
    r = c.robot
    if r.urdf is not None and r.model != "cartesian":
        raise SceneError(
            f"both robot.model = {r.model!r} and robot.urdf are given",
            field="robot.urdf",
            fix="give one of them",
        )
    if r.urdf is None and r.model != "cartesian":
        from seamtrack.control.kinematics import ARM_MODELS

        if r.model not in ARM_MODELS:
            close = difflib.get_close_matches(r.model, ["cartesian", *ARM_MODELS], n=1)
            hint = f"did you mean {close[0]!r}? " if close else ""
            raise SceneError(
                f"unknown robot model {r.model!r}",
                field="robot.model",
                fix=f"{hint}use one of cartesian, {', '.join(ARM_MODELS)}, or "
                'robot.urdf = "my_arm.urdf"',
            )
    if r.servo_gain_1_s is not None:
        gains = r.servo_gain_1_s if isinstance(r.servo_gain_1_s, list) else [r.servo_gain_1_s]
        worst = max(gains) * r.control_period_s
        if worst > MAX_GAIN_PERIOD:
            raise SceneError(
                f"K_v = {max(gains):g} 1/s at a control period of {r.control_period_s:g} s "
                f"gives K_v dt = {worst:.3g}: the discrete position loop would ring",
                field="robot.servo_gain_1_s",
                fix=f"use K_v <= {MAX_GAIN_PERIOD / r.control_period_s:.4g} 1/s, or a shorter "
                "robot.control_period_s",
            )
    if r.interpolation_period_s is not None and r.interpolation_period_s < r.control_period_s:
        raise SceneError(
            f"interpolation period {r.interpolation_period_s:g} s is shorter than the control "
            f"period {r.control_period_s:g} s",
            field="robot.interpolation_period_s",
            fix="use a whole multiple of robot.control_period_s",
        )


def sensor_mount(
    scene: Scene,
    sensor: LaserLineSensor,
    seam: Seam | None = None,
    caster: Any = None,
    view: FloatArray | None = None,
) -> Mount:
    """Where the sensor sits on the torch (``T_tcp_sensor``), and why.

    - Given in ``[robot.tool]`` (``sensor_xyz_mm``, ``sensor_rpy_deg``): as given.
    - ``sensor.mount_rotation_deg`` set, an arm, or no workpiece ``seam``: the paper scenes'
      mount: the laser points down the torch (z_L = -z_tcp) with its baseline along the
      look-ahead direction (x_L = +x_tcp), turned by those x-y-z angles in the laser frame. An
      arm turns its tool with the seam, so this mount keeps crossing it.
    - Otherwise, on a 3-axis robot with the workpiece ``seam`` (world frame): from the seam's
      torch frame (:func:`seamtrack.simulation.mount.seam_mount`; ``view``: a direction to look
      from instead of the torch's), the line of sight checked against the ``caster``'s part.

    The emitter sits on the laser axis ``range_mm`` (default: where the optical axis crosses the
    laser, b / tan theta_s) from the point ``look_ahead_mm`` ahead of the torch tip, so the
    central ray hits a seam at the torch tip's height there whatever the tilt.
    """
    c = scene.config
    s, tool = c.sensor, c.robot.tool
    if tool.sensor_xyz_mm is not None or tool.sensor_rpy_deg is not None:
        T = frames.from_xyz_rpy_deg(
            tool.sensor_xyz_mm or (0.0, 0.0, 0.0), tool.sensor_rpy_deg or (0.0, 0.0, 0.0)
        )
        return Mount(T)
    distance = s.range_mm if s.range_mm is not None else sensor.range_center_mm
    if s.mount_rotation_deg is not None or seam is None or is_arm(c):
        return angles_mount(s.mount_rotation_deg or (0.0, 0.0, 0.0), s.look_ahead_mm, distance)
    half_fan = math.atan(0.25 * (sensor.fov_near_mm + sensor.fov_far_mm) / distance)
    world = seam_mount(seam, s.look_ahead_mm, distance, sensor.baseline_mm, half_fan, caster, view)
    r = c.robot
    R_base_world = frames.from_xyz_rpy_deg(r.base_origin_mm, r.base_rotation_deg)[:3, :3].T
    T = world.T_tcp_sensor.copy()  # a gantry's TCP frame has the base's axes
    T[:3, :3] = R_base_world @ world.T_tcp_sensor[:3, :3]
    T[:3, 3] = R_base_world @ world.T_tcp_sensor[:3, 3]
    return dataclasses.replace(world, T_tcp_sensor=T)


def make_robot(scene: Scene, sensor: LaserLineSensor, mount: Mount | None = None) -> Any:
    """The scene's robot (a :class:`CartesianRobot` or an
    :class:`~seamtrack.control.arm.ArticulatedRobot`) with its tool, sensor (``mount``, default
    :func:`sensor_mount` without a seam) and servo."""
    c = scene.config
    r = c.robot
    T_world_base = frames.from_xyz_rpy_deg(r.base_origin_mm, r.base_rotation_deg)
    T_tcp_sensor = (mount if mount is not None else sensor_mount(scene, sensor)).T_tcp_sensor
    ipo = r.interpolation_period_s if r.interpolation_period_s is not None else r.control_period_s
    gains = r.servo_gain_1_s
    gain_list = None if gains is None else (gains if isinstance(gains, list) else [gains])
    if not is_arm(c):
        servo = None
        if gain_list is not None:
            servo = Servo(
                tuple(gain_list), ipo, r.control_period_s, r.velocity_max_mm_s,
                r.acceleration_max_mm_s2,
            )  # fmt: skip
        return CartesianRobot(
            position_min_mm=r.position_min_mm,
            position_max_mm=r.position_max_mm,
            velocity_max_mm_s=r.velocity_max_mm_s,
            acceleration_max_mm_s2=r.acceleration_max_mm_s2,
            control_period_s=r.control_period_s,
            T_world_base=T_world_base,
            T_tcp_sensor=T_tcp_sensor,
            servo=servo,
        )
    from seamtrack.control.arm import ArticulatedRobot
    from seamtrack.control.kinematics import ArmKinematics

    T_flange_tcp = frames.from_xyz_rpy_deg(r.tool.tcp_xyz_mm, r.tool.tcp_rpy_deg)
    if r.urdf is not None:
        kin = ArmKinematics.from_urdf(scene.resolve_path(r.urdf), T_flange_tcp)
    else:
        kin = ArmKinematics.named(r.model, T_flange_tcp)
    if r.joint_acceleration_max_deg_s2 is not None:
        accels = r.joint_acceleration_max_deg_s2
        accel_list = accels if isinstance(accels, list) else [accels]
        if len(accel_list) not in (1, kin.dof):
            raise SceneError(
                f"{len(accel_list)} accelerations for an arm of {kin.dof} joints",
                field="robot.joint_acceleration_max_deg_s2",
                fix=f"give one value (deg/s^2, for every joint), or {kin.dof} (one per joint)",
            )
        accel = np.radians(np.broadcast_to(np.array(accel_list, dtype=float), (kin.dof,)))
        kin = dataclasses.replace(kin, acceleration_max_rad_s2=np.array(accel, dtype=float))
    servo = None
    if gain_list is not None:
        if len(gain_list) not in (1, kin.dof):
            raise SceneError(
                f"{len(gain_list)} gains for an arm of {kin.dof} joints",
                field="robot.servo_gain_1_s",
                fix=f"give one K_v, or {kin.dof} (one per joint)",
            )
        servo = Servo(
            tuple(gain_list), ipo, r.control_period_s, tuple(kin.velocity_max_rad_s.tolist()),
            tuple(kin.acceleration_max_rad_s2.tolist()),
        )  # fmt: skip
    return ArticulatedRobot(
        kinematics=kin,
        control_period_s=r.control_period_s,
        T_world_base=T_world_base,
        T_tcp_sensor=T_tcp_sensor,
        velocity_max_mm_s=r.tcp_velocity_max_mm_s,
        acceleration_max_mm_s2=r.tcp_acceleration_max_mm_s2,
        angular_velocity_max_rad_s=math.radians(r.angular_velocity_max_deg_s),
        angular_acceleration_max_rad_s2=math.radians(r.angular_acceleration_max_deg_s2),
        servo=servo,
        min_wrist_angle_rad=math.radians(r.min_wrist_angle_deg),
    )


def tool_program(scene: Scene, seam: Seam) -> ToolProgram:
    """The tool orientations along the scene's nominal seam."""
    c = scene.config
    return ToolProgram(
        seam,
        work_rad=math.radians(c.torch.work_angle_deg),
        travel_rad=math.radians(c.torch.travel_angle_deg),
        look_ahead_mm=c.sensor.look_ahead_mm,
    )


def plan_along(
    robot: Any, program: ToolProgram, end_mm: float | None = None
) -> tuple[FloatArray, FloatArray]:
    """The arm's joint positions along the whole seam (or from its start to the arc length
    ``end_mm``), every :data:`PLAN_STEP_MM` or closer.

    Returns
    -------
    arc_length_mm : (m,) float
    joints : (m, n) float
        rad; a :class:`ReachError` names the first seam point that cannot be reached.
    """
    seam = program.seam
    end = seam.length_mm if end_mm is None else float(end_mm)
    count = max(2, int(math.ceil(end / PLAN_STEP_MM)) + 1)
    s = np.linspace(0.0, end, count)
    points, _, _ = program.frame(s)
    poses = np.tile(np.eye(4), (count, 1, 1))
    poses[:, :3, :3] = program.rotations(s)
    poses[:, :3, 3] = points
    return s, robot.plan(poses, "seam point", "seam")


def plan_arm(robot: Any, program: ToolProgram, start_world: FloatArray) -> FloatArray:
    """Joint positions at the start pose, after proving the whole seam reachable (a
    :class:`ReachError` names the first seam point that is not)."""
    _, joints = plan_along(robot, program)
    rotations = program.rotations([0.0])
    start = np.eye(4)
    start[:3, :3] = rotations[0]
    start[:3, 3] = start_world
    kin = robot.kinematics
    result = kin.ik(robot._T_base_world @ start, joints[0], max_iterations=100)
    if not result or (result.q < kin.lower_rad).any() or (result.q > kin.upper_rad).any():
        raise ReachError(
            f"the start point {np.round(start_world, 3).tolist()} mm is out of the arm's reach",
            field="robot.start_offset_mm",
            fix="start closer to the seam (robot.start_offset_mm)",
        )
    return np.asarray(result.q)


def sensor_pose_at(robot: Any, program: ToolProgram, at_mm: float) -> tuple[FloatArray, FloatArray]:
    """The sensor pose with the torch tip on the seam at arc length ``at_mm``, the tool placed
    as the robot would place it there (what ``seamtrack scan`` and ``render`` look from).

    Either robot answers :meth:`joints_for_tool` and :meth:`T_world_sensor` the same way: the
    gantry keeps its base's orientation; an arm turns the tool as the robot program says
    (``program``) and takes the joints of the run's plan, walked from the seam's start to
    ``at_mm`` (the same branch of the inverse kinematics as the run).

    Returns
    -------
    T_world_sensor : (4, 4) float
    joints : (n,) float
        Axis positions (mm) or joint positions (rad).
    """
    point = program.seam.interpolate([at_mm])[0]
    if robot.turns_tool:
        joints = plan_along(robot, program, at_mm)[1][-1]
    else:
        joints = robot.joints_for_tool(frames.make(robot.T_world_base[:3, :3], point))
    return robot.T_world_sensor(joints), joints


def check_sensor_outside(
    poses_T_world_tcp: FloatArray,
    T_tcp_sensor: FloatArray,
    sensor: LaserLineSensor,
    seam: Seam,
    mesh: Any = None,
    explicit_mount: bool = False,
    turns_tool: bool = True,
) -> None:
    """Refuse a sensor mount that puts the emitter or the camera inside the part.

    With a mesh (mesh mode) the test is the mesh's own inside test; without one (seam mode), a
    mount given in ``[robot.tool]`` must put the emitter and camera on the torch side of the
    seam (positive along its torch normal).
    """
    if mesh is None and not explicit_mount:
        return  # seam mode knows no part surface: only a mount the user set is judged there
    T = poses_T_world_tcp @ T_tcp_sensor
    emitter = T[:, :3, 3]
    camera = emitter + sensor.baseline_mm * T[:, :3, 0]
    points = np.concatenate([emitter, camera])
    inside = np.zeros(len(points), dtype=bool)
    if mesh is not None and getattr(mesh, "is_watertight", False):
        inside = np.asarray(mesh.contains(points), dtype=bool)
    else:
        closest = seam.closest(points)
        seg = closest.segment
        normal = seam.normals[seg]
        inside = np.sum((points - closest.points) * normal, axis=1) < 0.0
    if inside.any():
        i = int(np.flatnonzero(inside)[0])
        which = "emitter" if i < len(emitter) else "camera"
        where = (
            f"the sensor's {which} would be inside the part at "
            f"{np.round(points[i], 3).tolist()} mm (pose {i % len(emitter)} along the seam, "
            f"torch at {np.round(poses_T_world_tcp[i % len(emitter), :3, 3], 3).tolist()} mm)"
        )
        if explicit_mount:
            raise SceneError(
                where,
                field="robot.tool.sensor_xyz_mm",
                fix="mount the sensor above the torch tip on the torch side (z_tcp > 0), laser "
                "pointing down the torch",
            )
        if not turns_tool:
            raise SceneError(
                where + ": the gantry's torch and sensor cannot turn with the seam",
                field="robot.model",
                fix='use an arm that turns its tool (robot.model = "ur10e"), or a seam the '
                "sensor can see from above",
            )
        raise SceneError(
            where,
            field="sensor.look_ahead_mm",
            fix="a shorter look-ahead or range (sensor.range_mm), or another torch angle",
        )
