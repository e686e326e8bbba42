"""``seamtrack bench arc``: the trade between the arc, the look-ahead and the countermeasures,
measured (issue 38 item 5), and the calibration of the profile-mode arc model on the image
model (item 2).

The bench sweeps the welding current and the look-ahead, image mode (the arc drawn into the
camera's image, ``v-groove-arc``) against profile mode (the statistical model on the ray-cast
stripe, ``v-groove-arc-profile``), and the countermeasures. Each cell scans frames along the
straight V-groove open loop and compares the extractor's seam point with the seam's true
crossing of the laser plane (the noise-free truth): ``detect_rate``, ``median_mm``,
``p95_mm``, ``frames_per_s`` of the scan (render or ray cast, the arc, the extractor). Then it
runs the closed loop on the V-groove bent on a 200 mm radius (the look-ahead cuts the curve's
chord): ``loop_max_error_mm``. Beside the rows, :func:`image_cost` measures what the arc costs
image mode (``image_cost_ratio``: wall ms a frame with the arc over without it, on the same
frames, with the 1-minute load). Writes ``arc.json`` and ``arc.png``.

The calibration (:func:`calibrate`, ``python -m seamtrack.bench.arc --calibrate``) renders the
same frames with and without the arc and with an ideal camera, and measures per stripe column
how often the arc takes the true point and what it puts there: the parameters of
:data:`seamtrack.sensing.arc.profile_model.PROFILE_ARC`.
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import time
from pathlib import Path
from typing import Any

import numpy as np

from seamtrack.bench.common import machine_info, markdown_table

FloatArray = np.ndarray

#: The bench's grid (issue 38 item 5).
CURRENTS_A = (100.0, 150.0, 200.0, 250.0, 300.0, 350.0)
LOOK_AHEADS_MM = (10.0, 20.0, 30.0, 40.0, 50.0)
MODES = ("image", "profile")
#: The countermeasures compared: name -> scene overrides (the scene's one-word switch,
#: ``countermeasures``: peak rejection, the seam-point gate, hold or predict; docs/arc.md).
COUNTERMEASURES: dict[str, dict[str, Any]] = {
    "none": {"countermeasures": "none"},
    "default": {"countermeasures": "default"},
}
#: The scenes of the two modes.
SCENES = {"image": "v-groove-arc", "profile": "v-groove-arc-profile"}
#: The closed loop's curve: the V-groove on an arc of this radius (mm); 50 mm ahead on it the
#: laser line crosses the seam 6.3 mm off the torch's tangent.
CURVE_RADIUS_MM = 200.0
COLUMNS = (
    "current_a",
    "look_ahead_mm",
    "mode",
    "countermeasures",
    "detect_rate",
    "median_mm",
    "p95_mm",
    "loop_max_error_mm",
    "frames_per_s",
)
#: A seam point farther than this from the truth, or none, counts as a false or lost point in
#: the calibration (mm; the camera's own noise is a few hundredths).
CALIBRATION_TOLERANCE_MM = 0.5


# --------------------------------------------------------------------------- scenes
def arc_scene(
    current_a: float,
    look_ahead_mm: float,
    mode: str,
    countermeasures: str = "none",
    overrides: dict[str, Any] | None = None,
) -> Any:
    """The bench's scene of one cell (a :class:`seamtrack.simulation.config.Scene`)."""
    from seamtrack.simulation.scene import load_scene

    values = {"arc.current_a": float(current_a), "sensor.look_ahead_mm": float(look_ahead_mm)}
    values.update(COUNTERMEASURES[countermeasures])
    values.update(overrides or {})
    return load_scene(SCENES[mode], values)


def without_arc(scene: Any) -> Any:
    """The same scene with no ``[arc]``."""
    return dataclasses.replace(scene, config=scene.config.model_copy(update={"arc": None}))


def arc_in_laser_frame(parts: Any) -> FloatArray:
    """The arc's root (the torch's tip) in the laser frame (x_L, y_L, z_L): a gantry keeps it."""
    return np.asarray(np.linalg.inv(parts.robot.T_tcp_sensor)[:3, 3])


