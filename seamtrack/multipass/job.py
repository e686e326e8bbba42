"""A multi-pass job: every pass a full closed loop on the part and the beads laid before it.

:func:`run_job` runs a scene with ``[passes]``:

1. The empty groove's fill state (:class:`seamtrack.workpiece.fill.FillState`, stations every
   0.5 mm along the CAD seam) and, with ``passes.scan_first``, a scan-only pass (torch off; its
   time counts in the job's time) that measures the groove.
2. For each pass the planner (:mod:`seamtrack.control.planner`) gets the groove as the sensor
   measured it during the pass before (the groove extractor's 7 points and remaining area per
   frame, binned per station) and returns the pass: reference (a wall's foot, the middle, a
   top corner), lateral offset, travel speed (a profile along the seam), wire feed. The scene's
   ``[[passes.overrides]]`` replace its values.
3. The pass runs as :func:`seamtrack.simulation.loop.run` on parts built with the beads' mesh
   joined to the workpiece's (:func:`~seamtrack.simulation.assemble.build_parts`'s
   ``extra_mesh``), the groove extractor's ``reference`` set to the plan's, the plan's offset
   applied across the seam to every measured point, and the tracker's speed set along the seam
   from the plan's profile (and the planner's ``adapt``, when it has one). The pass is scored
   against its true path: the reference point of the true fill surface plus the offset.
4. After the pass the bead is laid along the torch's actual path (tracking errors included)
   with the area from mass conservation at the torch's actual speed
   (:meth:`FillState.deposit`). The arc is on over the run's welding portion; the speed in the
   area is bounded below by the process window (slower, at the crater, the arc is off).

The job's summary (``job.json``): passes, layers, beads per layer, the final reinforcement
along the seam (min, max, spread), the remaining underfill, the sidewall fusion margin per
station (how far the wall beads' toes reach into the wall; flagged below
``passes.fusion_margin_min_mm``), heat input per pass and the total arc time. Stations are
scored over the part of the seam every pass welded (the torch strikes the arc where the sensor,
``look_ahead_mm`` ahead of it, first saw the seam).
"""

from __future__ import annotations

import dataclasses
import gc
import math
import threading
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.control.fill_layout import Layout, MeasuredGroove, after_bead, layout
from seamtrack.control.planner import JobState, PassPlan, checked_plan, is_builtin, planner
from seamtrack.errors import PluginRuntimeError, SceneError, plugin_failed
from seamtrack.geometry.seam import Seam
from seamtrack.multipass.aim import wall_deg
from seamtrack.multipass.distortion import (
    JobDistortion,
    distorted_parts,
    into_the_part,
    locked_in,
    still,
)
from seamtrack.multipass.paths import (
    STATION_SPACING_MM,
    FrameGroove,
    arc_path,
    handover,
    measured_groove,
    pass_path,
    ramped,
    to_the_ends,
    true_groove,
)
from seamtrack.multipass.steering import SteeredSense
from seamtrack.multipass.summary import job_summary
from seamtrack.sensing.profiles import Feature
from seamtrack.simulation.assemble import Parts, build_parts
from seamtrack.simulation.checks import default_time_limit_s
from seamtrack.simulation.loop import Result, run
from seamtrack.simulation.process import heat_input_kj_mm, overridden, process_of
from seamtrack.simulation.robots import is_arm, tool_program
from seamtrack.simulation.scene import Scene, load_scene
from seamtrack.simulation.stop import INTERRUPTED, StopRequest
from seamtrack.workpiece.beads import bead_area_mm2

if TYPE_CHECKING:
    from seamtrack.workpiece.fill import FillState

FloatArray = NDArray[np.float64]

#: The most passes a job lays: ``passes.count``'s bound, and where an ``auto`` plan that is
#: not done by then stops (a plan the CAD groove says needs more is refused before the run).
MAX_PASSES = 200


@dataclass(frozen=True, eq=False)
class PassRecord:
    """One pass of a job: its plan (None for the scan-only pass), the run, what it laid."""

    name: str
    plan: PassPlan | None
    result: Result
    arc_time_s: float
    mean_speed_mm_s: float
    bead_area_mm2: float  # mean over the path
    heat_input_kj_mm: float
    build_s: float  # parts built: the workpiece and the beads joined, the Embree scene
    run_s: float
    deposit_s: float
    scene: Scene
    plan_s: float = 0.0  # the planner's plan() for this pass (wall time)
    plan_cpu_s: float = 0.0  # the same, the CPU time of the job's thread (time.thread_time)


