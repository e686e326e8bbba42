"""The loop's compiled control ticks: the built-in trajectory tracker on a gantry.

Between two events (a frame captured, a measurement arriving, a wall-clock check) every
control tick does the same small arithmetic (and every 10 ms the loop's progress check, the
same kernel the loop calls, :func:`~seamtrack.simulation.progress.progress_check`): the torch
tip from the axes, the tracker's set-point step
(:func:`seamtrack.control.path_kernels.setpoint_step`), the axis travel check, the axes' step
(the interpolator, and the position loops when the robot has a servo), and the
trace. In Python that costs ~10 us a tick, dozens of float operations each wrapped in an
object; :func:`gantry_ticks` runs the whole stretch in one compiled call, calling the compiled
steps the tracker and the robot use themselves (``setpoint_step``, ``axes_step``,
``loops_step``), so the run is the same to the last bit as the one the tracker protocol drives
(``tests/test_loop_fast.py``).
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.control.arm_kernels import (
    C_Q,
    C_V,
    M_FF,
    M_HAS,
    M_HAS_ROT,
    M_HAS_W,
    M_NEW_GOAL,
    M_ROT,
    M_SPEED,
    M_STOP,
    M_T,
    M_W,
    S_JOINTS,
    arm_step,
)  # fmt: skip
from seamtrack.control.orientation import turning_at
from seamtrack.control.path_kernels import V_SET, setpoint_step
from seamtrack.control.robot import CartesianRobot, RobotState, axes_step
from seamtrack.control.servo import loops_step
from seamtrack.simulation.progress import (
    CHECKED,
    FOUND,
    GO_ON,
    S_NOW,
    ProgressCheck,
    _closest_in_window,
    progress_check,
)

FloatArray = NDArray[np.float64]

#: What :func:`gantry_ticks` stopped on (besides an event tick); ``STOPPED``: its progress
#: check ended the run (what it found in the check's ``FOUND``).
EVENT, LIMIT, REFUSED, STOPPED = 0, 1, 2, 3
#: Rows of the axis limits (:attr:`CartesianRobot._limits`): travel min and max.
_LO, _HI = 2, 3


@numba.njit(cache=True, nogil=True)
def _checked(
    tick: int, t: float, x: float, y: float, z: float, v: FloatArray, check_every: int,
    wall_every: int, progress: FloatArray, seam: FloatArray, seam_s: FloatArray,
    seam_columns: FloatArray, checks: FloatArray,
) -> bool:  # fmt: skip
    """After a tick: True when the ticks stop here. A wall-clock tick (and every hundredth
    check, the progress bar's) is the loop's to check; any other check tick is checked here,
    as the loop would (:func:`~seamtrack.simulation.progress.progress_check`, the torch tip
    (x, y, z) at the tick's start, its speed after it), logged in ``checks`` (rows t, s; the
    count in its last row's first column), and stops the ticks when the run ends there."""
    if tick % wall_every == 0 or tick % (100 * check_every) == 0:
        return True
    if tick % check_every != 0:
        return False
    speed = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    found = progress_check(progress, t, x, y, z, speed, seam, seam_s, seam_columns)
    m = int(checks[-1, 0])
    checks[m, 0], checks[m, 1] = t, progress[S_NOW]
    checks[-1, 0] = m + 1
    progress[CHECKED], progress[FOUND] = tick, found
    return found != GO_ON


@numba.njit(cache=True, nogil=True)
def gantry_ticks(
    tick: int, max_ticks: int, dt: float, next_capture: float, next_arrival: float,
    check_every: int, wall_every: int, offset: FloatArray, axes: FloatArray, lim: FloatArray,
    servo: FloatArray, ipo: NDArray[np.int64], sp: FloatArray, path: FloatArray, s: FloatArray,
    env_s: FloatArray, env_v: FloatArray, seen: bool, tcp_out: FloatArray,
    target_out: FloatArray, k0: int, refused: FloatArray, progress: FloatArray,
    seam: FloatArray, seam_s: FloatArray, seam_columns: FloatArray, checks: FloatArray,
) -> tuple[int, int]:  # fmt: skip
    """Control ticks from ``tick`` on, until the next event: stops before a tick at which a
    frame is due (``next_capture``) or a measurement arrives (``next_arrival``), after a tick
    at which the loop checks the wall clock (``wall_every``; see :func:`_checked`), or at a
    target outside the travel (``LIMIT``), an unusable command (``REFUSED``: its target,
    speed, feed-forward and stop in ``refused``) or a progress check (every ``check_every``
    ticks, made here: ``progress``, ``seam``, ``seam_s``, ``seam_columns``, ``checks``, see
    :class:`~seamtrack.simulation.progress.ProgressCheck`) that ends the run (``STOPPED``).

    ``offset``: (tcp from axes (3), world to base (3)); ``axes``: rows q, v (the servo's
    output), set-point q, v, held set-point; ``ipo``: (ticks per interpolation, servo tick;
    -1: ideal axes). Writes the torch tip and the target of each tick into ``tcp_out`` and
    ``target_out``, rows from ``k0`` on. Returns (ticks run, what stopped it).
    """
    q, v, sq, sv, held = axes[0], axes[1], axes[2], axes[3], axes[4]
    has_servo = ipo[0] > 0
    first = tick
    while tick <= max_ticks:
        t = tick * dt
        if tick > first and (t + 1e-9 >= next_capture or next_arrival <= t + 1e-9):
            break
        k = tick - first
        r = k0 + k
        x, y, z = q[0] + offset[0], q[1] + offset[1], q[2] + offset[2]
        tcp_out[r, 0], tcp_out[r, 1], tcp_out[r, 2] = x, y, z
        if not seen:
            sp[2], sp[3], sp[4] = x, y, z  # the tracker's view of the torch (naive poses)
            target_out[r, :] = np.nan
            has_target = False
            tx = ty = tz = speed = fx = fy = fz = 0.0
            stop = False
        else:
            tx, ty, tz, speed, fx, fy, fz, stop = setpoint_step(sp, path, s, env_s, env_v, x, y, z)
            if not (0.0 < speed < math.inf and math.isfinite(tx + ty + tz + fx + fy + fz)):
                refused[:] = (tx, ty, tz, speed, fx, fy, fz, 1.0 if stop else 0.0)
                return k, REFUSED
            target_out[r, 0], target_out[r, 1], target_out[r, 2] = tx, ty, tz
            tx, ty, tz = tx + offset[3], ty + offset[4], tz + offset[5]
            if not (
                lim[_LO, 0] - 1e-9 <= tx <= lim[_HI, 0] + 1e-9
                and lim[_LO, 1] - 1e-9 <= ty <= lim[_HI, 1] + 1e-9
                and lim[_LO, 2] - 1e-9 <= tz <= lim[_HI, 2] + 1e-9
            ):
                return k + 1, LIMIT
            has_target = True
        if has_servo:  # CartesianRobot._step_servo and Servo.follow
            axes_step(sq, sv, lim, dt, has_target, tx, ty, tz, speed, fx, fy, fz, stop)
            if ipo[1] % ipo[0] == 0:
                held[:] = sq
            ipo[1] += 1
            loops_step(q, v, held, servo, dt)
            for i in range(3):
                q[i] = min(max(q[i], lim[_LO, i]), lim[_HI, i])
        else:
            axes_step(q, v, lim, dt, has_target, tx, ty, tz, speed, fx, fy, fz, stop)
        tick += 1
        if _checked(tick - 1, t, x, y, z, v, check_every, wall_every, progress, seam, seam_s,
                    seam_columns, checks):  # fmt: skip
            return tick - first, STOPPED if progress[FOUND] != GO_ON else EVENT
    return tick - first, EVENT


class _Logs:
    """The trace of a run's compiled ticks: the torch tip and the target of every tick (and an
    arm's torch axis and joints), rows ``[0, count)`` of arrays that grow by doubling, which
    the ticks write in place (the loop takes them at the end: nothing is copied per frame)."""

    def __init__(self, dof: int) -> None:
        self.count = 0
        self.tcp = np.empty((4096, 3))
        self.target = np.empty((4096, 3))
        self.axis = np.empty((4096 if dof else 0, 3))
        self.joints = np.empty((4096 if dof else 0, dof))

    def room(self, rows: int) -> bool:
        """At least ``rows`` rows free after ``count``; True when the arrays were replaced."""
        size = len(self.tcp)
        if self.count + rows <= size:
            return False
        while self.count + rows > size:
            size *= 2
        for name in ("tcp", "target", "axis", "joints"):
            old = getattr(self, name)
            if len(old):
                new = np.empty((size, old.shape[1]))
                new[: self.count] = old[: self.count]
                setattr(self, name, new)
        return True


class GantryTicks(_Logs):
    """The compiled ticks of one run: the robot's limits and state in arrays, the traces'
    rows (:class:`_Logs`); :meth:`run` advances a :class:`RobotState` in place."""

    def __init__(
        self, robot: CartesianRobot, tcp_offset: tuple[float, float, float], checks: ProgressCheck
    ) -> None:
        super().__init__(0)
        self.robot = robot
        self.checks = checks
        self.dt = robot.control_period_s
        self.lim = robot._limits
        self.origin = tcp_offset
        self.offset = np.array([*tcp_offset, *robot._base_shift])
        servo = robot.servo
        self.servo = np.zeros((3, 3))
        self.ipo = np.array([-1, 0], dtype=np.int64)
        if servo is not None and robot._ideal is not None:
            self.servo = servo._table
            self.ipo[0] = servo.ipo_ticks
        self.axes = np.zeros((5, 3))
        self.refused = np.zeros(8)

    def run(
        self, state: RobotState, tick: int, max_ticks: int, next_capture: float,
        next_arrival: float, check_every: int, wall_every: int, tracker: Any,
    ) -> tuple[int, int]:  # fmt: skip
        """Ticks from ``tick`` to the next event, ``state`` advanced (see :func:`gantry_ticks`);
        the ticks' torch tips and targets are logged (:class:`_Logs`)."""
        self.room(wall_every + 1)  # a stretch of ticks ends at a wall-clock tick
        self.checks.room(wall_every // check_every + 2)
        axes = self.axes
        axes[0], axes[1] = state.q, state.v
        servo = state.servo
        if servo is not None:
            assert state.setpoint is not None
            axes[2], axes[3], axes[4] = state.setpoint.q, state.setpoint.v, servo.held
            self.ipo[1] = servo.tick
        path = tracker._buffer
        n, why = gantry_ticks(
            tick, max_ticks, self.dt, next_capture, next_arrival, check_every, wall_every,
            self.offset, axes, self.lim, self.servo, self.ipo, tracker._sp, path.path, path.s,
            tracker._env_s, tracker._env_v, tracker._seen_seam, self.tcp, self.target,
            self.count, self.refused, *self.checks.args,
        )  # fmt: skip
        self.count += n
        state.q[:], state.v[:] = axes[0].tolist(), axes[1].tolist()
        if servo is not None:
            assert state.setpoint is not None
            state.setpoint.q[:], state.setpoint.v[:] = axes[2].tolist(), axes[3].tolist()
            servo.held[:] = axes[4].tolist()
            servo.tick = int(self.ipo[1])
        return n, why

    def tcp_now(self, state: RobotState) -> FloatArray:
        """The torch tip (world) of ``state``, as the loop computes it."""
        q, (x, y, z) = state.q, self.origin
        return np.array([q[0] + x, q[1] + y, q[2] + z])

    def finish(self, state: Any, tracker: Any) -> None:
        """After the run (nothing to hand back on a gantry)."""


@numba.njit(cache=True, nogil=True)
def _closest_near(
    points: FloatArray, knots: FloatArray, columns: FloatArray, q: FloatArray, hint: float
) -> float:
    """:meth:`ProgressTracker.closest_near <seamtrack.simulation.progress.ProgressTracker.
    closest_near>` compiled (the chosen segment's length by a scalar sqrt: equal to an ulp)."""
    length = knots[-1]
    n_seg = len(points) - 1
    window = 5.0
    while True:
        s0 = max(hint - window, 0.0)
        s1 = min(hint + window, length)
        i0 = min(max(int(np.searchsorted(knots, s0, side="right")) - 1, 0), n_seg - 1)
        i1 = min(max(int(np.searchsorted(knots, s1, side="left")), i0 + 1), n_seg)
        s_start, t, dx, dy, dz = _closest_in_window(points, knots, columns, q, s0, s1, i0, i1)
        s = s_start + t * math.sqrt(dx * dx + dy * dy + dz * dz)
        cut_low = s0 > 0.0 and s <= s0 + 1e-12
        cut_high = s1 < length and s >= s1 - 1e-12
        if not (cut_low or cut_high) or window >= length:
            return s
        window *= 2.0


@numba.njit(cache=True, nogil=True)
def _refresh_orientation(
    x: float, y: float, z: float, sp: FloatArray, base: FloatArray, prog: FloatArray,
    knots: FloatArray, seg_len: FloatArray, normals: FloatArray, prog_par: FloatArray,
    columns: FloatArray, turn: FloatArray, cmd: FloatArray,
) -> None:  # fmt: skip
    """The tracker's tool-orientation refresh (:meth:`TrajectoryTracker.command_floats
    <seamtrack.control.trajectory.TrajectoryTracker.command_floats>`: the program's rotation
    and turning rate at the seam point closest to the set-point) and the command's rotation in
    the base frame (``ArticulatedRobot.command_in_base``, ``_set_rotation``): ``turn`` holds
    the world rotation (9), angular velocity (3) and arc length."""
    q = np.array((x, y, z))
    s = _closest_near(prog, knots, columns, q, turn[12])
    R, w = turning_at(s, sp[V_SET], prog, knots, seg_len, normals, prog_par)
    turn[:9] = R.ravel()
    turn[9:12] = w
    turn[12] = s
    new = cmd[M_HAS_ROT] == 0.0
    for i in range(3):
        for j in range(3):
            r = base[i, 0] * R[0, j] + base[i, 1] * R[1, j] + base[i, 2] * R[2, j]
            new = new or r != cmd[M_ROT + 3 * i + j]
            cmd[M_ROT + 3 * i + j] = r
        cmd[M_W + i] = base[i, 0] * w[0] + base[i, 1] * w[1] + base[i, 2] * w[2]
    cmd[M_HAS_ROT], cmd[M_HAS_W] = 1.0, 1.0
    if new:
        cmd[M_NEW_GOAL] = 1.0


@numba.njit(cache=True, nogil=True)
def arm_ticks(
    tick: int, max_ticks: int, dt: float, next_capture: float, next_arrival: float,
    check_every: int, wall_every: int, world: FloatArray,
    base: FloatArray, reach: float, orient: NDArray[np.int64], par: FloatArray, lim: FloatArray,
    jl: FloatArray, servo: FloatArray, geo: FloatArray, place: FloatArray, axes: FloatArray,
    kinds: NDArray[np.int64], index: NDArray[np.int64], cart: FloatArray, rot: FloatArray,
    omega: FloatArray, jnt: FloatArray, cnt: NDArray[np.int64], cmd: FloatArray,
    work: FloatArray, sp: FloatArray, path: FloatArray, s: FloatArray, env_s: FloatArray,
    env_v: FloatArray,
    seen: bool, tcp_out: FloatArray, target_out: FloatArray, axis_out: FloatArray,
    joint_out: FloatArray, k0: int, refused: FloatArray, prog: FloatArray,
    knots: FloatArray, seg_len: FloatArray, normals: FloatArray, prog_par: FloatArray,
    columns: FloatArray, turn: FloatArray, progress: FloatArray, seam: FloatArray,
    seam_s: FloatArray, seam_columns: FloatArray, checks: FloatArray,
) -> tuple[int, int]:  # fmt: skip
    """:func:`gantry_ticks` for an arm and the built-in tracker: per tick the torch tip in the
    world (``world``: (3, 4) rotation and origin of the base), the tracker's set-point step,
    the command in the base frame (``base``: the inverse), the reach check (``LIMIT``), the
    traces (torch tip, target, torch axis, joints, rows from ``k0``) and the arm's compiled
    tick (:func:`~seamtrack.control.arm_kernels.arm_step` on the state's arrays).

    Every ``orient[0]``-th command of the tracker (its count in ``orient[1]``) refreshes the
    tool orientation from the robot program (``prog``: the seam's points, arc lengths, segment
    lengths, normals, the program's parameters, the points' columns; ``turn``: the rotation,
    angular velocity and arc length, see :func:`_refresh_orientation`). Returns (ticks run,
    what stopped it).
    """
    first = tick
    k = 0
    while tick <= max_ticks:
        t = tick * dt
        if tick > first and (t + 1e-9 >= next_capture or next_arrival <= t + 1e-9):
            break
        q = cart[C_Q]
        x = world[0, 0] * q[0] + world[0, 1] * q[1] + world[0, 2] * q[2] + world[0, 3]
        y = world[1, 0] * q[0] + world[1, 1] * q[1] + world[1, 2] * q[2] + world[1, 3]
        z = world[2, 0] * q[0] + world[2, 1] * q[1] + world[2, 2] * q[2] + world[2, 3]
        r = k0 + k
        tcp_out[r, 0], tcp_out[r, 1], tcp_out[r, 2] = x, y, z
        if not seen:
            sp[2], sp[3], sp[4] = x, y, z  # the tracker's view of the torch (naive poses)
            target_out[r, :] = np.nan
            cmd[M_HAS] = 0.0
        else:
            tx, ty, tz, speed, fx, fy, fz, stop = setpoint_step(sp, path, s, env_s, env_v, x, y, z)
            if not (0.0 < speed < math.inf and math.isfinite(tx + ty + tz + fx + fy + fz)):
                refused[:] = (tx, ty, tz, speed, fx, fy, fz, 1.0 if stop else 0.0)
                return k, REFUSED
            orient[1] += 1
            if orient[1] % orient[0] == 0:
                _refresh_orientation(
                    tx, ty, tz, sp, base, prog, knots, seg_len, normals, prog_par, columns, turn,
                    cmd,
                )  # fmt: skip
            target_out[r, 0], target_out[r, 1], target_out[r, 2] = tx, ty, tz
            cmd[M_HAS] = 1.0
            for i in range(3):
                cmd[M_T + i] = base[i, 0] * tx + base[i, 1] * ty + base[i, 2] * tz + base[i, 3]
                cmd[M_FF + i] = base[i, 0] * fx + base[i, 1] * fy + base[i, 2] * fz
            cmd[M_SPEED], cmd[M_STOP] = speed, 1.0 if stop else 0.0
        R = rot[2]
        for i in range(3):
            axis_out[r, i] = world[i, 0] * R[0, 2] + world[i, 1] * R[1, 2] + world[i, 2] * R[2, 2]
        joint_out[r] = jnt[S_JOINTS]
        if cmd[M_HAS] > 0.0:
            d = math.sqrt(cmd[M_T] ** 2 + cmd[M_T + 1] ** 2 + cmd[M_T + 2] ** 2)
            if d > reach:
                return k + 1, LIMIT
        arm_step(
            par, lim, jl, servo, geo, place, axes, kinds, index, cart, rot, omega, jnt, cnt, cmd,
            work,
        )  # fmt: skip
        tick += 1
        k += 1
        if _checked(tick - 1, t, x, y, z, cart[C_V], check_every, wall_every, progress, seam,
                    seam_s, seam_columns, checks):  # fmt: skip
            return k, STOPPED if progress[FOUND] != GO_ON else EVENT
    return k, EVENT


class ArmTicks(_Logs):
    """The compiled ticks of an arm run with the built-in tracker (:func:`arm_ticks`);
    :meth:`run` advances an :class:`~seamtrack.control.arm.ArmState` in place, and the
    tracker's tool orientation as :meth:`TrajectoryTracker.command_floats
    <seamtrack.control.trajectory.TrajectoryTracker.command_floats>` does (compiled, the same
    numbers to an ulp). Through a run the ticks keep the orientation (its command count,
    rotation, angular velocity and arc length) in their arrays, the only ones to change it
    while every tick is compiled; :meth:`finish` hands it back to the tracker."""

    def __init__(self, robot: Any, tracker: Any, checks: ProgressCheck) -> None:
        super().__init__(robot.kinematics.dof)
        self.robot = robot
        self.checks = checks
        self.dt = robot.control_period_s
        self.world = np.ascontiguousarray(robot.T_world_base[:3, :4])
        self.base = np.ascontiguousarray(robot._T_base_world[:3, :4])
        self._R, self._p0 = robot.T_world_base[:3, :3], robot.T_world_base[:3, 3]
        program = tracker._program
        self.prog, self.knots, self.seg_len, self.normals, self.prog_par = program._arrays
        self.columns = np.ascontiguousarray(program.seam.points.T)
        self.orient = np.array([tracker._orient_every, 0], dtype=np.int64)
        self.turn = np.zeros(13)
        self.refused = np.zeros(8)
        self._refreshed = -1  # the orientation refresh last handed to the tracker
        self._args: tuple[Any, ...] = (None, None, (), (), ())  # state, tracker, _fixed's

    def _rotation(self, state: Any, tracker: Any) -> None:
        """The tracker's commanded rotation into the state's command, converted as
        ``command_in_base`` converts it."""
        rotation, omega = tracker._rotation, tracker._omega
        R = self.robot._T_base_world[:3, :3]
        rot_base = None if rotation is None else R @ np.asarray(rotation, dtype=float)
        omega_base = None if omega is None else R @ np.asarray(omega, dtype=float)
        self.robot._set_rotation(state, rot_base, omega_base)

    def _fixed(self, state: Any, tracker: Any) -> tuple[tuple[Any, ...], ...]:
        """The arguments of :func:`arm_ticks` that stay the same objects while the logs and
        the checks keep their arrays (the robot's tables, the state's and the set-point's
        arrays, the outputs), gathered once: before the stored path's (which grows and
        moves), the logs, and after the logs' row count."""
        robot = self.robot
        place, axes, kinds, index = robot.kinematics.chain
        head = (
            self.world, self.base, robot._reach_mm, self.orient, robot._par,
            robot._cart._limits, robot._jl, robot._servo_table, robot.kinematics.geometry,
            place, axes, kinds, index, state.cart, state.rot, state.omega, state.jnt, state.cnt,
            state.cmd, state.work, tracker._sp,
        )  # fmt: skip
        logs = (self.tcp, self.target, self.axis, self.joints)
        tail = (
            self.refused, self.prog, self.knots, self.seg_len, self.normals, self.prog_par,
            self.columns, self.turn, *self.checks.args,
        )  # fmt: skip
        return head, logs, tail

    def run(
        self, state: Any, tick: int, max_ticks: int, next_capture: float, next_arrival: float,
        check_every: int, wall_every: int, tracker: Any,
    ) -> tuple[int, int]:  # fmt: skip
        """Ticks from ``tick`` to the next event (see :func:`arm_ticks`); the ticks' torch
        tips, targets, torch axes and joints are logged (:class:`_Logs`)."""
        grown = self.room(wall_every + 1)  # a stretch of ticks ends at a wall-clock tick
        self.checks.room(wall_every // check_every + 2)
        tail = self._args[4]
        grown = grown or not tail or tail[-1] is not self.checks.checks  # its log replaced
        if self._args[0] is not state or self._args[1] is not tracker:
            # The first stretch: the tracker's orientation, from here on the ticks'.
            self.orient[1] = tracker._tick
            self.turn[12] = tracker._s_program
            self._refreshed = tracker._tick // tracker._orient_every
            self._rotation(state, tracker)
            grown = True
        if grown:
            self._args = (state, tracker, *self._fixed(state, tracker))
        _, _, head, logs, tail = self._args
        path = tracker._buffer
        n, why = arm_ticks(  # type: ignore[call-arg]  # its arguments, gathered (_fixed)
            tick, max_ticks, self.dt, next_capture, next_arrival, check_every, wall_every,
            *head, path.path, path.s, tracker._env_s, tracker._env_v, tracker._seen_seam,
            *logs, self.count, *tail,
        )  # fmt: skip
        self.count += n
        return n, why

    def tcp_now(self, state: Any) -> FloatArray:
        """The torch tip (world) of ``state``, as the loop computes it."""
        return self._R @ state.cart[C_Q] + self._p0

    def finish(self, state: Any, tracker: Any) -> None:
        """After the run: the tool orientation back to the tracker, as it keeps it (its
        command count; where the ticks refreshed it, the rotation, the turning rate and the
        arc length)."""
        if self._args[1] is not tracker:
            return
        count = int(self.orient[1])
        if count // self.orient[0] != self._refreshed:
            tracker._rotation = self.turn[:9].reshape(3, 3).copy()
            tracker._omega = self.turn[9:12].copy()
            tracker._s_program = float(self.turn[12])
            state.goal_from = None  # the goal is in the command (compiled)
        tracker._tick = count


def compiled_ticks(
    robot: Any, tracker: Any, origin: tuple[float, float, float], unrotated: bool, turns: bool,
    checks: ProgressCheck,
) -> GantryTicks | ArmTicks | None:  # fmt: skip
    """The compiled ticks for this robot and tracker, or None (the loop's Python ticks): the
    built-in trajectory tracker on an unrotated gantry, or on an arm with its tool program;
    they make the run's progress checks between the loop's (``checks``)."""
    from seamtrack.control.trajectory import TrajectoryTracker

    if type(tracker) is not TrajectoryTracker:
        return None
    if unrotated and type(robot) is CartesianRobot and bool(robot._unrotated):
        return GantryTicks(robot, origin, checks)
    if turns and hasattr(robot, "_par") and getattr(tracker, "_program", None) is not None:
        return ArmTicks(robot, tracker, checks)
    return None
