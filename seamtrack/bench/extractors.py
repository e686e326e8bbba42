"""Bench of the feature extractors on synthetic profiles with ground truth.

Every extractor runs on its own joint family (the generic one on every family) and on flat
plates, at a ladder of imperfection levels, with random tilts (+-15 deg about both axes) and
lateral offsets (+-3 mm). Accuracy columns are seeded and repeat exactly; the timing column
(microseconds per profile) is kept apart, as it depends on the machine.
"""

from __future__ import annotations

import csv
import math
import time
from pathlib import Path
from typing import Any

import numpy as np

from seamtrack.features.extractors import BUILTIN, extractor
from seamtrack.features.synthetic import Imperfections, synthetic_profile
from seamtrack.sensing.sensor import LaserLineSensor, preset

#: A seam point this close to the truth (mm) counts as detected.
DETECTED_MM = 0.5

#: Imperfection levels, in bench order; ``noise-*`` levels make the error-vs-noise plot.
LEVELS: dict[str, Imperfections] = {
    "clean": Imperfections(),
    "noise-0.02": Imperfections(noise_mm=0.02),
    "noise-0.05": Imperfections(noise_mm=0.05),
    "noise-0.1": Imperfections(noise_mm=0.1),
    "noise-0.2": Imperfections(noise_mm=0.2),
    "outliers+reflection": Imperfections(
        noise_mm=0.05, outlier_fraction=0.05, reflection_probability=1.0
    ),
    "dropouts": Imperfections(noise_mm=0.05, dropout_runs=5, dropout_max_columns=10),
    "tack": Imperfections(noise_mm=0.05, tack_probability=1.0),
    "bead-cap": Imperfections(noise_mm=0.05, bead_height_mm=1.5),
}
FAMILIES = ("square-butt", "v-groove", "fillet", "lap", "outside-corner")
ACCURACY_COLUMNS = (
    "extractor",
    "joint",
    "level",
    "n",
    "detection_rate",
    "wrong_rate",
    "median_error_mm",
    "p95_error_mm",
    "flat_false_rate",
)
TIMING_COLUMNS = ("us_per_profile",)


def _profiles(
    joint: str, level: Imperfections, sensor: LaserLineSensor, n: int, seed: int, rays: int
) -> list[tuple[Any, Any]]:
    rng = np.random.default_rng(seed)
    return [
        synthetic_profile(
            joint,
            sensor,
            rng=rng,
            rays=rays,
            imperfections=level,
            pitch_deg=rng.uniform(-15, 15),
            roll_deg=rng.uniform(-15, 15),
            lateral_offset_mm=rng.uniform(-3, 3),
        )
        for _ in range(n)
    ]


