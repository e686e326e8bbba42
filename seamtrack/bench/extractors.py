"""Bench of the feature extractors on synthetic profiles with ground truth, and on real scans.

Every extractor runs on its own joint family (the generic one on every family) and on flat
plates, at a ladder of imperfection levels, with random tilts (+-15 deg about both axes) and
lateral offsets (+-3 mm). Accuracy columns are seeded and repeat exactly; the timing columns
(CPU microseconds per profile: the mean, median and 95th percentile over the profiles of each
profile's fastest of :data:`TIMING_REPEATS` calls, by ``time.process_time_ns``, which other
processes on a loaded machine disturb less than wall time) are kept apart, as they depend on
the machine.

:func:`bench_real` runs the family extractors and the classifier on folders of real profiles
with labels (:func:`load_real_set` reads the layout), one row per set.
"""

from __future__ import annotations

import csv
import json
import math
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from seamtrack.bench import common
from seamtrack.bench.extractors_angles import DETECTED_MM, angle_sweep, angle_table
from seamtrack.bench.extractors_groove import GROOVE_COLUMNS, bench_real_groove, groove_table
from seamtrack.bench.real_input import (
    LAYOUT,
    check_label_scale,
    check_npz_sizes,
    check_profiles,
    check_recorded,
    read_labels,
)
from seamtrack.errors import SeamtrackError
from seamtrack.features import classify
from seamtrack.features.extractors import BUILTIN, extractor
from seamtrack.features.synthetic import Imperfections, synthetic_profile
from seamtrack.sensing.profiles import Profile
from seamtrack.sensing.sensor import LaserLineSensor, preset

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
TIMING_COLUMNS = ("us_per_profile", "median_us", "p95_us")
#: Calls timed per profile; the fastest counts (extractors are deterministic: the same answer).
TIMING_REPEATS = 3
#: Profiles per cell of the included-angle sweep (:mod:`seamtrack.bench.extractors_angles`);
#: ``quick``: 20.
ANGLE_PROFILES = 300


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
        Receives ``extractors.csv``, ``extractors.md``, ``extractors.json``,
        ``extractors_angles.md`` and ``extractors_error_vs_noise.png``.
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

    The V-groove extractor's included-angle sweep on real-sensor artefact profiles
    (:func:`~seamtrack.bench.extractors_angles.angle_sweep`, :data:`ANGLE_PROFILES` profiles
    per cell) goes to ``extractors_angles.md`` and under ``angle_sweep`` in the JSON.

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
    # the joint families and the generic one; the groove extractor is scored on fill states
    # (tests/test_groove_extractor.py) and on real root passes (--real)
    extractors = {name: extractor(name) for name in sorted(BUILTIN) if name != "groove"}
    jobs = [
        (name, joint)
        for name in extractors
        for joint in (FAMILIES if name == "generic" else (name,))
    ]
    rows: list[dict[str, Any]] = []
    pooled: dict[str, list[int]] = {}  # per extractor: every profile's CPU time (ns)
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
            # Timed back to back, as a tracking loop calls it, each profile TIMING_REPEATS
            # times, its fastest kept (the rest is other jobs on a shared machine); scored
            # afterwards.
            features, took = [], []
            for profile, _ in cache[joint]:
                best = math.inf
                for _ in range(TIMING_REPEATS):
                    t0 = time.process_time_ns()
                    feature = ex(profile)
                    best = min(best, time.process_time_ns() - t0)
                features.append(feature)
                took.append(int(best))
            errors = [
                float(np.hypot(*(feature.point_laser - truth.seam_laser))) if feature else math.inf
                for feature, (_, truth) in zip(features, cache[joint], strict=True)
            ]
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
                    "us_per_profile": 1e-3 * float(np.mean(took)),
                    "median_us": 1e-3 * float(np.median(took)),
                    "p95_us": 1e-3 * float(np.percentile(took, 95)),
                }
            )
            pooled.setdefault(name, []).extend(took)
            bar.update(1)
    bar.close()
    sweep = angle_sweep(20 if quick else ANGLE_PROFILES, seed=seed)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    _write(out, rows, pooled, sweep)
    _plot(out / "extractors_error_vs_noise.png", rows)
    return rows


