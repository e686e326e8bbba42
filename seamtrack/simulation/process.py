"""A multi-pass job's scene sections (``[process]``, ``[passes]``, ``[planner]``) checked
against each other and the rest of the scene (when the scene loads), and turned into what the
planner and the job (:mod:`seamtrack.multipass`) use: :class:`~seamtrack.control.planner.Process`,
the heat input, the overrides applied to a plan.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
from numpy.typing import NDArray

from seamtrack.control.planner import PassPlan, Process, planner_class
from seamtrack.errors import Rule, SceneError, check_rules
from seamtrack.simulation.config import PassesConfig, ProcessConfig, SceneConfig
from seamtrack.simulation.robots import is_arm

FloatArray = NDArray[np.float64]


def wire_feed_mm_s(wire_feed_m_min: float) -> float:
    """m/min (the scene's edge) to mm/s (inside)."""
    return wire_feed_m_min * 1000.0 / 60.0


def process_of(c: SceneConfig, nominal_speed_mm_s: float | None = None) -> Process:
    """The planner's view of ``[process]`` (its defaults when the section is absent)."""
    p = c.process or ProcessConfig()
    ratio = p.bead.width_to_height
    if p.bead.model == "arc" and p.bead.wetting_angle_deg is not None:
        ratio = arc_width_to_height(math.radians(p.bead.wetting_angle_deg))
    return Process(
        wire_diameter_mm=p.wire_diameter_mm,
        wire_feed_mm_s=wire_feed_mm_s(p.wire_feed_m_min),
        deposition_efficiency=p.deposition_efficiency,
        speed_min_mm_s=p.travel_speed_min_mm_s,
        speed_max_mm_s=p.travel_speed_max_mm_s,
        nominal_speed_mm_s=nominal_speed_mm_s or c.simulation.welding_speed_mm_s,
        bead_model=p.bead.model,
        width_to_height=ratio,
    )


def arc_width_to_height(wetting_angle_rad: float) -> float:
    """A circular segment meeting a flat plate at ``wetting_angle_rad``: w / h =
    2 sin(a) / (1 - cos(a)) = 2 / tan(a / 2)."""
    return 2.0 / math.tan(0.5 * wetting_angle_rad)


def heat_input_kj_mm(c: SceneConfig, travel_speed_mm_s: float) -> float:
    """Arc energy times the thermal efficiency: k * U * I / v * 1e-3 (kJ/mm)."""
    p = c.process or ProcessConfig()
    return p.thermal_efficiency * p.voltage_v * p.current_a / travel_speed_mm_s * 1e-3


def check_passes(c: SceneConfig) -> None:
    """The multi-pass sections against each other and the scene (before anything is built)."""
    if c.passes is None:
        if c.planner is not None:
            raise SceneError(
                "[planner] is given but the scene has no [passes]",
                field="planner",
                fix='add [passes] (count = "auto") for a multi-pass job, or remove [planner]',
            )
        return
    p = c.process or ProcessConfig()
    v = c.simulation.welding_speed_mm_s
    v_min, v_max = p.travel_speed_min_mm_s, p.travel_speed_max_mm_s
    check_rules([
        Rule(c.sensor.mode != "mesh" or c.workpiece is None,
             "a multi-pass job lays beads on a workpiece's mesh", "passes",
             'set sensor.mode = "mesh" with a [workpiece] groove, or remove [passes]'),
        Rule(v_min >= v_max,
             f"travel_speed_min_mm_s {v_min} is not below travel_speed_max_mm_s {v_max}",
             "process.travel_speed_min_mm_s", "give a window with min < max"),
        Rule(not v_min <= v <= v_max,
             f"welding speed {v} mm/s is outside the process window [{v_min}, {v_max}] mm/s",
             "simulation.welding_speed_mm_s",
             "give a nominal speed inside process.travel_speed_min_mm_s .. _max_mm_s"),
        Rule(p.bead.wetting_angle_deg is not None and p.bead.model != "arc",
             f"a wetting angle sets the shape of an arc bead, not of a {p.bead.model} one",
             "process.bead.wetting_angle_deg",
             'set process.bead.model = "arc", or give width_to_height instead'),
        Rule(c.tracker.name != "trajectory",
             "a multi-pass job adapts its travel speed through the trajectory tracker, not "
             f"{c.tracker.name!r}", "tracker.name", 'set tracker.name = "trajectory"'),
        Rule(c.extractor.name != "groove",
             f"a multi-pass job measures the groove's 7 points, which {c.extractor.name!r} "
             "does not give", "extractor.name", 'set extractor.name = "groove"'),
    ])  # fmt: skip
    check_overrides(c.passes, arm=is_arm(c), config=c)
    name = c.planner.name if c.planner is not None else "adaptive"
    planner_class(name)  # an unknown or broken planner is refused before the run


def check_overrides(passes: PassesConfig, arm: bool, config: SceneConfig | None = None) -> None:
    """The scene's pass overrides: one entry a pass, within the job's passes, no work angle on
    a gantry, and (with the scene's ``config``) a travel speed inside the process window and
    within what the axes reach, as the scene's own welding speed must be."""
    numbers = [o.number for o in passes.overrides]
    for i, o in enumerate(passes.overrides):
        if o.number in numbers[:i]:
            raise SceneError(
                f"pass {o.number} is overridden more than once",
                field=f"passes.overrides.{i}.number",
                fix="merge the entries for that pass into one",
            )
        if isinstance(passes.count, int) and o.number > passes.count:
            raise SceneError(
                f"pass {o.number} is overridden but the job has {passes.count} passes",
                field=f"passes.overrides.{i}.number",
                fix="number the passes from 1 to passes.count",
            )
        if config is not None and o.travel_speed_mm_s is not None:
            _check_override_speed(o.travel_speed_mm_s, f"passes.overrides.{i}.travel_speed_mm_s",
                                  config, arm)  # fmt: skip
        if not arm and o.work_angle_deg:
            raise SceneError(
                f"a work angle of {o.work_angle_deg} deg on the gantry, which cannot tilt "
                "its torch",
                field=f"passes.overrides.{i}.work_angle_deg",
                fix="remove it (0 on a gantry), or weld on an arm (robot.model)",
            )


def _check_override_speed(speed: float, field: str, c: SceneConfig, arm: bool) -> None:
    p = c.process or ProcessConfig()
    if not p.travel_speed_min_mm_s <= speed <= p.travel_speed_max_mm_s:
        raise SceneError(
            f"travel speed {speed:g} mm/s is outside the process window "
            f"[{p.travel_speed_min_mm_s:g}, {p.travel_speed_max_mm_s:g}] mm/s",
            field=field,
            fix="give a speed inside process.travel_speed_min_mm_s .. _max_mm_s (or widen them)",
        )
    limits = c.robot.tcp_velocity_max_mm_s if arm else c.robot.velocity_max_mm_s
    reach = math.hypot(*limits)
    if speed > reach:
        raise SceneError(
            f"travel speed {speed:g} mm/s exceeds what the axes can reach (velocity limits "
            f"{list(limits)} mm/s)",
            field=field,
            fix=f"use at most {reach:.4g} mm/s (and at most the axis limit along a seam that "
            "follows one axis)",
        )


def overridden(plan: PassPlan, passes: PassesConfig, pass_index: int) -> PassPlan:
    """The plan with the scene's overrides for this pass (0-based index) applied."""
    for o in passes.overrides:
        if o.number != pass_index + 1:
            continue
        changes: dict[str, object] = {}
        if o.reference is not None:
            changes.update(reference=o.reference, offset_profile_mm=None)
        if o.offset_mm is not None:
            changes.update(offset_mm=o.offset_mm, offset_profile_mm=None)
        if o.work_angle_deg is not None:
            changes["work_angle_rad"] = math.radians(o.work_angle_deg)
        if o.travel_speed_mm_s is not None:
            changes.update(travel_speed_mm_s=o.travel_speed_mm_s, speed_profile_mm_s=None)
        if o.wire_feed_m_min is not None:
            changes["wire_feed_mm_s"] = wire_feed_mm_s(o.wire_feed_m_min)
        plan = dataclasses.replace(plan, **changes)  # type: ignore[arg-type]
    return plan
