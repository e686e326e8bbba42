"""``seamtrack bench``: the loop, sweep, mesh and extractor benchmarks, and the dispatcher that
runs any of them (the ray-casting bench lives in :mod:`seamtrack.bench.raycast`, the
speed/accuracy trade in :mod:`seamtrack.bench.tradeoff`).
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from seamtrack.bench.common import machine_info, markdown_table
from seamtrack.bench.common import peak_rss as _peak_rss
from seamtrack.bench.common import reset_peak_rss as _reset_peak_rss
from seamtrack.bench.raycast import bench_raycast

# --------------------------------------------------------------------------- sweep
#: paper-corner shortened to a 20 mm leg and a 14 mm leg after its 45 deg turn: ~0.3 s a run.
SWEEP_BENCH_OVERRIDES: dict[str, Any] = {
    "seam.points_mm": [[0.0, 0.0, 0.0], [20.0, 0.0, 0.0], [30.0, 10.0, 0.0]]
}


def bench_sweep(out_dir: str | Path, quick: bool = False) -> dict:
    """Wall time of a 200-case sweep on 1 and on 2 local worker processes.

    The cases are ``paper-corner`` shortened (:data:`SWEEP_BENCH_OVERRIDES`) over 200 radii of
    convergence (40 radii x 5 seeds would cost the same); both runs must give the same numbers.
    Writes ``sweep.json`` and ``sweep.md``.

    Parameters
    ----------
    out_dir : str or Path
    quick : bool
        20 cases instead of 200 (a smoke test, not a measurement).

    Returns
    -------
    dict
        ``machine``, ``cases``, ``case_time_s`` (mean single-run wall time), ``runs`` (one per
        worker count: ``workers``, ``wall_time_s``, ``ratio_to_1_worker``, ``cpu_time_s`` of
        all processes, and the 1-minute ``load_average_before``: other work on the machine
        shows there) and ``target``.
    """
    from seamtrack.batch.sweep import run_sweep

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    count = 20 if quick else 200
    radii = [round(float(r), 6) for r in np.geomspace(0.05, 6.0, count)]
    runs = []
    numbers: list[list[Any]] = []
    case_times: list[float] = []
    import resource

    for workers in (1, 2):
        load_before = os.getloadavg()[0]
        cpu_start = time.process_time()
        children_start = resource.getrusage(resource.RUSAGE_CHILDREN)
        start = time.perf_counter()
        rows = run_sweep(
            "paper-corner",
            "tracker.radius_mm",
            radii,
            overrides=SWEEP_BENCH_OVERRIDES,
            workers=workers,
        )
        wall = time.perf_counter() - start
        children = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (
            time.process_time()
            - cpu_start
            + (children.ru_utime - children_start.ru_utime)
            + (children.ru_stime - children_start.ru_stime)
        )
        failed = [row for row in rows if "summary" not in row]
        if failed:
            raise RuntimeError(f"bench_sweep: case failed: {failed[0]}")
        numbers.append([row["summary"]["max_error_mm"] for row in rows])
        if workers == 1:
            case_times = [row["summary"]["wall_time_s"] for row in rows]
        runs.append(
            {
                "workers": workers,
                "wall_time_s": wall,
                "cases_per_s": count / wall,
                "cpu_time_s": cpu,
                "load_average_before": load_before,
            }
        )
    for run in runs:
        run["ratio_to_1_worker"] = run["wall_time_s"] / runs[0]["wall_time_s"]
    m = machine_info()
    result: dict[str, Any] = {
        "machine": m,
        "scene": "paper-corner",
        "overrides": SWEEP_BENCH_OVERRIDES,
        "param": "tracker.radius_mm",
        "cases": count,
        "quick": quick,
        "case_time_s": float(np.mean(case_times)),
        "same_numbers": numbers[0] == numbers[1],
        "runs": runs,
        "target": "2 workers <= 0.6 x the wall time of 1 worker",
    }
    (out / "sweep.json").write_text(json.dumps(result, indent=2))
    lines = [
        f"Machine: {m['cpu']}, {m['cores']} cores; Python {m['python']}, numpy {m['numpy']}. "
        f"{count} cases of paper-corner shortened (20 mm + 14 mm), tracker.radius_mm "
        f"0.05..6 mm; one case takes {result['case_time_s']:.3f} s on its own; "
        f"identical numbers on 1 and 2 workers: {'yes' if result['same_numbers'] else 'NO'}.",
        "",
        "| workers | wall time (s) | cases/s | ratio to 1 worker | CPU time (s) | load before |",
        "|---:|---:|---:|---:|---:|---:|",
    ]
    for run in runs:
        lines.append(
            f"| {run['workers']} | {run['wall_time_s']:.1f} | {run['cases_per_s']:.2f} | "
            f"{run['ratio_to_1_worker']:.2f}x | {run['cpu_time_s']:.1f} | "
            f"{run['load_average_before']:.1f} |"
        )
    lines += ["", f"Target: {result['target']}."]
    (out / "sweep.md").write_text("\n".join(lines) + "\n")
    return result


# --------------------------------------------------------------------------- dispatch
def _bench_extractors(out: Path, quick: bool) -> Any:
    import sys

    from seamtrack.bench.extractors import bench_extractors

    return bench_extractors(out, quick=quick, progress=sys.stderr.isatty())


def _bench_mesh(out: Path, quick: bool) -> Any:
    from unittest import mock

    from seamtrack.workpiece import loader

    tolerances = (1.0, 0.1, 0.01) if quick else (1.0, 0.1, 0.01, 0.001)
    loader.mesh_tradeoff(tolerances=(1.0,), paths=("arc",))  # imports CadQuery/OCP, unmeasured
    rows = []
    step: list[int] = []  # the peak before meshing, the meshing step's start and peak (bytes)
    mesh = loader._mesh

    def measured(*args: Any, **kwargs: Any) -> Any:
        step[:] = [_peak_rss(), _reset_peak_rss()]
        result = mesh(*args, **kwargs)
        step.append(_peak_rss())
        return result

    for path in ("arc", "paper"):
        for tol in tolerances:
            before = _reset_peak_rss()
            # the meshing step (mesh, refine, measure the deviation, weld) timed on its own
            # peak, beside the whole row's (building the CAD solid and sampling its seam too)
            with mock.patch.object(loader, "_mesh", measured):
                (row,) = loader.mesh_tradeoff(tolerances=(tol,), paths=(path,))
            whole = max(_peak_rss(), step[0], step[2])
            n = max(row["triangles"], 1)
            row["peak_rss_mb"] = whole / 2**20
            # (a peak under the start is the allocator handing back pages: nothing added)
            row["peak_bytes_per_triangle"] = max(step[2] - step[1], 0) / n
            row["row_peak_bytes_per_triangle"] = max(whole - before, 0) / n
            rows.append(row)
    out.mkdir(parents=True, exist_ok=True)
    (out / "mesh.json").write_text(
        json.dumps({"machine": machine_info(), "rows": rows}, indent=2, default=float)
    )
    keys = list(rows[0]) if rows else []
    lines = markdown_table(
        keys,
        ([f"{r[k]:.4g}" if isinstance(r[k], float) else str(r[k]) for k in keys] for r in rows),
    )
    (out / "mesh.md").write_text("\n".join(lines) + "\n")
    return rows


def bench_loop(out_dir: str | Path, *, quick: bool = False) -> dict[str, Any]:
    """The closed loop on the paper's mesh scene (:mod:`seamtrack.bench.loop`)."""
    from seamtrack.bench.loop import bench_loop as run_bench

    return run_bench(out_dir, quick=quick)


