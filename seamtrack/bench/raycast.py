"""Benchmarks: what a stripe profile costs, and what our code adds to bare Embree.

``bench_raycast`` times one laser profile (a fan of 1024 rays and the shadow rays of its lit
points) on a ~100k-triangle V-groove plate and, when CadQuery is available, on the CAD V-groove
and the paper part, on the same rays: :func:`seamtrack.sensing.scan.scan_mesh` (a ``Profile``)
with the plane-section fan (:mod:`seamtrack.sensing.section`) and with the Embree fan, float64
refinement on and off; :func:`seamtrack.sensing.scan.stripe_hits` (the arrays, no ``Profile``)
likewise, on Embree packets (:mod:`seamtrack.sensing.embree`) and on the embreex fallback; bare
``embreex`` ``scene.run`` calls on pre-built float32 arrays; and trimesh's ``mesh.ray`` methods
(``intersects_location``, then ``intersects_any``). One thread, best of ``repeats`` runs. Each
case also reports the plane-section fan's agreement with the refined Embree fan
(:func:`fan_agreement`). Then the stripe's precision against exact hits on analytic parts up to
1e5 mm from the origin (:mod:`seamtrack.bench.raycast_precision`, ``precision``).
"""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from seamtrack import constants
from seamtrack.bench.common import best_rate, machine_info
from seamtrack.bench.raycast_precision import precision_rows
from seamtrack.geometry import frames

RAYS = 1024
#: Rays passing within this distance (mm) of a triangle edge that the laser plane crosses (a
#: section segment's end) at or before their hit are *edge rays*: there Embree's float32
#: traversal may take the neighbouring triangle, or miss a silhouette the exact ray grazes.
#: 1e-4 mm is about 7 float32 ulps at 200 mm from the local origin.
EDGE_MM = 1e-4
#: The agreement asked of the plane-section fan and the refined Embree hits (mm).
AGREE_MM = 1e-9


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


def _bare_rays(sensor: Any, caster: Any, T: np.ndarray) -> tuple[np.ndarray, ...]:
    """The very rays the pipeline casts at pose T, as arrays for bare Embree and trimesh:
    (fan origins f32, fan directions f32, shadow origins f32, shadow directions f32, shadow
    lengths f32, fan origins world f64, fan directions f64, shadow origins world f64, shadow
    directions f64)."""
    from seamtrack.sensing.scan import laser_fan, stripe_hits

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


def _pipeline_methods(
    sensor: Any, mesh: Any, caster: Any, embreex_caster: Any, poses: list[np.ndarray]
) -> dict[str, Callable[[], object]]:
    """The stripe as the library casts it (``scan_mesh``, ``stripe_hits``), by every fan and
    backend: one call casts one profile at every pose in turn."""
    from seamtrack.sensing.scan import scan_mesh, stripe_hits

    def every_pose(fn: Callable[[np.ndarray], object]) -> Callable[[], None]:
        def run() -> None:
            for T in poses:
                fn(T)

        return run

    return {
        "scan_mesh (Profile), plane-section fan": every_pose(
            lambda T: scan_mesh(sensor, mesh, T, rays=RAYS, fan="section")
        ),
        "scan_mesh (Profile), Embree fan, float64 refinement": every_pose(
            lambda T: scan_mesh(sensor, mesh, T, rays=RAYS, fan="embree")
        ),
        "scan_mesh (Profile), Embree fan, float32 only": every_pose(
            lambda T: scan_mesh(sensor, mesh, T, rays=RAYS, refine=False)
        ),
        "stripe_hits (arrays), plane-section fan": every_pose(
            lambda T: stripe_hits(sensor, caster, T, RAYS, fan="section")
        ),
        "stripe_hits (arrays), Embree fan, float64 refinement": every_pose(
            lambda T: stripe_hits(sensor, caster, T, RAYS, fan="embree")
        ),
        "stripe_hits (arrays), Embree fan, float32 only": every_pose(
            lambda T: stripe_hits(sensor, caster, T, RAYS, refine=False)
        ),
        "stripe_hits (arrays), Embree fan, embreex backend": every_pose(
            lambda T: stripe_hits(sensor, embreex_caster, T, RAYS, fan="embree")
        ),
    }