def poses_along(
    parts: Any, look_ahead_mm: float, frames: int, start_mm: float = 3.0
) -> list[FloatArray]:
    """``frames`` sensor poses with the torch on the seam from ``start_mm`` to where the
    laser line is 3 mm before the seam's end."""
    from seamtrack.simulation.robots import sensor_pose_at

    length = float(parts.seam.length_mm)
    stations = np.linspace(start_mm, max(length - look_ahead_mm - 3.0, start_mm + 1.0), frames)
    return [sensor_pose_at(parts.robot, parts.tool_program, float(s))[0] for s in stations]


# --------------------------------------------------------------------------- calibration
def _columns(on: Any, truth: Any, arc: FloatArray) -> dict[str, FloatArray]:
    """Per stripe column of one frame: the distance of the true point from the arc, whether
    the arc took it (lost), whether the reported point is false, its range offset from the
    true point (dz) and its range from the arc's (zr)."""
    tv, tp = truth.valid, truth.points_laser
    ov, op = on.valid, on.points_laser
    dz = op[:, 1] - tp[:, 1]
    off = ~(np.abs(dz) <= CALIBRATION_TOLERANCE_MM)
    d = np.sqrt(arc[0] ** 2 + (tp[:, 0] - arc[1]) ** 2 + (tp[:, 1] - arc[2]) ** 2)
    return {
        "d": d[tv],
        "y": tp[tv, 0],
        "lost": (~ov | off)[tv],
        "false": (ov & off)[tv],
        "dz": np.where(ov & off, dz, np.nan)[tv],
        "zr": np.where(ov & off, op[:, 1] - arc[2], np.nan)[tv],
    }


def measure_image_arc(
    process: str,
    currents_a: tuple[float, ...],
    look_ahead_mm: float,
    frames: int,
    seed: int | None = None,
    countermeasures: str = "none",
) -> dict[float, list[dict[str, FloatArray]]]:
    """Image-mode frames on ``v-groove-arc`` at one look-ahead: per current, the columns of
    each frame (:func:`_columns`) against the ideal camera's stripe without the arc; under
    ``-1.0`` the same camera without the arc (the camera's own losses). ``seed``: another
    run's seed, and stations shifted by 2 mm (a measurement the calibration did not make).
    ``countermeasures``: the frames with the arc measured under these (:data:`COUNTERMEASURES`:
    the camera the switch gives, its filter and exposure control, and its peak rejection, which
    turns the blob's false points into drop-outs), as the profile model of a scene with that
    switch stands for them."""
    base: dict[str, Any] = {"arc.process": process}
    if seed is not None:
        base["simulation.seed"] = seed
    truth_parts = _build(without_arc(arc_scene(250.0, look_ahead_mm, "image", overrides={
        **base, "sensor.camera.ideal": True})))  # fmt: skip
    arc = arc_in_laser_frame(truth_parts)
    poses = poses_along(truth_parts, look_ahead_mm, frames, 3.0 if seed is None else 5.0)
    truths = [truth_parts.scan(T, 0.04 * k, None)[0] for k, T in enumerate(poses)]
    out: dict[float, list[dict[str, FloatArray]]] = {}
    scenes: dict[float, Any] = {
        float(c): arc_scene(c, look_ahead_mm, "image", countermeasures, base) for c in currents_a
    }
    scenes[-1.0] = without_arc(scenes[float(currents_a[0])])
    for current, scene in scenes.items():
        parts = _build(scene)
        out[current] = [
            _columns(parts.scan(T, 0.04 * k, None)[0], truths[k], arc) for k, T in enumerate(poses)
        ]
    return out


def _build(scene: Any) -> Any:
    from seamtrack.simulation.assemble import build_parts

    return build_parts(scene)


