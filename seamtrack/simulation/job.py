"""A multi-pass job: every pass a full closed loop on the part and the beads laid before it.

:func:`run_job` runs a scene with ``[passes]``:

1. The empty groove's fill state (:class:`seamtrack.workpiece.fill.FillState`, stations every
   0.5 mm along the CAD seam) and, with ``passes.scan_first``, a scan-only pass (torch off; its
   time counts in the job's time) that measures the groove.
2. For each pass the planner (:mod:`seamtrack.control.planner`) gets the groove as the sensor
   measured it during the pass before (the groove extractor's 7 points and remaining area per
   frame, binned per station) and returns the pass: reference (left wall, right wall, centre),
   lateral offset, travel speed (a profile along the seam), wire feed. The scene's
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
import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.control.planner import (
    JobState,
    MeasuredGroove,
    PassPlan,
    checked_plan,
    planner,
)
from seamtrack.errors import PluginRuntimeError, SceneError, plugin_failed
from seamtrack.geometry.seam import Seam
from seamtrack.sensing.profiles import Feature, laser_to_world
from seamtrack.simulation.assemble import Parts, build_parts
from seamtrack.simulation.checks import default_time_limit_s
from seamtrack.simulation.job_summary import (  # noqa: F401 (the job's public names)
    fusion_margin_mm,
    is_wall_bead,
    job_summary,
    welded_range,
)
from seamtrack.simulation.loop import Result, run
from seamtrack.simulation.passes import (
    heat_input_kj_mm,
    offset_point,
    overridden,
    planned_feature,
    process_of,
    wall_deg,
)
from seamtrack.simulation.robots import is_arm, tool_program
from seamtrack.simulation.scene import Scene, load_scene
from seamtrack.workpiece.beads import bead_area_mm2

FloatArray = NDArray[np.float64]

#: Station spacing of the fill state (mm): the issue's "every <= 0.5 mm".
STATION_SPACING_MM = 0.5

_POINT_INDEX = {"left": 1, "right": 5, "centre": 3}

#: A frame whose fill surface lies this far (mm) below the pass before's is no groove.
FILL_DROP_MM = 1.0

#: A bead that stops this close (mm) to the part's end is run off the edge (:func:`_to_the_ends`).
RUN_OFF_MM = 3.0


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


@dataclass(frozen=True, eq=False)
class JobResult:
    """A finished job: ``summary`` (written as job.json), the passes, the final fill state."""

    summary: dict[str, Any]
    passes: list[PassRecord]
    fill: Any  # FillState

    @property
    def status(self) -> str:
        return str(self.summary["status"])


def run_job(
    scene: Scene | str,
    progress: bool = False,
    planner_override: Any = None,
    on_pass: Any = None,
) -> JobResult:
    """Run a multi-pass job (a scene with ``[passes]``); see the module docstring.

    ``planner_override``: a planner instance used instead of the scene's; ``on_pass(record,
    fill)`` is called after each pass (a notebook's or a bench's hook).
    """
    from seamtrack.workpiece.beads import BeadShape
    from seamtrack.workpiece.fill import FillState  # trimesh, scipy: a job's own imports

    if not isinstance(scene, Scene):
        scene = load_scene(scene)
    c = scene.config
    if c.passes is None:
        raise SceneError(
            "the scene has no [passes]", field="passes", fix="add [passes] for a multi-pass job"
        )
    rng = np.random.default_rng(c.simulation.seed)
    base_parts = build_parts(scene, rng)
    cad_seam = base_parts.seam
    fill = FillState.from_mesh(base_parts.mesh, cad_seam, spacing_mm=STATION_SPACING_MM)
    flip = _laser_flipped(base_parts, fill)
    process = process_of(c)
    shape = _bead_shape(c, BeadShape)
    name = c.planner.name if c.planner is not None else "adaptive"
    params = dict(c.planner.params) if c.planner is not None else {}
    plan_maker = planner_override if planner_override is not None else planner(name, **params)
    adapt = getattr(plan_maker, "adapt", None)
    adapt = adapt if callable(adapt) else None
    count = c.passes.count if isinstance(c.passes.count, int) else None
    state = JobState(process, count=count, reinforcement_mm=c.passes.reinforcement_mm)
    _check_bead_fits(fill, process, c)
    records: list[PassRecord] = []
    job_bar = _job_bar(progress, count)
    wall_start = time.perf_counter()

    groove: MeasuredGroove | None = None
    if c.passes.scan_first:
        scan = _pass(scene, None, fill, cad_seam, rng, process, progress, "pass_00_scan", flip)
        records.append(scan.record)
        if scan.groove is None:
            raise PluginRuntimeError(
                "the groove extractor measured the groove in no frame of the scan-only pass",
                field="extractor.name",
                fix="check the sensor sees the groove (seamtrack check) and the extractor is "
                "groove",
            )
        groove = scan.groove
        if c.extractor.name == "groove" and "wall_deg" not in c.extractor.params:
            scene = _with(scene, {"extractor.params.wall_deg": wall_deg(groove)})
    else:
        groove = _true_groove(fill)
    limit = count if count is not None else 200
    index = 0
    stopped = ""
    while index < limit:
        assert groove is not None
        plan = _plan(plan_maker, name, groove, index, state, arm=is_arm(c))
        if plan is None:
            break
        if c.passes.overrides:
            plan = checked_plan(overridden(plan, c.passes, index), name, index, groove,
                                gantry=not is_arm(c), field="passes.overrides")  # fmt: skip
            assert plan is not None
        done = _pass(scene, plan, fill, cad_seam, rng, process, progress, f"pass_{index + 1:02d}",
                     flip, adapt, name, groove)  # fmt: skip
        start = time.perf_counter()
        try:
            if len(done.path_world) >= 2:
                fill = fill.deposit(done.path_world, done.path_area_mm2, shape)
        except SceneError as exc:  # the torch left the groove: the bead cannot be laid
            stopped = f"the bead of pass {index + 1} could not be laid ({exc.message})"
        record = dataclasses.replace(done.record, deposit_s=time.perf_counter() - start)
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
    if job_bar is not None:
        job_bar.close()
    if index == 0:
        raise PluginRuntimeError(
            f"{name!r} planned no pass at all (a plan of zero beads)",
            field="planner.name",
            fix="return a PassPlan for pass 1 (None only when the groove is full)",
        )
    summary = job_summary(scene, records, fill, time.perf_counter() - wall_start, stopped)
    return JobResult(summary, records, fill)


def dry_run(
    fill: Any, plan_maker: Any, state: JobState, shape: Any, max_passes: int = 200
) -> tuple[Any, list[PassPlan]]:
    """The plan laid with perfect tracking and the true groove as the measurement: each bead
    along its true pass path (:func:`pass_path`) at the planned speed there. What a planner
    achieves by itself, without the sensor's and the tracker's errors (a planner's tests, and
    a quick look at a plan before a job)."""
    seam = Seam.from_points(fill.T_world_station[:, :3, 3], field="passes", name="stations")
    plans: list[PassPlan] = []
    for index in range(max_passes):
        groove = _true_groove(fill)
        plan = checked_plan(plan_maker.plan(groove, index, state), "planner", index, groove,
                            gantry=False)  # fmt: skip
        if plan is None:
            break
        path = pass_path(fill, plan.reference, plan)
        s = seam.closest(path.points).arc_length_mm
        area = state.process.bead_area_mm2(plan.speed_at(s), plan.wire_feed_mm_s)
        fill = fill.deposit(path.points, np.asarray(area, dtype=float), shape)
        plans.append(plan)
        state.done.append(plan)
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
    fill: Any,
    cad_seam: Seam,
    rng: np.random.Generator,
    process: Any,
    progress: bool,
    name: str,
    flip: bool,
    adapt: Any = None,
    planner_name: str = "planner",
    previous: MeasuredGroove | None = None,
) -> _Done:
    """One closed-loop pass (``plan`` None: the scan-only pass along the groove's middle).
    ``flip``: the laser's y_L runs against the stations' y (the extractor's left is the
    stations' right)."""
    c = scene.config
    reference = "centre" if plan is None else plan.reference
    laser_reference = (
        {"left": "right", "right": "left"}.get(reference, reference) if flip else (reference)
    )
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
    parts = build_parts(pass_scene, rng, extra_mesh=beads)
    true_path = pass_path(fill, reference, plan)
    parts = dataclasses.replace(
        parts,
        seam=true_path,
        tcp_start_world=true_path.points[0] + np.asarray(c.robot.start_offset_mm),
        tool_program=tool_program(pass_scene, true_path),
    )
    frames: list[tuple[Feature, FloatArray]] = []
    parts = _steered(parts, fill, cad_seam, plan, frames, adapt, planner_name, previous)
    build_s = time.perf_counter() - start
    start = time.perf_counter()
    result = run(parts, progress=progress, seed=c.simulation.seed)
    run_s = time.perf_counter() - start
    groove = measured_groove(frames, fill, cad_seam)
    path, t, speeds = _arc_path(result, parts.settings.trace_period_s, process.speed_min_mm_s)
    arc_time = float(t[-1] - t[0]) if len(t) > 1 else 0.0
    wire = process.wire_feed_mm_s if plan is None else plan.wire_feed_mm_s
    if plan is not None and len(path):
        planned = plan.speed_at(cad_seam.closest(path).arc_length_mm)
        speeds = _ramped(speeds, np.asarray(planned, dtype=float))
    area = np.asarray(
        bead_area_mm2(process.wire_diameter_mm, wire, speeds, process.deposition_efficiency),
        dtype=float,
    ).reshape(-1)
    path, area = _to_the_ends(path, area, cad_seam)
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


def _steered(
    parts: Parts,
    fill: Any,
    cad_seam: Seam,
    plan: PassPlan | None,
    frames: list[tuple[Feature, FloatArray]],
    adapt: Any = None,
    planner_name: str = "planner",
    previous: MeasuredGroove | None = None,
) -> Parts:
    """The parts with a sense function that records every frame's feature, moves the measured
    point by the plan's lateral offset there (station frame), and sets the tracker's speed
    along the seam from the plan; ``adapt(groove_ahead, plan)`` (a planner's, optional) may
    replace the speed and offset at the station the sensor sees, for when the torch gets
    there. A frame whose fill surface lies more than :data:`FILL_DROP_MM` below the one the
    pass before measured there (``previous``; the fill only grows) is taken as no groove."""
    sense = parts.sense
    tracker = parts.tracker
    T_sensor_tcp = np.linalg.inv(np.asarray(parts.robot.T_tcp_sensor, dtype=float))
    lateral = fill.T_world_station[:, :3, 1]
    s_stations = fill.s_mm
    set_speed = getattr(tracker, "set_speed", None)
    adapted = np.full((len(s_stations), 2), np.nan)  # speed, offset per station
    seen = [False]  # the pass's sensor has measured the groove

    def station(s: float) -> int:
        return min(int(np.searchsorted(s_stations, s)), len(s_stations) - 1)

    def steered(T_world_sensor: FloatArray, t_s: float, hint: Any = None) -> Feature:
        if hint is not None:
            feature = sense(T_world_sensor, t_s, hint)
        else:
            feature = sense(T_world_sensor, t_s)
        frames.append((feature, T_world_sensor))
        if plan is None:
            return feature
        if feature and previous is not None and _below_the_fill(frames[-1], fill, cad_seam,
                                                                previous):  # fmt: skip
            feature = Feature.failed("below the fill the pass before measured", feature.joint)
            frames[-1] = (feature, T_world_sensor)
        if feature:
            seen[0] = True
        elif not seen[0] and previous is not None:  # not yet seen: start on the plan
            feature = planned_feature(feature, T_world_sensor, fill, plan, previous,
                                      STATION_SPACING_MM, _POINT_INDEX)  # fmt: skip
        if feature:
            s = float(cad_seam.closest(feature.point_world[None]).arc_length_mm[0])
            i = station(s)
            if adapt is not None:
                ahead = measured_groove(frames[-1:], fill, cad_seam)
                if ahead is not None:
                    adapted[i] = _adapted(adapt, ahead, plan, planner_name, t_s)
            offset = adapted[i, 1] if np.isfinite(adapted[i, 1]) else float(plan.offset_at(s))
            here = measured_groove(frames[-1:], fill, cad_seam) if offset else None
            if here is not None:  # on the fill surface the frame measured, under the bead
                k = min(int(np.searchsorted(s_stations, here.s_mm[0])), len(s_stations) - 1)
                y, z = offset_point(here.points, _POINT_INDEX[plan.reference], offset)[0]
                point = (fill.T_world_station[k] @ np.array([0.0, y, z, 1.0]))[:3]
                feature = dataclasses.replace(feature, point_world=point)
            elif offset:  # the planned point (no groove measured yet)
                point = feature.point_world + offset * lateral[i]
                feature = dataclasses.replace(feature, point_world=point)
        if set_speed is not None:
            tcp = (T_world_sensor @ T_sensor_tcp)[:3, 3]
            s_tcp = float(cad_seam.closest(tcp[None]).arc_length_mm[0])
            speed = adapted[station(s_tcp), 0]
            set_speed(float(speed) if np.isfinite(speed) else float(plan.speed_at(s_tcp)))
        return feature

    return dataclasses.replace(parts, sense=steered)


def _below_the_fill(
    frame: tuple[Feature, FloatArray], fill: Any, seam: Seam, previous: MeasuredGroove
) -> bool:
    """Whether a frame's fill surface (its middle bottom point) lies more than
    :data:`FILL_DROP_MM` below the one measured there by the pass before, or its bottom
    corners lie more than twice that inside the pass before's (the fill surface only widens
    up a V's walls; a frame that shows part of it, at the part's end, is no groove)."""
    now = measured_groove([frame], fill, seam)
    if now is None or not len(previous):
        return False
    p = previous.points
    before = [float(np.interp(now.s_mm[0], previous.s_mm, p[:, k, c])) for k, c in _PAST]
    y_left, y_right, z_mid = now.points[0, 1, 0], now.points[0, 5, 0], now.points[0, 3, 1]
    return bool(
        z_mid < before[2] - FILL_DROP_MM
        or y_left > before[0] + 2 * FILL_DROP_MM
        or y_right < before[1] - 2 * FILL_DROP_MM
    )


#: The pass before's left foot's y, right foot's y, middle's z (row, column of the 7 points).
_PAST = ((1, 0), (5, 0), (3, 1))


def _adapted(adapt: Any, ahead: MeasuredGroove, plan: PassPlan, name: str,
             t_s: float) -> tuple[float, float]:  # fmt: skip
    """A planner's ``adapt`` answer checked: (speed, offset), NaN where it keeps the plan."""
    try:
        answer = adapt(ahead, plan)
    except Exception as exc:  # the user's planner may fail in any way
        raise plugin_failed("planner.name", name, "adapt", t_s, exc) from exc
    if answer is None:
        return math.nan, math.nan
    try:
        speed, offset = (float(v) for v in answer)
    except (TypeError, ValueError):
        speed, offset = math.nan, math.inf
    if not (math.isfinite(offset) and math.isfinite(speed) and speed > 0):
        raise PluginRuntimeError(
            f"{name!r} adapt() returned {answer!r} at t = {t_s:.6g} s",
            field="planner.name",
            fix="return (speed_mm_s > 0, offset_mm), or None to keep the plan",
        )
    return speed, offset


def _laser_flipped(parts: Parts, fill: Any) -> bool:
    """Whether the laser's y_L axis points against the stations' y at the start pose."""
    from seamtrack.geometry.frames import make as make_pose

    robot = parts.robot
    joints = parts.start_joints
    if joints is None:
        joints = robot.joints_for_tool(make_pose(translation=parts.tcp_start_world))
    T_world_sensor = np.asarray(robot.T_world_sensor(joints), dtype=float)
    return bool(T_world_sensor[:3, 1] @ fill.T_world_station[0, :3, 1] < 0.0)


def pass_path(fill: Any, reference: str, plan: PassPlan | None, window: int = 4) -> Seam:
    """A pass's true path in the world: at every station the reference point of the true fill
    surface (left or right wall's foot, or the middle; a running median over ``2 window + 1``
    stations, 2 mm: where a toe wets a wall the foot jumps along it from one station to the
    next, faster than any torch follows), moved across the seam by the plan's offset there,
    onto the fill surface the bottom points describe (:func:`~seamtrack.simulation.passes.
    offset_point`: where the bead aims, as the tracker does with the measured points)."""
    pts = fill.all_groove_points()
    padded = np.pad(pts, ((window, window), (0, 0), (0, 0)), mode="edge")
    pts = np.median(np.lib.stride_tricks.sliding_window_view(padded, 2 * window + 1, axis=0), -1)
    offset = np.zeros(len(pts)) if plan is None else plan.offset_at(fill.s_mm)
    yz = offset_point(pts, _POINT_INDEX[reference], offset)
    local = np.column_stack([np.zeros(len(yz)), yz[:, 0], yz[:, 1], np.ones(len(yz))])
    points = np.einsum("mij,mj->mi", fill.T_world_station, local)[:, :3]
    return Seam.from_points(points, field="passes", name="pass path")


def measured_groove(
    frames: list[tuple[Feature, FloatArray]], fill: Any, cad_seam: Seam
) -> MeasuredGroove | None:
    """The groove as the pass's sensor measured it (None: in no frame): every frame's 7
    points (the groove extractor's ``edges_laser``) in the frame of the station nearest to
    them, the median per station; stations no frame saw are left out."""
    s_list, pts_list, area_list = [], [], []
    for feature, T_world_sensor in frames:
        edges = np.asarray(feature.edges_laser, dtype=float)
        if not feature or edges.shape != (7, 2) or not np.isfinite(edges).all():
            continue
        world = laser_to_world(T_world_sensor, edges)
        s = float(cad_seam.closest(world[3][None]).arc_length_mm[0])
        i = min(int(round((s - fill.s_mm[0]) / STATION_SPACING_MM)), len(fill.s_mm) - 1)
        local = (np.linalg.inv(fill.T_world_station[i]) @ np.c_[world, np.ones(7)].T).T
        yz = local[:, 1:3]
        if yz[0, 0] > yz[6, 0]:  # the laser's left is the stations' right: y ascending
            yz = yz[::-1]
        s_list.append(i)
        pts_list.append(yz)
        area_list.append(feature.area_mm2)
    if not s_list:
        return None
    stations = np.asarray(s_list)
    points = np.asarray(pts_list)
    areas = np.asarray(area_list, dtype=float)
    keep = np.unique(stations)
    med_pts = np.stack([np.median(points[stations == k], axis=0) for k in keep])
    med_area = np.array([np.nanmedian(areas[stations == k]) for k in keep])
    return MeasuredGroove(fill.s_mm[keep], med_pts, med_area)


def _true_groove(fill: Any) -> MeasuredGroove:
    """The CAD groove's 7 points and area (no scan-only pass: the first plan is the nominal
    groove's; later ones are measured)."""
    points = np.stack([fill.groove_points(i) for i in range(len(fill.s_mm))])
    return MeasuredGroove(fill.s_mm, points, fill.remaining_area_mm2())


def _arc_path(
    result: Result, period_s: float, floor_mm_s: float
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The torch's path while the arc burns, its times and speeds (decimated to
    ``period_s``): from the first to the last tick at which the torch moves at least half the
    slowest process speed (the approach to the first measured point included: the torch
    starts on the groove at the seam's start); the speed bounded below by ``floor_mm_s``."""
    trace = result.trace
    idx = trace.decimated(period_s)
    path, t = trace.tcp_world[idx], trace.t_s[idx]
    if len(path) < 3:
        return path, t, np.full(len(path), floor_mm_s)
    speed = np.linalg.norm(np.gradient(path, t, axis=0), axis=1)
    moving = np.flatnonzero(speed >= 0.5 * floor_mm_s)
    if len(moving) < 2:
        return path[:0], t[:0], speed[:0]
    keep = slice(moving[0], moving[-1] + 1)
    return path[keep], t[keep], np.maximum(speed[keep], floor_mm_s)


def _ramped(speed: FloatArray, planned: FloatArray, fraction: float = 0.8) -> FloatArray:
    """The speed that sets the bead's area: the actual one, except while the torch speeds up
    from rest at the start and brakes to rest at the end (below ``fraction`` of the planned
    speed there), where the wire feed follows the travel speed (a controller's synchronised
    arc start and crater) and the bead has its planned area."""
    out = speed.copy()
    fast = np.flatnonzero(speed >= fraction * planned)
    if not len(fast):
        return planned.copy()
    out[: fast[0]] = planned[: fast[0]]
    out[fast[-1] + 1 :] = planned[fast[-1] + 1 :]
    return out


def _to_the_ends(path: FloatArray, area: FloatArray, seam: Seam) -> tuple[FloatArray, FloatArray]:
    """The path carried on along the seam to the part's ends where it stops within
    :data:`RUN_OFF_MM` of them (the torch stops at the last seam point its sensor saw, a
    fraction of a mm before the plate's edge; a welder runs the bead off the edge), with the
    area at its end."""
    if len(path) < 2:
        return path, area
    s = seam.closest(path[[0, -1]]).arc_length_mm
    ends = seam.interpolate([0.0, seam.length_mm])
    head = [ends[0] + (path[0] - seam.interpolate([s[0]])[0])] if 0 < s[0] <= RUN_OFF_MM else []
    gap = seam.length_mm - s[1]
    tail = [ends[1] + (path[-1] - seam.interpolate([s[1]])[0])] if 0 < gap <= RUN_OFF_MM else []
    path = np.vstack([*head, path, *tail])
    area = np.concatenate([area[:1]] * len(head) + [area] + [area[-1:]] * len(tail))
    return path, area


def _plan(maker: Any, name: str, groove: MeasuredGroove, index: int, state: JobState,
          arm: bool) -> PassPlan | None:  # fmt: skip
    try:
        plan = maker.plan(groove, index, state)
    except (PluginRuntimeError, SceneError):
        raise
    except Exception as exc:  # the user's planner may fail in any way
        raise plugin_failed("planner.name", name, "plan", 0.0, exc) from exc
    return checked_plan(plan, name, index, groove, gantry=not arm)


def _check_bead_fits(fill: Any, process: Any, c: Any) -> None:
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


def _bead_shape(c: Any, BeadShape: Any) -> Any:
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


def _job_bar(enabled: bool, total: int | None) -> Any:
    if not enabled:
        return None
    from tqdm import tqdm

    return tqdm(total=total, unit="pass", desc="job", leave=True, position=1)
