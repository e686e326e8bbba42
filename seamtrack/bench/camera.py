"""``seamtrack bench camera``: rendered stripe images against their oracles, extractors on profiles
measured from pixels, and what image mode costs.

1. **Ideal camera, matte tilted plate**: each peak detector against the analytic plane section,
   in pixels (RMS and max over the inner columns), tilts 0-60 deg about both axes.
2. **Speckle only** (no shot/read noise, no quantization), matte plate across the laser: range
   noise of the thresholded centroid against Dorsch, Haeusler and Herrmann (1994),
   dz = C lambda / (2 pi sin u_obs sin theta), C = 1, at three f-numbers; and how it grows with
   the line's thickness. Then the sweep over line width, f-number and pixel pitch
   (:mod:`seamtrack.bench.camera_speckle`): one column's centroid against Dorsch and against
   the line's own speckle formula, a square patch of the line against Dorsch's spot.
3. **Bright V-groove**: the false stripe's centroid against mirror geometry solved on the bevels'
   planes (:func:`mirror_oracle`), in mm in the laser plane.
4. **Extractors on image-mode profiles**: each joint family's built-in scene at 20 poses along its
   seam, the seam point from the ray-cast stripe (geometry) and from the camera image on two
   materials, scored against the CAD seam.
5. **Throughput**: 1024 x 512 images per second on one core, and an image-mode frame against a
   geometry-mode frame on the same part and poses. Times are the process's CPU time (one thread
   does all the work), so other load on the machine does not inflate them.
7. **Exposure: the default camera and detector on tilted plates** (issue 27.1): the paper's
   sensor's full chip, ``Camera()`` (multi-exposure merge) and the default detector (a threshold
   relative to each column's peak and the noise), a matte and a bright aluminium plate tilted
   0-70 deg about both axes and at the aluminium's mirror angle (half the triangulation angle):
   columns found, the range error against the analytic plane (p95, mm), the share of the
   stripe's columns saturated; and, for comparison, a fixed exposure with the old absolute
   threshold 0.1.
6. **Image-mode sets through the real-data bench**: section 4's image-mode profiles, labelled
   with the CAD seam's crossing of the laser plane, as sets of the real-data extractor bench
   (:mod:`seamtrack.bench.camera_sets`): detection, error, false joints, classification.

Writes ``camera.json`` and ``camera.md``.
"""

from __future__ import annotations

import itertools
import json
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from seamtrack.bench.camera_exposure import exposure_markdown, exposure_sweep
from seamtrack.bench.camera_parts import SENSOR, down, plane_rows, plate
from seamtrack.bench.camera_sets import ImageSet, bench_image_sets, markdown_rows
from seamtrack.bench.camera_speckle import (
    speckle_noise,
    speckle_sweep,
    speckle_sweep_table,
)
from seamtrack.bench.common import machine_info, markdown_table
from seamtrack.geometry import frames
from seamtrack.sensing.camera import Camera, StripeImage
from seamtrack.sensing.materials import material
from seamtrack.sensing.peaks import detect, find_peaks

ROWS, COLUMNS = 512, 1024
GRID: dict[str, Any] = {"rows": ROWS, "columns": COLUMNS}
HALF_WIDTH, DEPTH, LENGTH, PLATE = 5.0, 5.0 * math.tan(math.radians(60.0)), 120.0, 40.0
DETECTED_MM = 0.5
FAMILIES = {
    "square-butt": "square-butt",
    "v-groove": "v-groove-camera",
    "fillet": "fillet-t",
    "lap": "lap",
    "outside-corner": "outside-corner",
}
MATERIALS = ("mill-scale steel", "bright aluminium")
_SET_META = {
    "sensor": "paper",
    "camera": "512 x 1024 px, f/8, speckle, shot and read noise, 10 bits, centroid, threshold 0.02",
}


