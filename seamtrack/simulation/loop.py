"""The closed loop of the paper's Fig. 5: sense, track, move; then score the run.

Timing: the robot servo runs every control period; the sensor takes a frame every frame
period (captured at the robot's measured position at that tick); the frame reaches the tracker
``latency_s`` later. Time is ``tick * dt`` (an integer tick count, so no drift).

Scoring: the error is the distance from the torch tip to the true seam (the seam polyline of
the scene, or the CAD edge in mesh mode). The run starts with an approach from the start
position to the first seam point the sensor measured: before that point the tracker knows
nothing about the seam. The *welding portion* begins at arc-on, the first tick at which the
torch tip's closest seam point reaches the arc length of that first measured point, and lasts
to the end of the run. Every error statistic is over the welding portion only.

End of the run: the torch waits at rest, with the last frame showing no seam, for longer than
a frame period plus the latency (nothing new can come): ``completed`` when it got within
``end_tolerance_mm`` of the seam's end, else ``lost_seam``; ``stop_cause`` in the summary says
why it stopped (the tracker's own ``stop_cause`` when it has one). No
progress along the seam for ``stall_time_s`` (or the time or wall-clock limit) is ``stalled``,
its ``stop_cause`` ``stalled``, ``time_limit`` or ``wall_time_limit``; a commanded target
outside the axis travel is ``limit_violation``. A :class:`~seamtrack.simulation.stop.StopRequest`
(a signal, a bridge, a caller) stops the run at its next tick as ``interrupted``, scored up to
there. :func:`seamtrack.simulation.stop.outcome` names every end in one place.
"""

from __future__ import annotations

import math
import time
from array import array
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack import constants
from seamtrack.control.gate import GateSettings, SeamGate
from seamtrack.control.orientation import is_closed
from seamtrack.control.robot import MoveCommand
from seamtrack.control.tracking import Command, Measurement, TrackerContext
from seamtrack.errors import PluginRuntimeError, plugin_failed
from seamtrack.geometry.seam import Seam
from seamtrack.geometry.torch import torch_angles
from seamtrack.simulation.assemble import LoopSettings, Parts, build_parts
from seamtrack.simulation.progress import CHECKED, FOUND, GO_ON, LAST_SEEN, ProgressCheck
from seamtrack.simulation.scene import Scene, load_scene
from seamtrack.simulation.scoring import orientation_summary, torch_axes, with_joints
from seamtrack.simulation.stop import StopRequest, outcome
from seamtrack.simulation.ticks import LIMIT, REFUSED, STOPPED, compiled_ticks

FloatArray = NDArray[np.float64]

#: How often (in simulated seconds) progress along the seam is checked.
CHECK_PERIOD_S = 0.01

#: The wall-clock guard reads the clock every this many control ticks (a tick takes
#: microseconds, a mesh-mode frame milliseconds: the guard holds to well within a second).
WALL_CHECK_TICKS = 64


