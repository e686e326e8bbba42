"""A 6-axis articulated arm that carries the torch and the sensor, and turns them.

Every control tick (:meth:`ArticulatedRobot.step`), as an arm controller does:

1. **Position set-point**: the move is interpolated in Cartesian space by the same law as the
   paper's gantry (:class:`~seamtrack.control.robot.CartesianRobot`, without end stops): a path
   speed capped by Cartesian velocity limits per base axis, changed at most by the
   acceleration limits, and a velocity feed-forward.
2. **Orientation set-point**: the commanded tool rotation is a goal that turns on at the
   command's angular velocity (the feed-forward: a robot program that keeps turning the tool
   along a saddle or a girth) until the next command; the set-point turns at that rate plus a
   correction proportional to its rotation error (braking in time so as not to overshoot),
   capped by an angular speed and acceleration.
3. **Inverse kinematics** of the set-point pose (damped least squares from the last joint
   set-point: one or two Newton steps at 1 kHz, since the pose moves microns per tick).
4. **Joint limits** on the joint set-point: its velocity is scaled down (as a whole, keeping the
   path) to every joint's velocity limit and its change to every acceleration limit; positions
   are clamped to the joint ranges. A tick on which a limit acted is counted; the torch then
   falls behind its set-point, which the error shows.
5. **Servo** (optional, :mod:`seamtrack.control.servo`): each joint follows its set-point with
   a position-loop gain K_v; off, the joints are at their set-point.
6. **Forward kinematics** of the joints give the torch pose that the loop measures.

Before the run, :meth:`ArticulatedRobot.plan` walks the whole nominal seam with its tool
orientations (:class:`~seamtrack.control.orientation.ToolProgram`) by inverse kinematics and
refuses a seam with a point out of reach, out of a joint's range or at a wrist singularity,
naming the first such point, why, and the fix.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.linalg.lapack import dposv as _dposv

from seamtrack.control.kinematics import M_PER_MM, ArmKinematics, _pinocchio
from seamtrack.control.robot import CartesianRobot, MoveCommand, RobotState
from seamtrack.control.servo import Servo, ServoState
from seamtrack.errors import ReachError
from seamtrack.geometry import frames

FloatArray = NDArray[np.float64]

#: Travel of the Cartesian interpolator (mm): an arm's reach is limited by its joints instead.
_NO_END_STOP_MM = 1e7

#: Proportional gain (1/s) of the orientation set-point towards the commanded rotation.
ORIENTATION_GAIN_1_S = 20.0

#: Damping (m, rad) of the per-tick inverse kinematics: a Newton step where the arm is far from
#: a singularity (smallest singular value ~0.1-0.3), a bounded one near it.
TICK_DAMPING = 1e-3
_DAMPING2 = TICK_DAMPING**2 * np.eye(6)

#: A tick's pose error (m, rad) below which one Newton step is enough: its residual is of the
#: order of the error squared, plus the damping's share (TICK_DAMPING / sigma_min)^2 of it,
#: below 1e-5 mm; a larger error (a limit acted, or the start) gets up to two more steps.
ONE_STEP_ERROR = 1e-4


@dataclass(frozen=True)
class ArmMove(MoveCommand):
    """A :class:`MoveCommand` with the orientation's feed-forward.

    Attributes
    ----------
    angular_velocity : (3,) float or None
        Rate (rad/s, base axes) at which the goal ``rotation`` turns on until the next
        command's rotation.
    """

    angular_velocity: FloatArray | None = None


@dataclass
class ArmState:
    """The arm's moving state (the loop owns it).

    ``q`` and ``v`` are the torch tip's position and velocity in the base frame, as the
    gantry's axis positions are (the loop reads them the same way); ``joints`` are the joint
    positions (rad).
    """

    q: list[float]
    v: list[float]
    R: FloatArray
    joints: FloatArray
    setpoint: RobotState
    R_set: FloatArray
    omega: FloatArray
    q_ref: FloatArray
    qd_ref: FloatArray
    servo: ServoState | None
    data: Any
    R_goal: FloatArray = field(default_factory=lambda: np.eye(3))
    goal_from: FloatArray | None = None
    tcp_at_q_ref: tuple[FloatArray, FloatArray] | None = None  # (T_base_tcp in m, J) at q_ref
    limited_ticks: int = 0
    clamped_ticks: int = 0
    worst_ik_mm: float = 0.0


@dataclass(frozen=True, eq=False)
class ArticulatedRobot:
    """A serial arm with a torch (``T_flange_tcp`` in its kinematics) and a sensor.

    Parameters
    ----------
    kinematics : ArmKinematics
    control_period_s : float
    T_world_base : (4, 4) float
    T_tcp_sensor : (4, 4) float
    velocity_max_mm_s, acceleration_max_mm_s2 : (3,) float
        Cartesian limits of the torch's position set-point, per base axis.
    angular_velocity_max_rad_s, angular_acceleration_max_rad_s2 : float
        Limits of the tool's orientation set-point.
    servo : Servo or None
        Joint position loops (None: ideal joints).
    min_wrist_angle_rad : float
        The plan refuses a seam where the axes of joints 4 and 6 come closer than this.
    """

    kinematics: ArmKinematics
    control_period_s: float = 1e-3
    T_world_base: FloatArray = field(default_factory=lambda: np.eye(4))
    T_tcp_sensor: FloatArray = field(default_factory=lambda: np.eye(4))
    velocity_max_mm_s: tuple[float, float, float] = (250.0, 250.0, 250.0)
    acceleration_max_mm_s2: tuple[float, float, float] = (500.0, 500.0, 500.0)
    angular_velocity_max_rad_s: float = 1.0
    angular_acceleration_max_rad_s2: float = 1.0
    servo: Servo | None = None
    min_wrist_angle_rad: float = math.radians(5.0)
    turns_tool = True
    _cart: CartesianRobot = field(init=False, repr=False)
    _T_base_world: FloatArray = field(init=False, repr=False)
    _reach_mm: float = field(init=False, repr=False)
    #: The last orientation command converted to the base frame: (world rotation, world
    #: angular velocity, base rotation, base angular velocity). A tracker hands the same
    #: rotation for many ticks; converting it once keeps one object, which the tick then
    #: recognises by identity.
    _last_turn: list[Any] = field(init=False, repr=False, compare=False)
    _inv_velocity_max: FloatArray = field(init=False, repr=False)
    _inv_acceleration_max_dt: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "T_world_base", np.asarray(self.T_world_base, dtype=float))
        object.__setattr__(self, "T_tcp_sensor", np.asarray(self.T_tcp_sensor, dtype=float))
        object.__setattr__(self, "_T_base_world", frames.invert(self.T_world_base))
        cart = CartesianRobot(
            position_min_mm=(-_NO_END_STOP_MM,) * 3,
            position_max_mm=(_NO_END_STOP_MM,) * 3,
            velocity_max_mm_s=self.velocity_max_mm_s,
            acceleration_max_mm_s2=self.acceleration_max_mm_s2,
            control_period_s=self.control_period_s,
        )
        object.__setattr__(self, "_cart", cart)
        model = self.kinematics.model
        links = sum(float(np.linalg.norm(p.translation)) for p in model.jointPlacements)
        links += sum(float(np.linalg.norm(f.placement.translation)) for f in model.frames)
        tool = float(np.linalg.norm(self.kinematics.T_flange_tcp[:3, 3]))
        object.__setattr__(self, "_reach_mm", links / M_PER_MM + tool)
        object.__setattr__(self, "_last_turn", [None, None, None, None])
        kin = self.kinematics
        object.__setattr__(self, "_inv_velocity_max", 1.0 / kin.velocity_max_rad_s)
        accel_dt = kin.acceleration_max_rad_s2 * self.control_period_s
        object.__setattr__(self, "_inv_acceleration_max_dt", 1.0 / accel_dt)

    # ----------------------------------------------------------------- poses
    def T_world_tcp_of(self, state: ArmState) -> FloatArray:
        return self.T_world_base @ frames.make(state.R, state.q)

    def sensor_pose(self, state: ArmState) -> FloatArray:
        """``T_world_sensor`` of the measured (actual) joint positions."""
        return self.T_world_tcp_of(state) @ self.T_tcp_sensor

    def torch_axis_base(self, state: ArmState) -> FloatArray:
        return state.R[:, 2]

    def T_world_sensor(self, q: ArrayLike) -> FloatArray:
        """``T_world_base @ T_base_tcp(q) @ T_tcp_sensor`` for joint positions q (rad): the
        same call as :meth:`CartesianRobot.T_world_sensor <seamtrack.control.robot.
        CartesianRobot.T_world_sensor>` on axis positions."""
        return self.T_world_base @ self.kinematics.fk(q) @ self.T_tcp_sensor

    def joints_for_tool(
        self,
        T_world_tcp: ArrayLike,
        seed: ArrayLike | None = None,
        what: str = "tool pose",
        field_name: str = "seam",
    ) -> FloatArray:
        """(n,) joint positions (rad) that put the tool at the pose ``T_world_tcp`` (world,
        mm): inverse kinematics from ``seed`` (default: the home configuration), with the
        plan's checks (a :class:`ReachError` naming ``field_name`` where the pose is out of
        reach, out of a joint's range or at a wrist singularity). ``T_world_sensor`` of the
        result is the sensor pose at that tool placement, as on the gantry."""
        T = np.asarray(T_world_tcp, dtype=np.float64)[None]
        return self.plan(T, what, field_name, start=seed)[0]

    def within_travel(self, target: tuple[float, float, float]) -> bool:
        """Cheap reach bound for the loop's commanded targets (base frame, mm)."""
        return math.sqrt(sum(x * x for x in target)) <= self._reach_mm

    def command_in_base(
        self,
        target_world: ArrayLike,
        speed_mm_s: float,
        velocity_ff_world: ArrayLike | None = None,
        stop_at_target: bool = False,
        rotation_world: ArrayLike | None = None,
        angular_velocity_world: ArrayLike | None = None,
    ) -> MoveCommand:
        T = self._T_base_world
        R = T[:3, :3]
        q = (R @ np.asarray(target_world, dtype=float) + T[:3, 3]).tolist()
        ff = (0.0, 0.0, 0.0)
        if velocity_ff_world is not None:
            ffv = (R @ np.asarray(velocity_ff_world, dtype=float)).tolist()
            ff = (ffv[0], ffv[1], ffv[2])
        rotation = omega = None
        if rotation_world is not None:
            last = self._last_turn
            if rotation_world is last[0] and angular_velocity_world is last[1]:
                rotation, omega = last[2], last[3]
            else:
                rotation = R @ np.asarray(rotation_world, dtype=float)
                if angular_velocity_world is not None:
                    omega = R @ np.asarray(angular_velocity_world, dtype=float)
                last[:] = [rotation_world, angular_velocity_world, rotation, omega]
        return ArmMove(
            (float(q[0]), float(q[1]), float(q[2])),
            float(speed_mm_s),
            ff,
            bool(stop_at_target),
            rotation,
            omega,
        )

    # ----------------------------------------------------------------- state
    def state_at_joints(self, joints: ArrayLike) -> ArmState:
        """At rest at joint positions (rad)."""
        q = np.array(joints, dtype=np.float64)
        data = self.kinematics.new_data()
        T = self.kinematics.fk(q, data)
        p = [float(x) for x in T[:3, 3]]
        servo = self.servo.new_state(q.tolist()) if self.servo is not None else None
        return ArmState(
            q=p,
            v=[0.0, 0.0, 0.0],
            R=T[:3, :3].copy(),
            joints=q.copy(),
            setpoint=RobotState(q=list(p), v=[0.0, 0.0, 0.0]),
            R_set=T[:3, :3].copy(),
            omega=np.zeros(3),
            q_ref=q.copy(),
            qd_ref=np.zeros(len(q)),
            servo=servo,
            data=data,
        )

    # ----------------------------------------------------------------- control tick
    def step(self, state: ArmState, command: MoveCommand | None) -> None:
        """Advance ``state`` by one control period (None: brake to rest, keep orientation)."""
        pin = _pinocchio()
        kin = self.kinematics
        dt = self.control_period_s
        self._cart.step(state.setpoint, command)
        # Orientation set-point.
        omega = state.omega
        if command is not None and command.rotation is not None:
            ff = getattr(command, "angular_velocity", None)
            rotation = command.rotation
            # The same goal as the last tick's (command_in_base converts a rotation once, so
            # it is the same object, or failing that equal): it turns on at the feed-forward.
            if rotation is state.goal_from or (
                state.goal_from is not None and np.array_equal(rotation, state.goal_from)
            ):
                if ff is not None:
                    state.R_goal = pin.exp3(ff * dt) @ state.R_goal
            else:
                state.goal_from = rotation
                state.R_goal = rotation
            err = pin.log3(state.R_goal @ state.R_set.T)
            size = math.sqrt(err @ err)
            # Proportional, capped by the speed from which braking at the angular
            # acceleration limit stops on the goal (no overshoot), on top of the goal's own
            # turning; all capped by the angular speed.
            speed = min(
                ORIENTATION_GAIN_1_S * size,
                math.sqrt(2.0 * self.angular_acceleration_max_rad_s2 * size),
            )
            want = err * (speed / size) if size > 0.0 else np.zeros(3)
            if ff is not None:
                want = want + ff
            norm = math.sqrt(want @ want)
            if norm > self.angular_velocity_max_rad_s:
                want *= self.angular_velocity_max_rad_s / norm
        else:
            want = np.zeros(3)
        dw = want - omega
        norm = math.sqrt(dw @ dw)
        dw_max = self.angular_acceleration_max_rad_s2 * dt
        if norm > dw_max:
            dw *= dw_max / norm
        omega += dw
        if omega.any():
            state.R_set = pin.exp3(omega * dt) @ state.R_set
        # Inverse kinematics from the last joint set-point, whose pose and Jacobian the last
        # tick left (without a servo the joints are at their set-point). One Newton step
        # follows a pose that moved microns since the last tick (ONE_STEP_ERROR).
        p_set = np.array(state.setpoint.q) * M_PER_MM
        q = state.q_ref
        data = state.data
        known = state.tcp_at_q_ref
        e = np.empty(6)
        for _ in range(3):
            T, J = known if known is not None else kin.tcp_jacobian_m(q, data)
            known = None
            e[:3] = p_set - T[:3, 3]
            e[3:] = pin.log3(state.R_set @ T[:3, :3].T)
            A = J @ J.T + _DAMPING2
            y, info = _spd_solve(A, e)
            if info != 0:  # not positive definite: a NaN in the pose; let numpy say so
                y = np.asarray(np.linalg.solve(A, e), dtype=np.float64)
            q = q + J.T @ y
            if abs(e).max() < ONE_STEP_ERROR:
                break
        # Joint limits on the set-point's motion.
        qd = (q - state.q_ref) / dt
        limited = False
        over = float((np.abs(qd) * self._inv_velocity_max).max())
        if over > 1.0:
            qd /= over
            limited = True
        dqd = qd - state.qd_ref
        over = float((np.abs(dqd) * self._inv_acceleration_max_dt).max())
        if over > 1.0:
            qd = state.qd_ref + dqd / over
            limited = True
        q_ref = state.q_ref + qd * dt
        if (q_ref < kin.lower_rad).any() or (q_ref > kin.upper_rad).any():
            clamped = np.clip(q_ref, kin.lower_rad, kin.upper_rad)
            state.clamped_ticks += 1
            qd = (clamped - state.q_ref) / dt
            q_ref = clamped
        state.limited_ticks += limited
        state.q_ref = q_ref
        state.qd_ref = qd
        # Servo, then the measured pose.
        if state.servo is not None and self.servo is not None:
            self.servo.follow(state.servo, q_ref.tolist())
            joints = np.clip(np.array(state.servo.q), kin.lower_rad, kin.upper_rad)
        else:
            joints = q_ref
        state.joints = joints
        T, J = kin.tcp_jacobian_m(joints, data)
        state.tcp_at_q_ref = (T, J) if joints is q_ref else None
        old = state.q
        new = (T[:3, 3] / M_PER_MM).tolist()
        state.v = [(new[i] - old[i]) / dt for i in range(3)]
        state.q = new
        state.R = T[:3, :3]

    # ----------------------------------------------------------------- plan
    def plan(
        self,
        T_world_tcp: FloatArray,
        what: str,
        field_name: str,
        start: ArrayLike | None = None,
    ) -> FloatArray:
        """Joint positions along a sequence of tool poses, or a refusal naming the first pose
        that cannot be reached.

        The first pose is solved from ``start`` (default: the arm's home configuration), each
        later one from the previous solution (so the path stays on one branch, as a robot
        program's would).

        Parameters
        ----------
        T_world_tcp : (m, 4, 4) float
            Tool poses, world frame, mm; in order along the seam (at most ~1 mm apart).
        what : str
            What the poses are, for the error ("seam point").
        field_name : str
            The scene field to name.

        Returns
        -------
        joints : (m, n) float

        Raises
        ------
        ReachError
        """
        kin = self.kinematics
        data = kin.new_data()
        out = np.empty((len(T_world_tcp), kin.dof))
        q = kin.home_rad.copy() if start is None else np.array(start, dtype=np.float64)
        for i, T_world in enumerate(T_world_tcp):
            T = self._T_base_world @ T_world
            result = kin.ik(T, q, data, max_iterations=200 if i == 0 else 50)
            where = f"{what} {i} at world {np.round(T_world[:3, 3], 3).tolist()} mm"
            if not result:
                distance = float(np.linalg.norm(T[:3, 3]))
                raise ReachError(
                    f"{where}: the {kin.name} cannot put its torch there with the planned "
                    f"orientation (no joint solution; closest {result.error_mm:.3g} mm, "
                    f"{math.degrees(result.error_rad):.3g} deg away; {distance:.0f} mm from "
                    "the base)",
                    field=field_name,
                    fix="move the part (workpiece.offset_mm / seam.offset_mm) or the robot "
                    "base (robot.base_origin_mm) so the seam lies well inside the arm's reach",
                )
            q = _wrap_into_range(result.q, kin.lower_rad, kin.upper_rad)
            low = q < kin.lower_rad - 1e-9
            high = q > kin.upper_rad + 1e-9
            if low.any() or high.any():
                j = int(np.flatnonzero(low | high)[0])
                raise ReachError(
                    f"{where}: needs joint {j + 1} at {math.degrees(q[j]):.1f} deg, outside "
                    f"its range {math.degrees(kin.lower_rad[j]):.1f}.."
                    f"{math.degrees(kin.upper_rad[j]):.1f} deg",
                    field=field_name,
                    fix="turn or move the part or the robot base (robot.base_rotation_deg, "
                    "robot.base_origin_mm) so the tool need not turn as far",
                )
            wrist = kin.wrist_angle(q, data)
            if wrist < self.min_wrist_angle_rad:
                raise ReachError(
                    f"{where}: the wrist is singular there (the axes of joints 4 and 6 are "
                    f"{math.degrees(wrist):.2f} deg apart, below "
                    f"{math.degrees(self.min_wrist_angle_rad):.1f} deg): the arm would have to "
                    "spin its wrist",
                    field=field_name,
                    fix="tilt the torch (torch.travel_angle_deg / torch.work_angle_deg), or "
                    "move the part or the robot base so the wrist stays bent",
                )
            out[i] = q
        return out


def _spd_solve(A: FloatArray, b: FloatArray) -> tuple[FloatArray, int]:
    """x with A x = b for a symmetric positive definite A (LAPACK's Cholesky ``dposv``: a
    third of ``numpy.linalg.solve``'s call overhead on a 6 x 6 system), and LAPACK's info
    (0: solved)."""
    _, x, info = _dposv(A, b)
    return x, int(info)


def _wrap_into_range(q: FloatArray, lower: FloatArray, upper: FloatArray) -> FloatArray:
    """The same pose with each joint moved by whole turns into its range where that helps (a
    revolute joint at q and at q +- 2 pi puts the arm in the same place)."""
    out = q.copy()
    turn = 2.0 * math.pi
    for j in range(len(out)):
        while out[j] > upper[j] + 1e-9 and out[j] - turn >= lower[j] - 1e-9:
            out[j] -= turn
        while out[j] < lower[j] - 1e-9 and out[j] + turn <= upper[j] + 1e-9:
            out[j] += turn
    return out