def _fit_blob(d: FloatArray, lost: FloatArray, current: FloatArray, base: float) -> list[float]:
    """(R_ref, gamma, s) of p = base + (1 - base) logistic((R(I) - d) / s), by maximum
    likelihood, with R(I) not falling as the current rises (R_ref gamma >= 0: a gamma of the
    wrong sign is taken as 0, so the fit lands on the bound where the data say nothing more)."""
    from scipy.optimize import minimize

    from seamtrack.sensing.arc.profile_model import CURRENT_REF_A

    ratio = np.log(current / CURRENT_REF_A)

    def gamma(x: FloatArray) -> float:
        return float(x[1]) if x[0] * x[1] >= 0 else 0.0

    def nll(x: FloatArray) -> float:
        radius = x[0] * np.exp(gamma(x) * ratio)
        p = 0.5 * (1.0 - np.tanh(0.5 * (d - radius) / abs(x[2])))
        p = np.clip(base + (1.0 - base) * p, 1e-9, 1 - 1e-9)
        return float(-np.sum(np.where(lost, np.log(p), np.log1p(-p))))

    options = {"xatol": 1e-4, "fatol": 1e-6, "maxiter": 4000}
    starts = ([10.5, 0.2, 0.3], [13.0, 0.5, 1.0], [9.0, 0.1, 0.1])
    best = min(
        (minimize(nll, x0, method="Nelder-Mead", options=options) for x0 in starts),
        key=lambda r: r.fun,
    )
    return [float(best.x[0]), gamma(best.x), float(abs(best.x[2]))]


def _streak_runs(columns: dict[str, FloatArray], outside: FloatArray) -> list[float]:
    """The lengths (mm along y_L) of the runs of false points outside the blob (gaps of up to
    3 columns bridged)."""
    idx = np.flatnonzero(columns["false"] & outside)
    if len(idx) == 0:
        return []
    breaks = np.flatnonzero(np.diff(idx) > 4)
    starts = np.concatenate([[0], breaks + 1])
    ends = np.concatenate([breaks, [len(idx) - 1]])
    y = columns["y"]
    pitch = float(np.median(np.abs(np.diff(y)))) if len(y) > 1 else 0.0
    return [float(abs(y[idx[b]] - y[idx[a]]) + pitch) for a, b in zip(starts, ends, strict=True)]


def fit_profile_arc(
    process: str, data: dict[float, dict[float, list[dict[str, FloatArray]]]]
) -> dict[str, float]:
    """The parameters of :class:`~seamtrack.sensing.arc.profile_model.ProfileArcParams` for
    one process from its measured columns ``data[look_ahead][current]``."""
    from seamtrack.sensing.arc.profile_model import ArcProfileModel, ProfileArcParams

    def gather(key: str, with_arc: bool = True) -> FloatArray:
        return np.concatenate([
            c[key] if key != "I" else np.full(len(c["d"]), cur)
            for by_current in data.values() for cur, frames in by_current.items()
            if (cur > 0) == with_arc for c in frames
        ])  # fmt: skip

    base = float(np.mean(gather("lost", with_arc=False)))
    d, lost, current = gather("d"), gather("lost"), gather("I")
    radius, gamma, edge = _fit_blob(d, lost, current, base)
    model = ArcProfileModel(process, 250.0, ProfileArcParams(radius, gamma, edge, 1, 0, 0, 0, 1))
    inside = d < radius * (current / 250.0) ** gamma + 2.0 * edge
    false, zr = gather("false"), gather("zr")
    share = float(false[inside & lost].sum() / max((inside & lost).sum(), 1))
    offsets = zr[inside & false]
    runs: list[float] = []
    for by_current in data.values():
        for cur, frames in by_current.items():
            if cur <= 0:  # the camera without the arc
                continue
            m = dataclasses.replace(model, current_a=cur)
            for c in frames:
                runs += _streak_runs(c, c["d"] > m.blob_radius_mm() + 4.0 * edge)
    weight = _streak_weight(process, data, radius, gamma, edge)
    return {
        "blob_radius_mm": round(radius, 3),
        "blob_radius_exponent": round(gamma, 3),
        "blob_edge_mm": round(edge, 3),
        "blob_false_fraction": round(share, 3),
        "blob_offset_mm": round(float(np.mean(offsets)), 2) if len(offsets) else 0.0,
        "blob_offset_sd_mm": round(float(np.std(offsets)), 2) if len(offsets) else 0.0,
        "streak_probability": float(f"{len(runs) / weight:.3g}") if weight > 0 else 0.0,
        "streak_run_mm": round(float(np.mean(runs)), 2) if runs else 1.0,
        "lost_without_arc": round(base, 5),
        "streaks_counted": len(runs),
    }