def _checked(
    cmd: Any, name: str, t_s: float, known_rotation: Any = None, known_omega: Any = None
) -> Command:
    """A tracker's command, refused with a clear error when it is not a usable move."""

    def refuse(what: str, fix: str) -> PluginRuntimeError:
        return PluginRuntimeError(
            f"{name!r} command() returned {what} at t = {t_s:.6g} s", field="tracker.name", fix=fix
        )

    if not isinstance(cmd, Command):
        raise refuse(type(cmd).__name__ + "; expected Command or None", "return Command(...)")
    target = np.asarray(cmd.target_world, dtype=float) if _numeric(cmd.target_world) else None
    if target is None or target.shape != (3,) or not np.isfinite(target).all():
        raise refuse(
            f"the target {cmd.target_world!r}",
            "give target_world as a finite (x, y, z) point in mm",
        )
    speed = cmd.speed_mm_s
    if isinstance(speed, bool) or not isinstance(speed, int | float) or not 0 < speed < math.inf:
        raise refuse(f"the speed {speed!r}", "give a finite speed > 0 mm/s (return None to stop)")
    ff = cmd.velocity_ff_world
    if ff is not None:
        ff_arr = np.asarray(ff, dtype=float) if _numeric(ff) else None
        if ff_arr is None or ff_arr.shape != (3,) or not np.isfinite(ff_arr).all():
            raise refuse(f"the feed-forward {ff!r}", "give a finite (vx, vy, vz) in mm/s or None")
    omega = cmd.angular_velocity_world
    if omega is not None and omega is not known_omega:
        omega_arr = np.asarray(omega, dtype=float) if _numeric(omega) else None
        if omega_arr is None or omega_arr.shape != (3,) or not np.isfinite(omega_arr).all():
            raise refuse(
                f"the angular velocity {omega!r}", "give a finite (wx, wy, wz) in rad/s or None"
            )
    rot = cmd.rotation_world
    if rot is not None and rot is not known_rotation:
        rot_arr = np.asarray(rot, dtype=float) if _numeric(rot) else None
        if (
            rot_arr is None
            or rot_arr.shape != (3, 3)
            or not np.isfinite(rot_arr).all()
            or not np.allclose(rot_arr.T @ rot_arr, np.eye(3), atol=1e-6)
            or np.linalg.det(rot_arr) < 0
        ):
            raise refuse(
                f"the rotation {rot!r}", "give rotation_world as a (3, 3) rotation matrix or None"
            )
    return cmd


def _numeric(value: Any) -> bool:
    try:
        np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return False
    return True


@dataclass(frozen=True, eq=False)
class Trace:
    """Per-tick record of a run (arrays share the tick index).

    Attributes
    ----------
    t_s : (n,) float
    tcp_world : (n, 3) float
    target_world : (n, 3) float
        Commanded target (NaN while the tracker commands nothing).
    closest_world : (n, 3) float
        Closest true seam point to the torch tip.
    arc_length_mm : (n,) float
        Its arc length.
    error_mm : (n,) float
        Distance torch tip to seam.
    error_lateral_mm, error_vertical_mm : (n,) float
        The error split along the seam's lateral direction (tangent x normal) and its torch
        normal.
    welding : (n,) bool
        The welding portion (arc-on to the end).
    frames : dict of arrays
        Per sensor frame: ``t_capture_s``, ``found``, ``point_world`` (k, 3; NaN if none).
    work_angle_error_rad, travel_angle_error_rad : (n,) float
        The torch's work and travel angles in the seam frame at the closest seam point, less
        the scene's (:mod:`seamtrack.geometry.torch`).
    joints_rad : (n, k) float
        An arm's joint positions (k = 0 for the gantry).
    """

    t_s: FloatArray
    tcp_world: FloatArray
    target_world: FloatArray
    closest_world: FloatArray
    arc_length_mm: FloatArray
    error_mm: FloatArray
    error_lateral_mm: FloatArray
    error_vertical_mm: FloatArray
    welding: NDArray[np.bool_]
    frames: dict[str, FloatArray] = field(default_factory=dict)
    work_angle_error_rad: FloatArray = field(default_factory=lambda: np.zeros(0))
    travel_angle_error_rad: FloatArray = field(default_factory=lambda: np.zeros(0))
    joints_rad: FloatArray = field(default_factory=lambda: np.zeros((0, 0)))
    #: [distortion]: how far the seam has moved at the torch (none without it)
    seam_shift_mm: FloatArray = field(default_factory=lambda: np.zeros(0))

    def decimated(self, period_s: float) -> NDArray[np.intp]:
        """Indices of ticks one ``period_s`` apart (plus the last tick)."""
        if len(self.t_s) < 2 or period_s <= 0:
            return np.arange(len(self.t_s))
        dt = self.t_s[1] - self.t_s[0]
        step = max(1, int(round(period_s / dt)))
        idx = np.arange(0, len(self.t_s), step)
        if idx[-1] != len(self.t_s) - 1:
            idx = np.append(idx, len(self.t_s) - 1)
        return idx


@dataclass(frozen=True, eq=False)
class Result:
    """A finished run: ``summary`` (the dict written as summary.json) and ``trace``."""

    summary: dict[str, Any]
    trace: Trace

    @property
    def status(self) -> str:
        return str(self.summary["status"])


