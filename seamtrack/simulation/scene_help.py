"""What every key of a scene file means, one line each, and the commented scene file that
``seamtrack init`` writes from it.

The lines are kept beside the schema (:mod:`seamtrack.simulation.config`) rather than in it so
that the schema stays a list of types and bounds; a test holds the two in step (every field of
the schema has its line, and no line names a field that does not exist).
"""

from __future__ import annotations

import json
import math
from typing import Any

from pydantic import BaseModel

from seamtrack.simulation.config import Scene, SceneConfig

#: One line per key, by its dotted path (a list of tables: the table's path, e.g.
#: ``passes.overrides.number``). Units are in the key names; defaults that are computed say how.
KEY_HELP: dict[str, str] = {
    "name": "the scene's name (outputs and titles)",
    "description": "one line saying what the scene is (seamtrack init --list)",
    "countermeasures": '"default": blob rejection, seam-point gate, prediction on; "none": '
    'off (unset: "default" with an [arc]); explicit keys win',
    # [simulation]
    "simulation": "the run: speed, seed, when it ends, how often the trace is written",
    "simulation.welding_speed_mm_s": "the torch's travel speed along the seam",
    "simulation.seed": "seed of the run's one random generator (noise, dropouts)",
    "simulation.end_tolerance_mm": "completed when the torch stops this near the seam's end "
    "(unset: one frame's travel + 1 mm)",
    "simulation.stall_time_s": "no progress along the seam for this long ends the run as stalled",
    "simulation.time_limit_s": "simulated time limit (unset: 3 x length / speed + 60 s)",
    "simulation.wall_time_limit_s": "wall-clock limit of the run",
    "simulation.trace_period_s": "period of the rows of trace.csv",
    # [seam]
    "seam": "the true seam: the paper's curve, points, a CSV or a workpiece's edge",
    "seam.source": '"paper" (Eq. 15-17), "points", "csv" or "workpiece" (a CAD edge)',
    "seam.step_mm": "spacing of the points the paper's curve is sampled at",
    "seam.length_mm": "length of the paper's curve along X",
    "seam.points_mm": "the seam's corner points [[x, y, z], ...] (source = points)",
    "seam.file": "CSV of x_mm, y_mm, z_mm[, nx, ny, nz], relative to the scene file",
    "seam.offset_mm": "moves the seam in the world frame",
    "seam.rotation_deg": "turns the seam about X, Y, Z (deg), before the offset",
    # [sensor]
    "sensor": "the laser line sensor: make, mode, rate, mount",
    "sensor.preset": "the sensor's make (the paper's, or a real one's data sheet)",
    "sensor.mode": '"seam" (laser plane crossed with the seam) or "mesh" (rays on the part)',
    "sensor.source": '"geometry" (the stripe from rays) or "image" (a rendered camera image)',
    "sensor.camera": "the camera of image mode and its peak detector",
    "sensor.frame_rate_hz": "profiles per second",
    "sensor.latency_s": "delay from capture to the tracker",
    "sensor.look_ahead_mm": "how far ahead of the torch tip the laser line falls",
    "sensor.range_mm": "sensor to torch-tip height along the torch (unset: b / tan theta_s)",
    "sensor.mount_rotation_deg": "turns the sensor on the torch (unset: from the seam where "
    "the robot cannot turn it)",
    "sensor.quantize": "round ranges and positions to the sensor's pixel resolution",
    "sensor.noise_range_mm": "standard deviation of Gaussian noise along the range",
    "sensor.noise_lateral_mm": "standard deviation of Gaussian noise along the stripe",
    "sensor.rays": "rays along the stripe in mesh mode (unset: the preset's points)",
    "sensor.refine_float64": "recompute each hit in float64 from its triangle (Embree is float32)",
    "sensor.fan": 'how mesh mode casts the fan: "auto", "section" (plane section) or "embree"',
    "sensor.max_incidence_deg": "rays meeting the surface steeper than this are lost",
    "sensor.depth_of_field_mm": "data-sheet override: measuring range",
    "sensor.fov_near_mm": "data-sheet override: stripe width at the near end",
    "sensor.fov_far_mm": "data-sheet override: stripe width at the far end",
    "sensor.angle_deg": "data-sheet override: triangulation angle",
    "sensor.depth_resolution_mm": "data-sheet override: resolution along the range",
    "sensor.lateral_resolution_mm": "data-sheet override: resolution along the stripe",
    "sensor.focal_length_mm": "data-sheet override: the camera's focal length",
    "sensor.standoff_mm": "data-sheet override: housing front to the near end of the range",
    "sensor.stripe_noise": "point-level stripe noise: speckle, dropouts, reflections (keys of "
    "seamtrack.sensing.noise)",
    # [sensor.camera]
    "sensor.camera.rows": "image rows (unset: the preset's)",
    "sensor.camera.columns": "image columns (unset: the preset's)",
    "sensor.camera.roi": "region of interest [row, column, rows, columns] (unset: the whole image)",
    "sensor.camera.focal_length_mm": "lens focal length (unset: from the geometry)",
    "sensor.camera.f_number": "lens f-number (depth of focus, speckle size)",
    "sensor.camera.wavelength_nm": "laser wavelength (unset: the preset's data sheet, else 660)",
    "sensor.camera.line_thickness_mm": "laser line thickness at its waist",
    "sensor.camera.line_divergence_mrad": "the line's divergence (unset: a Gaussian beam's)",
    "sensor.camera.waist_range_mm": "range of the line's waist (unset: mid range)",
    "sensor.camera.exposure": "exposure as a fraction of full well at the brightest pixel",
    "sensor.camera.full_well_e": "pixel full-well capacity, electrons",
    "sensor.camera.read_noise_e": "read noise, electrons rms",
    "sensor.camera.bit_depth": "ADC bits (0: no quantization)",
    "sensor.camera.ambient": "ambient light as a fraction of full well",
    "sensor.camera.speckle": "draw laser speckle",
    "sensor.camera.shot_noise": "draw photon shot noise",
    "sensor.camera.supersample": "sub-pixels per pixel when rendering (unset: automatic)",
    "sensor.camera.ideal": "every noise source off",
    "sensor.camera.exposure_mode": '"multi" (HDR set), "auto" or "fixed" (unset: "fixed" under '
    '`countermeasures = "default"`, else "multi")',
    "sensor.camera.target_peak": "auto exposure's target peak, fraction of full scale",
    "sensor.camera.exposure_set": "the exposures of multi mode, relative",
    "sensor.camera.method": 'peak detector: "centroid", "gaussian" or "steger"',
    "sensor.camera.threshold": "fixed detection threshold, fraction of full scale (unset: per "
    "column, max(noise_sigmas x noise, relative x peak))",
    "sensor.camera.relative": "per-column threshold as a fraction of the column's peak",
    "sensor.camera.noise_sigmas": "per-column threshold in noise standard deviations",
    "sensor.camera.choose": 'which peak of a column: "strongest", "first" or "widest"',
    "sensor.camera.filter_centre_nm": "band-pass filter's centre wavelength, nm (unset: the "
    "laser's)",
    "sensor.camera.filter_fwhm_nm": "band-pass filter's full width at half maximum, nm (>= 0.1; "
    'unset: 10 under `countermeasures = "default"`, no filter under "none")',
    "sensor.camera.filter_shape": 'band-pass filter\'s transmission: "gaussian" or "top-hat"',
    "sensor.camera.laser_power_w": "the laser's power, W, against the arc's light (unset: 0.1)",
    "sensor.camera.reject": '"blobs": drop runs not shaped like the stripe (blobs, streaks, '
    'glow); "none" (unset: from countermeasures)',
    "sensor.camera.reject_max_width": "a run wider than this times the stripe's equivalent "
    "width is rejected (unset: 3)",
    "sensor.camera.reject_max_peak": "a run brighter than this times the stripe's height is "
    "rejected (unset: 20)",
    "sensor.camera.reject_min_peak": "a run dimmer than this times the stripe's height is "
    "rejected (unset: 0)",
    "sensor.camera.reject_stripe_width_px": "the stripe's equivalent width in pixels (unset: "
    "the frame's median)",
    # [robot]
    "robot": "the robot: the paper's 3-axis gantry or an articulated arm",
    "robot.model": '"cartesian" (the paper\'s gantry) or an arm ("ur10e", "kr16")',
    "robot.urdf": "an arm's URDF file instead of a built-in model",
    "robot.control_period_s": "servo period (the control tick)",
    "robot.servo_gain_1_s": "servo gain, one or one per axis/joint (unset: the model's)",
    "robot.interpolation_period_s": "an arm's interpolation period (unset: the control period)",
    "robot.tcp_velocity_max_mm_s": "an arm's tool speed limit, X, Y, Z",
    "robot.tcp_acceleration_max_mm_s2": "an arm's tool acceleration limit, X, Y, Z",
    "robot.angular_velocity_max_deg_s": "an arm's tool turning-rate limit",
    "robot.angular_acceleration_max_deg_s2": "an arm's tool turning-acceleration limit",
    "robot.joint_acceleration_max_deg_s2": "an arm's joint acceleration limits (unset: the "
    "model's)",
    "robot.min_wrist_angle_deg": "an arm keeps its wrist this far from the singularity",
    "robot.tool": "the torch on the flange and the sensor on the torch (arms)",
    "robot.tool.tcp_xyz_mm": "torch tip in the flange frame",
    "robot.tool.tcp_rpy_deg": "torch frame's roll, pitch, yaw in the flange frame",
    "robot.tool.sensor_xyz_mm": "sensor in the torch frame (unset: from look_ahead_mm, range_mm)",
    "robot.tool.sensor_rpy_deg": "sensor's roll, pitch, yaw in the torch frame (unset: from "
    "mount_rotation_deg)",
    "robot.position_min_mm": "the gantry's lower axis limits, X, Y, Z",
    "robot.position_max_mm": "the gantry's upper axis limits, X, Y, Z",
    "robot.velocity_max_mm_s": "the gantry's axis speed limits, X, Y, Z",
    "robot.acceleration_max_mm_s2": "the gantry's axis acceleration limits, X, Y, Z",
    "robot.base_origin_mm": "the robot base's origin in the world frame",
    "robot.base_rotation_deg": "the robot base's rotation about X, Y, Z in the world",
    "robot.start_offset_mm": "where the torch starts, from the seam's first point",
    # [torch]
    "torch": "torch angles relative to the seam frame",
    "torch.work_angle_deg": "work angle, about the seam's tangent",
    "torch.travel_angle_deg": "travel (push/drag) angle, in the plane of travel",
    # [tracker]
    "tracker": "the tracking algorithm",
    "tracker.name": '"point-to-point" (I), "convergence-radius" (II), "trajectory" or '
    '"package.module:Class"',
    "tracker.radius_mm": "algorithm II's convergence radius (unset: its default)",
    "tracker.tolerance_mm": "algorithm I's arrival tolerance (unset: its default)",
    "tracker.params": "keywords of the tracker's class",
    # [extractor]
    "extractor": "the feature extractor that finds the seam point in a profile",
    "extractor.name": "the extractor (unset: the one the seam's joint calls for, else v-groove)",
    "extractor.offset_mm": "torch aim offset from the seam point, (y, z) in the laser plane",
    "extractor.params": "keywords of the extractor",
    "extractor.expect": "expected joint geometry (angle_deg, depth_mm, gap_mm and their _tol)",
    # [workpiece]
    "workpiece": "the part in mesh mode: a CAD script, a STEP file or a weldx groove",
    "workpiece.script": "a cad/ script building the part (CadQuery)",
    "workpiece.step": "a STEP file (one solid or a weldment)",
    "workpiece.seam": "which seam: a script's seam name, an edge selector or a weldment's seam",
    "workpiece.seam_near_mm": "points along the seam, to pick its edges [[x, y, z], ...]",
    "workpiece.groove": "a weldx ISO 9692-1 groove instead of a script",
    "workpiece.tolerance_mm": "absolute meshing tolerance",
    "workpiece.angular_tolerance_deg": "angular meshing tolerance",
    "workpiece.params": "keywords of the script",
    "workpiece.offset_mm": "moves the part in the world frame",
    "workpiece.rotation_deg": "turns the part about X, Y, Z, before the offset",
    "workpiece.obstacles": "boxes (clamps, fixtures) that the laser can hit",
    "workpiece.obstacles.min_mm": "the box's lower corner, world frame",
    "workpiece.obstacles.max_mm": "the box's upper corner, world frame",
    "workpiece.material": "surface material in image mode (seamtrack.sensing.materials)",
    # [process]
    "arc": "the welding arc in the sensor's view (docs/arc.md); no section, no arc",
    "arc.process": '"mag-short", "mag-spray" or "tig"',
    "arc.current_a": "welding current, A (the arc's radiance, spatter and fume)",
    "arc.model": '"image", "profile" or "auto" (image when the sensor forms images)',
    "arc.spatter": "glowing droplets on ballistic paths",
    "arc.fume": "the fume's attenuation and veiling glow",
    "arc.glow": "the hot plate's own light near the arc",
    "gate": "the seam-point gate in time between the extractor and the tracker (docs/arc.md)",
    "gate.enabled": 'the gate on or off (unset: on with countermeasures = "default")',
    "gate.window_mm": "search window about the predicted seam point (unset: 15; 0: no gate)",
    "gate.reacquire_frames": "invalid frames in a row after which the next point is taken "
    "(unset: 20)",
    "gate.on_invalid": 'a refused frame: "hold" (no seam point: the last target) or '
    '"predict" (the predicted point); unset: from countermeasures',
    "distortion": "the butt joint moving while it is welded (docs/heat.md); none, still",
    "distortion.material": '"carbon_steel", "stainless_steel" or "aluminium"',
    "distortion.thickness_mm": "plate thickness, mm (the heat and the bending)",
    "distortion.plate_width_mm": "each plate's width off the weld line, to its pinned edge",
    "distortion.angle_peak_deg": "largest permanent angle of the Q/h^2 hump (your fit)",
    "distortion.angle_peak_q_per_h2_j_mm3": "the Q/h^2 at which the angle peaks, J/mm^3",
    "distortion.shrinkage_coefficient": "Okerblom's A (1: the whole free expansion)",
    "distortion.gap_rotation_deg": "the free plate's turn ahead of the arc (+ opens the gap)",
    "distortion.fixed_plate": '"left", "right" (clamped in its plane) or "none"',
    "distortion.stiff_below_c": "the weld locks its distortion in below this, degC",
    "distortion.transient": "the elastic bending near the arc (through-thickness heat)",
    "distortion.tacks": "tack welds across the joint: they hold the gap until they crack",
    "distortion.tacks.position_mm": "where along the seam, mm",
    "distortion.tacks.length_mm": "the tack's length along the seam, mm",
    "distortion.tacks.throat_mm": "the depth the tack fuses, mm",
    "distortion.clamps": "clamps across the joint: they hold the gap whatever the force",
    "distortion.clamps.position_mm": "where along the seam, mm",
    "process": "the welding process (GMAW) of a multi-pass job",
    "process.wire_diameter_mm": "wire diameter",
    "process.wire_feed_m_min": "wire feed speed, m/min",
    "process.deposition_efficiency": "fraction of the wire that ends in the bead",
    "process.voltage_v": "arc voltage, V",
    "process.current_a": "welding current, A",
    "process.thermal_efficiency": "arc thermal efficiency (MIG/MAG 0.8)",
    "process.ctwd_mm": "contact-tip-to-work distance",
    "process.travel_speed_min_mm_s": "slowest travel speed a planner may command",
    "process.travel_speed_max_mm_s": "fastest travel speed a planner may command",
    "process.bead": "the bead's cross-section model",
    "process.bead.model": '"arc", "parabola" or "cosine" (Ding et al. 2015)',
    "process.bead.width_to_height": "bead width over height on a flat plate",
    "process.bead.wetting_angle_deg": "the arc model's wetting angle (unset: from the ratio)",
    # [passes]
    "passes": "a multi-pass job",
    "passes.count": 'number of passes, or "auto" (the planner decides)',
    "passes.scan_first": "a scan-only pass measures the empty groove first",
    "passes.reinforcement_mm": "the cap's target height over the plates' top",
    "passes.fusion_margin_min_mm": "flag stations whose sidewall fusion margin is below this",
    "passes.overrides": "values that replace the planner's for one pass",
    "passes.overrides.number": "the pass (1-based, the scan-only pass not counted)",
    "passes.overrides.reference": 'where the bead aims: "left", "right", "centre", "left_top", '
    '"right_top"',
    "passes.overrides.offset_mm": "offset from the reference",
    "passes.overrides.work_angle_deg": "the pass's work angle",
    "passes.overrides.travel_speed_mm_s": "the pass's travel speed",
    "passes.overrides.wire_feed_m_min": "the pass's wire feed, m/min",
    # [planner]
    "planner": "the fill planner of a multi-pass job",
    "planner.name": '"adaptive", "fixed" or "package.module:Class"',
    "planner.params": "keywords of the planner's class",
}