# --------------------------------------------------------------------------- parts and oracles
def v_groove() -> Any:
    """A 60 deg V-groove along world x, apex at (y, z) = (0, -DEPTH), plates at z = 0."""
    import trimesh

    section = [(-PLATE, 0.0), (-HALF_WIDTH, 0.0), (0.0, -DEPTH), (HALF_WIDTH, 0.0), (PLATE, 0.0)]
    vertices: list[tuple[float, float, float]] = []
    faces: list[tuple[int, int, int]] = []
    for (y0, z0), (y1, z1) in itertools.pairwise(section):
        k = len(vertices)
        for x in (-0.5 * LENGTH, 0.5 * LENGTH):
            vertices += [(x, y0, z0), (x, y1, z1)]
        faces += [(k, k + 2, k + 1), (k + 1, k + 2, k + 3)]
    return trimesh.Trimesh(np.array(vertices, float), np.array(faces), process=False)


def groove_pose(pitch_deg: float, lateral_mm: float) -> np.ndarray:
    """The laser down, tilted ``pitch_deg`` about world y (a look-ahead sensor's travel angle),
    aimed 3 mm above the apex, ``lateral_mm`` off the groove's centre."""
    R = frames.from_xyz_rpy_deg([0, 0, 0], [180.0, pitch_deg, 0.0])[:3, :3]
    return frames.make(
        R, np.array([0.0, lateral_mm, -DEPTH + 3.0]) - SENSOR.range_center_mm * R[:, 2]
    )


def _plane_hit(
    origin: np.ndarray, direction: np.ndarray, point: np.ndarray, normal: np.ndarray
) -> float:
    den = float(direction @ normal)
    return math.inf if abs(den) < 1e-15 else float((point - origin) @ normal / den)


def mirror_oracle(T: np.ndarray, image: StripeImage) -> np.ndarray:
    """Per image column, the row of the false stripe on :func:`v_groove` by mirror geometry:
    each laser ray lights a bevel at P1, reflects (r = d - 2 (d.n) n) onto the other bevel at
    P2; where the camera sees P2 (lit side, not hidden by the first bevel) it images as the
    laser-plane point C + s (P2 - C), s = b / (b - x_P2). Solved on the planes (no mesh, no ray
    caster), sampled densely along the fan and interpolated to the column centres."""
    b = SENSOR.baseline_mm
    R, origin = T[:3, :3], T[:3, 3]
    camera = R @ np.array([b, 0, 0]) + origin
    bevels = {
        "left": (np.array([0.0, -HALF_WIDTH, 0.0]), np.array([0.0, DEPTH, HALF_WIDTH])),
        "right": (np.array([0.0, HALF_WIDTH, 0.0]), np.array([0.0, -DEPTH, HALF_WIDTH])),
    }
    bevels = {k: (p, n / np.linalg.norm(n)) for k, (p, n) in bevels.items()}

    def on(name: str, q: np.ndarray) -> bool:
        y = q[1] if name == "right" else -q[1]
        return bool(0.0 <= y <= HALF_WIDTH and abs(q[0]) <= 0.5 * LENGTH)

    chip = []
    for phi in np.linspace(-0.14, 0.14, 20001):
        d = R @ np.array([0.0, math.sin(phi), math.cos(phi)])
        first = min(bevels, key=lambda k: _plane_hit(origin, d, *bevels[k]))
        p1 = origin + _plane_hit(origin, d, *bevels[first]) * d
        other = "right" if first == "left" else "left"
        n1, n2 = bevels[first][1], bevels[other][1]
        r = d - 2 * (d @ n1) * n1
        p2 = p1 + _plane_hit(p1, r, *bevels[other]) * r
        to_cam = camera - p2
        t_block = _plane_hit(p2, to_cam, *bevels[first])
        blocked = 1e-9 < t_block < 1.0 and on(first, p2 + t_block * to_cam)
        if not on(first, p1) or not on(other, p2) or (to_cam @ n2) * (r @ n2) >= 0 or blocked:
            chip.append((np.nan, np.nan))
            continue
        q = R.T @ (p2 - origin)
        x_c, z_c = image.sensor.project(q[1] * b / (b - q[0]), q[2] * b / (b - q[0]))
        chip.append((float(x_c), float(z_c)))
    x_c, z_c = np.array(chip).T
    pitch_h, pitch_v = image.sensor.pixel_pitch_mm
    u = (x_c + 0.5 * image.sensor.chip_h_mm) / pitch_h - 0.5 - image.window[0]
    w = (z_c + 0.5 * image.sensor.chip_v_mm) / pitch_v - 0.5 - image.window[2]
    out = np.full(image.shape[1], np.nan)
    for i in range(len(u) - 1):
        lo, hi = sorted((w[i], w[i + 1]))
        if np.isfinite(lo) and np.isfinite(hi) and 0 < hi - lo < 1.0:
            col = math.ceil(lo)
            if col <= hi and 0 <= col < len(out):
                out[col] = u[i] + (col - w[i]) / (w[i + 1] - w[i]) * (u[i + 1] - u[i])
    return out