def _streak_weight(
    process: str, data: dict[float, dict[float, list[dict[str, FloatArray]]]], radius: float,
    gamma: float, edge: float,
) -> float:  # fmt: skip
    """Sum over the columns outside the blob of p_streak(d) / S_ref (the MLE's denominator)."""
    from seamtrack.sensing.arc.profile_model import ArcProfileModel, ProfileArcParams

    params = ProfileArcParams(radius, gamma, edge, 1.0, 0.0, 0.0, 1.0, 1.0)
    total = 0.0
    for by_current in data.values():
        for cur, frames in by_current.items():
            if cur <= 0:
                continue
            m = ArcProfileModel(process, cur, params)
            for c in frames:
                outside = c["d"] > m.blob_radius_mm() + 4.0 * edge
                total += float(np.sum(m.streak_probability(c["d"][outside])))
    return total


#: The calibration's grid: look-aheads around the blob's edge and beyond, currents across
#: the bench's range, frames per cell.
CALIBRATION_LOOK_AHEADS_MM = (10.0, 12.5, 15.0, 20.0, 30.0, 50.0)
CALIBRATION_CURRENTS_A = (100.0, 200.0, 300.0, 350.0)
CALIBRATION_FRAMES = 8


def calibrate(
    processes: tuple[str, ...] = ("mag-short", "mag-spray", "tig"),
    look_aheads_mm: tuple[float, ...] = CALIBRATION_LOOK_AHEADS_MM,
    currents_a: tuple[float, ...] = CALIBRATION_CURRENTS_A,
    frames: int = CALIBRATION_FRAMES,
    countermeasures: str = "none",
) -> dict[str, dict[str, float]]:
    """The profile model's parameters per process, measured from the image model under
    ``countermeasures`` (what :data:`~seamtrack.sensing.arc.profile_model.PROFILE_ARC` holds
    for that switch)."""
    fitted = {}
    for process in processes:
        data = {
            la: measure_image_arc(process, currents_a, la, frames, countermeasures=countermeasures)
            for la in look_aheads_mm
        }
        fitted[process] = fit_profile_arc(process, data)
    return fitted


# --------------------------------------------------------------------------- the bench
def _seam_error(parts: Any, T: FloatArray, feature: Any) -> float:
    from seamtrack.sensing.scan import laser_plane_crossings

    crossings = laser_plane_crossings(parts.seam, T)
    if not feature or len(crossings) == 0:
        return math.nan
    return float(np.min(np.linalg.norm(crossings - feature.point_laser, axis=1)))


def open_loop(scene: Any, frames: int) -> dict[str, float]:
    """Scan ``frames`` frames along the seam open loop: detection rate, the median and p95
    of the seam point's error against the seam's crossing of the laser plane, frames/s."""
    parts = _build(scene)
    look_ahead = scene.config.sensor.look_ahead_mm
    poses = poses_along(parts, look_ahead, frames)
    parts.scan(poses[0], 0.0, None)  # compiled kernels and caches warm, outside the timing
    errors = []
    start = time.perf_counter()
    for k, T in enumerate(poses):
        _, feature = parts.scan(T, 0.04 * (k + 1), None)
        errors.append(_seam_error(parts, T, feature))
    elapsed = time.perf_counter() - start
    e = np.asarray(errors)
    found = e[np.isfinite(e)]
    return {
        "detect_rate": float(len(found) / len(e)),
        "median_mm": float(np.median(found)) if len(found) else math.nan,
        "p95_mm": float(np.percentile(found, 95)) if len(found) else math.nan,
        "frames_per_s": float(len(e) / elapsed),
    }


def closed_loop_max_error(
    current_a: float, look_ahead_mm: float, mode: str, countermeasures: str,
    overrides: dict[str, Any],
) -> tuple[float, str]:  # fmt: skip
    """The closed loop's max error (mm) and status on the cell's scene with its V-groove bent on
    :data:`CURVE_RADIUS_MM` (``overrides`` as the open loop's)."""
    from seamtrack.simulation.loop import simulate

    curve = {**overrides, "workpiece.params.path": "arc",
             "workpiece.params.arc_radius_mm": CURVE_RADIUS_MM}  # fmt: skip
    scene = arc_scene(current_a, look_ahead_mm, mode, countermeasures, curve)
    summary = simulate(scene).summary
    value = summary.get("max_error_mm")
    return float(value) if value is not None else math.nan, str(summary.get("status"))