def simulate(scene: Any, progress: bool = False) -> Result:
    """Run a scene (a :class:`~seamtrack.simulation.scene.Scene`, a built-in name or a path)."""

    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    return run(build_parts(scene), progress=progress, seed=scene.config.simulation.seed)


def run(
    parts: Parts,
    progress: bool = False,
    seed: int | None = None,
    clock: Callable[[], float] = time.perf_counter,
    stop: StopRequest | None = None,
) -> Result:
    """The loop, then the metrics.

    ``clock`` (seconds) drives the wall-clock guard; it is read every
    :data:`WALL_CHECK_TICKS` ticks whatever the control period, so the guard stops a run
    within about that many ticks of its limit. ``stop``: a request from outside, checked
    every tick the loop runs in Python (at least once a sensor frame); once it is made the
    run ends there as ``interrupted`` (the loop only reads it).

    Raises
    ------
    PluginRuntimeError
        The tracker raised, or returned what is not a usable :class:`Command`.
    """
    cfg = parts.settings
    rng = np.random.default_rng(cfg.seed if seed is None else seed)
    wall_start = clock()
    sense = _gated(parts.sense, cfg.gate)  # a new gate per run: it holds the run's state
    state = _start_state(parts)
    _reset_tracker(parts, rng)
    loop = _Loop(parts, sense, state, clock, wall_start, progress)
    loop.compile_kernels()
    ending = loop.ticks_until_end(stop if stop is not None else StopRequest())
    return loop.result(ending)


def _start_state(parts: Parts) -> Any:
    """The robot's state at the run's start: an arm at its start joints, a gantry with its
    torch tip at the start point."""
    robot = parts.robot
    if robot.turns_tool:
        return robot.state_at_joints(parts.start_joints)
    return robot.state_at(robot.q_from_world(parts.tcp_start_world))


def _reset_tracker(parts: Parts, rng: np.random.Generator) -> None:
    """Tell the tracker what it tracks with (:class:`TrackerContext`): the run's timing, the
    robot's limits in the world frame, the sensor, the tool program."""
    cfg, robot = parts.settings, parts.robot
    R = robot.T_world_base[:3, :3]
    context = TrackerContext(
        welding_speed_mm_s=cfg.welding_speed_mm_s,
        control_period_s=robot.control_period_s,
        frame_period_s=cfg.frame_period_s,
        latency_s=cfg.latency_s,
        look_ahead_mm=parts.look_ahead_mm,
        sensor_resolution_mm=parts.sensor_resolution_mm,
        tcp_start_world=np.array(parts.tcp_start_world, dtype=float),
        velocity_max_world=np.abs(R @ np.array(robot.velocity_max_mm_s)),
        acceleration_max_world=np.abs(R @ np.array(robot.acceleration_max_mm_s2)),
        rng=rng,
        tool_program=parts.tool_program,
        turns_tool=bool(robot.turns_tool),
    )
    try:
        parts.tracker.reset(context)
    except Exception as exc:  # the user's tracker may fail in any way
        raise plugin_failed("tracker.name", parts.tracker_name, "reset", 0.0, exc) from exc


_NAN3 = (math.nan, math.nan, math.nan)


