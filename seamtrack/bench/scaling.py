"""Timings the test suite used to assert, measured here instead (a busy machine cannot fail a
test on them): the CAD cache's hit against its miss, a 1e5-point seam's run against the
2 mm one, and how close to its limit the wall-clock guard stops a run.

``seamtrack bench scaling`` writes ``scaling.json`` and ``scaling.md``.
"""

from __future__ import annotations

import json
import tempfile
import time
from pathlib import Path
from typing import Any

from seamtrack.bench.common import machine_info


def _cache_rows(quick: bool) -> dict[str, Any]:
    from seamtrack.workpiece.loader import load_workpiece

    with tempfile.TemporaryDirectory() as cache:
        start = time.perf_counter()
        miss = load_workpiece("v_groove", tolerance_mm=0.01, cache_dir=cache, path="arc")
        miss_s = time.perf_counter() - start
        start = time.perf_counter()
        hit = load_workpiece("v_groove", tolerance_mm=0.01, cache_dir=cache, path="arc")
        hit_s = time.perf_counter() - start
    assert hit.from_cache and not miss.from_cache
    return {"cache_miss_s": miss_s, "cache_hit_s": hit_s, "cache_speedup": miss_s / hit_s}


def _seam_density_rows(quick: bool) -> dict[str, Any]:
    from seamtrack.geometry.seam import Seam, paper_points
    from seamtrack.simulation.loop import simulate
    from seamtrack.simulation.scene import load_scene

    length = 100.0 if quick else 400.0
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "dense.csv"
        Seam.from_points(paper_points(0.004, length)).to_csv(path)
        base = {"seam.length_mm": length}
        coarse = simulate(load_scene("paper-verification", base))
        dense = simulate(
            load_scene("paper-verification", {**base, "seam.source": "csv", "seam.file": str(path)})
        )
    return {
        "seam_length_mm": length,
        "coarse_status": str(coarse.summary["status"]),
        "coarse_max_error_mm": float(coarse.summary["max_error_mm"]),
        "coarse_rms_error_mm": float(coarse.summary["rms_error_mm"]),
        "dense_seam_points": int(length / 0.004) + 1,
        "coarse_wall_s": float(coarse.summary["wall_time_s"]),
        "dense_wall_s": float(dense.summary["wall_time_s"]),
        "dense_over_coarse": float(dense.summary["wall_time_s"] / coarse.summary["wall_time_s"]),
    }


def _guard_rows(quick: bool) -> dict[str, Any]:
    from seamtrack.simulation.loop import simulate
    from seamtrack.simulation.scene import load_scene

    limit = 1.0 if quick else 2.0
    over = {
        "seam.length_mm": 20.0,
        "simulation.welding_speed_mm_s": 0.02,
        "simulation.time_limit_s": 3000.0,
        "simulation.wall_time_limit_s": limit,
        "robot.control_period_s": 1e-3,
    }
    start = time.perf_counter()
    result = simulate(load_scene("paper-verification", over))
    wall = time.perf_counter() - start
    return {
        "guard_limit_s": limit,
        "guard_status": result.summary["status"],
        "guard_stop_reason": result.summary["stop_reason"],
        "guard_total_wall_s": wall,
        "guard_overshoot_s": wall - limit,
    }


def bench_scaling(out_dir: str | Path, *, quick: bool = False) -> dict[str, Any]:
    """Run the three measurements; write ``scaling.json`` and ``scaling.md``."""
    out = Path(out_dir)
    row = {**_cache_rows(quick), **_seam_density_rows(quick), **_guard_rows(quick)}
    machine = machine_info()
    result: dict[str, Any] = {"machine": machine, "quick": quick, "row": row}
    out.mkdir(parents=True, exist_ok=True)
    (out / "scaling.json").write_text(json.dumps(result, indent=2) + "\n")
    m = machine
    lines = [
        f"Machine: {m['cpu']}, {m['cores']} cores, Python {m['python']}.",
        "",
        "| measurement | value |",
        "|---|---|",
        f"| CAD cache miss (v_groove, arc path, 0.01 mm) | {row['cache_miss_s']:.2f} s |",
        f"| CAD cache hit | {row['cache_hit_s']:.3f} s ({row['cache_speedup']:.0f}x faster) |",
        f"| paper-verification, 2 mm seam | {row['coarse_wall_s']:.2f} s "
        f"({row['coarse_status']}, max error {row['coarse_max_error_mm']:.3f} mm) |",
        f"| the same, {row['dense_seam_points']:,} seam points | {row['dense_wall_s']:.2f} s "
        f"({row['dense_over_coarse']:.2f}x) |",
        f"| wall-clock guard at {row['guard_limit_s']:g} s | stopped "
        f"{row['guard_status']} after {row['guard_total_wall_s']:.2f} s, scoring included "
        f"(+{row['guard_overshoot_s']:.2f} s) |",
    ]
    (out / "scaling.md").write_text("\n".join(lines) + "\n")
    return result