#: The image-mode cost of the arc (issue 38: at most 2x): its cell, frames and repeats of each
#: (quick, whole).
COST_CELL = (250.0, 30.0)
COST_FRAMES = (4, 20)
COST_REPEATS = (1, 3)


def image_cost(frames: int, overrides: dict[str, Any] | None = None,
               repeats: int = 1) -> dict[str, float]:  # fmt: skip
    """Image mode with the arc against without it on the same frames: ``v-groove-arc`` at
    :data:`COST_CELL` under the default countermeasures and the same scene with no ``[arc]``,
    each frame scanned (render, peaks, extractor) by one then the other, so both see the same
    load, ``repeats`` times, each frame's least time kept (the least disturbed by other work).
    Wall and CPU (this process's) ms a frame, their ratios, the 1-minute load."""
    current, look = COST_CELL
    scene = arc_scene(current, look, "image", "default", overrides)
    arc_parts, plain_parts = _build(scene), _build(without_arc(scene))
    poses = poses_along(arc_parts, look, frames)
    for parts in (arc_parts, plain_parts):  # compiled kernels and caches warm, untimed
        parts.scan(poses[0], 0.0, None)
    wall = {"arc": np.full(len(poses), np.inf), "no_arc": np.full(len(poses), np.inf)}
    cpu = {name: times.copy() for name, times in wall.items()}
    for _ in range(max(1, repeats)):
        for k, T in enumerate(poses):
            for name, parts in (("arc", arc_parts), ("no_arc", plain_parts)):
                w, c = time.perf_counter(), time.process_time()
                parts.scan(T, 0.04 * (k + 1), None)
                wall[name][k] = min(wall[name][k], time.perf_counter() - w)
                cpu[name][k] = min(cpu[name][k], time.process_time() - c)
    n = len(poses)
    return {
        "image_ms_per_frame_arc": 1000.0 * float(wall["arc"].mean()),
        "image_ms_per_frame_no_arc": 1000.0 * float(wall["no_arc"].mean()),
        "image_cost_ratio": float(wall["arc"].sum() / wall["no_arc"].sum()),
        "image_cpu_ms_per_frame_arc": 1000.0 * float(cpu["arc"].mean()),
        "image_cpu_ms_per_frame_no_arc": 1000.0 * float(cpu["no_arc"].mean()),
        "image_cost_ratio_cpu": float(cpu["arc"].sum() / cpu["no_arc"].sum()),
        "image_cost_frames": n,
        "image_cost_repeats": max(1, repeats),
        "image_cost_load_1min": os.getloadavg()[0],
    }


def measure_cost(quick: bool, extra: float) -> dict[str, float]:
    """:func:`image_cost` as the bench runs it (the seam ``extra`` mm beyond the look-ahead),
    with the 1-minute load before it (``image_cost_load_1min_before``)."""
    load = os.getloadavg()[0]
    cost = image_cost(COST_FRAMES[0] if quick else COST_FRAMES[1],
                      {"workpiece.params.seam_length_mm": COST_CELL[1] + extra,
                       **(QUICK_CAMERA if quick else {})},
                      COST_REPEATS[0] if quick else COST_REPEATS[1])  # fmt: skip
    cost["image_cost_load_1min_before"] = load
    return cost


def remeasure_cost(out_dir: str | Path) -> dict[str, Any]:
    """Measure the image cost again into an existing ``arc.json`` (its rows untouched): the
    cost is the figure that wants a quiet machine, the grid takes 10-25 minutes. The JSON
    records ``image_cost_command`` so the two measurements are told apart."""
    path = Path(out_dir) / "arc.json"
    data = json.loads(path.read_text())
    cost = measure_cost(bool(data["quick"]), float(data["seam_beyond_look_ahead_mm"]))
    data.update({k: _clean(v) for k, v in cost.items()})
    data["image_cost_command"] = f"python -m seamtrack.bench.arc --cost --out {out_dir}"
    path.write_text(json.dumps(data, indent=2))
    return data


