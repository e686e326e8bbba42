"""The mesh-mode stripe's precision against exact hits (part of ``seamtrack bench raycast``).

Each part is a polyline cross-section extruded along x (a flat plate, a V-groove, a fillet
T-joint), randomly rotated and moved ``offset`` mm from the origin; its planes give each ray's
exact first hit (:func:`analytic_first_hit`, the oracle ``tests/test_raycast.py`` also holds
the stripe to). :func:`precision_rows` measures, per part and offset, the largest distance
between the stripe's points and those hits with the float64 refinement, and how far the float32
hits stray without it, in the caster's local frame and in the world frame;
:func:`precision_table` is docs/mesh-mode.md's table.
"""

from __future__ import annotations

import dataclasses
import itertools
from typing import Any

import numpy as np

from seamtrack.geometry import frames

#: Cross-sections (y, z) in the part frame, the surface at z <= 0 seen from +z.
SECTIONS = {
    "flat": np.array([[-40.0, 0.0], [40.0, 0.0]]),
    "v_groove": np.array([[-40.0, 0.0], [-5.0, 0.0], [0.0, -8.0], [5.0, 0.0], [40.0, 0.0]]),
    # A fillet (T-) joint seen along the bisector, as a fillet weld is tracked: the flange and
    # the web at right angles, the corner at (0, -6).
    "fillet": np.array([[-30.0, 24.0], [0.0, -6.0], [30.0, 24.0]]),
}
OFFSETS_MM = (0.0, 1e3, 1e4, 1e5)
RAYS = 301


def ideal_sensor() -> Any:
    """The paper's sensor without quantization."""
    from seamtrack.sensing.sensor import preset

    return dataclasses.replace(preset("paper"), quantize=False)


def extruded_mesh(
    section: np.ndarray,
    T_world_part: np.ndarray,
    *,
    length: float = 60.0,
    n_along: int = 13,
    n_per_segment: int = 7,
) -> Any:
    """A sheet: ``section`` (k, 2) extruded along the part's x, subdivided, posed in the world."""
    import trimesh

    ys, zs = [], []
    for (y0, z0), (y1, z1) in itertools.pairwise(section):
        s = np.linspace(0.0, 1.0, n_per_segment, endpoint=False)
        ys.append(y0 + s * (y1 - y0))
        zs.append(z0 + s * (z1 - z0))
    yz = np.column_stack(
        [np.concatenate([*ys, [section[-1, 0]]]), np.concatenate([*zs, [section[-1, 1]]])]
    )
    x = np.linspace(-0.5 * length, 0.5 * length, n_along)
    grid = np.stack(np.meshgrid(x, np.arange(len(yz)), indexing="ij"), axis=-1).reshape(-1, 2)
    vertices = np.column_stack([grid[:, 0], yz[grid[:, 1].astype(int)]])
    idx = np.arange(len(x) * len(yz)).reshape(len(x), len(yz))
    a, b = idx[:-1, :-1].ravel(), idx[1:, :-1].ravel()
    c, d = idx[1:, 1:].ravel(), idx[:-1, 1:].ravel()
    faces = np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    return trimesh.Trimesh(frames.apply(T_world_part, vertices), faces, process=False)


def analytic_first_hit(
    section: np.ndarray,
    T_world_part: np.ndarray,
    origin: np.ndarray,
    directions: np.ndarray,
    length: float = 60.0,
) -> np.ndarray:
    """Exact first hit (world, (n, 3), NaN on a miss) of rays on the extruded ``section``."""
    T_part_world = frames.invert(T_world_part)
    o = frames.apply(T_part_world, origin)
    d = frames.apply_vectors(T_part_world, directions)
    best = np.full(len(d), np.inf)
    for (y0, z0), (y1, z1) in itertools.pairwise(section):
        normal = np.array([0.0, -(z1 - z0), y1 - y0])
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (normal @ (np.array([0.0, y0, z0]) - o)) / (d @ normal)
            p = o + t[:, None] * d
            u = ((p[:, 1] - y0) * (y1 - y0) + (p[:, 2] - z0) * (z1 - z0)) / (
                (y1 - y0) ** 2 + (z1 - z0) ** 2
            )
        ok = (t > 0) & (u >= -1e-12) & (u <= 1 + 1e-12) & (np.abs(p[:, 0]) <= 0.5 * length)
        best = np.where(ok & (t < best), t, best)
    hit = np.where(np.isfinite(best)[:, None], o + best[:, None] * d, np.nan)
    return frames.apply(T_world_part, hit)