@dataclass(frozen=True)
class PlanTime:
    """The planner's time for a pass (s): wall time, and the CPU time the job's thread spent
    in it (:func:`time.thread_time`), which a loaded machine's other processes do not add
    to (on 2 cores at a load of 8-15 a 2 ms plan() took 17-41 ms of wall time once a job)."""

    wall_s: float
    cpu_s: float


@dataclass(frozen=True, eq=False)
class JobResult:
    """A finished job: ``summary`` (written as job.json), the passes, the final fill state."""

    summary: dict[str, Any]
    passes: list[PassRecord]
    fill: FillState  # FillState

    @property
    def status(self) -> str:
        return str(self.summary["status"])


def run_job(
    scene: Scene | str,
    progress: bool = False,
    planner_override: Any = None,
    on_pass: Any = None,
    stop: StopRequest | None = None,
) -> JobResult:
    """Run a multi-pass job (a scene with ``[passes]``); see the module docstring.

    ``planner_override``: a planner instance used instead of the scene's; ``on_pass(record,
    fill)`` is called after each pass (a notebook's or a bench's hook). ``stop``: a request
    from outside (a signal); the pass it lands in ends there as ``interrupted``, and the job
    with it (status ``interrupted``, the passes up to the stop kept).

    Memory: the objects that exist when the job starts are frozen out of Python's garbage
    collections for its duration (:func:`gc.freeze`, unless the caller froze some already),
    so the full collection after each pass scans only the job's own.
    """
    frozen = gc.get_freeze_count() == 0
    if frozen:
        gc.collect()
        gc.freeze()
    try:
        return _run_job(scene, progress, planner_override, on_pass, frozen, stop)
    finally:
        if frozen:
            gc.unfreeze()


def _run_job(
    scene: Scene | str,
    progress: bool,
    planner_override: Any,
    on_pass: Any,
    freeze: bool,
    stop: StopRequest | None = None,
) -> JobResult:
    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    c = scene.config
    if c.passes is None:
        raise SceneError(
            "the scene has no [passes]", field="passes", fix="add [passes] for a multi-pass job"
        )
    from seamtrack.workpiece.beads import BeadShape

    rng, cad_seam, fill, flip = _empty_groove(scene)
    process = process_of(c)
    shape = bead_shape(c, BeadShape)
    name, plan_maker, adapt = _planner_of(c, planner_override)
    count = c.passes.count if isinstance(c.passes.count, int) else None
    state = JobState(process, count=count, reinforcement_mm=c.passes.reinforcement_mm)
    _check_bead_fits(fill, process, c)
    planned_layout(fill, c)  # a plan that cannot fill the groove is refused before the run
    window = (process.speed_min_mm_s, process.speed_max_mm_s)
    budget_s = c.simulation.wall_time_limit_s
    records: list[PassRecord] = []
    bent = JobDistortion() if c.distortion is not None else None  # the angle so far
    job_bar = _job_bar(progress, count)
    wall_start = time.perf_counter()

    if c.passes.scan_first:
        scan = _pass(scene, None, fill, cad_seam, rng, process, progress, "pass_00_scan", flip,
                     stop=stop)  # fmt: skip
        _release_pass(freeze)
        records.append(scan.record)
        if stop is not None and stop.requested:
            return _interrupted(scene, records, fill, wall_start, stop, job_bar)
        scene, groove = _scanned(scene, scan)
    else:
        groove = true_groove(fill)
    limit = count if count is not None else MAX_PASSES
    index = 0
    stopped = ""
    while index < limit:
        assert groove is not None
        plan, plan_s = _next_plan(scene, plan_maker, name, groove, index, state, window, budget_s)
        if plan is None:
            _check_overrides_laid(c.passes, index, name)
            break
        done = _pass(scene, plan, fill, cad_seam, rng, process, progress, f"pass_{index + 1:02d}",
                     flip, adapt, name, groove, stop,
                     after_bead(groove, state.last_bead_area_mm2), bent)  # fmt: skip
        _release_pass(freeze)
        if stop is not None and stop.requested:  # the bead of a stopped pass is not laid
            records.append(done.record)
            return _interrupted(scene, records, fill, wall_start, stop, job_bar)
        fill, record, stopped = _laid(fill, done, shape, plan_s, index)
        records.append(record)
        if stopped:
            break
        state.done.append(plan)
        if on_pass is not None:
            on_pass(record, fill)
        if job_bar is not None:
            job_bar.update(1)
        index += 1
        if done.groove is None:
            stopped = f"the groove extractor measured the groove in no frame of {record.name}"
            break
        state.last_bead_area_mm2 = np.interp(done.groove.s_mm, done.path_s_mm,
                                             done.path_area_mm2)  # fmt: skip
        groove = done.groove
    else:
        if count is None:  # the planner was not done after MAX_PASSES passes
            stopped = (
                f"{name!r} was not done after {MAX_PASSES} passes, the most a job lays "
                "(the groove is not full)"
            )
    return _finished(scene, records, fill, wall_start, stopped, bent, job_bar, name, index)