#: The grid the documentation's figures were measured on when the whole grid would take over
#: 5 minutes on a busy machine (``python -m seamtrack.bench.arc --reduced``).
REDUCED_CURRENTS_A = (100.0, 250.0, 350.0)
REDUCED_LOOK_AHEADS_MM = (10.0, 20.0, 30.0, 50.0)


def bench_cells(quick: bool, reduced: bool = False) -> list[tuple[float, float, str, str]]:
    """The cells run: (current, look-ahead, mode, countermeasures)."""
    currents = (250.0,) if quick else REDUCED_CURRENTS_A if reduced else CURRENTS_A
    looks = (30.0,) if quick else REDUCED_LOOK_AHEADS_MM if reduced else LOOK_AHEADS_MM
    return [(i, la, m, cm) for i in currents for la in looks for m in MODES
            for cm in COUNTERMEASURES]  # fmt: skip


def bench_arc(
    out_dir: str | Path,
    quick: bool = False,
    reduced: bool = False,
    frames: int | None = None,
    loop: bool = True,
) -> dict[str, Any]:
    """Run the cells (:func:`bench_cells`), write ``arc.json``, ``arc.md`` and ``arc.png``.
    ``reduced``: the smaller grid, 12 frames a cell and a seam 30 mm longer than the
    look-ahead (40 mm in the whole grid)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    frames = frames or (4 if quick else 12 if reduced else 20)
    extra = 10.0 if quick else 30.0 if reduced else 40.0  # seam beyond the look-ahead (mm)
    rows = []
    load_before = os.getloadavg()[0]
    for current, look, mode, cm in bench_cells(quick, reduced):
        given = {"workpiece.params.seam_length_mm": look + extra}
        given.update(QUICK_CAMERA if quick and mode == "image" else {})
        row: dict[str, Any] = {"current_a": current, "look_ahead_mm": look, "mode": mode,
                               "countermeasures": cm}  # fmt: skip
        row.update(open_loop(arc_scene(current, look, mode, cm, given), frames))
        row["loop_max_error_mm"], row["loop_status"] = (
            closed_loop_max_error(current, look, mode, cm, given) if loop else (math.nan, "")
        )
        row["load_1min"] = round(os.getloadavg()[0], 2)
        rows.append({k: row[k] for k in (*COLUMNS, "loop_status", "load_1min")})
    cost = measure_cost(quick, extra)
    result = {
        "machine": machine_info(),
        "command": (
            "python -m seamtrack.bench.arc --reduced"
            if reduced
            else "seamtrack bench arc" + (" --quick" if quick else "")
        ),
        "quick": quick,
        "reduced": reduced,
        "seam_beyond_look_ahead_mm": extra,
        "curve_radius_mm": CURVE_RADIUS_MM,
        "frames": frames,
        "load_1min_before": round(load_before, 2),
        "columns": list(COLUMNS),
        **{k: _clean(v) for k, v in cost.items()},
        "rows": [{k: _clean(v) for k, v in r.items()} for r in rows],
    }
    (out / "arc.json").write_text(json.dumps(result, indent=2))
    (out / "arc.md").write_text(arc_table(result))
    plot_arc(result, out / "arc.png")
    return result


#: ``--quick``: a smaller camera in image mode (the arc's cost scales with its pixels): a
#: smoke run, not the docs' figures.
QUICK_CAMERA: dict[str, Any] = {"sensor.camera.rows": 128, "sensor.camera.columns": 256}


def _clean(value: Any) -> Any:
    if isinstance(value, float):
        return None if not math.isfinite(value) else round(value, 4)
    return value


def _fmt(value: Any, digits: int) -> str:
    return "-" if value is None else f"{value:.{digits}f}"


def arc_table(data: dict[str, Any]) -> str:
    """The bench's markdown table, one row per cell."""
    header = ["current (A)", "look-ahead (mm)", "mode", "countermeasures", "detected",
              "median (mm)", "p95 (mm)", "loop max (mm)", "frames/s", "1-min load"]  # fmt: skip
    rows = (
        [f"{r['current_a']:.0f}", f"{r['look_ahead_mm']:.0f}", r["mode"], r["countermeasures"],
         f"{100 * r['detect_rate']:.0f} %", _fmt(r["median_mm"], 3), _fmt(r["p95_mm"], 3),
         _fmt(r["loop_max_error_mm"], 3), _fmt(r["frames_per_s"], 1),
         _fmt(r.get("load_1min"), 1)]
        for r in data["rows"]
    )  # fmt: skip
    lines = markdown_table(header, rows, right=[True, True, False, False, *[True] * 6])
    return "\n".join(lines) + "\n"