def posed(offset: float, standoff_mm: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(T_world_part, T_world_sensor): a randomly rotated part ``offset`` mm from the origin,
    the sensor ``standoff_mm`` above it looking down -z_part with the laser plane across the
    part's x."""
    from scipy.spatial.transform import Rotation

    rng = np.random.default_rng(seed)
    rotation = Rotation.random(random_state=rng).as_matrix()
    T_world_part = frames.make(
        rotation, offset * np.array([1.0, -0.6, 0.3]) + rng.uniform(-1, 1, 3)
    )
    T_part_sensor = frames.make(
        frames.look_rotation([0.1, 0.05, -1.0], [1.0, 0.0, 0.0]), [0.7, 0.3, standoff_mm]
    )
    return T_world_part, T_world_part @ T_part_sensor


def laser_errors(
    sensor: Any, name: str, offset: float, part: object, rays: int = RAYS
) -> tuple[float, int]:
    """Largest distance (mm) between valid stripe points and the exact hits, and the number of
    valid points."""
    from seamtrack.sensing.scan import laser_fan, scan_mesh

    T_world_part, T_world_sensor = posed(offset, sensor.range_center_mm)
    profile = scan_mesh(sensor, part, T_world_sensor, rays=rays)
    fan = laser_fan(sensor, rays).directions
    exact = analytic_first_hit(
        SECTIONS[name],
        T_world_part,
        T_world_sensor[:3, 3],
        frames.apply_vectors(T_world_sensor, fan),
    )
    exact_laser = frames.apply(frames.invert(T_world_sensor), exact)[:, 1:]
    assert profile.valid is not None
    valid = int(profile.valid.sum())
    if not valid:
        return float("nan"), 0
    return float(np.abs(profile.valid_points - exact_laser[profile.valid]).max()), valid


def precision(sensor: Any, name: str, offset: float) -> dict[str, Any]:
    """One part at one offset: the refined stripe against the exact hits, and the float32 hits
    (local frame, and world frame: a caster with its origin at the world's) against the
    refined ones."""
    from seamtrack.sensing.raycast import RayCaster
    from seamtrack.sensing.scan import scan_mesh

    T_world_part, T_world_sensor = posed(offset, sensor.range_center_mm)
    mesh = extruded_mesh(SECTIONS[name], T_world_part)
    refined, valid = laser_errors(sensor, name, offset, mesh)
    exact = scan_mesh(sensor, mesh, T_world_sensor, rays=RAYS).valid_points
    local = scan_mesh(sensor, mesh, T_world_sensor, rays=RAYS, refine=False).valid_points
    naive_caster = RayCaster.from_mesh(mesh, local_origin=np.zeros(3))
    naive = scan_mesh(sensor, naive_caster, T_world_sensor, rays=RAYS, refine=False)
    return {
        "part": name,
        "offset_mm": offset,
        "rays": RAYS,
        "valid": valid,
        "refined_mm": refined,
        "float32_local_mm": float(np.abs(local - exact).max()),
        "float32_world_mm": float(np.abs(naive.valid_points - exact).max()),
    }


def precision_rows() -> list[dict[str, Any]]:
    """:func:`precision` for every part at every offset of :data:`OFFSETS_MM`."""
    sensor = ideal_sensor()
    return [precision(sensor, name, offset) for offset in OFFSETS_MM for name in SECTIONS]


def _sci(value: float) -> str:
    mantissa, exponent = f"{value:.1e}".split("e")
    return f"{mantissa}e{int(exponent)}"


def _sci_span(values: list[float]) -> str:
    """``1.4-2.3e-5`` for a range within one power of ten, else ``4.0e-5-1.1e-4``."""
    low, high = _sci(min(values)), _sci(max(values))
    if low == high:
        return low
    (m_low, e_low), (m_high, e_high) = low.split("e"), high.split("e")
    return f"{m_low}-{m_high}e{e_low}" if e_low == e_high else f"{low}-{high}"


def precision_table(result: dict[str, Any]) -> str:
    """Per offset, over the parts: the refined stripe's largest error against the exact hits,
    and the float32 hits' range of largest distances from the refined ones (a ``raycast.json``)."""
    rows = result["precision"]
    lines = [
        "| part offset from the origin | float64 refined | float32, local frame "
        "(refine=False) | float32, world frame (naive) |",
        "|---:|---:|---:|---:|",
    ]
    for offset in sorted({r["offset_mm"] for r in rows}):
        at = [r for r in rows if r["offset_mm"] == offset]
        refined = max(r["refined_mm"] for r in at)
        local = _sci_span([r["float32_local_mm"] for r in at])
        world = _sci_span([r["float32_world_mm"] for r in at])
        where = "0" if offset == 0 else _sci(offset).replace(".0e", "e")
        lines.append(f"| {where} mm | {_sci(refined)} mm | {local} mm | {world} mm |")
    return "\n".join(lines) + "\n"