def _write(
    out: Path,
    rows: list[dict[str, Any]],
    pooled: dict[str, list[int]],
    sweep: list[dict[str, Any]] | None = None,
) -> None:
    columns = (*ACCURACY_COLUMNS, *TIMING_COLUMNS)
    with open(out / "extractors.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)
    (out / "extractors.md").write_text(markdown_table(rows, pooled))
    timing = {k: [1e-3 * t for t in v] for k, v in pooled.items()}
    if sweep is None:
        write_json(out / "extractors.json", rows, timing_summary(timing))
        return
    (out / "extractors_angles.md").write_text(angle_table(sweep))
    write_json(out / "extractors.json", rows, timing_summary(timing), angle_sweep=sweep)


def timing_summary(timing: dict[str, list[float]]) -> dict[str, dict[str, float]]:
    """Per extractor: the profiles timed and the median, p95 and max CPU us per profile (the
    markdown table's timing rows)."""
    return {
        k: {
            "profiles": len(v),
            "median_us": float(np.median(v)),
            "p95_us": float(np.percentile(v, 95)),
            "max_us": float(np.max(v)),
        }
        for k, v in timing.items()
    }


def _json_value(value: Any) -> Any:
    return None if isinstance(value, float) and math.isnan(value) else value


def write_json(
    path: Path,
    rows: list[dict[str, Any]],
    timing: dict[str, dict[str, float]] | None = None,
    **tables: list[dict[str, Any]],
) -> None:
    """The bench's rows (and per-extractor timing, if any; further ``tables`` of rows under
    their own keys) as JSON, the machine beside them; NaN (no seam point found) is written
    as null."""
    from seamtrack.bench.common import machine_info

    data: dict[str, Any] = {
        "machine": machine_info(),
        "rows": [{k: _json_value(v) for k, v in r.items()} for r in rows],
    }
    if timing is not None:
        data["timing"] = timing
    for key, table in tables.items():
        data[key] = [{k: _json_value(v) for k, v in r.items()} for r in table]
    path.write_text(json.dumps(data, indent=2) + "\n")


def _fmt(value: Any) -> str:
    if isinstance(value, float):
        return "-" if math.isnan(value) else f"{value:.3f}"
    return str(value)


def markdown_table(rows: list[dict[str, Any]], pooled: dict[str, list[int]] | None = None) -> str:
    """The accuracy columns as a markdown table, then the timings in a table of their own
    (the first is seeded and repeats exactly; the second depends on the machine): per
    extractor, the median and 95th percentile of the CPU time of every profile it ran on
    (``pooled``, ns; without it, of the rows' mean times)."""
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
    lines = common.markdown_table(head, ([_fmt(r[k]) for k in keys] for r in rows))
    timing: dict[str, list[float]] = {}
    if pooled:
        timing = {k: [1e-3 * t for t in v] for k, v in pooled.items()}
    else:
        for r in rows:
            timing.setdefault(r["extractor"], []).append(r["us_per_profile"])
    head_t = "| extractor | profiles | median us per profile | p95 us per profile | max us |"
    lines += ["", head_t, "|---|---|---|---|---|"]
    lines += [
        f"| {k} | {len(v)} | {np.median(v):.0f} | {np.percentile(v, 95):.0f} | {np.max(v):.0f} |"
        for k, v in timing.items()
    ]
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


# --------------------------------------------------------------------------- real data
#: The family extractors the real-data bench runs (the classifier's families).
REAL_FAMILIES = classify.FAMILIES
REAL_COLUMNS = (
    "set",
    "joint",
    "n",
    "detection_rate",
    "wrong_rate",
    "median_error_mm",
    "p95_error_mm",
    "false_joint_rate",
    "worst_false",
    "classified_rate",
    "us_per_profile",
    "classify_us",
)


@dataclass(frozen=True)
class RealSet:
    """One set of real profiles (:func:`load_real_sets`)."""

    name: str
    joint: str
    profiles: list[Profile]
    labels: np.ndarray | None  # (n, 2) seam points (y_L, z_L), mm; None for "none" sets
    meta: dict[str, Any]


def _real_error(message: str, path: Path, fix: str) -> SeamtrackError:
    return SeamtrackError(f"{path}: {message}", field="--real", fix=fix)


def load_real_set(path: str | Path) -> RealSet:
    """A set in the bench's layout: ``set.json`` (``joint``: a family or ``"none"``; anything
    else is kept as metadata), ``profiles.npz`` (``y_mm``, ``z_mm``: (n, m) laser-frame
    coordinates in mm, the emitter at the origin, NaN where the sensor saw nothing; ``y_mm``
    may be one (m,) row for all) and, for a joint, ``labels.csv`` (``index,y_mm,z_mm``: the
    seam point of every profile).

    Raises
    ------
    SeamtrackError
        A missing or malformed file (field ``--real``, with a fix).
    """
    d = Path(path)
    layout = LAYOUT
    try:
        meta = json.loads((d / "set.json").read_text())
        check_npz_sizes(d / "profiles.npz")  # from the headers, before anything is allocated
        with np.load(d / "profiles.npz") as data:
            y, z = np.asarray(data["y_mm"], dtype=float), np.asarray(data["z_mm"], dtype=float)
    except (OSError, ValueError, KeyError) as exc:
        raise _real_error(f"not a real-data set ({exc})", d, layout) from exc
    joint = meta.get("joint") if isinstance(meta, dict) else None
    if joint not in (*REAL_FAMILIES, "none"):
        raise _real_error(
            f"set.json names no joint family ({joint!r})",
            d,
            f"set joint to one of {', '.join(REAL_FAMILIES)} or 'none'",
        )
    if z.ndim != 2 or y.shape not in (z.shape, z.shape[1:]):
        raise _real_error(f"y_mm {y.shape} and z_mm {z.shape} do not match", d, layout)
    y = np.broadcast_to(y, z.shape)
    check_profiles(y, z, d)  # none, all NaN, or not in mm
    labels = None
    if joint != "none":
        labels = read_labels(d, len(z))
        check_label_scale(labels, y, z, d)
    profiles = [Profile(np.column_stack([yi, zi])) for yi, zi in zip(y, z, strict=True)]
    return RealSet(d.name, str(joint), profiles, labels, meta)


def load_real_sets(
    path: str | Path,
    topic: str | None = None,
    labels: str | None = None,
    joint: str | None = None,
) -> list[RealSet]:
    """The set at ``path`` (a folder with ``set.json``), or every set in its sub-folders; or
    the PointCloud2 profiles of a recording (an MCAP file or a ROS bag: ``topic``, ``labels``
    and ``joint`` as :func:`seamtrack.bridge.importer.read_scans` takes them)."""
    d = Path(path)
    from seamtrack.bridge.extra import is_recording, require_ros

    if is_recording(d):
        require_ros("--real")
        return [_recorded_set(d, topic, labels, joint)]
    if (d / "set.json").is_file():
        return [load_real_set(d)]
    sets = sorted(p for p in d.glob("*/set.json")) if d.is_dir() else []
    if not sets:
        raise _real_error(
            "no real-data set here (no set.json in it or its sub-folders)",
            d,
            "point --real at a set folder or a folder of sets (docs/extractors.md, 'Real data')",
        )
    return [load_real_set(p.parent) for p in sets]


def _recorded_set(path: Path, topic: str | None, labels: str | None, joint: str | None) -> RealSet:
    """A recording's profiles as a set (the joint: ``joint``, else the recording's, else
    ``"none"`` when it has no labels)."""
    from seamtrack.bridge.importer import read_scans

    scans = read_scans(path, topic, labels, joint=joint)
    check_recorded(scans.profiles, scans.labels, path)  # no point, metres, labels not finite
    kind = scans.joint or ("none" if scans.labels is None else None)
    if kind not in (*REAL_FAMILIES, "none"):
        raise SeamtrackError(
            f"{path}: the joint of its profiles is {'not known' if kind is None else repr(kind)}",
            field="--joint",
            fix=f"name it: --joint with one of {', '.join(REAL_FAMILIES)} or none",
        )
    return RealSet(scans.name, str(kind), scans.profiles,
                   None if kind == "none" else scans.labels, scans.meta)  # fmt: skip


def _timed(ex: Any, profiles: list[Profile]) -> tuple[list[Any], float]:
    """The answers, and the median CPU time per profile (us)."""
    ex(profiles[0])  # warm-up, untimed
    out, took = [], []
    for p in profiles:
        t0 = time.process_time_ns()
        out.append(ex(p))
        took.append(time.process_time_ns() - t0)
    return out, 1e-3 * float(np.median(took)) if took else 0.0


def bench_real(
    real_dir: str | Path, out_dir: str | Path, *, progress: bool = True, **recording: Any
) -> list[dict[str, Any]]:
    """The family extractors and the classifier on real profiles, one row per set.

    ``detection_rate``, ``wrong_rate``, ``median_error_mm``, ``p95_error_mm``: the set's own
    family extractor against the labels (found within :data:`DETECTED_MM`, found farther;
    errors over the found). ``false_joint_rate``: share of (profile, other family extractor)
    answers that found a seam (every family on a ``"none"`` set); ``worst_false``: the
    extractor that answered most. ``classified_rate``: share the classifier names the set's
    joint (``"none"`` included). ``us_per_profile``: the median CPU time per profile of the
    set's extractor (on ``"none"`` sets, the families' mean), ``classify_us``: the
    classifier's. Writes
    ``extractors_real.csv``, ``extractors_real.md`` and ``extractors_real.json`` into
    ``out_dir``, and for the V-groove sets the groove extractor's checks
    (:mod:`seamtrack.bench.extractors_groove`) into ``extractors_real_groove.csv`` and
    ``.md``. ``recording``: ``topic``, ``labels``, ``joint`` for a recording
    (:func:`load_real_sets`).
    """
    from tqdm import tqdm

    from seamtrack.features.classify import classify

    sets = load_real_sets(real_dir, **recording)
    exs = {name: extractor(name) for name in REAL_FAMILIES}
    rows: list[dict[str, Any]] = []
    for rs in tqdm(sets, disable=not progress, desc="real sets", unit="set"):
        answers, times = {}, {}
        for name, ex in exs.items():
            answers[name], times[name] = _timed(ex, rs.profiles)
        kinds, classify_us = _timed(lambda p: classify(p)[0], rs.profiles)
        row: dict[str, Any] = {"set": rs.name, "joint": rs.joint, "n": len(rs.profiles)}
        if rs.labels is not None:
            e = np.array(
                [
                    float(np.hypot(*(f.point_laser - lab))) if f else math.inf
                    for f, lab in zip(answers[rs.joint], rs.labels, strict=True)
                ]
            )
            found = e[np.isfinite(e)]
            row |= {
                "detection_rate": float(np.mean(e <= DETECTED_MM)),
                "wrong_rate": float(np.mean(np.isfinite(e) & (e > DETECTED_MM))),
                "median_error_mm": float(np.median(found)) if found.size else math.nan,
                "p95_error_mm": float(np.percentile(found, 95)) if found.size else math.nan,
                "us_per_profile": times[rs.joint],
            }
        else:
            row |= {k: math.nan for k in ("detection_rate", "wrong_rate")}
            row |= {k: math.nan for k in ("median_error_mm", "p95_error_mm")}
            row["us_per_profile"] = float(np.mean(list(times.values())))
        others = {k: float(np.mean([bool(f) for f in v])) for k, v in answers.items()}
        others.pop(rs.joint, None)
        worst = max(others, key=lambda k: others[k])
        row |= {
            "false_joint_rate": float(np.mean(list(others.values()))),
            "worst_false": f"{worst} {others[worst]:.3f}",
            "classified_rate": float(np.mean([k == rs.joint for k in kinds])),
            "classify_us": classify_us,
        }
        rows.append(row)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "extractors_real.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=REAL_COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    (out / "extractors_real.md").write_text(real_table(rows))
    write_json(out / "extractors_real.json", rows)
    groove = bench_real_groove(sets)  # the groove extractor's 7 points on the V-groove sets
    if groove:
        with open(out / "extractors_real_groove.csv", "w", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=GROOVE_COLUMNS)
            writer.writeheader()
            writer.writerows(groove)
        (out / "extractors_real_groove.md").write_text(groove_table(groove))
    return rows


def real_table(rows: list[dict[str, Any]]) -> str:
    """The real-data rows as a markdown table."""
    head = (
        "set", "joint", "n", "detect", "wrong", "median mm", "p95 mm", "false joints",
        "worst false", "classified", "us/profile", "classify us",
    )  # fmt: skip
    cells = [
        [*(_fmt(r[k]) for k in REAL_COLUMNS[:-2]), f"{r['us_per_profile']:.0f}",
         f"{r['classify_us']:.0f}"]
        for r in rows
    ]  # fmt: skip
    return "\n".join(common.markdown_table(head, cells)) + "\n"
