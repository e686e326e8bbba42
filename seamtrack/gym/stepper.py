"""The closed loop as the environment steps it, its ticks compiled: :class:`HeldRun`, one run
frame by frame, and :class:`TickBatch`, the compiled ticks of many runs in one call.

:class:`~seamtrack.gym.lockstep.LockstepRun` runs :func:`seamtrack.simulation.loop.run` itself,
whose ticks for a Python tracker go one by one in Python. Here the loop's events stay in Python
(a frame captured and sensed, a measurement arriving, a new command taken) and the ticks between
them run compiled (:func:`seamtrack.gym.ticks.held_ticks`), in the loop's order and with its
arithmetic: the same profiles, torch states and endings (``tests/test_gym_ticks.py`` steps
both side by side). It serves the loop's usual case: a gantry whose base is not rotated, a part
that does not move; :func:`supports` says whether a scene's parts are one.

A batch (:class:`TickBatch`) keeps every run's axes, command and progress check in rows of
shared arrays, so the vector environment steps the ticks of all its scenes in one compiled call
between their sensing.
"""

from __future__ import annotations

import math
from collections import deque

import numpy as np
from numpy.typing import NDArray

from seamtrack.control.gate import SeamGate
from seamtrack.control.orientation import is_closed
from seamtrack.control.robot import CartesianRobot
from seamtrack.control.tracking import Command, Measurement
from seamtrack.geometry.frames import invert
from seamtrack.gym import ticks
from seamtrack.gym.lockstep import Ended, Frame
from seamtrack.gym.ticks import A_Q, A_V, ENDED, EVENT, TIME_OVER, held_ticks
from seamtrack.sensing.profiles import Profile
from seamtrack.simulation.assemble import Parts
from seamtrack.simulation.loop import CHECK_PERIOD_S
from seamtrack.simulation.progress import (
    LAST_SEEN,
    PROGRESS_FIELDS,
    ProgressCheck,
    ProgressTracker,
)
from seamtrack.simulation.ticks import GantryTicks

FloatArray = NDArray[np.float64]
_EYE4 = np.eye(4)


def supports(parts: Parts) -> bool:
    """Whether :class:`HeldRun` runs these parts as the loop would: a Cartesian gantry with an
    unrotated base, a scan (mesh or image mode), no part that moves during the run."""
    robot = parts.robot
    return (
        type(robot) is CartesianRobot
        and not robot.turns_tool
        and bool(np.array_equal(robot.T_world_base[:3, :3], np.eye(3)))
        and parts.scan is not None
        and parts.moving is None
    )


class TickBatch:
    """The compiled ticks of ``n`` runs of one scene: one row each in the arrays of
    :func:`seamtrack.gym.ticks.batch_arrays`, the settings they share (the loop's timing, the
    robot's limits and servo, the seam the progress checks follow), from the first run's
    parts."""

    def __init__(self, parts: Parts, n: int) -> None:
        robot, cfg, seam = parts.robot, parts.settings, parts.seam
        self.n = n
        self.dt = dt = robot.control_period_s
        self.max_ticks = int(math.ceil(cfg.time_limit_s / dt))  # as the loop counts them
        self.check_every = max(1, int(round(CHECK_PERIOD_S / dt)))
        self.tcp_offset = np.ascontiguousarray(robot.T_world_base[:3, 3], dtype=np.float64)
        # a world point less this is the base frame's (``command_in_base``'s shift, bit for bit)
        shift = invert(robot.T_world_base)[:3, 3]
        self.base_shift = (float(shift[0]), float(shift[1]), float(shift[2]))
        gantry = GantryTicks(robot, tuple(self.tcp_offset.tolist()), _checks(parts))
        self.limits, self.servo, self.ipo_every = gantry.lim, gantry.servo, int(gantry.ipo[0])
        near = ProgressTracker(seam)
        self.seam = (near.points, near.knots, near.columns)
        self.arrays = a = ticks.batch_arrays(n)
        self.progress = np.zeros((n, PROGRESS_FIELDS))
        self.first, self.next_capture, self.next_arrival = a.first, a.next_capture, a.next_arrival
        self.axes, self.counters, self.command = a.axes, a.counters, a.command
        self.ran, self.why = a.ran, a.why

    def run(self, rows: NDArray[np.int64]) -> None:
        """The ticks of runs ``rows`` to each one's next event or end (``ran``, ``why``)."""
        held_ticks(
            rows, self.first, self.next_capture, self.next_arrival, self.max_ticks, self.dt,
            self.check_every, self.tcp_offset, self.limits, self.servo, self.axes, self.counters,
            self.command, self.progress, *self.seam, self.ran, self.why,
        )  # fmt: skip