def _finished(
    scene: Scene, records: list[PassRecord], fill: FillState, wall_start: float, stopped: str,
    bent: JobDistortion | None, bar: Any, name: str, laid: int,
) -> JobResult:  # fmt: skip
    """The job's result: its summary (why it stopped, when ``stopped`` says; the plates'
    angle with ``[distortion]``), its passes and its fill; refused when the planner ``name``
    planned no pass (``laid`` 0)."""
    if bar is not None:
        bar.close()
    if laid == 0:
        raise PluginRuntimeError(
            f"{name!r} planned no pass at all (a plan of zero beads)",
            field="planner.name",
            fix="return a PassPlan for pass 1 (None only when the groove is full)",
        )
    summary = job_summary(scene, records, fill, time.perf_counter() - wall_start, stopped)
    summary.update(bent.summary() if bent is not None else {})
    return JobResult(summary, records, fill)


def _empty_groove(scene: Scene) -> tuple[np.random.Generator, Seam, FillState, bool]:
    """The job's generator (seeded by the scene), the CAD seam, the empty groove's fill state
    and whether the laser's y_L runs against the stations' y (:func:`_laser_flipped`)."""
    from seamtrack.workpiece.fill import FillState  # trimesh, scipy: a job's own imports

    rng = np.random.default_rng(scene.config.simulation.seed)
    base_parts = build_parts(scene, rng)
    cad_seam = base_parts.seam
    fill = FillState.from_mesh(base_parts.mesh, cad_seam, spacing_mm=STATION_SPACING_MM)
    return rng, cad_seam, fill, _laser_flipped(base_parts, fill)


def _planner_of(c: Any, override: Any) -> tuple[str, Any, Any]:
    """The scene's planner (or ``override``): its name, the planner, its ``adapt`` (None:
    it has none)."""
    name = c.planner.name if c.planner is not None else "adaptive"
    params = dict(c.planner.params) if c.planner is not None else {}
    plan_maker = override if override is not None else planner(name, **params)
    adapt = getattr(plan_maker, "adapt", None)
    return name, plan_maker, adapt if callable(adapt) else None


def _scanned(scene: Scene, scan: _Done) -> tuple[Scene, MeasuredGroove]:
    """After the scan-only pass: the groove it measured, and the scene with the groove
    extractor's ``wall_deg`` set from it (unless the scene sets it)."""
    if scan.groove is None:
        raise PluginRuntimeError(
            "the groove extractor measured the groove in no frame of the scan-only pass",
            field="extractor.name",
            fix="check the sensor sees the groove (seamtrack check) and the extractor is groove",
        )
    c = scene.config
    if c.extractor.name == "groove" and "wall_deg" not in c.extractor.params:
        scene = _with(scene, {"extractor.params.wall_deg": wall_deg(scan.groove)})
    return scene, scan.groove


