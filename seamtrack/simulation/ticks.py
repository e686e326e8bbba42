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
from typing import Any, NamedTuple

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
    ArmData,
    ArmModel,
    arm_step,
)  # fmt: skip
from seamtrack.control.orientation import turning_at
from seamtrack.control.path_kernels import TCP_X, TCP_Y, TCP_Z, V_SET, setpoint_step
from seamtrack.control.robot import CartesianRobot, RobotState, axes_step
from seamtrack.control.servo import loops_step
from seamtrack.jit import KERNEL, compile_for
from seamtrack.simulation.progress import (
    CHECKED,
    FOUND,
    GO_ON,
    NEAR_WINDOW_MM,
    S_NOW,
    SCALAR_NORM,
    CheckArrays,
    ProgressCheck,
    progress_check,
    progress_near,
)

FloatArray = NDArray[np.float64]

#: What :func:`gantry_ticks` stopped on (besides an event tick); ``STOPPED``: its progress
#: check ended the run (what it found in the check's ``FOUND``).
EVENT, LIMIT, REFUSED, STOPPED = 0, 1, 2, 3
#: Rows of the axis limits (:attr:`CartesianRobot._limits`): travel min and max.
_LO, _HI = 2, 3


class Clock(NamedTuple):
    """A stretch of ticks: the first tick, the last the run may reach, the control period (s),
    when the next frame is due and the next measurement arrives (s), and every how many ticks
    the run's progress is checked and the loop looks at the wall clock."""

    tick: int
    max_ticks: int
    dt: float
    next_capture: float
    next_arrival: float
    check_every: int
    wall_every: int


class Follow(NamedTuple):
    """The built-in tracker as its set-point step (:func:`~seamtrack.control.path_kernels.
    setpoint_step`) takes it: the set-point (fields ``S_SET``... of ``path_kernels``), the
    stored path and its arc lengths, the speed envelope (arc lengths, speeds), and whether it
    has seen the seam."""

    setpoint: FloatArray
    path: FloatArray
    s: FloatArray
    envelope_s: FloatArray
    envelope_v: FloatArray
    seen: bool


class Trace(NamedTuple):
    """Where the ticks log: the torch tip and the target of each tick, and an arm's torch axis
    and joints (empty on a gantry); the kernels write from a given row on (:class:`_Logs`)."""

    tcp: FloatArray
    target: FloatArray
    axis: FloatArray
    joints: FloatArray


class GantryAxes(NamedTuple):
    """A gantry as its ticks take it: the offsets (the torch tip from the axes (3), the world
    to the base (3)), the axes (rows q, v (the servo's output), the set-point's q, v, the held
    set-point), the limits (:attr:`CartesianRobot._limits`), the servo's table, and
    ``ipo`` (ticks per interpolation, the servo's tick; -1: ideal axes)."""

    offset: FloatArray
    axes: FloatArray
    limits: FloatArray
    servo: FloatArray
    ipo: NDArray[np.int64]


class ArmMount(NamedTuple):
    """Where an arm stands: ``world`` (3, 4), the base's rotation and origin in the world,
    ``base`` (3, 4) its inverse, and the arm's reach (mm) from the base."""

    world: FloatArray
    base: FloatArray
    reach: float


class ToolProgram(NamedTuple):
    """The robot program's tool orientation, as the tracker refreshes it every ``orient[0]``-th
    command (its count in ``orient[1]``): the seam's points, arc lengths, segment lengths,
    normals, the program's parameters, the points' columns, and the last refresh's rotation
    (3, 3), angular velocity (3) and arc length (1) (see :func:`_refresh_orientation`)."""

    points: FloatArray
    knots: FloatArray
    seg_len: FloatArray
    normals: FloatArray
    par: FloatArray
    columns: FloatArray
    rotation: FloatArray
    omega: FloatArray
    at_s: FloatArray
    orient: NDArray[np.int64]