def _checks(parts: Parts) -> ProgressCheck:
    """A run's progress check as the loop sets it up."""
    cfg, seam = parts.settings, parts.seam
    rest_window = cfg.frame_period_s + cfg.latency_s + 2 * parts.robot.control_period_s
    done = seam.length_mm - cfg.end_tolerance_mm
    return ProgressCheck(seam, is_closed(seam), done, cfg.stall_time_s, rest_window)


class HeldRun:
    """One run of the loop, stepped frame by frame (the interface of
    :class:`~seamtrack.gym.lockstep.LockstepRun`), its ticks in row ``row`` of ``batch``.

    Parameters
    ----------
    parts : Parts
        The scene's parts (:func:`supports`); the tracker's is the caller's part.
    batch : TickBatch, optional
        Where the ticks run (default: a batch of one of its own).
    row : int
        This run's row in ``batch``.
    """

    def __init__(self, parts: Parts, batch: TickBatch | None = None, row: int = 0) -> None:
        self.batch = batch = TickBatch(parts, 1) if batch is None else batch
        self.row = row
        self.rows = np.array([row], dtype=np.int64)
        self.parts = parts
        robot, cfg = parts.robot, parts.settings
        assert parts.scan is not None
        self.scan = parts.scan
        # The plane section's seeds (the last stripe's triangles, cut first) belong to the
        # caster; a caster shared by many runs keeps each run's own here.
        self.caster = parts.caster
        self.section_seeds = None if parts.caster is None else parts.caster.section_seeds
        self.robot = robot
        self.frame_period_s, self.latency_s = cfg.frame_period_s, cfg.latency_s
        self.gate = SeamGate(cfg.gate) if cfg.gate is not None else None
        self.checks = _checks(parts)
        state = robot.state_at(robot.q_from_world(parts.tcp_start_world))
        axes, counters = batch.axes[row], batch.counters[row]
        axes[:] = 0.0
        axes[A_Q], axes[A_V] = state.q, state.v
        counters[ticks.I_EVERY], counters[ticks.I_COUNT] = batch.ipo_every, 0
        if state.servo is not None and batch.ipo_every > 0:
            assert state.setpoint is not None
            axes[ticks.A_SQ], axes[ticks.A_SV] = state.setpoint.q, state.setpoint.v
            axes[ticks.A_HELD] = state.servo.held
            counters[ticks.I_COUNT] = state.servo.tick
        batch.progress[row] = self.checks.P
        batch.command[row] = 0.0  # no target: the axes brake (they are at rest)
        batch.first[row] = 0
        batch.next_capture[row] = 0.0
        batch.next_arrival[row] = math.inf
        self.tick = 0  # the tick whose events come next
        self.pending: deque[tuple[Profile, Measurement]] = deque()
        self.ended: Ended | None = None

    # ------------------------------------------------------------------ the frame's steps
    def take(self, command: Command) -> Ended | None:
        """The command to hold from this tick on (the loop's ``_take_command``: converted to
        the base frame; a target outside the axis travel ends the run)."""
        if self.ended is not None:
            return self.ended
        move = self.robot.command_in_base(
            command.target_world, command.speed_mm_s, command.velocity_ff_world,
            command.stop_at_target,
        )  # fmt: skip
        if not self.robot.within_travel(move.target):
            return self._end("limit_violation", self.tick * self.batch.dt)
        row = self.batch.command[self.row]
        row[ticks.C_HAS] = 1.0
        row[ticks.C_X : ticks.C_X + 3] = move.target
        row[ticks.C_SPEED] = move.speed
        row[ticks.C_FX : ticks.C_FX + 3] = move.feed_forward
        row[ticks.C_STOP] = 1.0 if move.stop_at_target else 0.0
        return None

    def hold(
        self, target_world: tuple[float, float, float], speed_mm_s: float, stop: bool
    ) -> Ended | None:
        """:meth:`take` of ``Command(target_world, speed_mm_s, None, stop)`` on floats (the
        environment's command every step)."""
        if self.ended is not None:
            return self.ended
        tx, ty, tz = self.batch.base_shift
        x, y, z = target_world
        target = (x + tx, y + ty, z + tz)
        if not self.robot.within_travel(target):
            return self._end("limit_violation", self.tick * self.batch.dt)
        row = self.batch.command[self.row]
        row[ticks.C_HAS : ticks.C_Z + 1] = (1.0, *target)
        row[ticks.C_SPEED : ticks.C_STOP + 1] = (speed_mm_s, 0.0, 0.0, 0.0, 1.0 if stop else 0.0)
        return None

    def advance(
        self, target_world: tuple[float, float, float], speed_mm_s: float, stop: bool
    ) -> Frame | Ended:
        """:meth:`next_frame` of the command :meth:`hold` takes."""
        ended = self.hold(target_world, speed_mm_s, stop)
        if ended is not None:
            return ended
        return self._run_to_frame()

    def after_ticks(self) -> Frame | Ended | None:
        """After the batch ran this row's ticks: the run's end, or the events of the tick it
        stopped before (a frame captured, a measurement arriving): the frame that arrived, or
        None (more ticks to run before one does)."""
        batch, row = self.batch, self.row
        why, ran = int(batch.why[row]), int(batch.ran[row])
        if why == TIME_OVER:
            return self._end("stalled", batch.max_ticks * batch.dt)
        if why >= ENDED:
            self.checks.P[:] = batch.progress[row]
            status, _ = self.checks.ended(why - ENDED)
            return self._end(status, (self.tick + ran - 1) * batch.dt)
        assert why == EVENT
        self.tick += ran
        return self.events()

    def events(self) -> Frame | None:
        """The loop's events at :attr:`tick`: a frame captured (sensed now), the frame that
        arrives (handed out, with the torch's state at this tick), and where the next ticks
        start."""
        batch, row, tick = self.batch, self.row, self.tick
        t = tick * batch.dt
        q = batch.axes[row, A_Q]
        ox, oy, oz = batch.tcp_offset.tolist()
        qx, qy, qz = q.tolist()
        tcp_list = [qx + ox, qy + oy, qz + oz]
        if t + 1e-9 >= batch.next_capture[row]:
            batch.next_capture[row] += self.frame_period_s
            self._capture(t, q, tcp_list)
        frame = None
        pending = self.pending
        if pending and pending[0][1].t_arrival_s <= t + 1e-9:
            profile, measurement = pending.popleft()
            while pending and pending[0][1].t_arrival_s <= t + 1e-9:  # never at a frame rate
                profile, measurement = pending.popleft()
            batch.progress[row, LAST_SEEN] = 1.0 if measurement else 0.0
            velocity = batch.axes[row, A_V].copy()
            frame = Frame(profile, measurement.feature, measurement, t, np.array(tcp_list),
                          velocity)  # fmt: skip
        batch.first[row] = tick
        batch.next_arrival[row] = pending[0][1].t_arrival_s if pending else math.inf
        return frame

    def _capture(self, t: float, q: FloatArray, tcp_list: list[float]) -> None:
        """A sensor frame at the axes' position now (``robot.sensor_pose``'s arithmetic)."""
        T = _EYE4.copy()
        T[:3, 3] = q
        robot = self.robot
        T_ws = robot.T_world_base @ T @ robot.T_tcp_sensor
        caster = self.caster
        if caster is not None:  # a shared caster: this run's seeds (they only save work)
            caster.section_seeds = self.section_seeds
        profile, feature = self.scan(T_ws, t, None)
        if caster is not None:
            self.section_seeds = caster.section_seeds
        if self.gate is not None:
            feature = self.gate(feature, T_ws)
        self.pending.append(
            (profile, Measurement(feature, t, t + self.latency_s, T_ws, np.array(tcp_list)))
        )

    def _end(self, status: str, t_s: float) -> Ended:
        self.ended = Ended(status=status, t_s=t_s)
        return self.ended

    # ------------------------------------------------------------------ LockstepRun's interface
    def next_frame(self, command: Command | None = None, first: bool = False) -> Frame | Ended:
        """Hold the command (none for the first frame), then run to the next frame that
        arrives, or to the end of the run."""
        if self.ended is not None:
            return self.ended
        if first:
            frame = self.events()
            if frame is not None:
                return frame
        elif command is not None:
            ended = self.take(command)
            if ended is not None:
                return ended
        return self._run_to_frame()

    def _run_to_frame(self) -> Frame | Ended:
        while True:
            self.batch.run(self.rows)
            out = self.after_ticks()
            if out is not None:
                return out

    def stop(self) -> None:
        """End the run (nothing runs between calls: this only marks it ended)."""
        self.ended = self.ended or Ended(status="interrupted")

    @property
    def alive(self) -> bool:
        """Whether the run goes on."""
        return self.ended is None