def _part_methods(
    rays: list[tuple[np.ndarray, ...]],
    caster: Any,
    scene: Any,
    intersector: Any,
    poses: list[np.ndarray],
) -> dict[str, Callable[[], object]]:
    """The same rays through the bare libraries (embreex, trimesh), and each part of the
    stripe alone (the fan, the shadow rays, the plane section)."""
    from seamtrack.sensing import section
    from seamtrack.sensing.scan import laser_fan
    from seamtrack.sensing.sensor import preset

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

    index = caster.section
    origins = [T[:3, 3] - caster.local_origin for T in poses]
    rotations = [np.ascontiguousarray(T[:3, :3]) for T in poses]
    fan = laser_fan(preset("paper"), RAYS).directions
    tree = (index.lo, index.hi, index.child, index.count, index.order, caster.vertices_local,
            caster.faces)  # fmt: skip

    def section_fan() -> None:
        for origin, rotation in zip(origins, rotations, strict=True):
            section.section_hits(*tree, origin, rotation, fan)

    return {
        "bare embreex scene.run (same rays)": bare,
        "trimesh mesh.ray (same rays)": via_trimesh,
        "part: plane-section fan only (float64 hits)": section_fan,
        "part: Embree packets, fan only": packets_fan,
        "part: Embree packets, shadow rays only": packets_shadow,
        "part: bare embreex, fan only": bare_fan,
        "part: bare embreex, shadow rays only": bare_shadow,
    }