def _next_plan(
    scene: Scene, plan_maker: Any, name: str, groove: MeasuredGroove, index: int,
    state: JobState, window: tuple[float, float], budget_s: float,
) -> tuple[PassPlan | None, PlanTime]:  # fmt: skip
    """Pass ``index``'s plan, checked, with the scene's overrides for it (None: the planner is
    done), and the planner's time for it."""
    c = scene.config
    assert c.passes is not None
    planning, cpu = time.perf_counter(), time.thread_time()
    plan = _plan(plan_maker, name, groove, index, state, arm=is_arm(c), window=window,
                 budget_s=budget_s)  # fmt: skip
    plan_s = PlanTime(time.perf_counter() - planning, time.thread_time() - cpu)
    if plan is not None and c.passes.overrides:
        plan = checked_plan(overridden(plan, c.passes, index), name, index, groove,
                            gantry=not is_arm(c), field="passes.overrides",
                            window=window)  # fmt: skip
        assert plan is not None
    return plan, plan_s


def _laid(
    fill: FillState, done: _Done, shape: Any, plan_s: PlanTime, index: int
) -> tuple[FillState, PassRecord, str]:
    """The fill with the pass's bead laid along the path its torch followed, the pass's record
    (with the deposition's and the planner's times), and why the job stops here ("" when it
    goes on): the torch left the groove, so the bead cannot be laid."""
    start = time.perf_counter()
    stopped = ""
    try:
        if len(done.path_world) >= 2:
            fill = fill.deposit(done.path_world, done.path_area_mm2, shape)
    except SceneError as exc:  # the torch left the groove: the bead cannot be laid
        stopped = f"the bead of pass {index + 1} could not be laid ({exc.message})"
    record = dataclasses.replace(done.record, deposit_s=time.perf_counter() - start,
                                 plan_s=plan_s.wall_s, plan_cpu_s=plan_s.cpu_s)  # fmt: skip
    return fill, record, stopped


def _interrupted(
    scene: Scene,
    records: list[PassRecord],
    fill: FillState,
    wall_start: float,
    stop: StopRequest,
    bar: Any,
) -> JobResult:
    """A job stopped from outside: its passes up to the stop, status ``interrupted``."""
    if bar is not None:
        bar.close()
    why = f"{stop.reason} during {records[-1].name}"
    summary = job_summary(scene, records, fill, time.perf_counter() - wall_start, why)
    summary["status"] = INTERRUPTED
    return JobResult(summary, records, fill)


def dry_run(
    fill: FillState,
    plan_maker: Any,
    state: JobState,
    shape: Any,
    max_passes: int = 200,
    lagged: bool = False,
) -> tuple[Any, list[PassPlan]]:
    """The plan laid with perfect tracking and the true groove as the measurement: each bead
    along its true pass path (:func:`pass_path`) at the planned speed there. What a planner
    achieves by itself, without the sensor's and the tracker's errors (a planner's tests, and
    a quick look at a plan before a job).

    ``lagged``: the planner gets the groove as the job gives it, one pass behind: the true
    groove *before* the last pass's bead (a pass's sensor measures the groove ahead of its
    torch) and that bead's area along the seam in ``state.last_bead_area_mm2``; else the
    groove after every bead laid so far (and no last bead)."""
    seam = Seam.from_points(fill.T_world_station[:, :3, 3], field="passes", name="stations")
    plans: list[PassPlan] = []
    groove = true_groove(fill)
    for index in range(max_passes):
        plan = checked_plan(plan_maker.plan(groove, index, state), "planner", index, groove,
                            gantry=False)  # fmt: skip
        if plan is None:
            break
        path = pass_path(fill, plan.reference, plan)
        s = seam.closest(path.points).arc_length_mm
        area = np.asarray(
            state.process.bead_area_mm2(plan.speed_at(s), plan.wire_feed_mm_s), dtype=float
        )
        seen = true_groove(fill) if lagged else None  # this pass's sensor: before its bead
        fill = fill.deposit(path.points, area, shape)
        plans.append(plan)
        state.done.append(plan)
        if seen is not None:
            order = np.argsort(s)
            state.last_bead_area_mm2 = np.interp(seen.s_mm, s[order], area[order])
            groove = seen
        else:
            groove = true_groove(fill)
    return fill, plans


@dataclass(frozen=True, eq=False)
class _Done:
    record: PassRecord
    groove: MeasuredGroove | None
    path_world: FloatArray
    path_s_mm: FloatArray
    path_area_mm2: FloatArray


