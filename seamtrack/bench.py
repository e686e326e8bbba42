"""Benchmarks: what a stripe profile costs, and what our code adds to bare Embree.

``bench_raycast`` times one laser profile (a fan of 1024 rays and the shadow rays of its lit
points) on a ~100k-triangle V-groove plate and, when CadQuery is available, on the CAD V-groove,
on the same rays: :func:`seamtrack.scan.scan_mesh` (a ``Profile``) with float64 refinement on
and off, :func:`seamtrack.scan.stripe_hits` (the arrays, no ``Profile``) on the default backend
(Embree packets, :mod:`seamtrack.embree`) and on the embreex fallback, bare ``embreex``
``scene.run`` calls on pre-built float32 arrays, and trimesh's ``mesh.ray`` methods
(``intersects_location``, then ``intersects_any``). One thread, best of ``repeats`` runs.
"""

from __future__ import annotations

import json
import os
import platform
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from . import constants, frames

RAYS = 1024


def v_groove_plate_mesh(
    *,
    triangles: int = 100_000,
    width_mm: float = 100.0,
    length_mm: float = 100.0,
    depth_mm: float = 10.0,
    half_angle_rad: float = np.radians(30.0),
    roughness_mm: float = 0.005,
    seed: int = 0,
) -> Any:
    """A finely triangulated V-groove plate (a sheet), with Gaussian roughness on z.

    The groove runs along x at y = 0, its root at z = -depth; the plate's top is z = 0.
    Returns a ``trimesh.Trimesh`` of about ``triangles`` faces.
    """
    import trimesh

    g = depth_mm * np.tan(half_angle_rad)
    ys = np.array([-0.5 * width_mm, -g, 0.0, g, 0.5 * width_mm])
    zs = np.array([0.0, 0.0, -depth_mm, 0.0, 0.0])
    n_across = int(np.sqrt(triangles / 4.0))
    n_along = max(2, triangles // (2 * n_across))
    arc = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(ys), np.diff(zs)))])
    s = np.union1d(np.linspace(0.0, arc[-1], n_across), arc)
    yz = np.column_stack([np.interp(s, arc, ys), np.interp(s, arc, zs)])
    x = np.linspace(-0.5 * length_mm, 0.5 * length_mm, n_along + 1)
    grid_x, grid_k = np.meshgrid(x, np.arange(len(yz)), indexing="ij")
    vertices = np.column_stack([grid_x.ravel(), yz[grid_k.ravel()]])
    vertices[:, 2] += np.random.default_rng(seed).normal(0.0, roughness_mm, len(vertices))
    idx = np.arange(len(vertices)).reshape(len(x), len(yz))
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    faces = np.concatenate([np.column_stack([a, c, b]), np.column_stack([a, d, c])])
    return trimesh.Trimesh(vertices, faces, process=False)


def _best_rate(fn: Callable[[], object], calls: int, repeats: int) -> float:
    """Profiles per second: best of ``repeats`` runs of ``calls`` calls."""
    fn()
    best = np.inf
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(calls):
            fn()
        best = min(best, (time.perf_counter() - start) / calls)
    return 1.0 / best


def _bare_rays(sensor: Any, caster: Any, T: np.ndarray) -> tuple[np.ndarray, ...]:
    """The very rays the pipeline casts at pose T, as arrays for bare Embree and trimesh:
    (fan origins f32, fan directions f32, shadow origins f32, shadow directions f32, shadow
    lengths f32, fan origins world f64, fan directions f64, shadow origins world f64, shadow
    directions f64)."""
    from .scan import laser_fan, stripe_hits

    hits = stripe_hits(sensor, caster, T, RAYS)
    fan_world = laser_fan(sensor, RAYS).directions @ T[:3, :3].T
    origin_local = T[:3, 3] - caster.local_origin
    fan_o32 = np.ascontiguousarray(np.broadcast_to(origin_local, fan_world.shape), np.float32)
    shadow = np.flatnonzero(np.isin(hits.reason, [0, 2]) & (hits.face >= 0))
    camera = origin_local + sensor.baseline_mm * T[:3, 0]
    lit = origin_local + hits.distance_mm[shadow, None] * fan_world[shadow]
    to_camera = camera - lit
    length = np.linalg.norm(to_camera, axis=1)
    sh_d = to_camera / length[:, None]
    sh_o32 = (lit + constants.SHADOW_RAY_OFFSET_MM * sh_d).astype(np.float32)
    return (
        fan_o32,
        fan_world.astype(np.float32),
        sh_o32,
        sh_d.astype(np.float32),
        (length - constants.SHADOW_RAY_OFFSET_MM).astype(np.float32),
        fan_o32.astype(np.float64) + caster.local_origin,
        fan_world,
        sh_o32.astype(np.float64) + caster.local_origin,
        sh_d,
    )