def false_stripe_rows(image: StripeImage, threshold: float) -> np.ndarray:
    """Per column, the centroid of the brightest peak that is not the true stripe (NaN: none)."""
    peaks = find_peaks(image.pixels, threshold)
    rows = np.full(image.shape[1], np.nan)
    for col in np.flatnonzero(image.reflection):
        mine = np.flatnonzero(peaks.column == col)
        truth = image.truth_row[col]
        direct = (
            np.isfinite(truth) & (peaks.start[mine] - 3 <= truth) & (truth <= peaks.stop[mine] + 2)
        )
        others = mine[~direct]
        if len(others):
            rows[col] = peaks.centroid[others[np.argmax(peaks.peak[others])]]
    return rows


# --------------------------------------------------------------------------- the sections
def _plane_accuracy(quick: bool) -> list[dict[str, Any]]:
    tilts = (
        [(0, 0), (30, 0), (60, 0), (0, 60)]
        if quick
        else [(0, 0), (15, 0), (30, 0), (45, 0), (60, 0), (0, 30), (0, 60)]
    )
    rows = []
    for roll, pitch in tilts:
        image = SENSOR.render(
            plate(roll, pitch),
            down(),
            camera=Camera.ideal(**GRID),
            material="mill-scale steel",
            seed=0,
        )
        normal = frames.from_xyz_rpy_deg([0, 0, 0], [roll, pitch, 0])[:3, 2]
        expected = plane_rows(image, normal)[2:-2]
        for method in ("centroid", "gaussian", "steger"):
            error = detect(image.pixels, method=method, threshold=0.01)[2:-2] - expected
            rows.append(
                {
                    "roll_deg": roll,
                    "pitch_deg": pitch,
                    "method": method,
                    "rms_px": float(np.sqrt(np.nanmean(error**2))),
                    "max_px": float(np.nanmax(np.abs(error))),
                    "found": float(np.mean(np.isfinite(error))),
                }
            )
    return rows


def _false_stripe(quick: bool) -> list[dict[str, Any]]:
    rows = []
    poses = [(12.0, 0.0)] if quick else [(12.0, 0.0), (20.0, 1.5), (-15.0, -1.0)]
    for pitch, lateral in poses:
        T = groove_pose(pitch, lateral)
        image = SENSOR.render(
            v_groove(),
            T,
            camera=Camera.ideal(exposure=5.0, **GRID),
            material="bright aluminium",
            seed=0,
        )
        oracle, measured = mirror_oracle(T, image), false_stripe_rows(image, 0.015)
        both = np.isfinite(measured) & np.isfinite(oracle)
        both[1:-1] &= both[:-2] & both[2:]  # a column where the stripe ends sees part of it
        both[[0, -1]] = False
        error = np.linalg.norm(
            image.triangulate_rows(np.where(both, measured, np.nan))[both]
            - image.triangulate_rows(np.where(both, oracle, np.nan))[both],
            axis=1,
        )
        rows.append(
            {
                "pitch_deg": pitch,
                "lateral_mm": lateral,
                "columns_with_reflection": int(image.reflection.sum()),
                "columns_compared": int(both.sum()),
                "max_error_mm": float(error.max()) if len(error) else math.nan,
                "median_error_mm": float(np.median(error)) if len(error) else math.nan,
            }
        )
    return rows