def _pass(
    scene: Scene,
    plan: PassPlan | None,
    fill: FillState,
    cad_seam: Seam,
    rng: np.random.Generator,
    process: Any,
    progress: bool,
    name: str,
    flip: bool,
    adapt: Any = None,
    planner_name: str = "planner",
    previous: MeasuredGroove | None = None,
    stop: StopRequest | None = None,
    expected: MeasuredGroove | None = None,
    bent: JobDistortion | None = None,
) -> _Done:
    """One closed-loop pass (``plan`` None: the scan-only pass along the groove's middle).
    ``flip``: the laser's y_L runs against the stations' y (the extractor's left is the
    stations' right)."""
    c = scene.config
    reference = "centre" if plan is None else plan.reference
    # the extractor knows the feet and the middle; from a top corner the job aims itself
    laser_reference = reference if reference in ("left", "right") else "centre"
    if flip:
        laser_reference = {"left": "right", "right": "left"}.get(laser_reference, "centre")
    speed = c.simulation.welding_speed_mm_s if plan is None else plan.travel_speed_mm_s
    slowest = speed if plan is None else float(np.min(plan.speed_at(fill.s_mm)))
    overrides: dict[str, Any] = {
        "extractor.params.reference": laser_reference,
        "simulation.welding_speed_mm_s": float(speed),
        "simulation.time_limit_s": default_time_limit_s(cad_seam.length_mm, min(slowest, speed)),
    }
    if plan is not None and plan.work_angle_rad:
        overrides["torch.work_angle_deg"] = math.degrees(plan.work_angle_rad)
    pass_scene = _with(scene, overrides)
    start = time.perf_counter()
    beads = fill.mesh() if len(fill.beads) else None
    parts = build_parts(still(pass_scene), rng, extra_mesh=beads)  # the job moves the part
    true_path = pass_path(fill, reference, plan)
    parts = dataclasses.replace(
        parts,
        seam=true_path,
        tcp_start_world=true_path.points[0] + np.asarray(c.robot.start_offset_mm),
        tool_program=tool_program(pass_scene, true_path),
    )
    parts, moving = distorted_parts(parts, pass_scene, plan, fill, process, bent, cad_seam)
    frames: list[tuple[Feature, FloatArray]] = []
    each: list[FrameGroove | None] = []  # every frame's groove, as the sense function saw it
    sense = SteeredSense(parts, fill, cad_seam, plan, frames, adapt, planner_name, previous, each,
                         expected)  # fmt: skip
    parts = dataclasses.replace(parts, sense=sense)
    build_s = time.perf_counter() - start
    start = time.perf_counter()
    result = run(parts, progress=progress, seed=c.simulation.seed, stop=stop)
    run_s = time.perf_counter() - start
    groove = measured_groove(frames, fill, cad_seam, each=each)
    path, t, speeds = arc_path(result, parts.settings.trace_period_s, process.speed_min_mm_s)
    if moving is not None:  # the bead is laid on the part, in its own frame
        path = into_the_part(moving, path, t)
        locked_in(moving, bent)
    arc_time = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    wire = process.wire_feed_mm_s if plan is None else plan.wire_feed_mm_s
    if plan is not None and len(path):
        s_on = cad_seam.closest(path).arc_length_mm
        planned = plan.speed_at(s_on)
        speeds = ramped(speeds, np.asarray(planned, dtype=float), handover=handover(result, s_on))
    area = np.asarray(
        bead_area_mm2(process.wire_diameter_mm, wire, speeds, process.deposition_efficiency),
        dtype=float,
    ).reshape(-1)
    path, area = to_the_ends(path, area, cad_seam)
    s_path = cad_seam.closest(path).arc_length_mm if len(path) else np.zeros(0)
    mean_speed = float(np.mean(speeds)) if len(speeds) else math.nan
    record = PassRecord(
        name=name,
        plan=plan,
        result=result,
        arc_time_s=0.0 if plan is None else arc_time,
        mean_speed_mm_s=mean_speed,
        bead_area_mm2=0.0 if plan is None else float(np.mean(area)) if len(area) else 0.0,
        heat_input_kj_mm=0.0 if plan is None else heat_input_kj_mm(c, mean_speed),
        build_s=build_s,
        run_s=run_s,
        deposit_s=0.0,
        scene=pass_scene,
    )
    return _Done(record, groove, path, s_path, np.asarray(area, dtype=float))


