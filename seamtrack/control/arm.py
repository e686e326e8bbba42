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
3. **Inverse kinematics** of the set-point pose: closed-form where the arm has one (the UR
   family, spherical-wrist arms: :mod:`seamtrack.control.closed_form`), the branch nearest the
   last joint set-point; otherwise damped least squares from the last joint set-point (one or
   two Newton steps at 1 kHz, since the pose moves microns per tick).
4. **Joint limits** on the joint set-point: its velocity is scaled down (as a whole, keeping the
   path) to every joint's velocity limit and its change to every acceleration limit; positions
   are clamped to the joint ranges. A tick on which a limit acted is counted; the torch then
   falls behind its set-point, which the error shows.
5. **Servo** (optional, :mod:`seamtrack.control.servo`): each joint follows its set-point with
   a position-loop gain K_v; off, the joints are at their set-point.
6. **Forward kinematics** of the joints give the torch pose that the loop measures.

The whole tick is one compiled call (:func:`seamtrack.control.arm_kernels.arm_step`) on the
arrays of an :class:`ArmState`.

Before the run, :meth:`ArticulatedRobot.plan` walks the whole nominal seam with its tool
orientations (:class:`~seamtrack.control.orientation.ToolProgram`) by inverse kinematics and
refuses a seam with a point out of reach, out of a joint's range or at a wrist singularity,
naming the first such point, why, and the fix.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.control import arm_kernels as ak
from seamtrack.control.closed_form import KIND_NONE
from seamtrack.control.kinematics import M_PER_MM, ArmKinematics
from seamtrack.control.robot import CartesianRobot, MoveCommand, RobotState
from seamtrack.control.servo import Servo
from seamtrack.errors import ReachError
from seamtrack.geometry import frames

FloatArray = NDArray[np.float64]

#: Travel of the Cartesian interpolator (mm): an arm's reach is limited by its joints instead.
_NO_END_STOP_MM = 1e7
_EYE4 = np.eye(4)  # the identity pose, copied (np.eye costs more)

#: Proportional gain (1/s) of the orientation set-point towards the commanded rotation.
ORIENTATION_GAIN_1_S = 20.0

#: Damping (m, rad) of the per-tick Newton steps (arms without a closed form): a Newton step
#: where the arm is far from a singularity (smallest singular value ~0.1-0.3), a bounded one
#: near it.
TICK_DAMPING = ak.TICK_DAMPING

#: A tick's pose error (m, rad) below which one Newton step is enough (see
#: :data:`seamtrack.control.arm_kernels.ONE_STEP_ERROR`).
ONE_STEP_ERROR = ak.ONE_STEP_ERROR


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