def _bench_tradeoff(out: Path, quick: bool) -> Any:
    from seamtrack.bench.tradeoff import bench_tradeoff

    return bench_tradeoff(out, quick=quick)


def _bench_scaling(out: Path, quick: bool) -> Any:
    from seamtrack.bench.scaling import bench_scaling

    return bench_scaling(out, quick=quick)


def _bench_camera(out: Path, quick: bool) -> Any:
    from seamtrack.bench.camera import bench_camera

    return bench_camera(out, quick=quick)


def _bench_failures(out: Path, quick: bool) -> Any:
    from seamtrack.bench.failures import bench_failures

    return bench_failures(out, quick=quick)


def _bench_dataset(out: Path, quick: bool) -> Any:
    from seamtrack.bench.dataset import bench_dataset

    return bench_dataset(out, quick=quick)


def _bench_gym(out: Path, quick: bool) -> Any:
    from seamtrack.bench.gym import bench_gym

    return bench_gym(out, quick=quick)


def _bench_bridge(out: Path, quick: bool) -> Any:
    from seamtrack.bench.bridge import bench_bridge

    return bench_bridge(out, quick=quick)


def _bench_multipass(out: Path, quick: bool) -> dict:
    from seamtrack.bench.multipass import bench_multipass

    return bench_multipass(out, quick=quick)