class _Loop:
    """One run's loop: what it runs (robot, tracker, sense), what it logs (per tick and per
    frame), the frames on their way to the tracker and the progress checks."""

    def __init__(
        self,
        parts: Parts,
        sense: Callable[..., Any],
        state: Any,
        clock: Callable[[], float],
        wall_start: float,
        progress: bool,
    ) -> None:
        cfg = self.cfg = parts.settings
        robot = self.robot = parts.robot
        seam = self.seam = parts.seam
        self.parts, self.sense, self.state = parts, sense, state
        self.clock, self.wall_start = clock, wall_start
        self.tracker, self.name = parts.tracker, parts.tracker_name
        self.dt = dt = robot.control_period_s
        self.R, self.p0 = robot.T_world_base[:3, :3], robot.T_world_base[:3, 3]
        self.turns_tool = turns_tool = bool(robot.turns_tool)

        self.tcp_log: Any = array("d")  # or the compiled ticks' logs (ticks.tcp, ...)
        self.target_log: Any = array("d")
        self.frame_t = array("d")
        self.frame_found = array("b")
        self.frame_points = array("d")
        self.axis_log: Any = array("d")  # an arm's torch axis (world) and joints, per tick
        self.joint_log: Any = array("d")
        self.pending: deque[Measurement] = deque()
        self.sense_time = 0.0

        self.max_ticks = int(math.ceil(cfg.time_limit_s / dt))
        self.check_every = max(1, int(round(CHECK_PERIOD_S / dt)))
        rest_window = cfg.frame_period_s + cfg.latency_s + 2 * dt
        self.last_cmd: Command | None = None
        # the last command's rotation, angular velocity
        self.last_rot: tuple[Any, Any] = (None, None)
        self.move: MoveCommand | None = None
        self.bar = _progress_bar(progress, cfg.time_limit_s, seam.length_mm)
        self.closed = is_closed(seam)
        # The torch starts at the seam's start: progress follows the seam from there.
        done = seam.length_mm - cfg.end_tolerance_mm
        self.checks = ProgressCheck(seam, self.closed, done, cfg.stall_time_s, rest_window)
        self.unrotated = bool(np.array_equal(self.R, np.eye(3))) and not turns_tool
        # The fast paths: the built-in trajectory tracker's ticks between events compiled on an
        # unrotated gantry and on an arm (seamtrack.simulation.ticks); the same arithmetic.
        p0 = tuple(self.p0.tolist())
        self.ticks = compiled_ticks(
            robot, self.tracker, p0, self.unrotated, turns_tool, self.checks
        )
        # A tracker that knows where the seam is heading tells the extractor (``hint``): where
        # the laser plane crosses two grooves (a mitre) the extractor takes the V that
        # continues it.
        hint = getattr(self.tracker, "hint", None)
        self.tracker_hint = hint if callable(hint) and parts.sense_uses_hint else None

    def compile_kernels(self) -> None:
        """The compiled ticks' and the built-in tracker's kernels compiled (or loaded from
        numba's cache) before the first frame. On a first run (an empty cache) the run compiles
        them while its warming child compiles the extractor (:mod:`seamtrack.features.warm`),
        instead of after waiting for that child at the first frame's extraction."""
        if self.ticks is not None:  # the built-in trajectory tracker
            self.ticks.compile_kernels(self.state, self.tracker)

    def ticks_until_end(self, stop: StopRequest) -> StopRequest:
        """Tick until the run ends (its outcome, the loop's own ``stop`` or ``stop`` asked from
        outside); return how it ended."""
        cfg, dt, state, ticks, pending, checks = (
            self.cfg, self.dt, self.state, self.ticks, self.pending, self.checks
        )  # fmt: skip
        R, p0, unrotated, check_every = self.R, self.p0, self.unrotated, self.check_every
        p0x, p0y, p0z = p0.tolist()
        ending = StopRequest()  # how the run ended: outcome() names it after the loop
        next_capture = 0.0
        tcp: Any = None
        tcp_list: list[float] = []
        vel: Any = None
        tick = -1
        while tick < self.max_ticks:
            tick += 1
            t = tick * dt
            if ticks is not None:  # the compiled ticks log the torch tip (a frame takes it below)
                pass
            elif unrotated:  # the usual robot: spare the matrix products on this hot path
                q = state.q
                tcp_list = [q[0] + p0x, q[1] + p0y, q[2] + p0z]
                tcp = np.array(tcp_list)
                vel = np.array(state.v)
            else:
                tcp = R @ state.q + p0
                tcp_list = tcp.tolist()
                vel = R @ state.v
            if t + 1e-9 >= next_capture:
                next_capture += cfg.frame_period_s
                self._capture(t, tcp)
            if pending and pending[0].t_arrival_s <= t + 1e-9:
                self._deliver(t)
            if ticks is not None:
                tick = self._compiled_span(tick, next_capture, ending)
                t = tick * dt
                if ending.status:
                    break
            elif self._python_tick(t, tcp, tcp_list, vel, ending):
                break
            if stop.status:  # asked from outside (a signal, a bridge): stop here
                ending.end(stop.status, stop.reason, stop.cause)
                break
            if not tick % WALL_CHECK_TICKS and self._past_wall_time(ending):
                break
            if tick % check_every == 0 and tick != checks.P[CHECKED]:
                if self._progress_ends(tick, t, tcp_list, ending):
                    break
        return ending

    def _capture(self, t: float, tcp: Any) -> None:
        """A sensor frame at the robot's pose now (with the tracker's hint), on its way to the
        tracker; logged."""
        T_ws = self.robot.sensor_pose(self.state)
        tracker_hint = self.tracker_hint
        hint = tracker_hint(T_ws) if tracker_hint is not None else None  # the tracker's
        sense_start = self.clock()
        feature = self.sense(T_ws, t, hint) if hint is not None else self.sense(T_ws, t)
        self.sense_time += self.clock() - sense_start
        if self.ticks is not None:
            tcp = self.ticks.tcp_now(self.state)
        self.pending.append(Measurement(feature, t, t + self.cfg.latency_s, T_ws, tcp))
        self.frame_t.append(t)
        seen = bool(feature)
        self.frame_found.append(1 if seen else 0)
        self.frame_points.extend(feature.point_world if seen else _NAN3)

    def _deliver(self, t: float) -> None:
        """Hand the tracker every frame that has arrived by ``t``."""
        pending = self.pending
        while pending and pending[0].t_arrival_s <= t + 1e-9:
            measurement = pending.popleft()
            self.checks.P[LAST_SEEN] = 1.0 if measurement else 0.0
            try:
                self.tracker.update(measurement)
            except Exception as exc:
                raise plugin_failed("tracker.name", self.name, "update", t, exc) from exc

    def _compiled_span(self, tick: int, next_capture: float, ending: StopRequest) -> int:
        """The compiled ticks from ``tick`` up to the next event (a frame, an arrival, a check
        that ends the run); the last tick run (its checks follow). ``ending`` says when the
        span ended the run."""
        ticks, pending = self.ticks, self.pending
        assert ticks is not None
        arrival = pending[0].t_arrival_s if pending else math.inf
        n, why = ticks.run(
            self.state,
            tick,
            self.max_ticks,
            next_capture,
            arrival,
            self.check_every,
            WALL_CHECK_TICKS,
            self.tracker,
        )
        if why == REFUSED:  # what the reference path would refuse, refused the same way
            tx, ty, tz, speed, fx, fy, fz, at_target = ticks.refused.tolist()
            ff = np.array((fx, fy, fz))
            _checked(
                Command(np.array((tx, ty, tz)), speed, ff, at_target > 0),
                self.name,
                (tick + n) * self.dt,
            )
        if why == LIMIT:
            ending.end("limit_violation")
            return tick
        tick += n - 1
        if why == STOPPED:  # its own progress check ended the run
            ending.end(*self.checks.ended(int(self.checks.P[FOUND])))
        return tick

    def _python_tick(
        self, t: float, tcp: Any, tcp_list: list[float], vel: Any, ending: StopRequest
    ) -> bool:
        """One tick of a tracker in Python: its command (checked when it is a new one), the
        logs, the servo step. True: the command leaves the axis travel (the run ends)."""
        try:
            cmd = self.tracker.command(t, tcp, vel)
        except Exception as exc:
            raise plugin_failed("tracker.name", self.name, "command", t, exc) from exc
        if cmd is not self.last_cmd:
            self._take_command(cmd, t, ending)
        self.tcp_log.extend(tcp_list)
        if self.turns_tool:
            self.axis_log.extend((self.R @ self.state.R[:, 2]).tolist())
            self.joint_log.extend(self.state.joints.tolist())
        self.target_log.extend(_NAN3 if cmd is None else np.asarray(cmd.target_world).tolist())
        if ending.status:
            return True
        self.robot.step(self.state, self.move)
        return False

    def _take_command(self, cmd: Any, t: float, ending: StopRequest) -> None:
        """A new command from the tracker: checked, turned into the robot's move."""
        self.last_cmd = cmd
        self.move = (
            None
            if cmd is None
            else _to_move(self.robot, _checked(cmd, self.name, t, *self.last_rot))
        )
        self.last_rot = (
            (None, None) if cmd is None else (cmd.rotation_world, cmd.angular_velocity_world)
        )
        if self.move is not None and not self.robot.within_travel(self.move.target):
            ending.end("limit_violation")

    def _past_wall_time(self, ending: StopRequest) -> bool:
        """The wall-clock guard: the run has taken longer than it may (it ends ``stalled``)."""
        limit_s = self.cfg.wall_time_limit_s
        if self.clock() - self.wall_start > limit_s:
            ending.end("stalled", f"wall-clock limit {limit_s:g} s", "wall_time_limit")
            return True
        return False

    def _progress_ends(
        self, tick: int, t: float, tcp_list: list[float], ending: StopRequest
    ) -> bool:
        """The progress check along the seam (completed, lost, stalled: ``ending`` says which);
        the progress bar moves on."""
        ticks = self.ticks
        if ticks is not None:
            tcp_list = ticks.tcp[ticks.count - 1].tolist()
        found = self.checks.check(t, tcp_list, self.state.v)
        if found != GO_ON:
            ending.end(*self.checks.ended(found))
            return True
        bar = self.bar
        if bar is not None and tick % (self.check_every * 100) == 0:
            bar.update(t - bar.n)
        return False

    def result(self, ending: StopRequest) -> Result:
        """The run scored: its trace and summary."""
        cfg, robot, seam, ticks, state = self.cfg, self.robot, self.seam, self.ticks, self.state
        if self.bar is not None:
            self.bar.close()
        if not ending.status:
            ending.end("stalled", f"time limit {cfg.time_limit_s:g} s", "time_limit")
        status, stop_reason, stop_cause = outcome(
            ending, self.closed, getattr(self.tracker, "stop_cause", "")
        )
        tcp_log, target_log = self.tcp_log, self.target_log
        axis_log, joint_log = self.axis_log, self.joint_log
        if ticks is not None:  # every tick ran compiled, and logged there
            ticks.finish(state, self.tracker)
            tcp_log, target_log = ticks.tcp[: ticks.count], ticks.target[: ticks.count]
            axis_log, joint_log = ticks.axis[: ticks.count], ticks.joints[: ticks.count]

        axis = torch_axes(robot, axis_log)
        trace = _trace(
            seam, self.dt, tcp_log, target_log, self.frame_t, self.frame_found, self.frame_points,
            (self.checks.t_log, self.checks.s_log),
            axis, (cfg.work_angle_rad, cfg.travel_angle_rad),
        )  # fmt: skip
        trace = with_joints(trace, joint_log, robot)
        moving = self.parts.moving
        if moving is not None:  # scored against the seam where it is at each tick
            trace = moving.rescore(trace)
        summary = _summary(trace, seam, status, cfg, self.clock() - self.wall_start)
        if moving is not None:
            summary.update(moving.summary(trace))
        summary.update(orientation_summary(trace, robot, cfg, state))
        summary["stop_reason"] = stop_reason
        summary["stop_cause"] = stop_cause
        summary["sense_wall_time_s"] = self.sense_time
        summary.update(_gate_summary(self.sense))
        return Result(summary=summary, trace=trace)


