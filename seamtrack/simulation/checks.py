"""Scene checks that bound what a run may cost, and the free-form sections checked against
the plugins that take them: every knob that sets an array size (rays, seam points, control
ticks, trace rows, mesh tolerance) against :mod:`seamtrack.constants`, so that a typo is
refused in one line before anything runs.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack import constants
from seamtrack.control.registry import tracker_class
from seamtrack.errors import SceneError
from seamtrack.features.base import ExtractorBase
from seamtrack.features.expect import parse_expect
from seamtrack.features.extractors import extractor_target
from seamtrack.params import check_params
from seamtrack.sensing.scan import StripeNoise, sense_seam
from seamtrack.sensing.sensor import LaserLineSensor
from seamtrack.simulation.config import SceneConfig


def default_time_limit_s(seam_length_mm: float, welding_speed_mm_s: float) -> float:
    """The run's time limit when the scene sets none: three times the nominal welding time,
    plus a minute."""
    return 3.0 * seam_length_mm / welding_speed_mm_s + 60.0


def check_ticks(c: SceneConfig, seam_length_mm: float | None) -> None:
    """Refuse a run of more than :data:`constants.MAX_TICKS` control ticks (the loop's logs
    grow with them); ``seam_length_mm`` None: not known before the seam is built."""
    limit = c.simulation.time_limit_s
    if limit is None and seam_length_mm is None:
        return
    if limit is None:
        assert seam_length_mm is not None
        limit = default_time_limit_s(seam_length_mm, c.simulation.welding_speed_mm_s)
    ticks = limit / c.robot.control_period_s
    needed_period_s = limit / constants.MAX_TICKS
    if (
        ticks > constants.MAX_TICKS
        and c.simulation.time_limit_s is None
        and needed_period_s > 1.0 / c.sensor.frame_rate_hz
    ):
        # No control period both holds the default time limit and keeps up with the sensor:
        # the speed sets that limit, so the speed is at fault (1e-300 mm/s, not the period).
        assert seam_length_mm is not None
        slowest = (
            3.0 * seam_length_mm / (constants.MAX_TICKS / c.sensor.frame_rate_hz - 60.0)
            if constants.MAX_TICKS / c.sensor.frame_rate_hz > 60.0
            else math.inf
        )
        raise SceneError(
            f"a welding speed of {c.simulation.welding_speed_mm_s:.3g} mm/s gives the "
            f"{seam_length_mm:.4g} mm seam a default time limit of {limit:.3g} s: more than "
            f"the {constants.MAX_TICKS:.0e} control ticks a run holds at any control period "
            f"up to the sensor's frame period ({1.0 / c.sensor.frame_rate_hz:.3g} s)",
            field="simulation.welding_speed_mm_s",
            fix=(
                f"use a welding speed of at least {slowest:.3g} mm/s, or set "
                "simulation.time_limit_s"
                if math.isfinite(slowest)
                else "set simulation.time_limit_s"
            ),
        )
    if ticks > constants.MAX_TICKS:
        raise SceneError(
            f"a time limit of {limit:.4g} s at a control period of {c.robot.control_period_s:.3g} "
            f"s is {ticks:.3g} control ticks, more than the {constants.MAX_TICKS:.0e} a run holds "
            "in memory",
            field="robot.control_period_s",
            fix=f"use a control period of at least {limit / constants.MAX_TICKS:.3g} s, or "
            "set a shorter simulation.time_limit_s",
        )


def _polyline_length(points: list[list[float]]) -> float:
    return sum(math.dist(a, b) for a, b in itertools.pairwise(points))


def check_sizes(c: SceneConfig) -> None:
    """Every knob that sets an array size, against the bounds in :mod:`seamtrack.constants`."""
    s = c.seam
    if s.source == "paper" and s.length_mm / s.step_mm + 1 > constants.MAX_SEAM_POINTS:
        raise SceneError(
            f"a {s.length_mm:.4g} mm seam at a {s.step_mm:.3g} mm step has "
            f"{s.length_mm / s.step_mm + 1:.3g} points, more than {constants.MAX_SEAM_POINTS:.0e}",
            field="seam.step_mm",
            fix=f"use a step of at least {s.length_mm / (constants.MAX_SEAM_POINTS - 1):.3g} mm "
            "(or a shorter seam.length_mm)",
        )
    if s.points_mm is not None and len(s.points_mm) > constants.MAX_SEAM_POINTS:
        raise SceneError(
            f"{len(s.points_mm)} points, more than {constants.MAX_SEAM_POINTS:.0e}",
            field="seam.points_mm",
            fix="thin the points out, or give them as a CSV file",
        )
    if c.sensor.rays is not None and c.sensor.rays > constants.MAX_RAYS:
        raise SceneError(
            f"{c.sensor.rays} rays, more than the {constants.MAX_RAYS} a profile may have",
            field="sensor.rays",
            fix=f"use at most {constants.MAX_RAYS} (a real sensor has 1024-4096 points)",
        )
    if c.sensor.fan == "section" and not c.sensor.refine_float64:
        raise SceneError(
            "the plane-section fan's hits are exact float64: it has no float32 stage to keep, "
            "so refine_float64 = false cannot apply to it",
            field="sensor.fan",
            fix='set sensor.fan = "auto" or "embree" to keep Embree\'s float32 hits, or '
            "sensor.refine_float64 = true",
        )
    if c.simulation.trace_period_s < c.robot.control_period_s:
        raise SceneError(
            f"trace period {c.simulation.trace_period_s:.3g} s is shorter than the control "
            f"period {c.robot.control_period_s:.3g} s: the trace would repeat ticks",
            field="simulation.trace_period_s",
            fix=f"use at least the control period ({c.robot.control_period_s:.3g} s)",
        )
    if c.workpiece is not None and c.workpiece.tolerance_mm < constants.MIN_MESH_TOLERANCE_MM:
        raise SceneError(
            f"meshing tolerance {c.workpiece.tolerance_mm:.3g} mm is finer than "
            f"{constants.MIN_MESH_TOLERANCE_MM:.0e} mm: a curved face would mesh into more "
            "triangles than fit in memory",
            field="workpiece.tolerance_mm",
            fix=f"use at least {constants.MIN_MESH_TOLERANCE_MM:.0e} mm (0.01 is the default)",
        )
    if c.workpiece is not None and c.workpiece.tolerance_mm > constants.MAX_MESH_TOLERANCE_MM:
        raise SceneError(
            f"meshing tolerance {c.workpiece.tolerance_mm:.3g} mm is coarser than "
            f"{constants.MAX_MESH_TOLERANCE_MM:g} mm: the facets would move the part's curved "
            "faces by that much, and the tracker would follow them, not the part",
            field="workpiece.tolerance_mm",
            fix=f"use at most {constants.MAX_MESH_TOLERANCE_MM:g} mm (0.01 is the default)",
        )
    length = {"paper": s.length_mm, "points": _polyline_length(s.points_mm or [])}.get(s.source)
    check_ticks(c, length)


def check_seam_scale(seam: Any, look_ahead_mm: float, field: str) -> None:
    """Refuse a seam (from a file or a list of points) shorter than the sensor's look-ahead: the
    laser line starts past its end, so no frame can see it. Most often its points are in metres
    (a 400 mm seam given as 0.4): then say so."""
    length = float(seam.length_mm)
    if length >= look_ahead_mm:
        return
    span = float(np.ptp(seam.points, axis=0).max())
    metres = 1000.0 * length >= look_ahead_mm
    raise SceneError(
        f"the points span {span:.3g} mm (a seam {length:.3g} mm long), shorter than the "
        f"sensor's {look_ahead_mm:.3g} mm look-ahead: the laser line starts past the seam's end"
        + (f"; looks like metres (x1000: {1000.0 * length:.4g} mm)" if metres else ""),
        field=field,
        fix="give the points in millimetres (multiply metres by 1000)"
        if metres
        else "give a seam longer than sensor.look_ahead_mm, or a shorter look-ahead",
    )


def check_seam_in_view(
    poses_T_world_sensor: NDArray[np.float64], sensor: LaserLineSensor, seam: Any
) -> int:
    """How many of the sensor poses along the planned path see the seam (the laser plane
    crosses it inside the field of view and depth of field; geometry only, no occlusion).
    Refuse a sensor that sees it from none of them: the run could only end ``lost_seam``."""
    reasons: dict[str, int] = {}
    seen = 0
    for T in poses_T_world_sensor:
        found = sense_seam(seam, T, sensor)
        if found:
            seen += 1
        else:
            reasons[found.reason] = reasons.get(found.reason, 0) + 1
    if seen:
        return seen
    reason = max(reasons, key=lambda r: reasons[r]) if reasons else "no pose"
    crosses = "field of view" in reason  # the plane crosses it, but out of range
    raise SceneError(
        f"the seam is never in view: from none of {len(poses_T_world_sensor)} sensor poses "
        f"along the planned path ({reason})",
        field="sensor.range_mm" if crosses else "sensor.mount_rotation_deg",
        fix="bring the seam into the sensor's range (sensor.range_mm, sensor.look_ahead_mm; "
        "seamtrack sensor shows the range)"
        if crosses
        else "turn the laser line across the seam (sensor.mount_rotation_deg, or leave it unset "
        "to mount the sensor from the seam)",
    )


def check_plugin_params(c: SceneConfig) -> None:
    """The free-form sections against the signatures that take them (strict types, declared
    ranges), so that a bad value is refused before the run rather than deep inside it."""
    check_params(StripeNoise, c.sensor.stripe_noise, "sensor.stripe_noise")
    check_params(tracker_class(c.tracker.name), c.tracker.params, "tracker.params")
    if c.extractor.params and c.extractor.name is None:
        raise SceneError(
            "extractor.params given, but no extractor.name (the joint type picks one)",
            field="extractor.name",
            fix='name the extractor the parameters are for, e.g. extractor.name = "fillet"',
        )
    if c.extractor.name is not None and (c.sensor.mode == "mesh" or c.extractor.params):
        target = extractor_target(c.extractor.name)
        if isinstance(target, type):
            check_params(target, c.extractor.params, "extractor.params")
    if c.extractor.expect:
        check_expect(c.extractor.name, c.extractor.expect)


def check_expect(name: str | None, expect: dict[str, Any]) -> None:
    """``[extractor.expect]`` against the family extractor it is for (the joint type's, checked
    when the part is loaded, when ``name`` is None)."""
    if name is None:
        return
    target = extractor_target(name)
    if not (isinstance(target, type) and issubclass(target, ExtractorBase)):
        raise SceneError(
            f"{name!r} takes no expectations (only the built-in family extractors do)",
            field="extractor.expect",
            fix="remove [extractor.expect], or name a family extractor (v-groove, fillet, ...)",
        )
    parse_expect(expect, str(target.name))


def union_errors(errors: list[Any]) -> list[Any]:
    """Pydantic's errors with those of a union field (a number or a list, e.g.
    ``robot.servo_gain_1_s``) cut to what concerns the value given: a value that fits no member
    is told by every member, "not a number" by one and "the list's item 2 must be > 0" by the
    other. Each union field keeps its members' errors other than a mere wrong type (or, when
    there are only those, the one deepest in the value), under the field's own path (without
    the member's name that pydantic puts in it, like ``list[constrained-float]``)."""
    out: list[Any] = []
    groups: dict[tuple[Any, ...], list[Any]] = {}
    for err in errors:
        loc = tuple(err["loc"])
        tag = next((i for i, p in enumerate(loc) if isinstance(p, str) and ("[" in p or "-" in p)),
                   None)  # fmt: skip
        if tag is None:
            out.append(err)
            continue
        field = loc[:tag]
        if field not in groups:
            groups[field] = []
            out.append(field)  # a placeholder: the group's errors go here, in order
        groups[field].append({**err, "loc": field + loc[tag + 1 :]})
    kept: list[Any] = []
    for item in out:
        if isinstance(item, tuple):
            group = groups[item]
            specific = [e for e in group if not e["type"].endswith(("_type", "_parsing"))]
            kept += specific or [max(group, key=lambda e: len(e["loc"]))]  # the deepest
        else:
            kept.append(item)
    return kept


