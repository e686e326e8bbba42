"""The groove and v-groove extractors on the defects of real scans (issue 42, item 7).

Each variant of :data:`SPECS` is a seeded, labelled profile: the real-sensor artefact model
(:mod:`seamtrack.features.artefacts`, its defaults) over a V, posed as the groove bench poses
it (roll and pitch +-5 deg, lateral offset +-2 mm), with one defect of
:mod:`seamtrack.features.scan_defects`. The label is the geometry's noise-free truth: the
v-groove's root (the midpoint of the root corners under hi-lo), the groove's 7 points.

* **v-groove**: a 60 deg V, 7 mm deep, no gap nor root face, on the paper sensor (2048
  columns, as the angle sweep); detected: the seam point within :data:`DETECTED_MM`.
* **groove**: the 60 deg, 20 mm V with a 2 mm gap on a backing bar, 0-6 layers of 20 mm^2
  beads (uniform, jittered +-0.5 mm), on the ``wide`` preset (2048 columns); detected: all 7
  points within :data:`DETECTED_MM`; the p95 and median pool the 7 points' errors.

The wide V is the exception: 145 deg, no gap, empty, sampled at 0.05 mm pitch
(:func:`rays_at_pitch`: 470 columns of the paper sensor, 1126 of the wide one) at the
artefact model's range unit of 0.05 mm, at the depths of :data:`WIDE_DEPTHS_MM`.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections import Counter
from collections.abc import Callable
from typing import Any, NamedTuple

import numpy as np

from seamtrack.bench.common import markdown_table
from seamtrack.bench.extractors_angles import DETECTED_MM
from seamtrack.features import scan_defects as sd
from seamtrack.features.artefacts import real_sensor_profile
from seamtrack.features.extractors import extractor
from seamtrack.features.synthetic_groove import fill, groove, groove_profile
from seamtrack.sensing.profiles import Profile
from seamtrack.sensing.sensor import preset

#: The wide V's included angle (deg), column pitch (mm) and depths (mm) in the bench.
WIDE_DEG = 145.0
WIDE_PITCH_MM = 0.05
WIDE_DEPTHS_MM = (2.0, 1.0, 0.5, 0.25)
#: The variants: name -> (defect, its drawn range): the hidden share of a wall, the hi-lo
#: step (mm) and the plates' tilt (deg) are uniform in their range, either sign; the wide V's
#: depth (mm) is fixed.
SPECS: dict[str, tuple[str, tuple[float, float]]] = {
    "none": ("none", (0.0, 0.0)),
    "outlier 150 mm": ("outlier", (sd.OUTLIER_MM, sd.OUTLIER_MM)),
    "second bounce 1-3 mm": ("reflection", sd.BOUNCE_SPAN_MM),
    "wall hidden 50-70 %": ("occlusion", (0.5, 0.7)),
    "wall hidden 70-90 %": ("occlusion", (0.7, 0.9)),
    "hi-lo 0.5 mm": ("hi-lo", (0.5, 0.5)),
    "hi-lo 1-2 mm": ("hi-lo", (1.0, 2.0)),
    "tilt 2-4 deg": ("tilt", (2.0, 4.0)),
    **{f"wide V {d:g} mm deep": ("wide-v", (d, d)) for d in WIDE_DEPTHS_MM},
}
VARIANTS = tuple(SPECS)
#: Fill states of the groove extractor's V (layers, uniform).
MAX_LAYERS = 6
COLUMNS = (
    "extractor",
    "variant",
    "n",
    "detection_rate",
    "wrong_rate",
    "median_error_mm",
    "p95_error_mm",
    "empty_detection_rate",
    "filled_detection_rate",
    "refusals",
)


class Case(NamedTuple):
    """One labelled profile: the profile, its label (the v-groove's seam point (2,), the
    groove's 7 points (7, 2)), the defect's own label (None for a cross-section's) and the
    layers of beads in the groove (0 for the v-groove's)."""

    profile: Profile
    label: np.ndarray
    defect: sd.Defect | None
    layers: int = 0


def rays_at_pitch(sensor: Any, pitch_mm: float) -> int:
    """Columns that sample ``sensor``'s fan at ``pitch_mm`` across its range's centre."""
    from seamtrack.features.synthetic import ray_angles

    fan = ray_angles(sensor, 2)
    return int(round((fan[1] - fan[0]) * sensor.range_center_mm / pitch_mm)) + 1


def _pose(rng: np.random.Generator) -> tuple[float, float, float]:
    """Roll, pitch (deg) and lateral offset (mm), as the groove bench draws them."""
    return float(rng.uniform(-5, 5)), float(rng.uniform(-5, 5)), float(rng.uniform(-2, 2))


def _signed(rng: np.random.Generator, bounds: tuple[float, float]) -> float:
    return float(rng.choice([-1.0, 1.0]) * rng.uniform(*bounds))


def vgroove_case(variant: str, rng: np.random.Generator) -> Case:
    """One v-groove profile of ``variant``."""
    kind, bounds = SPECS[variant]
    step = _signed(rng, bounds) if kind == "hi-lo" else 0.0
    tilt = _signed(rng, bounds) if kind == "tilt" else 0.0
    sensor = dataclasses.replace(preset("paper"), quantize=False)
    rays = 2048
    if kind == "wide-v":
        rays = rays_at_pitch(sensor, WIDE_PITCH_MM)
        section = sd.v_section(WIDE_DEG, bounds[0])
    else:
        section = sd.v_section(60.0, 7.0, step_mm=step, tilt_deg=tilt)
    roll, pitch, offset = _pose(rng)
    profile, truth = real_sensor_profile(
        "v-groove", rng, sensor=sensor, rays=rays, section=section,
        roll_deg=roll, pitch_deg=pitch, lateral_offset_mm=offset,
    )  # fmt: skip
    top, root = truth.edges_laser, truth.seam_laser
    walls = np.array([[top[0], root], [top[1], root]])
    profile, defect = _defect(variant, profile, walls, rng)
    return Case(profile, truth.seam_laser, defect)


def groove_case(variant: str, rng: np.random.Generator) -> Case:
    """One groove profile of ``variant``."""
    kind, bounds = SPECS[variant]
    if kind == "wide-v":
        g = groove("v", angle_deg=WIDE_DEG, gap_mm=0.0, thickness_mm=bounds[0])
        sensor = dataclasses.replace(preset("wide"), quantize=False)
        rays = rays_at_pitch(sensor, WIDE_PITCH_MM)
        roll, pitch, offset = _pose(rng)
        profile, truth = groove_profile(
            g, None, rng=rng, rays=rays, roll_deg=roll, pitch_deg=pitch, lateral_offset_mm=offset
        )
        return Case(profile, truth.points_laser, None)
    g = groove("v")
    if kind == "hi-lo":
        g = sd.groove_hi_lo(g, _signed(rng, bounds))
    elif kind == "tilt":
        g = sd.groove_tilt(g, _signed(rng, bounds))
    layers = int(rng.integers(0, MAX_LAYERS + 1))
    s = fill(g, layers, bead_area_mm2=20.0, rng=rng, jitter_mm=0.5)[0] if layers else None
    roll, pitch, offset = _pose(rng)
    profile, truth = groove_profile(
        g, s, rng=rng, roll_deg=roll, pitch_deg=pitch, lateral_offset_mm=offset
    )
    p = truth.points_laser
    walls = np.array([[p[0], p[1]], [p[6], p[5]]])
    profile, defect = _defect(variant, profile, walls, rng)
    return Case(profile, p, defect, layers)


def _defect(
    variant: str, profile: Profile, walls: np.ndarray, rng: np.random.Generator
) -> tuple[Profile, sd.Defect | None]:
    kind, bounds = SPECS[variant]
    if kind == "outlier":
        return sd.far_outlier(profile, rng, bounds[0])
    if kind == "reflection":
        return sd.second_bounce(profile, walls, rng, bounds)
    if kind == "occlusion":
        return sd.hide_wall(profile, walls, rng, bounds)
    return profile, None


class ScanErrors(NamedTuple):
    """An extractor on ``n`` profiles of a variant: per profile the error that decides
    detection (the v-groove's seam point's; the groove's worst of its 7 points; inf where
    refused) and the layers in the groove; the errors pooled for the p95 and median (the
    groove's 7 a profile); the refusals' reasons."""

    worst: list[float]
    layers: list[int]
    pooled: list[float]
    why: Counter[str]


def _rate(e: np.ndarray) -> float | None:
    return float(np.mean(e <= DETECTED_MM)) if e.size else None


def scan_errors(name: str, variant: str, n: int, seed: int = 0) -> ScanErrors:
    """Extractor ``name`` ("v-groove" or "groove") on ``n`` seeded profiles of ``variant``."""
    case: Callable[[str, np.random.Generator], Case]
    case = vgroove_case if name == "v-groove" else groove_case
    ex = extractor(name)
    rng = np.random.default_rng([seed, VARIANTS.index(variant), 0 if name == "v-groove" else 1])
    out = ScanErrors([], [], [], Counter[str]())
    for _ in range(n):
        c = case(variant, rng)
        f = ex(c.profile)
        out.layers.append(c.layers)
        if not f:
            out.worst.append(math.inf)
            out.why[re.sub(r"[\d.]+", "x", f.reason.split(" (")[0])] += 1
            continue
        if name == "v-groove":
            d = np.atleast_1d(np.hypot(*(f.point_laser - c.label)))
        else:
            d = np.hypot(*(f.edges_laser - c.label).T)
        out.worst.append(float(np.max(d)))
        out.pooled.extend(d.tolist())
    return out


def _row(name: str, variant: str, r: ScanErrors) -> dict[str, Any]:
    e, pooled = np.array(r.worst), np.array(r.pooled)
    empty = np.array(r.layers) == 0
    return {
        "extractor": name,
        "variant": variant,
        "n": len(e),
        "detection_rate": float(np.mean(e <= DETECTED_MM)),
        "wrong_rate": float(np.mean(np.isfinite(e) & (e > DETECTED_MM))),
        "median_error_mm": float(np.median(pooled)) if pooled.size else math.nan,
        "p95_error_mm": float(np.percentile(pooled, 95)) if pooled.size else math.nan,
        "empty_detection_rate": _rate(e[empty]) if name == "groove" else None,
        "filled_detection_rate": _rate(e[~empty]) if name == "groove" else None,
        "refusals": dict(r.why.most_common()),
    }


def scans_bench(
    n: int = 100, seed: int = 0, variants: tuple[str, ...] = VARIANTS
) -> list[dict[str, Any]]:
    """One row per (extractor, variant): :data:`COLUMNS`, ``n`` profiles each."""
    return [
        _row(name, variant, scan_errors(name, variant, n, seed))
        for name in ("v-groove", "groove")
        for variant in variants
    ]


def claim_holds(row: dict[str, Any]) -> bool:
    """The issue's bar: >= 90 % detected with p95 <= 0.5 mm."""
    p95 = row["p95_error_mm"]
    return bool(row["detection_rate"] >= 0.9 and p95 is not None and p95 <= DETECTED_MM)


def _num(value: Any) -> str:
    return (
        "-"
        if value is None or (isinstance(value, float) and math.isnan(value))
        else (f"{value:.3f}")
    )


def scans_table(data: dict[str, Any]) -> str:
    """The bench's rows (``extractors_scans.json``) as a markdown table; "holds": the issue's
    bar (:func:`claim_holds`); "empty / filled": the groove's detection on empty and on
    filled grooves."""
    head = ("extractor", "variant", "n", "detect", "wrong", "median mm", "p95 mm", "holds",
            "detect empty / filled", "refusals")  # fmt: skip
    body = []
    for r in data["rows"]:
        keys = ("detection_rate", "wrong_rate", "median_error_mm", "p95_error_mm")
        split = r.get("empty_detection_rate"), r.get("filled_detection_rate")
        cells = [
            r["extractor"], r["variant"], str(r["n"]), *(_num(r[k]) for k in keys),
            "yes" if claim_holds(r) else "**no**",
            "-" if r["extractor"] != "groove" else " / ".join(_num(v) for v in split),
            "; ".join(f"{k}: {v}" for k, v in r["refusals"].items()) or "-",
        ]  # fmt: skip
        body.append(cells)
    return "\n".join(markdown_table(head, body)) + "\n"


def scans_result(n: int = 100, seed: int = 0) -> dict[str, Any]:
    """The bench as ``extractors_scans.json`` holds it: the machine, ``n``, ``seed`` and the
    rows (NaN written as null)."""
    from seamtrack.bench.common import machine_info

    clean = [
        {k: None if isinstance(v, float) and math.isnan(v) else v for k, v in r.items()}
        for r in scans_bench(n, seed)
    ]
    return {"machine": machine_info(), "n": n, "seed": seed, "rows": clean}