class _GatedSense:
    """``sense`` with the seam-point gate of one run on its features
    (:mod:`seamtrack.control.gate`)."""

    def __init__(self, sense: Callable[..., Any], settings: GateSettings) -> None:
        self.sense, self.gate = sense, SeamGate(settings)

    def __call__(self, T_world_sensor: FloatArray, t_s: float, *hint: Any) -> Any:
        return self.gate(self.sense(T_world_sensor, t_s, *hint), T_world_sensor)


def _gated(sense: Callable[..., Any], gate: GateSettings | None) -> Callable[..., Any]:
    """``sense`` through a new seam-point gate, or ``sense`` itself without one."""
    return sense if gate is None else _GatedSense(sense, gate)


def _gate_summary(sense: Callable[..., Any]) -> dict[str, int]:
    """What the gate did (summary keys ``gate_*``), none without a gate: frames accepted,
    refused (a point outside the window), handed on as a prediction, and re-acquisitions."""
    if not isinstance(sense, _GatedSense):
        return {}
    g = sense.gate
    return {"gate_accepted": g.accepted, "gate_refused": g.refused,
            "gate_predicted": g.predicted, "gate_reacquired": g.reacquired}  # fmt: skip


def _to_move(robot: Any, cmd: Command) -> MoveCommand:
    args = (cmd.target_world, cmd.speed_mm_s, cmd.velocity_ff_world, cmd.stop_at_target)
    if cmd.rotation_world is None:
        return robot.command_in_base(*args)
    return robot.command_in_base(
        *args, rotation_world=cmd.rotation_world, angular_velocity_world=cmd.angular_velocity_world
    )


