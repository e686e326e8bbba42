"""The 3-axis Cartesian robot of the paper (Sec. 2.3, Table 2) and its servo model.

Each axis is driven independently. The joint vector q is the TCP (torch tip) position in the
base frame {RB}, so ``T_base_tcp(q)`` is a pure translation; the torch keeps its orientation.

Servo model, at the control period dt: the commanded move (a target, a path speed, an optional
velocity feed-forward) becomes a desired velocity along the straight line to the target, scaled
down as a whole if any axis would exceed its velocity limit; each axis then limits its component
to the speed from which it can still stop before its position limit, and finally its change
to the acceleration limit times dt. The
"can still stop" speed is the exact discrete-time one (:func:`stop_speed`): braking by a dt per
tick from it covers exactly d, so no limit is ever crossed. A point-to-point
move (``stop_at_target``) uses the same law towards its target and lands on it exactly.

The hot loop runs on Python floats: for three axes that is several times faster than numpy.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np
from numpy.typing import ArrayLike, NDArray

from seamtrack.control.servo import Servo, ServoState
from seamtrack.errors import ReachError, SceneError
from seamtrack.geometry import frames
from seamtrack.jit import KERNEL

FloatArray = NDArray[np.float64]

#: Table 2 of the paper: X, Y, Z in {RB}.
PAPER_STROKE_MM = (800.0, 150.0, 150.0)
PAPER_VELOCITY_MAX_MM_S = (20.0, 10.0, 10.0)
PAPER_ACCELERATION_MAX_MM_S2 = (30.0, 15.0, 15.0)

_NO_FEED_FORWARD = (0.0, 0.0, 0.0)
#: The identity pose, copied where a pose is filled in every frame (np.eye costs more).
_EYE4 = np.eye(4)


@dataclass(frozen=True)
class MoveCommand:
    """A move in the robot's base frame (the tracker's :class:`~seamtrack.control.tracking.Command`,
    converted once when it changes).

    Attributes
    ----------
    target : tuple of 3 float
        Target TCP position, mm.
    speed : float
        Path speed towards it, mm/s (capped by the axis limits).
    feed_forward : tuple of 3 float
        Velocity added to the path velocity, mm/s.
    stop_at_target : bool
        Brake so as to arrive at rest (point-to-point) instead of passing through at speed.
    rotation : (3, 3) float or None
        Tool rotation ``R_base_tcp`` to turn to (a robot that turns its tool); None keeps it.
    """

    target: tuple[float, float, float]
    speed: float
    feed_forward: tuple[float, float, float] = (0.0, 0.0, 0.0)
    stop_at_target: bool = False
    rotation: FloatArray | None = None


@dataclass
class RobotState:
    """Mutable axis state, advanced in place by :meth:`CartesianRobot.step`.

    With a servo, ``q`` and ``v`` are the axes' actual positions and velocities, ``setpoint``
    the interpolator's state and ``servo`` the position loops' state.
    """

    q: list[float]
    v: list[float]
    setpoint: RobotState | None = None
    servo: ServoState | None = None


@numba.njit(**KERNEL)
def stop_speed(distance: float, accel: float, dt: float) -> float:
    """Largest speed from which braking by ``accel * dt`` per tick stops within ``distance``.

    Braking from (m + f) a dt through (m - 1 + f) a dt, ..., f a dt to 0 covers
    a dt^2 (m (m + 1) / 2 + (m + 1) f); with u = distance / (a dt^2), m is the largest whole
    number with m (m + 1) / 2 <= u and f = (u - m (m + 1) / 2) / (m + 1) < 1. Exact at every
    distance, so braking along it never needs more than the acceleration limit.
    """
    if distance <= 0.0:
        return 0.0
    u = distance / (accel * dt * dt)
    m = math.floor((math.sqrt(1.0 + 8.0 * u) - 1.0) / 2.0)
    if (m + 1) * (m + 2) / 2 <= u:  # rounding in the square root
        m += 1
    f = (u - m * (m + 1) / 2) / (m + 1)
    return accel * dt * (m + f)


#: Rows of :attr:`CartesianRobot._limits` (:func:`axes_step`).
_VMAX, _AMAX, _LO, _HI, _FREE = 0, 1, 2, 3, 4


@numba.njit(**KERNEL)
def axes_step(
    q: FloatArray, v: FloatArray, lim: FloatArray, dt: float, has_target: bool,
    tx: float, ty: float, tz: float, speed: float, fx: float, fy: float, fz: float, stop: bool,
) -> None:  # fmt: skip
    """One control period of three ideal axes (``q``, ``v`` updated in place) moving towards
    a target (``has_target``; else braking to rest) at ``speed`` along the straight line, plus
    the feed-forward velocity; ``stop``: arrive at rest. ``lim`` rows: velocity and
    acceleration limits, travel min and max, free travel (beyond it no end stop can limit an
    allowed speed). Compiled: the loop runs it every tick (:mod:`seamtrack.simulation.ticks`)."""
    if not has_target:
        d0 = d1 = d2 = 0.0
    else:
        ex, ey, ez = tx - q[0], ty - q[1], tz - q[2]
        dist = math.sqrt(ex * ex + ey * ey + ez * ez)
        if dist > 0.0:
            ux, uy, uz = ex / dist, ey / dist, ez / dist
            # Path speed limited by every axis' velocity limit along this direction.
            a_path = math.inf
            unit = (ux, uy, uz)
            for i in range(3):
                au = abs(unit[i])
                if au > 1e-12:
                    c = lim[_VMAX, i] / au
                    speed = c if c < speed else speed
                    c = lim[_AMAX, i] / au
                    a_path = c if c < a_path else a_path
            if stop:
                c = stop_speed(dist, a_path, dt)
                speed = c if c < speed else speed
            # Never step past the target in one tick.
            c = dist / dt
            speed = c if c < speed else speed
            d0, d1, d2 = fx + ux * speed, fy + uy * speed, fz + uz * speed
        else:
            d0, d1, d2 = fx, fy, fz
    desired = (d0, d1, d2)
    # A velocity beyond an axis limit is scaled down as a whole, keeping its direction (as a
    # Cartesian controller's speed override does); clipping one axis alone would bend the path.
    scale = 1.0
    for i in range(3):
        if abs(desired[i]) > lim[_VMAX, i]:
            scale = min(scale, lim[_VMAX, i] / abs(desired[i]))
    for i in range(3):
        vd = desired[i] * scale
        qi = q[i]
        lo_i, hi_i = lim[_LO, i], lim[_HI, i]
        # Keep the ability to stop before the axis travel ends (near an end stop only).
        if vd > 0.0 and hi_i - qi < lim[_FREE, i]:
            vd = min(vd, stop_speed(hi_i - qi, lim[_AMAX, i], dt))
        elif vd < 0.0 and qi - lo_i < lim[_FREE, i]:
            vd = max(vd, -stop_speed(qi - lo_i, lim[_AMAX, i], dt))
        dv_max = lim[_AMAX, i] * dt
        vi = v[i]
        change = vd - vi  # clipped to +-dv_max
        change = -dv_max if -dv_max > change else change
        change = dv_max if dv_max < change else change
        vi += change
        qi += vi * dt
        # Rounding can leave a sub-nanometre overshoot: clamp the position to the end stop
        # (the velocity is already the last braking step; zeroing it would be a jump).
        qi = lo_i if lo_i > qi else qi
        qi = hi_i if hi_i < qi else qi
        q[i] = qi
        v[i] = vi


@dataclass(frozen=True)
class CartesianRobot:
    """Three independent linear axes with position, velocity and acceleration limits.

    Parameters
    ----------
    position_min_mm, position_max_mm : (3,) float
        Axis travel in the base frame.
    velocity_max_mm_s, acceleration_max_mm_s2 : (3,) float
        Per-axis limits (Table 2).
    control_period_s : float
        Servo period dt.
    T_world_base : (4, 4) float
        Pose of the robot base in the world.
    T_tcp_sensor : (4, 4) float
        Pose of the sensor's laser frame relative to the torch tip.
    servo : Servo or None
        Position loops of the axes (None: ideal axes, at their set-point on every tick).
    """

    position_min_mm: tuple[float, float, float] = (0.0, 0.0, 0.0)
    position_max_mm: tuple[float, float, float] = PAPER_STROKE_MM
    velocity_max_mm_s: tuple[float, float, float] = PAPER_VELOCITY_MAX_MM_S
    acceleration_max_mm_s2: tuple[float, float, float] = PAPER_ACCELERATION_MAX_MM_S2
    control_period_s: float = 1e-3
    T_world_base: FloatArray = field(default_factory=lambda: np.eye(4))
    T_tcp_sensor: FloatArray = field(default_factory=lambda: np.eye(4))
    servo: Servo | None = None
    turns_tool = False
    _T_base_world: FloatArray = field(init=False, repr=False, compare=False)
    _ideal: CartesianRobot | None = field(init=False, repr=False, compare=False)
    _unrotated: bool = field(init=False, repr=False, compare=False)
    _base_shift: tuple[float, float, float] = field(init=False, repr=False, compare=False)
    _free_travel: tuple[float, float, float] = field(init=False, repr=False, compare=False)
    #: Rows velocity, acceleration, travel min, travel max, free travel (:func:`axes_step`).
    _limits: FloatArray = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for key in ("velocity_max_mm_s", "acceleration_max_mm_s2"):
            values = tuple(float(v) for v in getattr(self, key))
            if len(values) != 3 or not all(math.isfinite(v) and v > 0 for v in values):
                raise SceneError(
                    f"needs three positive limits, got {values}",
                    field=f"robot.{key}",
                    fix="give [x, y, z] limits > 0",
                )
            object.__setattr__(self, key, values)
        lo = tuple(float(v) for v in self.position_min_mm)
        hi = tuple(float(v) for v in self.position_max_mm)
        if len(lo) != 3 or len(hi) != 3 or not all(a < b for a, b in zip(lo, hi, strict=True)):
            raise SceneError(
                f"position_min_mm {lo} must lie below position_max_mm {hi}",
                field="robot.position_max_mm",
                fix="give [x, y, z] with min < max",
            )
        object.__setattr__(self, "position_min_mm", lo)
        object.__setattr__(self, "position_max_mm", hi)
        if not (math.isfinite(self.control_period_s) and self.control_period_s > 0):
            raise SceneError(
                f"must be > 0, got {self.control_period_s}",
                field="robot.control_period_s",
                fix="e.g. 0.001 (1 kHz)",
            )
        object.__setattr__(self, "T_world_base", np.asarray(self.T_world_base, dtype=float))
        object.__setattr__(self, "_T_base_world", frames.invert(self.T_world_base))
        object.__setattr__(
            self, "_unrotated", bool(np.allclose(self.T_world_base[:3, :3], np.eye(3), atol=0.0))
        )
        shift = self._T_base_world[:3, 3]
        object.__setattr__(self, "_base_shift", (float(shift[0]), float(shift[1]), float(shift[2])))
        # Braking from v (discrete, :func:`stop_speed`) covers at most v^2/2a + v dt/2 + a dt^2/8:
        # farther than this from an end stop, the end stop cannot limit any allowed speed.
        dt = self.control_period_s
        free = tuple(
            1.000001 * (v * v / (2.0 * a) + 0.5 * v * dt + 0.125 * a * dt * dt)
            for v, a in zip(self.velocity_max_mm_s, self.acceleration_max_mm_s2, strict=True)
        )
        object.__setattr__(self, "_free_travel", free)
        limits = (self.velocity_max_mm_s, self.acceleration_max_mm_s2, lo, hi, free)
        object.__setattr__(self, "_limits", np.array(limits, dtype=np.float64))
        object.__setattr__(self, "T_tcp_sensor", np.asarray(self.T_tcp_sensor, dtype=float))
        ideal = None
        if self.servo is not None:
            ideal = CartesianRobot(**{
                k: getattr(self, k)
                for k in (
                    "position_min_mm", "position_max_mm", "velocity_max_mm_s",
                    "acceleration_max_mm_s2", "control_period_s", "T_world_base", "T_tcp_sensor",
                )
            })  # fmt: skip
        object.__setattr__(self, "_ideal", ideal)

    # ----------------------------------------------------------------- kinematics
    @staticmethod
    def T_base_tcp(q: ArrayLike) -> FloatArray:
        """Pose of the torch tip in the base frame for joint positions q (a translation)."""
        return frames.make(translation=q)

    def T_world_tcp(self, q: ArrayLike) -> FloatArray:
        return self.T_world_base @ self.T_base_tcp(q)

    def T_world_sensor(self, q: ArrayLike) -> FloatArray:
        """``T_world_base @ T_base_tcp(q) @ T_tcp_sensor``."""
        return self.T_world_base @ self.T_base_tcp(q) @ self.T_tcp_sensor

    def joints_for_tool(
        self,
        T_world_tcp: ArrayLike,
        seed: ArrayLike | None = None,
        what: str = "tool pose",
        field_name: str = "seam",
    ) -> FloatArray:
        """Axis positions (mm) that put the torch tip at the origin of ``T_world_tcp``: the
        same call as :meth:`ArticulatedRobot.joints_for_tool
        <seamtrack.control.arm.ArticulatedRobot.joints_for_tool>`. A gantry cannot turn its
        tool, so the pose's rotation is the base's whatever is asked, and ``seed`` is not
        needed; a tip outside the axis travel is a :class:`ReachError` naming ``field_name``."""
        tcp = np.asarray(T_world_tcp, dtype=np.float64)[:3, 3]
        self.require_reachable(tcp, what, field_name)
        return self.q_from_world(tcp)

    def sensor_pose(self, state: RobotState) -> FloatArray:
        """``T_world_sensor`` at the state's (actual) axis positions."""
        T = _EYE4.copy()  # T_base_tcp(state.q), without its conversions (every frame)
        T[:3, 3] = state.q
        return self.T_world_base @ T @ self.T_tcp_sensor

    def T_world_tcp_of(self, state: RobotState) -> FloatArray:
        return self.T_world_tcp(state.q)

    def tcp_world(self, q: ArrayLike) -> FloatArray:
        return frames.apply(self.T_world_base, np.asarray(q, dtype=float))

    def q_from_world(self, tcp_world: ArrayLike) -> FloatArray:
        """Joint positions that put the TCP at a world point."""
        return frames.apply(self._T_base_world, np.asarray(tcp_world, dtype=float))

    def reachable(self, tcp_world: ArrayLike) -> NDArray[np.bool_]:
        """(n,) True where world points lie inside the axis travel."""
        q = np.atleast_2d(self.q_from_world(tcp_world))
        lo, hi = np.array(self.position_min_mm), np.array(self.position_max_mm)
        return np.asarray(((q >= lo - 1e-9) & (q <= hi + 1e-9)).all(axis=1))

    def require_reachable(self, tcp_world: ArrayLike, what: str, field: str) -> None:
        """Raise :class:`ReachError` naming the first point outside the axis travel."""
        points = np.atleast_2d(np.asarray(tcp_world, dtype=float))
        ok = self.reachable(points)
        if not ok.all():
            i = int(np.flatnonzero(~ok)[0])
            q = self.q_from_world(points[i])
            raise ReachError(
                f"{what} point {i} at world {np.round(points[i], 3).tolist()} mm needs axis "
                f"positions {np.round(q, 3).tolist()} mm, outside the travel "
                f"{list(self.position_min_mm)}..{list(self.position_max_mm)}",
                field=field,
                fix="move the part (seam.offset_mm) or the robot base (robot.base_origin_mm) so "
                "the whole seam lies inside the robot's reach",
            )

    def command_in_base(
        self,
        target_world: ArrayLike,
        speed_mm_s: float,
        velocity_ff_world: ArrayLike | None = None,
        stop_at_target: bool = False,
        rotation_world: ArrayLike | None = None,
    ) -> MoveCommand:
        """Convert a world-frame move to the base frame (on plain floats when the base is not
        rotated: this runs whenever a tracker issues a new command, often every tick)."""
        if self._unrotated:
            tx, ty, tz = self._base_shift
            px, py, pz = np.asarray(target_world, dtype=float).reshape(3).tolist()
            ff0 = (0.0, 0.0, 0.0)
            if velocity_ff_world is not None:
                fx, fy, fz = np.asarray(velocity_ff_world, dtype=float).reshape(3).tolist()
                ff0 = (fx, fy, fz)
            return MoveCommand(
                (px + tx, py + ty, pz + tz), float(speed_mm_s), ff0, bool(stop_at_target)
            )  # a gantry cannot turn its tool: a commanded rotation is ignored
        T_base_world: FloatArray = self._T_base_world
        q = frames.apply(T_base_world, np.asarray(target_world, dtype=float))
        ff = (0.0, 0.0, 0.0)
        if velocity_ff_world is not None:
            ffv = frames.apply_vectors(T_base_world, np.asarray(velocity_ff_world, dtype=float))
            ff = (float(ffv[0]), float(ffv[1]), float(ffv[2]))
        return MoveCommand(
            (float(q[0]), float(q[1]), float(q[2])), float(speed_mm_s), ff, bool(stop_at_target)
        )

    # ----------------------------------------------------------------- servo
    def within_travel(self, q: tuple[float, float, float]) -> bool:
        """True when joint positions lie inside the axis travel (cheap: for the hot loop)."""
        lo, hi = self.position_min_mm, self.position_max_mm
        return (
            lo[0] - 1e-9 <= q[0] <= hi[0] + 1e-9
            and lo[1] - 1e-9 <= q[1] <= hi[1] + 1e-9
            and lo[2] - 1e-9 <= q[2] <= hi[2] + 1e-9
        )

    def state_at(self, q: ArrayLike) -> RobotState:
        """A state at rest at joint positions q (must be inside the travel)."""
        qs = [float(x) for x in np.asarray(q, dtype=float)]
        if self.servo is None:
            return RobotState(q=qs, v=[0.0, 0.0, 0.0])
        servo = self.servo.new_state(qs)
        return RobotState(servo.q, servo.v, RobotState(q=list(qs), v=[0.0, 0.0, 0.0]), servo)

    def step(self, state: RobotState, command: MoveCommand | None) -> None:
        """Advance ``state`` by one control period under ``command`` (None: brake to rest)."""
        if command is None:
            self.step_move(state, None, 0.0, _NO_FEED_FORWARD, False)
        else:
            self.step_move(
                state, command.target, command.speed, command.feed_forward, command.stop_at_target
            )

    def step_move(
        self,
        state: RobotState,
        target: tuple[float, float, float] | None,
        speed: float,
        feed_forward: tuple[float, float, float],
        stop_at_target: bool,
    ) -> None:
        """:meth:`step` on the fields of a :class:`MoveCommand` (``target`` None: brake to
        rest): the servo's interpolator and ideal axes take one :func:`axes_step`."""
        if self._ideal is not None:
            # the servo: the interpolator moves the set-point, the position loops the axes
            assert self.servo is not None
            assert state.setpoint is not None and state.servo is not None
            self._ideal.step_move(state.setpoint, target, speed, feed_forward, stop_at_target)
            self.servo.follow(state.servo, state.setpoint.q)
            lo, hi = self.position_min_mm, self.position_max_mm
            q_servo = state.servo.q
            for i in range(3):
                q_servo[i] = min(max(q_servo[i], lo[i]), hi[i])
            return
        q, v = np.array(state.q), np.array(state.v)
        tx, ty, tz = (0.0, 0.0, 0.0) if target is None else target
        fx, fy, fz = feed_forward
        axes_step(q, v, self._limits, self.control_period_s, target is not None, tx, ty, tz,
                  speed, fx, fy, fz, stop_at_target)  # fmt: skip
        state.q[:], state.v[:] = q.tolist(), v.tolist()