@numba.njit(**KERNEL)
def _checked(
    tick: int, t: float, x: float, y: float, z: float, v: FloatArray, clock: Clock,
    checks: CheckArrays,
) -> bool:  # fmt: skip
    """After a tick: True when the ticks stop here. A wall-clock tick (and every hundredth
    check, the progress bar's) is the loop's to check; any other check tick is checked here,
    as the loop would (:func:`~seamtrack.simulation.progress.progress_check`, the torch tip
    (x, y, z) at the tick's start, its speed after it), logged in ``checks.log`` (rows t, s;
    the count in its last row's first column), and stops the ticks when the run ends there."""
    every = clock.check_every
    if tick % clock.wall_every == 0 or tick % (100 * every) == 0:
        return True
    if tick % every != 0:
        return False
    speed = math.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
    progress, log = checks.state, checks.log
    found = progress_check(progress, t, x, y, z, speed, checks.points, checks.knots,
                           checks.columns)  # fmt: skip
    m = int(log[-1, 0])
    log[m, 0], log[m, 1] = t, progress[S_NOW]
    log[-1, 0] = m + 1
    progress[CHECKED], progress[FOUND] = tick, found
    return found != GO_ON


@numba.njit(**KERNEL, inline="always")
def _usable_setpoint(
    follow: Follow, x: float, y: float, z: float, refused: FloatArray
) -> tuple[float, float, float, float, float, float, float, bool, bool]:
    """The set-point's step along the tracker's path from the torch tip (x, y, z): target,
    speed, feed-forward, stop at the target (:func:`setpoint_step`), and whether the command is
    usable (a speed in (0, inf), every value finite); an unusable one is written into
    ``refused``, for the loop to refuse as the reference path would."""
    tx, ty, tz, speed, fx, fy, fz, stop = setpoint_step(
        follow.setpoint, follow.path, follow.s, follow.envelope_s, follow.envelope_v, x, y, z
    )
    usable = 0.0 < speed < math.inf and math.isfinite(tx + ty + tz + fx + fy + fz)
    if not usable:
        refused[:] = (tx, ty, tz, speed, fx, fy, fz, 1.0 if stop else 0.0)
    return tx, ty, tz, speed, fx, fy, fz, stop, usable


@numba.njit(**KERNEL)
def gantry_ticks(
    clock: Clock, row: int, follow: Follow, gantry: GantryAxes, trace: Trace,
    checks: CheckArrays, refused: FloatArray,
) -> tuple[int, int]:  # fmt: skip
    """Control ticks from ``clock.tick`` on, until the next event: stops before a tick at
    which a frame is due (``next_capture``) or a measurement arrives (``next_arrival``), after
    a tick at which the loop checks the wall clock (``wall_every``; see :func:`_checked`), or
    at a target outside the travel (``LIMIT``), an unusable command (``REFUSED``: its target,
    speed, feed-forward and stop in ``refused``) or a progress check (every ``check_every``
    ticks, made here on ``checks``, see :class:`~seamtrack.simulation.progress.ProgressCheck`)
    that ends the run (``STOPPED``).

    Steps ``gantry``'s axes and ``follow``'s set-point in place and writes the torch tip and
    the target of each tick into ``trace``, rows from ``row`` on. Returns (ticks run, what
    stopped it).
    """
    offset, lim, servo, ipo, dt = gantry.offset, gantry.limits, gantry.servo, gantry.ipo, clock.dt
    axes = gantry.axes
    q, v, sq, sv, held = axes[0], axes[1], axes[2], axes[3], axes[4]
    sp, tcp_out, target_out = follow.setpoint, trace.tcp, trace.target
    has_servo = ipo[0] > 0
    tick = first = clock.tick
    while tick <= clock.max_ticks:
        t = tick * dt
        if tick > first and (t + 1e-9 >= clock.next_capture or clock.next_arrival <= t + 1e-9):
            break
        k = tick - first
        r = row + k
        x, y, z = q[0] + offset[0], q[1] + offset[1], q[2] + offset[2]
        tcp_out[r, 0], tcp_out[r, 1], tcp_out[r, 2] = x, y, z
        if not follow.seen:
            sp[TCP_X], sp[TCP_Y], sp[TCP_Z] = x, y, z  # the tracker's view of the torch
            target_out[r, :] = np.nan
            has_target = False
            tx = ty = tz = speed = fx = fy = fz = 0.0
            stop = False
        else:
            tx, ty, tz, speed, fx, fy, fz, stop, usable = _usable_setpoint(follow, x, y, z, refused)
            if not usable:
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
        if has_servo:  # CartesianRobot.step_move and Servo.follow
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
        if _checked(tick - 1, t, x, y, z, v, clock, checks):
            return tick - first, STOPPED if checks.state[FOUND] != GO_ON else EVENT
    return tick - first, EVENT