def schema_keys(model: type[BaseModel] = SceneConfig, prefix: str = "") -> list[str]:
    """Every key of the schema by its dotted path, tables and their keys."""
    keys = []
    for name, info in model.model_fields.items():
        path = prefix + name
        keys.append(path)
        sub = _submodel(info.annotation)
        if sub is not None:
            keys += schema_keys(sub, path + ".")
    return keys


def _submodel(annotation: Any) -> type[BaseModel] | None:
    """The section model in a field's type (``X``, ``X | None``, ``list[X]``), else None."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    for arg in getattr(annotation, "__args__", ()):
        found = _submodel(arg)
        if found is not None:
            return found
    return None


def _toml(value: Any) -> str:
    """One TOML value on one line (the json dump of a config: str, bool, numbers, lists, dicts)."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return json.dumps(value)
    if isinstance(value, int):
        return str(value)
    if isinstance(value, float):
        return (
            repr(value)
            if math.isfinite(value)
            else ("nan" if value != value else ("inf" if value > 0 else "-inf"))
        )
    if isinstance(value, list | tuple):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{ " + ", ".join(f"{_key(k)} = {_toml(v)}" for k, v in value.items()) + " }"
    raise TypeError(f"no TOML form for {type(value).__name__}")


def _key(name: str) -> str:
    return name if name.replace("_", "").replace("-", "").isalnum() else json.dumps(name)