class ArmState:
    """The arm's moving state (the loop owns it), in the arrays the compiled tick
    (:func:`~seamtrack.control.arm_kernels.arm_step`) works on.

    ``q`` and ``v`` are the torch tip's position and velocity in the base frame, as the
    gantry's axis positions are (the loop reads them the same way); ``R`` the tool's rotation;
    ``joints`` the measured joint positions (rad); ``q_ref``, ``qd_ref`` the joint set-point
    and its velocity; ``R_set``, ``omega`` the orientation set-point and its angular velocity.
    """

    def __init__(self, joints: FloatArray, T_base_tcp: FloatArray, servo: bool) -> None:
        n = len(joints)
        p, R = T_base_tcp[:3, 3], T_base_tcp[:3, :3]
        self.cart = np.zeros((4, 3))  # rows: set-point q, v (mm), torch tip q, v
        self.cart[ak.C_SQ] = self.cart[ak.C_Q] = p
        self.rot = np.stack([R, np.eye(3), R])  # set-point, goal, measured
        self.omega = np.zeros(3)
        self.jnt = np.zeros((6, n))  # rows: set-point, its velocity, joints, servo q, v, held
        for row in (ak.S_REF, ak.S_JOINTS, ak.S_SQ, ak.S_HELD):
            self.jnt[row] = joints
        self.cnt = np.zeros(4, dtype=np.int64)  # limited, clamped, servo tick, ipo ticks
        self.cmd = np.zeros(ak.CMD_FIELDS)
        self.work = np.empty(ak.work_size(n))  # the compiled tick's scratch
        #: The arrays above, as the compiled tick takes them (the same objects).
        self.data = ak.ArmData(
            self.cart, self.rot, self.omega, self.jnt, self.cnt, self.cmd, self.work
        )
        #: The last goal rotation handed in (a tracker hands the same object for many ticks).
        self.goal_from: Any = None
        self.servo = servo

    @property
    def q(self) -> list[float]:
        return self.cart[ak.C_Q].tolist()

    @property
    def v(self) -> list[float]:
        return self.cart[ak.C_V].tolist()

    @property
    def R(self) -> FloatArray:
        return self.rot[2].copy()

    @property
    def R_set(self) -> FloatArray:
        return self.rot[0].copy()

    @property
    def joints(self) -> FloatArray:
        return self.jnt[ak.S_JOINTS].copy()

    @property
    def q_ref(self) -> FloatArray:
        return self.jnt[ak.S_REF].copy()

    @property
    def qd_ref(self) -> FloatArray:
        return self.jnt[ak.S_QD].copy()

    @property
    def setpoint(self) -> RobotState:
        """The Cartesian position set-point and its velocity (mm, base), a copy."""
        return RobotState(q=self.cart[ak.C_SQ].tolist(), v=self.cart[ak.C_SV].tolist())

    @property
    def limited_ticks(self) -> int:
        return int(self.cnt[ak.K_LIMITED])

    @property
    def clamped_ticks(self) -> int:
        return int(self.cnt[ak.K_CLAMPED])


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
    #: The compiled tick's tables (:func:`~seamtrack.control.arm_kernels.arm_step`):
    #: parameters, joint limits, servo table.
    _par: FloatArray = field(init=False, repr=False)
    _jl: FloatArray = field(init=False, repr=False)
    _servo_table: FloatArray = field(init=False, repr=False)
    #: The tables above and the chain, as the compiled tick takes them.
    _model: ak.ArmModel = field(init=False, repr=False)

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
        dt = self.control_period_s
        par = np.zeros(ak.PAR_FIELDS)
        par[ak.P_DT], par[ak.P_W_MAX] = dt, self.angular_velocity_max_rad_s
        par[ak.P_DW_MAX] = self.angular_acceleration_max_rad_s2 * dt
        par[ak.P_A_MAX] = self.angular_acceleration_max_rad_s2
        par[ak.P_GAIN], par[ak.P_SOLVER] = ORIENTATION_GAIN_1_S, kin.solver
        jl = np.array(
            [kin.lower_rad, kin.upper_rad, 1.0 / kin.velocity_max_rad_s,
             1.0 / (kin.acceleration_max_rad_s2 * dt)], dtype=np.float64,
        )  # fmt: skip
        table = self.servo._table if self.servo is not None else np.zeros((3, kin.dof))
        object.__setattr__(self, "_par", par)
        object.__setattr__(self, "_jl", jl)
        object.__setattr__(self, "_servo_table", table)
        object.__setattr__(
            self, "_model",
            ak.ArmModel(par, cart._limits, jl, table, kin.geometry, *kin.chain),
        )  # fmt: skip

    def with_iterative_ik(self) -> ArticulatedRobot:
        """The same arm with the tick's inverse kinematics by Newton steps only (as before the
        closed forms: one or two damped least-squares steps from the last set-point): the
        reference that the closed form's runs are held to (``seamtrack bench loop``)."""
        robot = dataclasses.replace(self)
        robot._par[ak.P_SOLVER] = KIND_NONE
        return robot

    # ----------------------------------------------------------------- poses
    def T_world_tcp_of(self, state: ArmState) -> FloatArray:
        T = _EYE4.copy()  # frames.make(state.R, state.q), from the state's arrays (every frame)
        T[:3, :3] = state.rot[2]
        T[:3, 3] = state.cart[ak.C_Q]
        return self.T_world_base @ T

    def sensor_pose(self, state: ArmState) -> FloatArray:
        """``T_world_sensor`` of the measured (actual) joint positions."""
        return self.T_world_tcp_of(state) @ self.T_tcp_sensor

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
        state = ArmState(q, self.kinematics.fk(q), self.servo is not None)
        if self.servo is not None:
            state.cnt[ak.K_IPO] = self.servo.ipo_ticks
        return state

    # ----------------------------------------------------------------- control tick
    def step(self, state: ArmState, command: MoveCommand | None) -> None:
        """Advance ``state`` by one control period (None: brake to rest, keep orientation):
        the command into the state's command array, then one compiled
        :func:`~seamtrack.control.arm_kernels.arm_step`."""
        cmd = state.cmd
        if command is None:
            cmd[ak.M_HAS] = 0.0
        else:
            cmd[ak.M_HAS] = 1.0
            cmd[ak.M_T : ak.M_T + 3] = command.target
            cmd[ak.M_SPEED] = command.speed
            cmd[ak.M_FF : ak.M_FF + 3] = command.feed_forward
            cmd[ak.M_STOP] = 1.0 if command.stop_at_target else 0.0
            self._set_rotation(state, command.rotation, getattr(command, "angular_velocity", None))
        self._tick(state)

    def _set_rotation(self, state: ArmState, rotation: Any, angular_velocity: Any) -> None:
        """The command's orientation into the state's command array: a new goal when the
        rotation is another one than the last (the same object, or failing that equal: the
        goal turns on at the feed-forward ``angular_velocity``)."""
        cmd = state.cmd
        if rotation is None:
            cmd[ak.M_HAS_ROT] = 0.0
            return
        cmd[ak.M_HAS_ROT] = 1.0
        if angular_velocity is None:
            cmd[ak.M_HAS_W] = 0.0
        else:
            cmd[ak.M_HAS_W] = 1.0
            cmd[ak.M_W : ak.M_W + 3] = angular_velocity
        last = state.goal_from
        if rotation is not last and (last is None or not np.array_equal(rotation, last)):
            state.goal_from = rotation
            cmd[ak.M_NEW_GOAL] = 1.0
            cmd[ak.M_ROT : ak.M_ROT + 9] = np.asarray(rotation, dtype=np.float64).ravel()

    def _tick(self, state: ArmState) -> None:
        ak.arm_step(self._model, state.data)

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
            where = f"{what} {i} at world {np.round(T_world[:3, 3], 3).tolist()} mm"
            closed = self._closed_form(T, q)
            if closed is not None:
                q = closed
            else:
                q = self._iterative(T, q, i, where, field_name, data)
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

    def _closed_form(self, T_base_tcp: FloatArray, q_near: FloatArray) -> FloatArray | None:
        """The closed-form branch nearest ``q_near`` (as the iterative solver from there
        would find it), each joint then moved by whole turns into its range where that helps;
        None where the arm has no closed form or the pose no solution."""
        kin = self.kinematics
        if kin.solver == KIND_NONE:
            return None
        branches = kin.ik_branches(T_base_tcp, q_near)
        if not len(branches):
            return None
        best = branches[int(np.argmin(np.sum((branches - q_near) ** 2, axis=1)))]
        return _wrap_into_range(best, kin.lower_rad, kin.upper_rad)

    def _iterative(
        self, T_base_tcp: FloatArray, q: FloatArray, i: int, where: str, field_name: str,
        data: Any,
    ) -> FloatArray:  # fmt: skip
        """Damped least squares from ``q`` (Pinocchio), or the refusal of a pose out of
        reach."""
        kin = self.kinematics
        result = kin.ik(T_base_tcp, q, data, max_iterations=200 if i == 0 else 50)
        if not result:
            distance = float(np.linalg.norm(T_base_tcp[:3, 3]))
            raise ReachError(
                f"{where}: the {kin.name} cannot put its torch there with the planned "
                f"orientation (no joint solution; closest {result.error_mm:.3g} mm, "
                f"{math.degrees(result.error_rad):.3g} deg away; {distance:.0f} mm from "
                "the base)",
                field=field_name,
                fix="move the part (workpiece.offset_mm / seam.offset_mm) or the robot "
                "base (robot.base_origin_mm) so the seam lies well inside the arm's reach",
            )
        return _wrap_into_range(result.q, kin.lower_rad, kin.upper_rad)


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