def bench_extractors(
    out_dir: str | Path,
    *,
    seed: int = 0,
    n_profiles: int = 200,
    quick: bool = False,
    progress: bool = True,
    rays: int = 1024,
    sensor: LaserLineSensor | None = None,
) -> list[dict[str, Any]]:
    """Detection rate and error of every built-in extractor per joint and imperfection level.

    Parameters
    ----------
    out_dir : str or Path
        Receives ``extractors.csv``, ``extractors.md`` and ``extractors_error_vs_noise.png``.
    seed : int
        Seeds every profile; two runs give the same accuracy columns.
    n_profiles : int
        Profiles per (joint, level); ``quick`` uses 20 and four levels.
    progress : bool
        A tqdm progress bar on stderr.
    rays : int
        Columns per profile (1024: the speed target's profile size).
    sensor : LaserLineSensor, optional
        Default ``preset("paper")``.

    Returns
    -------
    rows : list of dict
        One per (extractor, joint, level): :data:`ACCURACY_COLUMNS` + :data:`TIMING_COLUMNS`.
        ``detection_rate``: found within :data:`DETECTED_MM`; ``wrong_rate``: found farther;
        errors over the found; ``flat_false_rate``: seam points reported on flat plates at
        that level.
    """
    from tqdm import tqdm

    sensor = preset("paper") if sensor is None else sensor
    n = 20 if quick else int(n_profiles)
    levels = {
        k: LEVELS[k]
        for k in (["clean", "noise-0.05", "noise-0.2", "outliers+reflection"] if quick else LEVELS)
    }
    extractors = {name: extractor(name) for name in sorted(BUILTIN)}
    jobs = [
        (name, joint)
        for name in extractors
        for joint in (FAMILIES if name == "generic" else (name,))
    ]
    rows: list[dict[str, Any]] = []
    bar = tqdm(
        total=len(levels) * (len(jobs) + len(FAMILIES) + 1),
        disable=not progress,
        desc="extractors bench",
        unit="set",
    )
    for li, (level_name, level) in enumerate(levels.items()):
        cache = {
            joint: _profiles(joint, level, sensor, n, seed + 1000 * li + j, rays)
            for j, joint in enumerate((*FAMILIES, "flat"))
        }
        bar.update(len(FAMILIES) + 1)
        flat_false = {
            name: float(np.mean([bool(ex(p)) for p, _ in cache["flat"]]))
            for name, ex in extractors.items()
        }
        for name, joint in jobs:
            ex = extractors[name]
            ex(cache[joint][0][0])  # warm-up, untimed: a tracking loop runs in steady state
            errors, elapsed = [], 0.0
            for profile, truth in cache[joint]:
                t0 = time.perf_counter()
                feature = ex(profile)
                elapsed += time.perf_counter() - t0
                errors.append(
                    float(np.hypot(*(feature.point_laser - truth.seam_laser)))
                    if feature
                    else math.inf
                )
            e = np.array(errors)
            found = e[np.isfinite(e)]
            rows.append(
                {
                    "extractor": name,
                    "joint": joint,
                    "level": level_name,
                    "n": n,
                    "detection_rate": float(np.mean(e <= DETECTED_MM)),
                    "wrong_rate": float(np.mean(np.isfinite(e) & (e > DETECTED_MM))),
                    "median_error_mm": float(np.median(found)) if found.size else math.nan,
                    "p95_error_mm": float(np.percentile(found, 95)) if found.size else math.nan,
                    "flat_false_rate": flat_false[name],
                    "us_per_profile": 1e6 * elapsed / n,
                }
            )
            bar.update(1)
    bar.close()
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    _write(out, rows)
    _plot(out / "extractors_error_vs_noise.png", rows)
    return rows


def _write(out: Path, rows: list[dict[str, Any]]) -> None:
    columns = (*ACCURACY_COLUMNS, *TIMING_COLUMNS)
    with open(out / "extractors.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)
    (out / "extractors.md").write_text(markdown_table(rows))


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return "-" if math.isnan(value) else f"{value:.3f}"
    return str(value)


def markdown_table(rows: list[dict[str, Any]]) -> str:
    """The accuracy columns as a markdown table, then the timings in a table of their own
    (the first is seeded and repeats exactly; the second depends on the machine)."""
    head = ("extractor", "joint", "level", "detect", "wrong", "median mm", "p95 mm", "flat false")
    keys = (
        "extractor",
        "joint",
        "level",
        "detection_rate",
        "wrong_rate",
        "median_error_mm",
        "p95_error_mm",
        "flat_false_rate",
    )
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(_fmt(r[k]) for k in keys) + " |" for r in rows]
    timing: dict[str, list[float]] = {}
    for r in rows:
        timing.setdefault(r["extractor"], []).append(r["us_per_profile"])
    lines += ["", "| extractor | median us per profile | max us per profile |", "|---|---|---|"]
    lines += [f"| {k} | {np.median(v):.0f} | {np.max(v):.0f} |" for k, v in timing.items()]
    return "\n".join(lines) + "\n"


def _plot(path: Path, rows: list[dict[str, Any]]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    noise = [
        (
            r,
            float(r["level"].split("-")[1])
            if r["level"].startswith("noise-")
            else 0.0
            if r["level"] == "clean"
            else None,
        )
        for r in rows
    ]
    for name, joint in sorted({(r["extractor"], r["joint"]) for r in rows}):
        pts = sorted(
            (sigma, r["p95_error_mm"])
            for r, sigma in noise
            if sigma is not None and r["extractor"] == name and r["joint"] == joint
        )
        if pts:
            style = "--" if name == "generic" else "-"
            ax.plot(
                *zip(*pts, strict=True),
                style,
                marker="o",
                label=f"{name} on {joint}" if name == "generic" else name,
            )
    ax.set_xlabel("range noise sigma (mm)")
    ax.set_ylabel("p95 seam-point error (mm)")
    ax.set_yscale("log")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    ax.set_title("Extractors: error vs noise (paper sensor, tilts +-15 deg)")
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)