def follow(tracker: Any) -> Follow:
    """The built-in trajectory tracker's arrays as the compiled ticks step them, each of one
    type through a run: the stored path and arc lengths are views that
    :class:`~seamtrack.control.path_kernels.PathBuffer` cuts from float64 C arrays, and the
    envelope is always a new 1-D float64 array (it is replaced at every tracker update)."""
    path = tracker._buffer
    return Follow(
        tracker._sp, path.path, path.s, tracker._env_s, tracker._env_v, bool(tracker._seen_seam)
    )


class _Direct:
    """A compiled kernel called through its entry point while its arguments' types cannot
    have changed. numba's dispatcher types every argument of every call, a record of arrays
    in Python (about 2 us a record, against 0.1 us an array), and a stretch of ticks is short
    (10 ticks between two 100 Hz frames). Each stretch passes a new :class:`Clock` and
    :class:`Follow` (each field of one type through a run: :func:`clock`, :func:`follow`), its
    first row, and the records of the last stretch, the same objects until an array in them
    is replaced (a log grown): while they are, the call skips the dispatcher."""

    def __init__(self, kernel: Any) -> None:
        self.kernel = kernel
        self.records: tuple[Any, ...] = ()
        self.entry: Any = None

    def __call__(self, clock: Clock, row: int, follow: Follow, *records: Any) -> tuple[int, int]:
        last = self.records
        if len(last) == len(records) and all(a is b for a, b in zip(last, records, strict=True)):
            return self.entry(clock, row, follow, *records)
        kernel = self.kernel
        out = kernel(clock, row, follow, *records)
        types = tuple(kernel.typeof_pyval(a) for a in (clock, row, follow, *records))
        self.records, self.entry = records, kernel.overloads[types].entry_point
        return out


def clock(
    tick: int, max_ticks: int, dt: float, next_capture: float, next_arrival: float,
    check_every: int, wall_every: int,
) -> Clock:  # fmt: skip
    """A :class:`Clock`, each field of the type the kernels were compiled for."""
    return Clock(
        int(tick), int(max_ticks), float(dt), float(next_capture), float(next_arrival),
        int(check_every), int(wall_every),
    )  # fmt: skip