def check_arc(c: SceneConfig) -> None:
    """An ``[arc]`` the run can draw: a stripe profile to act on (mesh mode), the image model
    only where the camera forms images, the laser line outside the torch's nozzle."""
    a = c.arc
    if a is None:
        return
    if c.sensor.mode != "mesh":
        raise SceneError(
            "the arc acts on the stripe, and seam mode has none",
            field="arc.model",
            fix='set sensor.mode = "mesh" (with a [workpiece]), or remove [arc]',
        )
    if a.model == "image" and c.sensor.source != "image":
        raise SceneError(
            "the image model draws the arc into the camera's image, and this sensor forms none",
            field="arc.model",
            fix='set arc.model = "profile" (or "auto"), or sensor.source = "image"',
        )
    from seamtrack.sensing.arc.profile_model import MIN_LOOK_AHEAD_MM

    if c.sensor.look_ahead_mm < MIN_LOOK_AHEAD_MM:
        raise SceneError(
            f"a {c.sensor.look_ahead_mm:g} mm look-ahead puts the laser line under the torch's "
            f"nozzle (radius {MIN_LOOK_AHEAD_MM:g} mm)",
            field="sensor.look_ahead_mm",
            fix=f"look at least {MIN_LOOK_AHEAD_MM:g} mm ahead of the arc (trackers: 20-40 mm)",
        )