def _scene_overrides(mode: str) -> dict[str, Any]:
    if mode == "geometry":
        return {"sensor.source": "geometry", "sensor.mode": "mesh", "sensor.rays": 1024}
    surface = material(mode)
    return {
        "sensor.source": "image",
        "sensor.mode": "mesh",
        "workpiece.material": mode,
        "sensor.camera.rows": GRID["rows"],
        "sensor.camera.columns": GRID["columns"],
        # an auto-exposure: the diffuse return peaks near 10 % of full scale
        "sensor.camera.exposure": 0.1 / surface.diffuse_albedo,
        "sensor.camera.threshold": 0.02,
    }


def _extractor_rows(quick: bool) -> tuple[list[dict[str, Any]], list[ImageSet]]:
    from seamtrack.simulation.assemble import build_parts
    from seamtrack.simulation.scene import load_scene

    rows, sets = [], []
    poses = 6 if quick else 20
    for family, scene_name in FAMILIES.items():
        for mode in ("geometry", *MATERIALS):
            scene = load_scene(scene_name, _scene_overrides(mode))
            parts = build_parts(scene)
            assert parts.scan is not None
            ahead = scene.config.sensor.look_ahead_mm
            arcs = np.linspace(2.0, parts.seam.length_mm - ahead - 2.0, poses)
            errors, elapsed = [], 0.0
            ex = scene.config.extractor
            offset = (float(ex.offset_mm[0]), float(ex.offset_mm[1]))
            kept = (
                None
                if mode == "geometry"
                else ImageSet(family, parts.extractor_name, mode, scene_name, offset)
            )
            for tcp in parts.seam.interpolate(arcs):
                T = parts.robot.T_world_sensor(parts.robot.q_from_world(tcp))
                start = time.process_time()
                profile, feature = parts.scan(T, 0.0)
                elapsed += time.process_time() - start
                if kept is not None:
                    kept.add(profile, parts.seam.points, T)
                errors.append(
                    float(parts.seam.closest(feature.point_world).distance_mm[0])
                    if feature
                    else math.inf
                )
            e = np.array(errors)
            found = e[np.isfinite(e)]
            rows.append(
                {
                    "joint": family,
                    "scene": scene_name,
                    "profile": "geometry" if mode == "geometry" else f"image, {mode}",
                    "n": poses,
                    "detection_rate": float(np.mean(e <= DETECTED_MM)),
                    "median_error_mm": float(np.median(found)) if len(found) else math.nan,
                    "p95_error_mm": float(np.percentile(found, 95)) if len(found) else math.nan,
                    "ms_per_frame": 1e3 * elapsed / poses,
                }
            )
            if kept is not None:
                sets.append(kept)
    return rows, sets


def write_image_sets(out_dir: str | Path, *, quick: bool = False) -> list[Path]:
    """Write section 6's sets (every family on both materials) as real-data sets under
    ``out_dir``, for ``seamtrack extractors bench --real out_dir``; return their folders."""
    _, sets = _extractor_rows(quick)
    return [s.write(out_dir, _SET_META) for s in sets]