def plot_arc(data: dict[str, Any], path: Path) -> None:
    """Against the look-ahead, one line per mode, countermeasures and current: the detection
    rate (left) and the p95 of the seam point's error (right; none where nothing was found)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (left, right) = plt.subplots(1, 2, figsize=(9, 3.8))
    rows = data["rows"]
    for key in sorted({(r["mode"], r["countermeasures"], r["current_a"]) for r in rows}):
        sel = sorted((r for r in rows if (r["mode"], r["countermeasures"], r["current_a"]) == key),
                     key=lambda r: r["look_ahead_mm"])  # fmt: skip
        x = [r["look_ahead_mm"] for r in sel]
        p95 = [r["p95_mm"] if r["p95_mm"] is not None else np.nan for r in sel]
        style = "-" if key[0] == "image" else "--"
        label = f"{key[0]}, {key[1]}, {key[2]:.0f} A"
        left.plot(x, [100 * r["detect_rate"] for r in sel], style, marker="o", label=label)
        right.plot(x, p95, style, marker="o", label=label)
    left.set_xlabel("look-ahead (mm)")
    left.set_ylabel("seam point detected (% of frames)")
    right.set_xlabel("look-ahead (mm)")
    right.set_ylabel("p95 seam-point error (mm)")
    right.set_yscale("log")
    right.legend(fontsize=7, ncol=2)
    fig.suptitle("seamtrack bench arc: image mode (v-groove-arc), profile mode "
                 "(v-groove-arc-profile)", fontsize=10)  # fmt: skip
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main(argv: list[str] | None = None) -> int:
    """``python -m seamtrack.bench.arc --calibrate``: print the fitted profile-model
    parameters (what :data:`~seamtrack.sensing.arc.profile_model.PROFILE_ARC` holds)."""
    import argparse

    parser = argparse.ArgumentParser(prog="python -m seamtrack.bench.arc")
    parser.add_argument("--calibrate", action="store_true", help="fit the profile model")
    parser.add_argument("--reduced", action="store_true", help="run the bench's smaller grid")
    parser.add_argument(
        "--cost",
        action="store_true",
        help="measure the image cost again into OUT/arc.json (its rows kept)",
    )
    parser.add_argument("--out", default="bench-results/arc", help="the bench's folder")
    parser.add_argument(
        "--countermeasures",
        choices=[*COUNTERMEASURES, "both"],
        default="both",
        help="the switch to calibrate the profile model for",
    )
    parser.add_argument(
        "--process",
        action="append",
        choices=["mag-short", "mag-spray", "tig"],
        help="the processes to calibrate (repeatable; unset: all three)",
    )
    args = parser.parse_args(argv)
    if args.reduced:
        bench_arc(args.out, reduced=True)
    if args.cost:
        cost = remeasure_cost(args.out)
        print(
            f"image cost {cost['image_cost_ratio']:.2f}x (CPU {cost['image_cost_ratio_cpu']:.2f}x),"
            f" 1-min load {cost['image_cost_load_1min_before']:.2f}"
        )
    if args.calibrate:
        both = args.countermeasures == "both"
        switches = list(COUNTERMEASURES) if both else [args.countermeasures]
        processes = tuple(args.process or ("mag-short", "mag-spray", "tig"))
        for switch in switches:
            start = time.perf_counter()
            load = os.getloadavg()[0]
            fitted = calibrate(processes, countermeasures=switch)
            print(json.dumps({switch: fitted}, indent=2))
            print(f"# {switch}: {time.perf_counter() - start:.0f} s, 1-min load {load:.1f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