def _comment(text: str) -> str:
    return f"# {text}"


def _table(
    lines: list[str], model: type[BaseModel], data: dict[str, Any], path: str, header: str
) -> None:
    """Write one table: its comment and header, each key with its comment line, unset keys
    commented out, then its sub-tables."""
    lines += ["", _comment(KEY_HELP.get(path, path)), header]
    later: list[tuple[str, Any, Any]] = []
    for name, info in model.model_fields.items():
        key = f"{path}.{name}"
        sub = _submodel(info.annotation)
        value = data.get(name)
        if (sub is not None and value) or isinstance(value, dict):
            later.append((name, sub, value))
            continue
        lines.append(_comment(KEY_HELP.get(key, key)))
        lines.append(f"{name} = {_toml(value)}" if value is not None else f"# {name} = (unset)")
    for name, sub, value in later:
        key = f"{path}.{name}"
        if sub is not None and isinstance(value, list):  # a list of tables
            for item in value:
                _table(lines, sub, item, key, f"[[{key}]]")
        elif sub is not None:
            _table(lines, sub, value, key, f"[{key}]")
        else:  # free keywords (params, stripe_noise, expect, groove)
            lines += ["", _comment(KEY_HELP.get(key, key)), f"[{key}]"]
            for k, v in (value or {}).items():
                lines += [_comment(f"a keyword of {key}"), f"{_key(k)} = {_toml(v)}"]


def commented_scene(scene: Scene, header: str = "") -> str:
    """The scene as a TOML file with every key of its resolved form, each under a comment line
    saying what it means (``seamtrack init``); keys left unset are written commented out.
    ``header``: comment lines to open the file with (a template's own)."""
    data = scene.config.model_dump(mode="json")
    lines = [header.rstrip(), ""] if header.strip() else []
    lines += [
        _comment("Every key, each under a line saying what it means (units in the key names)."),
        _comment("Unset keys are commented out; `seamtrack check FILE` checks the file."),
        "",
    ]
    for name in ("name", "description"):
        lines += [_comment(KEY_HELP[name]), f"{name} = {_toml(data[name])}"]
    switch = data["countermeasures"]
    lines += [_comment(KEY_HELP["countermeasures"]),
              f"countermeasures = {_toml(switch)}" if switch is not None else
              "# countermeasures = (unset)"]  # fmt: skip
    for name, info in SceneConfig.model_fields.items():
        sub = _submodel(info.annotation)
        if sub is None:
            continue
        if data.get(name) is None:
            continue  # a section the scene does not use (mesh, multi-pass)
        _table(lines, sub, data[name], name, f"[{name}]")
    return "\n".join(lines) + "\n"