def _compile_ticks(kernel: Any, dt: float, count: Any, tracker: Any, *rest: Any) -> None:
    """Compile (or load from numba's cache) the built-in ``tracker``'s update kernel and the
    ticks ``kernel`` for the types ``kernel(clock, count, follow(tracker), *rest)`` has, without
    running either (:func:`seamtrack.jit.compile_for`)."""
    tracker.compile_kernels()
    compile_for(kernel, clock(0, 0, dt, 0.0, 0.0, 1, 1), count, follow(tracker), *rest)


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
        self.trace = Trace(self.tcp, self.target, self.axis, self.joints)

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
        self.trace = Trace(self.tcp, self.target, self.axis, self.joints)
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
        self.gantry = GantryAxes(self.offset, self.axes, self.lim, self.servo, self.ipo)
        self.refused = np.zeros(8)
        self._ticks = _Direct(gantry_ticks)

    def compile_kernels(self, state: RobotState, tracker: Any) -> None:
        """Compile (or load from numba's cache) :func:`gantry_ticks` for the types :meth:`run`
        calls it with, and the kernel of the built-in ``tracker``'s update, without running
        them (:func:`seamtrack.jit.compile_for`)."""
        _compile_ticks(
            gantry_ticks, self.dt, self.count, tracker, self.gantry, self.trace,
            self.checks.args, self.refused,
        )  # fmt: skip

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
        when = clock(tick, max_ticks, self.dt, next_capture, next_arrival, check_every, wall_every)
        n, why = self._ticks(
            when, self.count, follow(tracker), self.gantry, self.trace, self.checks.args,
            self.refused,
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


@numba.njit(**KERNEL)
def _refresh_orientation(
    x: float, y: float, z: float, speed: float, base: FloatArray, program: ToolProgram,
    cmd: FloatArray,
) -> None:  # fmt: skip
    """The tracker's tool-orientation refresh (:meth:`TrajectoryTracker.command_floats
    <seamtrack.control.trajectory.TrajectoryTracker.command_floats>`: the program's rotation
    and turning rate at the seam point closest to the set-point (x, y, z), moving at
    ``speed``) and the command's rotation in the base frame (``ArticulatedRobot.
    command_in_base``, ``_set_rotation``), kept in ``program``."""
    q = np.array((x, y, z))
    s = progress_near(
        program.points, program.knots, program.columns, q, program.at_s[0], program.knots[-1],
        NEAR_WINDOW_MM, SCALAR_NORM,
    )  # fmt: skip
    R, w = turning_at(
        s, speed, program.points, program.knots, program.seg_len, program.normals, program.par
    )
    program.rotation[:, :] = R
    program.omega[:] = w
    program.at_s[0] = s
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


@numba.njit(**KERNEL)
def arm_ticks(
    clock: Clock, row: int, follow: Follow, mount: ArmMount, model: ArmModel, data: ArmData,
    program: ToolProgram, trace: Trace, checks: CheckArrays, refused: FloatArray,
) -> tuple[int, int]:  # fmt: skip
    """:func:`gantry_ticks` for an arm and the built-in tracker: per tick the torch tip in the
    world (``mount.world``), the tracker's set-point step, the command in the base frame
    (``mount.base``), the reach check (``LIMIT``), the traces (torch tip, target, torch axis,
    joints) and the arm's compiled tick (:func:`~seamtrack.control.arm_kernels.arm_step` on
    ``model`` and ``data``). Every ``program.orient[0]``-th command of the tracker refreshes
    the tool orientation from the robot program (:func:`_refresh_orientation`). Returns
    (ticks run, what stopped it).
    """
    world, base, sp, cart, cmd = mount.world, mount.base, follow.setpoint, data.cart, data.cmd
    orient = program.orient
    tick = first = clock.tick
    k = 0
    while tick <= clock.max_ticks:
        t = tick * clock.dt
        if tick > first and (t + 1e-9 >= clock.next_capture or clock.next_arrival <= t + 1e-9):
            break
        q = cart[C_Q]
        x = world[0, 0] * q[0] + world[0, 1] * q[1] + world[0, 2] * q[2] + world[0, 3]
        y = world[1, 0] * q[0] + world[1, 1] * q[1] + world[1, 2] * q[2] + world[1, 3]
        z = world[2, 0] * q[0] + world[2, 1] * q[1] + world[2, 2] * q[2] + world[2, 3]
        r = row + k
        trace.tcp[r, 0], trace.tcp[r, 1], trace.tcp[r, 2] = x, y, z
        if not follow.seen:
            sp[TCP_X], sp[TCP_Y], sp[TCP_Z] = x, y, z  # the tracker's view of the torch
            trace.target[r, :] = np.nan
            cmd[M_HAS] = 0.0
        else:
            tx, ty, tz, speed, fx, fy, fz, stop, usable = _usable_setpoint(follow, x, y, z, refused)
            if not usable:
                return k, REFUSED
            orient[1] += 1
            if orient[1] % orient[0] == 0:
                _refresh_orientation(tx, ty, tz, sp[V_SET], base, program, cmd)
            trace.target[r, 0], trace.target[r, 1], trace.target[r, 2] = tx, ty, tz
            cmd[M_HAS] = 1.0
            for i in range(3):
                cmd[M_T + i] = base[i, 0] * tx + base[i, 1] * ty + base[i, 2] * tz + base[i, 3]
                cmd[M_FF + i] = base[i, 0] * fx + base[i, 1] * fy + base[i, 2] * fz
            cmd[M_SPEED], cmd[M_STOP] = speed, 1.0 if stop else 0.0
        R = data.rot[2]
        for i in range(3):
            trace.axis[r, i] = world[i, 0] * R[0, 2] + world[i, 1] * R[1, 2] + world[i, 2] * R[2, 2]
        trace.joints[r] = data.jnt[S_JOINTS]
        if cmd[M_HAS] > 0.0:
            d = math.sqrt(cmd[M_T] ** 2 + cmd[M_T + 1] ** 2 + cmd[M_T + 2] ** 2)
            if d > mount.reach:
                return k + 1, LIMIT
        arm_step(model, data)
        tick += 1
        k += 1
        if _checked(tick - 1, t, x, y, z, cart[C_V], clock, checks):
            return k, STOPPED if checks.state[FOUND] != GO_ON else EVENT
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
        self.mount = ArmMount(
            np.ascontiguousarray(robot.T_world_base[:3, :4]),
            np.ascontiguousarray(robot._T_base_world[:3, :4]),
            float(robot._reach_mm),
        )
        self._R, self._p0 = robot.T_world_base[:3, :3], robot.T_world_base[:3, 3]
        program = tracker._program
        points, knots, seg_len, normals, par = program._arrays
        self.program = ToolProgram(
            points, knots, seg_len, normals, par, np.ascontiguousarray(program.seam.points.T),
            np.zeros((3, 3)), np.zeros(3), np.zeros(1),
            np.array([tracker._orient_every, 0], dtype=np.int64),
        )  # fmt: skip
        self.orient = self.program.orient
        self.refused = np.zeros(8)
        self._refreshed = -1  # the orientation refresh last handed to the tracker
        self._started: tuple[Any, Any] = (None, None)  # the state and tracker of this run
        self._ticks = _Direct(arm_ticks)

    def _rotation(self, state: Any, tracker: Any) -> None:
        """The tracker's commanded rotation into the state's command, converted as
        ``command_in_base`` converts it."""
        rotation, omega = tracker._rotation, tracker._omega
        R = self.robot._T_base_world[:3, :3]
        rot_base = None if rotation is None else R @ np.asarray(rotation, dtype=float)
        omega_base = None if omega is None else R @ np.asarray(omega, dtype=float)
        self.robot._set_rotation(state, rot_base, omega_base)

    def compile_kernels(self, state: Any, tracker: Any) -> None:
        """Compile (or load from numba's cache) :func:`arm_ticks` for the types :meth:`run`
        calls it with, and the kernel of the built-in ``tracker``'s update, without running
        them (:func:`seamtrack.jit.compile_for`)."""
        _compile_ticks(
            arm_ticks, self.dt, self.count, tracker, self.mount, self.robot._model,
            state.data, self.program, self.trace, self.checks.args, self.refused,
        )  # fmt: skip

    def run(
        self, state: Any, tick: int, max_ticks: int, next_capture: float, next_arrival: float,
        check_every: int, wall_every: int, tracker: Any,
    ) -> tuple[int, int]:  # fmt: skip
        """Ticks from ``tick`` to the next event (see :func:`arm_ticks`); the ticks' torch
        tips, targets, torch axes and joints are logged (:class:`_Logs`)."""
        self.room(wall_every + 1)  # a stretch of ticks ends at a wall-clock tick
        self.checks.room(wall_every // check_every + 2)
        if self._started[0] is not state or self._started[1] is not tracker:
            # The first stretch: the tracker's orientation, from here on the ticks'.
            self.orient[1] = tracker._tick
            self.program.at_s[0] = tracker._s_program
            self._refreshed = tracker._tick // tracker._orient_every
            self._rotation(state, tracker)
            self._started = (state, tracker)
        when = clock(tick, max_ticks, self.dt, next_capture, next_arrival, check_every, wall_every)
        n, why = self._ticks(
            when, self.count, follow(tracker), self.mount, self.robot._model, state.data,
            self.program, self.trace, self.checks.args, self.refused,
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
        if self._started[1] is not tracker:
            return
        count = int(self.orient[1])
        if count // self.orient[0] != self._refreshed:
            tracker._rotation = self.program.rotation.copy()
            tracker._omega = self.program.omega.copy()
            tracker._s_program = float(self.program.at_s[0])
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