def _laser_flipped(parts: Parts, fill: FillState) -> bool:
    """Whether the laser's y_L axis points against the stations' y at the start pose."""
    from seamtrack.geometry.frames import make as make_pose

    robot = parts.robot
    joints = parts.start_joints
    if joints is None:
        joints = robot.joints_for_tool(make_pose(translation=parts.tcp_start_world))
    T_world_sensor = np.asarray(robot.T_world_sensor(joints), dtype=float)
    return bool(T_world_sensor[:3, 1] @ fill.T_world_station[0, :3, 1] < 0.0)


def _plan(maker: Any, name: str, groove: MeasuredGroove, index: int, state: JobState,
          arm: bool, window: tuple[float, float] | None = None,
          budget_s: float = math.inf) -> PassPlan | None:  # fmt: skip
    """The planner's plan for pass ``index``, checked. A plugin's ``plan()`` runs under the
    wall-time budget ``budget_s`` (:func:`within_budget`); one of seamtrack's own that fails
    is seamtrack's bug, raised as it is, never blamed on a plugin."""
    if is_builtin(maker):
        plan = maker.plan(groove, index, state)
    else:
        try:
            plan = within_budget(lambda: maker.plan(groove, index, state), budget_s)
        except (PluginRuntimeError, SceneError):
            raise
        except TimeoutError:
            raise PluginRuntimeError(
                f"{name!r} plan() for pass {index + 1} did not return within "
                f"simulation.wall_time_limit_s = {budget_s:g} s (it is left running until "
                "seamtrack exits: Python cannot stop a thread)",
                field="planner.name",
                fix="make plan() return a PassPlan, or None when the groove is full (or raise "
                "simulation.wall_time_limit_s)",
            ) from None
        except Exception as exc:  # the user's planner may fail in any way
            raise plugin_failed("planner.name", name, "plan", 0.0, exc) from exc
    return checked_plan(plan, name, index, groove, gantry=not arm, window=window)


def within_budget(call: Any, budget_s: float) -> Any:
    """``call()``'s answer, or TimeoutError when it has not returned within ``budget_s``.

    The call runs in a daemon thread the caller waits for with a timeout (an interruptible
    wait: Ctrl-C still reaches the main thread). On time-out the thread is abandoned, not
    killed: Python has no sound way to stop a thread (an exception injected into it lands
    anywhere, in a ``finally`` or a lock, and never inside compiled code), nor does Linux
    (``pthread_cancel`` under a running interpreter corrupts it); SIGALRM reaches the main
    thread only, and only between bytecodes. The job stops with an error, and the process's
    exit ends the thread. A plugin's state is not shared with a second process, so running
    ``plan()`` in a subprocess (which could be killed) would lose the planner's memory of the
    passes before."""
    if not math.isfinite(budget_s):
        return call()
    box: dict[str, Any] = {}

    def target() -> None:
        try:
            box["value"] = call()
        except BaseException as exc:  # handed to the waiting thread
            box["error"] = exc

    worker = threading.Thread(target=target, name="seamtrack-planner", daemon=True)
    worker.start()
    worker.join(budget_s)
    if worker.is_alive():
        raise TimeoutError(f"no answer within {budget_s:g} s")
    if "error" in box:
        raise box["error"]
    return box.get("value")


def _check_overrides_laid(passes: Any, laid: int, name: str) -> None:
    """An override for a pass the plan never lays is refused (it would be silently ignored)."""
    for i, o in enumerate(passes.overrides):
        if o.number > laid:
            raise SceneError(
                f"pass {o.number} is overridden but {name!r} planned {laid} passes",
                field=f"passes.overrides.{i}.number",
                fix=f"number the overridden passes from 1 to {laid}",
            )