def _progress_bar(enabled: bool, total_s: float, length_mm: float) -> Any:
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(
        total=None,
        unit="sim s",
        desc=f"seam {length_mm:.0f} mm",
        leave=False,
        bar_format="{desc}: {n:.1f} {unit} [{elapsed}, {rate_fmt}]",
    )


def _trace(
    seam: Seam,
    dt: float,
    tcp_log: array | FloatArray,  # the loop's logs, or the compiled ticks' (rows)
    target_log: array | FloatArray,
    frame_t: array,
    frame_found: array,
    frame_points: array,
    progress: tuple[FloatArray, FloatArray],
    axis_world: FloatArray | None = None,
    angles_rad: tuple[float, float] = (0.0, 0.0),
) -> Trace:
    tcp = np.frombuffer(tcp_log, dtype=np.float64).reshape(-1, 3).copy()
    target = np.frombuffer(target_log, dtype=np.float64).reshape(-1, 3).copy()
    n = len(tcp)
    t_s = np.arange(n, dtype=np.float64) * dt
    closest = seam.closest(tcp)
    # Progress along the seam, followed continuously during the run (so a stretch of seam
    # that passes close by, like a hairpin's other leg, is not mistaken for progress); the
    # error itself is the distance to the nearest point of the whole seam.
    check_t = np.frombuffer(progress[0], dtype=np.float64)
    check_s = np.frombuffer(progress[1], dtype=np.float64)
    arc_length = np.interp(t_s, check_t, check_s) if len(check_t) else closest.arc_length_mm
    error_vec = tcp - closest.points
    seg = closest.segment
    tangent = seam.points[seg + 1] - seam.points[seg]
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    # Torch normal at the closest point, interpolated between the segment's end normals.
    w = np.clip(
        (closest.arc_length_mm - seam.arc_length_mm[seg]) / seam.segment_lengths_mm[seg], 0.0, 1.0
    )[:, None]
    normal = (1 - w) * seam.normals[seg] + w * seam.normals[seg + 1]
    normal -= np.sum(normal * tangent, axis=1, keepdims=True) * tangent
    normal /= np.linalg.norm(normal, axis=1, keepdims=True)
    lateral = np.cross(tangent, normal)
    if axis_world is None:
        axis_world = np.array([0.0, 0.0, 1.0])
    angles = torch_angles(axis_world, tangent, normal) if n else np.zeros((0, 2))
    work_err = _wrap(angles[:, 0] - angles_rad[0])
    travel_err = _wrap(angles[:, 1] - angles_rad[1])
    frames = {
        "t_capture_s": np.frombuffer(frame_t, dtype=np.float64).copy(),
        "found": np.frombuffer(frame_found, dtype=np.int8).astype(bool),
        "point_world": np.frombuffer(frame_points, dtype=np.float64).reshape(-1, 3).copy(),
    }
    welding = np.zeros(n, dtype=bool)
    if frames["found"].any():
        first_point = frames["point_world"][np.argmax(frames["found"])]
        s_first = float(seam.closest(first_point).arc_length_mm[0])
        arc_on = np.flatnonzero(arc_length >= s_first - constants.PROGRESS_EPS_MM)
        if len(arc_on):
            welding[arc_on[0] :] = True
        # Past the seam's end the torch is off the joint: that is overrun, not welding.
        at_end = np.flatnonzero(arc_length >= seam.length_mm - 1e-9)
        if len(at_end):
            welding[at_end[0] + 1 :] = False
    return Trace(
        t_s=t_s,
        tcp_world=tcp,
        target_world=target,
        closest_world=closest.points,
        arc_length_mm=arc_length,
        error_mm=closest.distance_mm,
        error_lateral_mm=np.sum(error_vec * lateral, axis=1),
        error_vertical_mm=np.sum(error_vec * normal, axis=1),
        welding=welding,
        frames=frames,
        work_angle_error_rad=work_err,
        travel_angle_error_rad=travel_err,
    )


