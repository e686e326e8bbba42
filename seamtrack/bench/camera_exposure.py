"""Section 7 of ``seamtrack bench camera`` (issue 27.1): the default camera (multi-exposure
merge) and detector (a threshold relative to each column's peak and the noise) on matte and
bright aluminium plates tilted 0-70 deg, against the analytic plane section; with the tilted
plates and their analytic oracles the camera bench shares.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from seamtrack.bench.camera_parts import SENSOR, down, plane_rows, plate
from seamtrack.geometry import frames
from seamtrack.sensing.camera import Camera, StripeImage
from seamtrack.sensing.peaks import detect

MATERIALS = ("mill-scale steel", "bright aluminium")


#: The old detector's absolute threshold (before issue 27.1), kept for the comparison.
OLD_THRESHOLD = 0.1


def stripe_errors(image: StripeImage, rows: np.ndarray, normal_world: np.ndarray) -> np.ndarray:
    """Per column of the stripe (where the ideal stripe images), the distance in mm in the laser
    plane between the point of ``rows`` and the analytic plane section's; NaN where not found."""
    cols = np.isfinite(image.truth_row)
    found = image.triangulate_rows(rows)[cols]
    expected = image.triangulate_rows(plane_rows(image, normal_world))[cols]
    return np.asarray(np.linalg.norm(found - expected, axis=1))


def exposure_tilt(axis: str, tilt_deg: float, surface: str, seed: int = 0) -> dict[str, Any]:
    """One row of section 7: the default camera and detector on a plate tilted ``tilt_deg``
    about world ``axis`` ("roll": x, along the stripe's columns; "pitch": y, in the
    triangulation plane), against a fixed exposure with the old threshold."""
    roll, pitch = (tilt_deg, 0.0) if axis == "roll" else (0.0, tilt_deg)
    normal = frames.from_xyz_rpy_deg([0, 0, 0], [roll, pitch, 0])[:3, 2]
    part = plate(roll, pitch)
    image = SENSOR.render(part, down(), camera=Camera(), material=surface, seed=seed)
    cols = np.isfinite(image.truth_row)
    error = stripe_errors(image, detect(image.pixels), normal)
    fixed = SENSOR.render(part, down(), camera=Camera(exposure_mode="fixed"), material=surface,
                          seed=seed)  # fmt: skip
    old = stripe_errors(fixed, detect(fixed.pixels, threshold=OLD_THRESHOLD), normal)
    assert image.column_exposure is not None
    return {
        "axis": axis,
        "tilt_deg": tilt_deg,
        "material": surface,
        "columns": int(cols.sum()),
        "found": float(np.mean(np.isfinite(error))),
        "p95_error_mm": (
            float(np.nanpercentile(error, 95)) if np.isfinite(error).any() else math.nan
        ),
        "saturated": float(np.mean(image.pixels.max(axis=0)[cols] >= 1.0)),
        "shortest_exposure": float(image.column_exposure[cols].min()),
        "fixed_peak": float(fixed.pixels.max(axis=0)[cols].max()),
        "fixed_saturated": float(np.mean(fixed.pixels.max(axis=0)[cols] >= 1.0)),
        "fixed_found_old_threshold": float(np.mean(np.isfinite(old))),
    }


def mirror_tilt_deg() -> float:
    """The pitch that turns a plate's mirror reflection of the laser into the camera: half the
    triangulation angle."""
    return round(0.5 * math.degrees(SENSOR.angle_rad), 2)


def exposure_sweep(quick: bool) -> list[dict[str, Any]]:
    """Section 7's rows (``quick``: 0, 35 and 70 deg)."""
    tilts = (0.0, 35.0, 70.0) if quick else (0.0, 10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 70.0)
    poses = [(axis, t) for axis in ("roll", "pitch") for t in tilts]
    poses.insert(len(tilts) + 1, ("pitch", mirror_tilt_deg()))
    return [exposure_tilt(axis, t, m) for m in MATERIALS for axis, t in poses]


def exposure_markdown(
    rows: list[dict[str, Any]], table: Callable[[list[str], list[list[Any]]], list[str]]
) -> list[str]:
    """Section 7's heading and table (``table``: the camera bench's table writer)."""
    lines: list[str] = []
    lines += [
        "",
        "**7. Exposure: the default camera and detector on tilted plates** (the paper's sensor, "
        "its full chip, `Camera()`: multi-exposure merge; the default detector: each column's "
        "threshold relative to its peak and the noise): columns of the stripe found, range "
        "error against the analytic plane, stripe columns saturated; then a fixed exposure "
        f"(0.5) with the old absolute threshold {OLD_THRESHOLD}.",
        "",
    ]
    lines += table(
        ["material", "tilt axis", "tilt deg", "found", "p95 error mm", "saturated",
         "shortest exposure", "fixed: peak", "fixed: saturated", "fixed, threshold 0.1: found"],
        [
            [r["material"], r["axis"], r["tilt_deg"], r["found"], r["p95_error_mm"],
             r["saturated"], r["shortest_exposure"], r["fixed_peak"], r["fixed_saturated"],
             r["fixed_found_old_threshold"]]
            for r in rows
        ],
    )  # fmt: skip
    return lines