def _case(name: str, mesh: Any, poses: list[np.ndarray], calls: int, repeats: int) -> dict:
    """Time every method on one mesh: each call casts one profile at every pose in turn."""
    import trimesh

    from seamtrack.sensing import raycast, section
    from seamtrack.sensing.scan import ray_caster, stripe_hits
    from seamtrack.sensing.sensor import preset

    sensor = preset("paper")
    build_start = time.perf_counter()
    raycast.RayCaster.from_mesh(mesh)
    build_s = time.perf_counter() - build_start
    caster = ray_caster(mesh)  # the cached one that scan_mesh uses
    section.build(caster.vertices_local, caster.faces)  # compiled and warm before it is timed
    build_start = time.perf_counter()
    section.build(caster.vertices_local, caster.faces)
    section_build_s = time.perf_counter() - build_start
    # embreex's own scene (the fallback backend): the bare calls and the pipeline on it.
    embreex_caster = raycast.RayCaster.from_mesh(mesh, backend="embreex")
    rays = [_bare_rays(sensor, caster, T) for T in poses]
    intersector = mesh.ray
    index = caster.section  # built once per mesh, like the Embree scene (timed below)
    methods = {
        **_pipeline_methods(sensor, mesh, caster, embreex_caster, poses),
        **_part_methods(rays, caster, embreex_caster.scene, intersector, poses),
    }
    rates = {key: 0.0 for key in methods}
    for _ in range(repeats):  # interleaved, so that drift hits every method alike
        for key, fn in methods.items():
            rates[key] = max(rates[key], len(poses) * best_rate(fn, calls, 1))
    shadow = [len(r[2]) for r in rays]
    hits = stripe_hits(sensor, caster, poses[0], RAYS)
    return {
        "mesh": name,
        "triangles": len(mesh.faces),
        "backend": caster.backend,
        "scene_build_s": build_s,
        "section_build_s": section_build_s,
        "section_index_mb": index.nbytes / 1e6,
        "agreement": fan_agreement(sensor, caster, agreement_poses(poses)),
        "rays": RAYS,
        "poses": len(poses),
        "shadow_rays": int(np.mean(shadow)),
        "valid_points": int((hits.reason == 0).sum()),
        "trimesh_intersector": f"{type(intersector).__module__}.{type(intersector).__name__}",
        "trimesh_has_embree": bool(trimesh.ray.has_embree),
        "profiles_per_s": rates,
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
        from seamtrack.sensing.sensor import preset
        from seamtrack.workpiece.loader import load_workpiece

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
        from seamtrack.simulation.assemble import build_parts
        from seamtrack.simulation.scene import load_scene

        overrides = {"workpiece.params.seam_length_mm": 40.0} if quick else {}
        parts = build_parts(load_scene("paper-v-groove", overrides))
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
        section_scan = r["scan_mesh (Profile), plane-section fan"]
        embree_scan = r["scan_mesh (Profile), Embree fan, float64 refinement"]
        embree_hits = r["stripe_hits (arrays), Embree fan, float64 refinement"]
        bare = r["bare embreex scene.run (same rays)"]
        case["ratios"] = {
            "scan_mesh, plane-section / Embree fan": section_scan / embree_scan,
            "fan only, plane-section / Embree packets": r[
                "part: plane-section fan only (float64 hits)"
            ]
            / r["part: Embree packets, fan only"],
            "scan_mesh (plane-section) / bare embreex": section_scan / bare,
            "scan_mesh (Embree fan) / bare embreex": embree_scan / bare,
            "stripe_hits (Embree fan) / bare embreex": embree_hits / bare,
            "scan_mesh (plane-section) / trimesh": section_scan / r["trimesh mesh.ray (same rays)"],
            "refinement cost (scan_mesh, Embree fan)": r[
                "scan_mesh (Profile), Embree fan, float32 only"
            ]
            / embree_scan
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
        "precision": precision_rows(),
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
            f"built in {case['scene_build_s'] * 1e3:.0f} ms, the plane section's hierarchy in "
            f"{case['section_build_s'] * 1e3:.0f} ms ({case['section_index_mb']:.1f} MB); "
            "trimesh intersector "
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
        a = case["agreement"]
        lines += [
            "",
            f"Plane-section fan against the float64-refined Embree fan on the same "
            f"{a['rays']} rays ({a['poses']} poses): {a['disagree']} rays disagree off the "
            f"edges (hit or miss {a['hit_mismatch']}, reason {a['reason_mismatch']}, distance "
            f"> {a['agree_mm']:g} mm), largest distance difference {a['max_dt_mm']:.1e} mm; "
            f"{a['edge_rays']} edge rays (within {a['edge_mm']:g} mm of a crossed triangle "
            f"edge, or on an edge in the laser plane), of which {a['disagree_edge']} disagree "
            f"(largest distance difference {a['max_dt_edge_mm']:.1e} mm); "
            f"{a['other_face']} rays lit a different triangle at the same point; "
            f"{a['embree_unrefined']} Embree hits left in float32.",
            "",
        ]
    for key, why in result["skipped"].items():
        lines.append(f"Skipped {key}: {why}")
    return "\n".join(lines) + "\n"


def agreement_poses(poses: list[np.ndarray]) -> list[np.ndarray]:
    """The poses the agreement is measured at: a case's own, and when it has one pose, that
    pose moved 0.37 and -7.1 mm along the laser plane's normal and turned 0.2 rad about the
    laser axis (off the grid lines a pose may sit on)."""
    if len(poses) > 1:
        return poses
    T = poses[0]
    turned = T.copy()
    c, s = np.cos(0.2), np.sin(0.2)
    turned[:3, :3] = T[:3, :3] @ np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    shifted = []
    for step in (0.37, -7.1):
        moved = T.copy()
        moved[:3, 3] += step * T[:3, 0]
        shifted.append(moved)
    return [T, *shifted, turned]


def fan_agreement(
    sensor: Any, caster: Any, poses: list[np.ndarray], *, rays: int = RAYS,
    edge_mm: float = EDGE_MM,
) -> dict[str, Any]:  # fmt: skip
    """The plane-section fan against the float64-refined Embree fan on the same rays.

    Every ray counts once per pose. An *edge ray* passes within ``edge_mm`` of a section
    segment's end (a crossed triangle edge; silhouettes included) no farther than its hit plus
    ``edge_mm``; a ray *disagrees* when the two fans differ in hit or miss, in reason, or in hit
    distance by more than :data:`AGREE_MM`. Returns the counts, the largest distance difference
    off the edges and on them (mm), how many Embree hits were not refined (kept in float32: no
    neighbouring triangle contained the float64 point), and on how many rays the two fans lit
    different triangles (at the same point: a shared edge).
    """
    from seamtrack.sensing import section
    from seamtrack.sensing.scan import laser_fan, stripe_hits

    fan = laser_fan(sensor, rays)
    tans = fan.directions[:, 1] / fan.directions[:, 2]
    tan_max = float(np.abs(tans).max()) * (1 + 1e-9) + 1e-9
    index = caster.section
    out: dict[str, Any] = dict.fromkeys(
        ("rays", "edge_rays", "disagree", "disagree_edge", "hit_mismatch", "reason_mismatch",
         "embree_unrefined", "other_face"), 0)  # fmt: skip
    out.update(poses=len(poses), max_dt_mm=0.0, max_dt_edge_mm=0.0, edge_mm=edge_mm,
               agree_mm=AGREE_MM)  # fmt: skip
    for T in poses:
        a = stripe_hits(sensor, caster, T, rays, fan="section")
        b = stripe_hits(sensor, caster, T, rays, fan="embree")
        refined = caster.first_hit(T[:3, 3], a.directions_local).refined
        origin = np.asarray(T[:3, 3] - caster.local_origin, dtype=np.float64)
        segs, _ = section.section_segments(
            index.lo, index.hi, index.child, index.count, index.order, caster.vertices_local,
            caster.faces, origin, np.ascontiguousarray(T[:3, :3]), tan_max,
        )  # fmt: skip
        ends = np.concatenate([segs[:, :2], segs[:, 2:]])  # (e, 2) = (y_L, z_L)
        d = fan.directions[:, 1:]  # (n, 2)
        along = d @ ends.T  # (n, e): distance along each ray to each end's foot
        off = np.abs(d[:, :1] * ends[None, :, 1] - d[:, 1:] * ends[None, :, 0])
        reach = np.where(np.isfinite(a.distance_mm), a.distance_mm, np.inf)
        near = (off < edge_mm) & (along > 0) & (along <= reach[:, None] + edge_mm)
        # A ray on an edge that lies in the laser plane (the triangles on both sides give the
        # same segment) is an edge ray too.
        x_axis = T[:3, 0]
        lit = np.flatnonzero(a.face >= 0)
        x_l = (caster.vertices_local[caster.faces[a.face[lit]]] - origin) @ x_axis
        in_plane = np.zeros(len(a.face), dtype=bool)
        in_plane[lit] = (np.abs(x_l) < edge_mm).sum(axis=1) >= 2
        edge = near.any(axis=1) | in_plane
        hit_a, hit_b = a.face >= 0, b.face >= 0
        both = hit_a & hit_b
        dt = np.zeros(len(hit_a))
        dt[both] = np.abs(a.distance_mm[both] - b.distance_mm[both])
        hit_diff = hit_a != hit_b
        reason_diff = a.reason != b.reason
        bad = hit_diff | reason_diff | (dt > AGREE_MM)
        out["rays"] += len(hit_a)
        out["edge_rays"] += int(edge.sum())
        out["disagree"] += int((bad & ~edge).sum())
        out["disagree_edge"] += int((bad & edge).sum())
        out["hit_mismatch"] += int((hit_diff & ~edge).sum())
        out["reason_mismatch"] += int((reason_diff & ~edge).sum())
        out["embree_unrefined"] += int((hit_b & ~refined).sum())
        out["other_face"] += int((both & (a.face != b.face)).sum())
        if (both & ~edge).any():
            out["max_dt_mm"] = max(out["max_dt_mm"], float(dt[both & ~edge].max()))
        if (both & edge).any():
            out["max_dt_edge_mm"] = max(out["max_dt_edge_mm"], float(dt[both & edge].max()))
    return out