def planned_layout(fill: FillState, c: Any) -> Layout | None:
    """The plan a built-in planner lays on the CAD groove ``fill`` (None: a plugin's, which
    only its run knows; the scan-only pass's measured groove may change it by a pass or so),
    refused when it cannot fill the groove: an ``auto`` plan of more than
    :data:`MAX_PASSES` passes (the process lays beads too small), or a ``passes.count`` of
    beads that, each the largest the process lays (at its slowest travel speed), hold less
    than the groove. Overrides of passes beyond the plan are refused too."""
    name = c.planner.name if c.planner is not None else "adaptive"
    if not is_builtin(name):
        return None
    process = process_of(c)
    count = c.passes.count if isinstance(c.passes.count, int) else None
    groove = true_groove(fill)
    state = JobState(process, count=count, reinforcement_mm=c.passes.reinforcement_mm)
    plan = layout(groove, state)
    area = float(np.median(groove.area_mm2))
    largest = float(process.bead_area_mm2(process.speed_min_mm_s))
    if count is None and plan.passes > MAX_PASSES:
        raise SceneError(
            f"the plan needs {plan.passes} passes to fill the groove ({area:.4g} mm^2) with "
            f"beads of {float(process.bead_area_mm2(process.nominal_speed_mm_s)):.3g} mm^2 at "
            f"the nominal speed; a job lays at most {MAX_PASSES}",
            field="process.wire_feed_m_min",
            fix="feed more wire (process.wire_feed_m_min or process.wire_diameter_mm), or "
            "weld slower (simulation.welding_speed_mm_s)",
        )
    if count is not None and count * largest < area:
        need = math.ceil(area / largest)
        raise SceneError(
            f"{count} passes cannot fill the groove: {area:.4g} mm^2, and the largest bead "
            f"the process lays is {largest:.3g} mm^2 (at process.travel_speed_min_mm_s = "
            f"{process.speed_min_mm_s:g} mm/s)",
            field="passes.count",
            fix=f'give at least {need} passes, or count = "auto"',
        )
    for i, o in enumerate(c.passes.overrides):
        if o.number > plan.passes:
            raise SceneError(
                f"pass {o.number} is overridden but the plan lays {plan.passes} passes",
                field=f"passes.overrides.{i}.number",
                fix=f"number the overridden passes from 1 to {plan.passes}",
            )
    return plan


def _check_bead_fits(fill: FillState, process: Any, c: Any) -> None:
    """A bead at the fastest travel speed larger than the whole groove cannot be laid."""
    area = float(np.median(fill.remaining_area_mm2()))
    smallest = float(process.bead_area_mm2(process.speed_max_mm_s))
    if smallest > area:
        raise SceneError(
            f"the smallest bead the process lays ({smallest:.3g} mm^2 at "
            f"{process.speed_max_mm_s} mm/s) is larger than the groove ({area:.3g} mm^2)",
            field="process.wire_feed_m_min",
            fix="lower the wire feed or the wire diameter, or raise process.travel_speed_max_mm_s",
        )


def bead_shape(c: Any, BeadShape: Any) -> Any:
    from seamtrack.simulation.config import ProcessConfig

    bead = (c.process or ProcessConfig()).bead
    wetting = None if bead.wetting_angle_deg is None else math.radians(bead.wetting_angle_deg)
    return BeadShape(kind=bead.model, width_to_height=bead.width_to_height,
                     wetting_angle_rad=wetting)  # fmt: skip


def _with(scene: Scene, overrides: dict[str, Any]) -> Scene:
    """The scene with dotted keys replaced (validated again)."""
    data = scene.config.model_dump(mode="python")
    for dotted, value in overrides.items():
        *path, key = dotted.split(".")
        node = data
        for part in path:
            if node.get(part) is None:
                node[part] = {}
            node = node[part]
        node[key] = value
    config = type(scene.config).model_validate(data)
    return dataclasses.replace(scene, config=config)


def _release_pass(freeze: bool) -> None:
    """Free what the pass just run built: its meshes (the part with the beads joined) are held
    by trimesh's own reference cycles, with their caches and ray-casting scenes, until Python's
    next full collection; collected after each pass, a job's peak memory stays that of one
    pass's parts, not of several. ``freeze``: then what survives is frozen out of the next
    collections (the job's imports, its records; :func:`run_job` unfreezes them at its end),
    which then scan only what the next pass made."""
    gc.collect()
    if freeze:
        gc.freeze()


def _job_bar(enabled: bool, total: int | None) -> Any:
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, unit="pass", desc="job", leave=True, position=1)