def _throughput(quick: bool) -> dict[str, Any]:
    from seamtrack.features.extractors import extractor
    from seamtrack.sensing.raycast import RayCaster
    from seamtrack.sensing.scan import scan_mesh

    caster = RayCaster.from_mesh(v_groove())
    find = extractor("v-groove")
    poses = [groove_pose(0.0, lateral) for lateral in np.linspace(-2.0, 2.0, 5 if quick else 20)]
    cameras = {"ideal": Camera.ideal(**GRID), "full": Camera(f_number=8.0, **GRID)}
    out: dict[str, Any] = {"image_px": [GRID["rows"], GRID["columns"]], "poses": len(poses)}
    for name, cam in cameras.items():
        SENSOR.render(caster, poses[0], camera=cam, seed=0)  # compile and build, untimed
        start = time.process_time()
        images = [SENSOR.render(caster, T, camera=cam, seed=i) for i, T in enumerate(poses)]
        render_s = (time.process_time() - start) / len(poses)
        start = time.process_time()
        profiles = [image.profile("centroid", threshold=0.02) for image in images]
        detect_s = (time.process_time() - start) / len(poses)
        start = time.process_time()
        for profile in profiles:
            find(profile)
        extract_s = (time.process_time() - start) / len(poses)
        out[name] = {
            "render_ms": 1e3 * render_s,
            "images_per_s": 1.0 / render_s,
            "detect_ms": 1e3 * detect_s,
            "extract_ms": 1e3 * extract_s,
            "frame_ms": 1e3 * (render_s + detect_s + extract_s),
            "supersample": cam.supersampling(cam.imaging_sensor(SENSOR)),
        }
    scan_mesh(SENSOR, caster, poses[0], rays=1024)
    start = time.process_time()
    profiles = [scan_mesh(SENSOR, caster, T, rays=1024) for T in poses]
    scan_s = (time.process_time() - start) / len(poses)
    start = time.process_time()
    for profile in profiles:
        find(profile)
    extract_s = (time.process_time() - start) / len(poses)
    out["geometry"] = {
        "scan_ms": 1e3 * scan_s,
        "extract_ms": 1e3 * extract_s,
        "frame_ms": 1e3 * (scan_s + extract_s),
    }
    for name in cameras:
        out[name]["cost_vs_geometry"] = out[name]["frame_ms"] / out["geometry"]["frame_ms"]
    return out


def bench_camera(out_dir: str | Path, *, quick: bool = False) -> dict[str, Any]:
    """Run the five sections (``quick``: fewer tilts, seeds, poses); write the results."""
    seeds = 2 if quick else 4
    result: dict[str, Any] = {
        "machine": machine_info(),
        "quick": quick,
        "sensor": "paper",
        "image_px": [GRID["rows"], GRID["columns"]],
        "plane": _plane_accuracy(quick),
        "speckle": [speckle_noise(n, 0.1, seeds, GRID) for n in (4.0, 8.0, 16.0)],
        "speckle_vs_thickness": [
            speckle_noise(8.0, w, max(2, seeds - 1), GRID)
            for w in ((0.05, 0.5) if quick else (0.05, 0.1, 0.2, 0.5, 1.0))
        ],
        "speckle_sweep": speckle_sweep(quick),
        "false_stripe": _false_stripe(quick),
    }
    result["extractors"], sets = _extractor_rows(quick)
    result["image_sets"] = bench_image_sets(sets, _SET_META)
    result["throughput"] = _throughput(quick)
    result["exposure"] = exposure_sweep(quick)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "camera.json").write_text(json.dumps(result, indent=2, default=float) + "\n")
    (out / "camera.md").write_text(markdown(result))
    return result


def _table(header: list[str], rows: list[list[Any]]) -> list[str]:
    def cell(v: Any) -> str:
        if isinstance(v, float):
            return "-" if math.isnan(v) else f"{v:.4g}"
        return str(v)

    return markdown_table(header, ([cell(v) for v in row] for row in rows))