def _case(name: str, mesh: Any, poses: list[np.ndarray], calls: int, repeats: int) -> dict:
    """Time every method on one mesh: each call casts one profile at every pose in turn."""
    import trimesh

    from . import raycast
    from .scan import ray_caster, scan_mesh, stripe_hits
    from .sensor import preset

    sensor = preset("paper")
    build_start = time.perf_counter()
    raycast.RayCaster.from_mesh(mesh)
    build_s = time.perf_counter() - build_start
    caster = ray_caster(mesh)  # the cached one that scan_mesh uses
    # embreex's own scene (the fallback backend): the bare calls and the pipeline on it.
    embreex_caster = raycast.RayCaster.from_mesh(mesh, backend="embreex")
    rays = [_bare_rays(sensor, caster, T) for T in poses]
    scene = embreex_caster.scene
    intersector = mesh.ray

    def bare() -> None:
        for fan_o32, fan_d32, sh_o32, sh_d32, sh_far32, *_ in rays:
            scene.run(fan_o32, fan_d32, output=1)
            scene.run(sh_o32, sh_d32, dists=sh_far32.copy(), query="OCCLUDED")

    def packets_fan() -> None:
        for fan_o32, fan_d32, *_ in rays:
            caster.cast_local(fan_o32[:1], fan_d32)

    def packets_shadow() -> None:
        for _, _, sh_o32, sh_d32, sh_far32, *_ in rays:
            caster.occluded_local(sh_o32, sh_d32, sh_far32)

    def bare_fan() -> None:
        for fan_o32, fan_d32, *_ in rays:
            scene.run(fan_o32, fan_d32, output=1)

    def bare_shadow() -> None:
        for _, _, sh_o32, sh_d32, sh_far32, *_ in rays:
            scene.run(sh_o32, sh_d32, dists=sh_far32.copy(), query="OCCLUDED")

    def via_trimesh() -> None:
        for *_, fan_o64, fan_world, sh_o64, sh_d in rays:
            intersector.intersects_location(fan_o64, fan_world, multiple_hits=False)
            intersector.intersects_any(sh_o64, sh_d)

    def every_pose(fn: Callable[[np.ndarray], object]) -> Callable[[], None]:
        def run() -> None:
            for T in poses:
                fn(T)

        return run

    methods: dict[str, Callable[[], object]] = {
        "scan_mesh (Profile), float64 refinement": every_pose(
            lambda T: scan_mesh(sensor, mesh, T, rays=RAYS)
        ),
        "scan_mesh (Profile), float32 only": every_pose(
            lambda T: scan_mesh(sensor, mesh, T, rays=RAYS, refine=False)
        ),
        "stripe_hits (arrays), float64 refinement": every_pose(
            lambda T: stripe_hits(sensor, caster, T, RAYS)
        ),
        "stripe_hits (arrays), float32 only": every_pose(
            lambda T: stripe_hits(sensor, caster, T, RAYS, refine=False)
        ),
        "stripe_hits (arrays), embreex backend": every_pose(
            lambda T: stripe_hits(sensor, embreex_caster, T, RAYS)
        ),
        "bare embreex scene.run (same rays)": bare,
        "trimesh mesh.ray (same rays)": via_trimesh,
        "part: Embree packets, fan only": packets_fan,
        "part: Embree packets, shadow rays only": packets_shadow,
        "part: bare embreex, fan only": bare_fan,
        "part: bare embreex, shadow rays only": bare_shadow,
    }
    rates = {key: 0.0 for key in methods}
    for _ in range(repeats):  # interleaved, so that drift hits every method alike
        for key, fn in methods.items():
            rates[key] = max(rates[key], len(poses) * _best_rate(fn, calls, 1))
    shadow = [len(r[2]) for r in rays]
    hits = stripe_hits(sensor, caster, poses[0], RAYS)
    return {
        "mesh": name,
        "triangles": len(mesh.faces),
        "backend": caster.backend,
        "scene_build_s": build_s,
        "rays": RAYS,
        "poses": len(poses),
        "shadow_rays": int(np.mean(shadow)),
        "valid_points": int((hits.reason == 0).sum()),
        "trimesh_intersector": f"{type(intersector).__module__}.{type(intersector).__name__}",
        "trimesh_has_embree": bool(trimesh.ray.has_embree),
        "profiles_per_s": rates,
    }