def _wrap(angle: FloatArray) -> FloatArray:
    return (angle + np.pi) % (2 * np.pi) - np.pi


def _summary(
    trace: Trace, seam: Seam, status: str, cfg: LoopSettings, wall_time_s: float
) -> dict[str, Any]:
    weld = trace.welding
    err = trace.error_mm[weld]
    nan = float("nan")
    stats = {
        "max_error_mm": nan,
        "min_error_mm": nan,
        "mean_error_mm": nan,
        "rms_error_mm": nan,
        "p95_error_mm": nan,
    }
    mean_speed = nan
    speed_kept = nan
    welded = 0.0
    if err.size:
        stats = {
            "max_error_mm": float(err.max()),
            "min_error_mm": float(err.min()),
            "mean_error_mm": float(err.mean()),
            "rms_error_mm": float(np.sqrt(np.mean(err**2))),
            "p95_error_mm": float(np.percentile(err, 95)),
        }
        i0 = int(np.argmax(weld))
        s = trace.arc_length_mm
        s_end = float(np.max(s[i0:]))
        # A completed run ends with the torch waiting at the seam's end: not welding time. Any
        # other run's waiting is exactly what its mean speed must show.
        i1 = (
            i0 + int(np.argmax(s[i0:] >= s_end - constants.PROGRESS_EPS_MM))
            if status == "completed"
            else len(s) - 1
        )
        welded = s_end - float(s[i0])
        if i1 > i0:
            duration = trace.t_s[i1] - trace.t_s[i0]
            mean_speed = welded / duration
            dt = trace.t_s[1] - trace.t_s[0]
            speed = np.linalg.norm(np.diff(trace.tcp_world[i0 : i1 + 1], axis=0), axis=1) / dt
            speed_kept = float(
                np.mean(np.abs(speed - cfg.welding_speed_mm_s) <= 0.1 * cfg.welding_speed_mm_s)
            )
    found = np.asarray(trace.frames.get("found", np.zeros(0)), dtype=bool)
    # The error as a system that logs only at its sensor frames would see it.
    frame_ticks = np.searchsorted(trace.t_s, trace.frames.get("t_capture_s", np.zeros(0)))
    frame_ticks = frame_ticks[frame_ticks < len(weld)]
    at_frames = trace.error_mm[frame_ticks[weld[frame_ticks]]]
    s_max = float(np.max(trace.arc_length_mm)) if len(trace.arc_length_mm) else 0.0
    past_end = trace.arc_length_mm >= seam.length_mm - 1e-9
    overrun = float(np.max(trace.error_mm[past_end])) if past_end.any() else 0.0
    return {
        "status": status,
        **stats,
        "max_error_at_frames_mm": float(at_frames.max()) if at_frames.size else nan,
        "min_error_at_frames_mm": float(at_frames.min()) if at_frames.size else nan,
        "sim_time_s": float(trace.t_s[-1]) if len(trace.t_s) else 0.0,
        "wall_time_s": wall_time_s,
        "frames": len(found),
        "frames_without_seam": int(np.count_nonzero(~found)),
        "seam_length_mm": seam.length_mm,
        "welded_length_mm": welded,
        "completed_fraction": min(1.0, s_max / seam.length_mm),
        "overrun_mm": overrun,
        "mean_speed_mm_s": mean_speed,
        "speed_kept_fraction": speed_kept,
        "welding_speed_mm_s": cfg.welding_speed_mm_s,
        "seed": cfg.seed,
    }