def markdown(result: dict[str, Any]) -> str:
    """The bench's tables (the numbers the README quotes)."""
    m = result["machine"]
    lines = [
        f"Machine: {m['cpu']}, {m['cores']} cores, Python {m['python']}, numpy {m['numpy']}; "
        f"the paper's sensor, {result['image_px'][0]} x {result['image_px'][1]} pixels.",
        "",
        "**1. Ideal camera on a matte (mill-scale) plate**: detected row minus the analytic "
        "plane section, pixels, inner columns.",
        "",
    ]
    lines += _table(
        ["roll deg", "pitch deg", "detector", "RMS px", "max px", "columns found"],
        [
            [r["roll_deg"], r["pitch_deg"], r["method"], r["rms_px"], r["max_px"], r["found"]]
            for r in result["plane"]
        ],
    )
    lines += [
        "",
        "**2. Speckle only** (white matte plate across the laser at the range "
        "centre, 660 nm; threshold 0): range noise against Dorsch et al. 1994, C = 1.",
        "",
    ]
    rows = [
        [
            r["f_number"],
            r["line_thickness_mm"],
            r["dorsch_mm"],
            r["centroid_mm"],
            r["centroid_ratio"],
            r["gaussian_ratio"],
            r["steger_ratio"],
        ]
        for r in result["speckle"] + result["speckle_vs_thickness"]
    ]
    lines += _table(
        [
            "f-number",
            "line mm",
            "Dorsch dz mm",
            "centroid sigma mm",
            "centroid ratio",
            "gaussian ratio",
            "steger ratio",
        ],
        rows,
    )
    lines += speckle_sweep_table(result.get("speckle_sweep", []), _table)
    lines += [
        "",
        "**3. False stripe on a bright aluminium V-groove** against mirror geometry "
        "(laser plane, mm).",
        "",
    ]
    lines += _table(
        [
            "pitch deg",
            "lateral mm",
            "columns with reflection",
            "compared",
            "max error mm",
            "median error mm",
        ],
        [
            [
                r["pitch_deg"],
                r["lateral_mm"],
                r["columns_with_reflection"],
                r["columns_compared"],
                r["max_error_mm"],
                r["median_error_mm"],
            ]
            for r in result["false_stripe"]
        ],
    )
    lines += [
        "",
        f"**4. Extractors on CAD joints**, seam point within {DETECTED_MM} mm of "
        "the CAD seam; image mode: f/8, speckle, shot and read noise, 10 bits, centroid.",
        "",
    ]
    lines += _table(
        ["joint", "profile", "n", "detect", "median mm", "p95 mm", "ms/frame"],
        [
            [
                r["joint"],
                r["profile"],
                r["n"],
                r["detection_rate"],
                r["median_error_mm"],
                r["p95_error_mm"],
                r["ms_per_frame"],
            ]
            for r in result["extractors"]
        ],
    )
    t = result["throughput"]
    lines += [
        "",
        f"**5. Throughput** (one core, {t['image_px'][0]} x {t['image_px'][1]} px, "
        f"V-groove, {t['poses']} poses).",
        "",
    ]
    lines += _table(
        ["frame", "render ms", "images/s", "detect ms", "extract ms", "frame ms", "x geometry"],
        [
            [
                f"image, {k} camera",
                t[k]["render_ms"],
                t[k]["images_per_s"],
                t[k]["detect_ms"],
                t[k]["extract_ms"],
                t[k]["frame_ms"],
                t[k]["cost_vs_geometry"],
            ]
            for k in ("ideal", "full")
        ]
        + [
            [
                "geometry (1024 rays)",
                t["geometry"]["scan_ms"],
                "",
                "",
                t["geometry"]["extract_ms"],
                t["geometry"]["frame_ms"],
                1.0,
            ]
        ],
    )
    lines += markdown_rows(result.get("image_sets", []), _table)
    lines += exposure_markdown(result.get("exposure", []), _table)
    return "\n".join(lines) + "\n"