def _bench_trackers(out: Path, quick: bool) -> Any:
    from seamtrack.bench.trackers import bench_trackers

    return bench_trackers(out, quick=quick)


def _bench_paper(out: Path, quick: bool) -> Any:
    from seamtrack.bench.paper import bench_paper

    return bench_paper(out, quick=quick)


def _bench_firstrun(out: Path, quick: bool) -> Any:
    from seamtrack.bench.firstrun import bench_firstrun

    return bench_firstrun(out, quick=quick)


def _bench_distortion(out: Path, quick: bool) -> Any:
    from seamtrack.bench.distortion import bench_distortion

    return bench_distortion(out, quick=quick)


def _bench_weldments(out: Path, quick: bool) -> Any:
    from seamtrack.bench.weldments import bench_weldments

    return bench_weldments(out, quick=quick)


def _bench_stability(out: Path, quick: bool) -> Any:
    from seamtrack.bench.stability import bench_stability

    return bench_stability(out, quick=quick)


def _bench_arc(out: Path, quick: bool) -> Any:
    from seamtrack.bench.arc import bench_arc

    return bench_arc(out, quick=quick)


def _bench_beads(out: Path, quick: bool) -> Any:
    from seamtrack.bench.published_beads import bench_beads

    return bench_beads(out, quick=quick)


BENCHES: dict[str, Callable[[Path, bool], Any]] = {
    "raycast": lambda out, quick: bench_raycast(out, quick=quick),
    "extractors": _bench_extractors,
    "mesh": _bench_mesh,
    "loop": lambda out, quick: bench_loop(out, quick=quick),
    "tradeoff": _bench_tradeoff,
    "sweep": lambda out, quick: bench_sweep(out, quick=quick),
    "scaling": _bench_scaling,
    "failures": _bench_failures,
    "camera": _bench_camera,
    "dataset": _bench_dataset,
    "gym": _bench_gym,
    "bridge": _bench_bridge,
    "multipass": _bench_multipass,
    "trackers": _bench_trackers,
    "paper": _bench_paper,
    "firstrun": _bench_firstrun,
    "distortion": _bench_distortion,
    "weldments": _bench_weldments,
    "stability": _bench_stability,
    "arc": _bench_arc,
    "beads": _bench_beads,
}


def run_benches(which: str, out_dir: Path, quick: bool = False) -> dict[str, Any]:
    """Run one benchmark by name (or ``all``), each into ``out_dir/<name>/``."""
    from seamtrack.errors import SceneError

    names = list(BENCHES) if which == "all" else [which]
    unknown = [n for n in names if n not in BENCHES]
    if unknown:
        raise SceneError(
            f"unknown benchmark {unknown[0]!r}",
            field="bench",
            fix=f"use one of {', '.join(BENCHES)} or all",
        )
    results = {}
    for name in names:
        print(f"bench {name} -> {out_dir / name}")
        results[name] = BENCHES[name](out_dir / name, quick)
    return results