def machine_info() -> dict[str, Any]:
    """CPU model (from /proc/cpuinfo), core count, Python and library versions."""
    import embreex
    import numba
    import trimesh

    cpu = platform.processor() or "unknown"
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {
        "cpu": cpu,
        "cores": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "embreex": getattr(embreex, "__version__", "?"),
        "trimesh": trimesh.__version__,
        "numba": numba.__version__,
    }


def bench_raycast(out_dir: str | Path, *, repeats: int = 30, quick: bool = False) -> dict:
    """Profiles per second of the mesh-mode stripe; writes ``raycast.json`` and ``raycast.md``.

    Parameters
    ----------
    out_dir : str or Path
    repeats : int
        Runs of 50 profiles per method (the best is kept), interleaved across methods, so
        that other load on the machine shows as fewer fast runs, not as slower ones. The
        paper part is cast at 200 poses along its seam, each run once through all of them
        (``repeats // 6`` runs, at least 3): one pose repeated lets the CPU learn Embree's
        branches, which new rays every profile do not allow.
    quick : bool
        Fewer calls per run and a 20k-triangle plate (a smoke test, not a measurement).

    Returns
    -------
    dict
        ``machine``, ``cases`` (one per mesh: rates per method), ``skipped`` (why a mesh was
        left out) and the ``ratios`` the targets are stated in.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    calls = 10 if quick else 50
    repeats = min(repeats, 3) if quick else repeats
    triangles = 20_000 if quick else 100_000
    T_plate = frames.make(frames.look_rotation([0.0, 0.0, -1.0], [1.0, 0.0, 0.0]), [0.0, 0.0, 91.0])
    cases = [
        _case(
            f"V-groove plate, {triangles // 1000}k triangles, 5 um roughness",
            v_groove_plate_mesh(triangles=triangles),
            [T_plate],
            calls,
            repeats,
        )
    ]
    skipped: dict[str, str] = {}
    try:
        from .sensor import preset
        from .workpiece import load_workpiece

        part = load_workpiece("v_groove", tolerance_mm=0.01)
        root = part.seam.interpolate(0.5 * part.seam.length_mm)
        T_cad = frames.make(
            frames.look_rotation([0.0, 0.0, -1.0], [1.0, 0.0, 0.0]),
            root + np.array([0.0, 0.0, preset("paper").range_center_mm]),
        )
        cases.append(
            _case(
                "CAD v_groove (load_workpiece, tolerance 0.01 mm)",
                part.mesh,
                [T_cad],
                calls,
                repeats,
            )
        )
    except Exception as error:  # CadQuery missing or the CAD module not ready: say so
        skipped["CAD v_groove"] = f"{type(error).__name__}: {error}"
    try:  # the realistic case: a new pose, so new rays, for every profile
        from .scene import load_scene

        overrides = {"workpiece.params.seam_length_mm": 40.0} if quick else {}
        parts = load_scene("paper-v-groove", overrides).build()
        arc = np.linspace(0.0, 0.95 * parts.seam.length_mm, 20 if quick else 200)
        robot = parts.robot
        poses = [robot.T_world_sensor(robot.q_from_world(p)) for p in parts.seam.interpolate(arc)]
        assert parts.mesh is not None
        cases.append(
            _case(
                f"paper-v-groove part along its seam, {len(poses)} poses (new rays every profile)",
                parts.mesh,
                poses,
                1,
                max(3, repeats // 6),
            )
        )
    except Exception as error:
        skipped["paper-v-groove"] = f"{type(error).__name__}: {error}"
    for case in cases:
        r = case["profiles_per_s"]
        case["ratios"] = {
            "scan_mesh / bare embreex": r["scan_mesh (Profile), float64 refinement"]
            / r["bare embreex scene.run (same rays)"],
            "stripe_hits / bare embreex": r["stripe_hits (arrays), float64 refinement"]
            / r["bare embreex scene.run (same rays)"],
            "scan_mesh / trimesh": r["scan_mesh (Profile), float64 refinement"]
            / r["trimesh mesh.ray (same rays)"],
            "refinement cost (scan_mesh)": r["scan_mesh (Profile), float32 only"]
            / r["scan_mesh (Profile), float64 refinement"]
            - 1.0,
            "refinement cost (stripe_hits)": r["stripe_hits (arrays), float32 only"]
            / r["stripe_hits (arrays), float64 refinement"]
            - 1.0,
        }
    result = {
        "machine": machine_info(),
        "rays": RAYS,
        "repeats": repeats,
        "calls": calls,
        "quick": quick,
        "cases": cases,
        "skipped": skipped,
    }
    (out / "raycast.json").write_text(json.dumps(result, indent=2))
    (out / "raycast.md").write_text(raycast_markdown(result))
    return result


def raycast_markdown(result: dict) -> str:
    """The markdown table of a :func:`bench_raycast` result."""
    m = result["machine"]
    lines = [
        f"Machine: {m['cpu']}, {m['cores']} cores; Python {m['python']}, numpy {m['numpy']}, "
        f"embreex {m['embreex']}, trimesh {m['trimesh']}, numba {m['numba']}. One thread; "
        f"{result['rays']} rays per profile plus one shadow ray per lit point in range; best "
        f"of {result['repeats']} runs of {result['calls']} profiles.",
        "",
    ]
    for case in result["cases"]:
        lines += [
            f"**{case['mesh']}** ({case['triangles']} triangles, {case['shadow_rays']} shadow "
            f"rays, {case['valid_points']} valid points; `{case['backend']}` backend, scene "
            f"built in {case['scene_build_s'] * 1e3:.0f} ms; trimesh intersector "
            f"`{case['trimesh_intersector']}`, embree "
            f"{'available' if case['trimesh_has_embree'] else 'NOT available'})",
            "",
            "| method | profiles/s | us per profile | vs bare embreex |",
            "|---|---:|---:|---:|",
        ]
        bare = case["profiles_per_s"]["bare embreex scene.run (same rays)"]
        for key, rate in case["profiles_per_s"].items():
            lines.append(f"| {key} | {rate:,.0f} | {1e6 / rate:.0f} | {rate / bare:.2f}x |")
        lines += ["", "| ratio | value |", "|---|---:|"]
        for key, value in case["ratios"].items():
            text = f"{value * 100:+.1f} %" if "cost" in key else f"{value:.2f}x"
            lines.append(f"| {key} | {text} |")
        lines.append("")
    for key, why in result["skipped"].items():
        lines.append(f"Skipped {key}: {why}")
    return "\n".join(lines) + "\n"


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
    from .sweep import run_sweep

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

    from .extractors_bench import bench_extractors

    return bench_extractors(out, quick=quick, progress=sys.stderr.isatty())


def _bench_mesh(out: Path, quick: bool) -> Any:
    from .workpiece import mesh_tradeoff

    tolerances = (1.0, 0.1, 0.01) if quick else (1.0, 0.1, 0.01, 0.001)
    rows = mesh_tradeoff(tolerances=tolerances)
    out.mkdir(parents=True, exist_ok=True)
    (out / "mesh.json").write_text(
        json.dumps({"machine": machine_info(), "rows": rows}, indent=2, default=float)
    )
    keys = list(rows[0]) if rows else []
    lines = ["| " + " | ".join(keys) + " |", "|" + "---|" * len(keys)]
    lines += [
        "| "
        + " | ".join(f"{r[k]:.4g}" if isinstance(r[k], float) else str(r[k]) for k in keys)
        + " |"
        for r in rows
    ]
    (out / "mesh.md").write_text("\n".join(lines) + "\n")
    return rows


def bench_loop(out_dir: str | Path, *, quick: bool = False) -> dict[str, Any]:
    """The closed loop on the paper's mesh scene: simulated seconds per wall second, and the
    share of the run spent outside ray casting and feature extraction.

    ``paper-v-groove``: the Eq. 15-17 seam as a CAD V-groove, 100 profiles/s of 1024 rays with
    shadow rays, the v-groove extractor, the trajectory tracker at 1 kHz control, 5 mm/s (the
    whole 405 mm seam; ``quick``: 40 mm). Writes ``loop.json`` and ``loop.md``.
    """
    from .scene import load_scene
    from .simulation import run

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    overrides = {"workpiece.params.seam_length_mm": 40.0} if quick else {}
    scene = load_scene("paper-v-groove", overrides)
    parts = scene.build()  # meshing and the Embree scene are set-up, not loop
    result = run(parts)
    s = result.summary
    wall, sense = float(s["wall_time_s"]), float(s["sense_wall_time_s"])
    # Split sensing into ray casting and extraction on frames along the seam.
    from .features import extractor
    from .scan import scan_mesh

    assert parts.sensor is not None and parts.mesh is not None
    find = extractor(scene.config.extractor.name)
    arc = np.linspace(0.0, parts.seam.length_mm * 0.95, 200)
    poses = [
        parts.robot.T_world_sensor(parts.robot.q_from_world(p)) for p in parts.seam.interpolate(arc)
    ]
    find(scan_mesh(parts.sensor, parts.mesh, poses[0], rays=1024))  # set-up (Embree scene), untimed
    profiles = []
    start = time.perf_counter()
    for T in poses:
        profiles.append(scan_mesh(parts.sensor, parts.mesh, T, rays=1024))
    scan_s = (time.perf_counter() - start) / len(poses)
    start = time.perf_counter()
    for profile in profiles:
        find(profile)
    extract_s = (time.perf_counter() - start) / len(poses)
    row = {
        "scene": "paper-v-groove",
        "quick": quick,
        "status": s["status"],
        "simulated_s": float(s["sim_time_s"]),
        "wall_s": wall,
        "sensing_s": sense,
        "frames": int(s["frames"]),
        "control_ticks": int(round(s["sim_time_s"] / 1e-3)) + 1,
        "sim_s_per_wall_s": float(s["sim_time_s"]) / wall,
        "loop_overhead_fraction": (wall - sense) / wall,
        "scan_ms_per_frame": 1e3 * scan_s,
        "extract_ms_per_frame": 1e3 * extract_s,
        "max_error_mm": float(s["max_error_mm"]),
    }
    result_dict: dict[str, Any] = {"machine": machine_info(), "rows": [row]}
    (out / "loop.json").write_text(json.dumps(result_dict, indent=2))
    m = result_dict["machine"]
    lines = [
        f"Machine: {m['cpu']}, {m['cores']} cores, Python {m['python']}.",
        "",
        "| scene | simulated s | wall s | sim s / wall s | sensing s | loop overhead | "
        "ray cast ms/frame | extraction ms/frame | frames | max error mm |",
        "|---|---|---|---|---|---|---|---|---|---|",
        f"| {row['scene']} | {row['simulated_s']:.1f} | {wall:.1f} | "
        f"{row['sim_s_per_wall_s']:.2f} | {sense:.1f} | "
        f"{100 * row['loop_overhead_fraction']:.0f} % | "
        f"{row['scan_ms_per_frame']:.3f} | {row['extract_ms_per_frame']:.3f} | {row['frames']} | "
        f"{row['max_error_mm']:.4f} |",
    ]
    (out / "loop.md").write_text("\n".join(lines) + "\n")
    return result_dict


def _bench_tradeoff(out: Path, quick: bool) -> Any:
    from .bench_tradeoff import bench_tradeoff

    return bench_tradeoff(out, quick=quick)


BENCHES: dict[str, Callable[[Path, bool], Any]] = {
    "raycast": lambda out, quick: bench_raycast(out, quick=quick),
    "extractors": _bench_extractors,
    "mesh": _bench_mesh,
    "loop": lambda out, quick: bench_loop(out, quick=quick),
    "tradeoff": _bench_tradeoff,
    "sweep": lambda out, quick: bench_sweep(out, quick=quick),
}


def run_benches(which: str, out_dir: Path, quick: bool = False) -> dict[str, Any]:
    """Run one benchmark by name (or ``all``), each into ``out_dir/<name>/``."""
    from .errors import SceneError

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
