"""Embree ray casting in a local float32 frame, refined in float64 (seamtrack.sensing.raycast).

Oracles are analytic: every test mesh is a polyline cross-section extruded along x (a flat
plate, a V-groove, a fillet T-joint), whose planes give each ray's exact hit
(:func:`seamtrack.bench.raycast_precision.analytic_first_hit`, which ``seamtrack bench raycast``
uses for docs/mesh-mode.md's precision table too).
"""

from __future__ import annotations

import dataclasses
import gc

import numpy as np
import pytest
import trimesh

from seamtrack.bench.raycast_precision import SECTIONS, extruded_mesh
from seamtrack.bench.raycast_precision import laser_errors as bench_laser_errors
from seamtrack.bench.raycast_precision import posed as bench_posed
from seamtrack.geometry import frames
from seamtrack.sensing.profiles import Reason
from seamtrack.sensing.raycast import RayCaster
from seamtrack.sensing.scan import laser_fan, scan_mesh
from seamtrack.sensing.sensor import preset

pytestmark = pytest.mark.embree

SENSOR = preset("paper")
IDEAL = dataclasses.replace(SENSOR, quantize=False)
STANDOFF = SENSOR.range_center_mm


def posed(offset: float, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """(T_world_part, T_world_sensor): a randomly rotated part ``offset`` mm from the origin,
    the sensor above it looking down -z_part with the laser plane across the part's x."""
    return bench_posed(offset, STANDOFF, seed)


def laser_errors(name: str, offset: float, part: object, rays: int = 301) -> float:
    """Largest distance (mm) between valid stripe points and the exact hits."""
    error, valid = bench_laser_errors(IDEAL, name, offset, part, rays)
    assert valid > rays // 2
    return error


PRECISION: dict[tuple[str, float], tuple[float, float, float]] = {}


@pytest.mark.parametrize("name", sorted(SECTIONS))
@pytest.mark.parametrize("offset", [0.0, 1e3, 1e4, 1e5])
def test_refined_stripe_points_lie_on_the_exact_planes(name: str, offset: float) -> None:
    T_world_part, _ = posed(offset)
    mesh = extruded_mesh(SECTIONS[name], T_world_part)
    refined = laser_errors(name, offset, mesh)
    T_world_sensor = posed(offset)[1]
    float32 = np.abs(
        scan_mesh(IDEAL, mesh, T_world_sensor, rays=301, refine=False).valid_points
        - scan_mesh(IDEAL, mesh, T_world_sensor, rays=301).valid_points
    ).max()
    naive_caster = RayCaster.from_mesh(mesh, local_origin=np.zeros(3))
    naive = np.abs(
        scan_mesh(IDEAL, naive_caster, T_world_sensor, rays=301, refine=False).valid_points
        - scan_mesh(IDEAL, mesh, T_world_sensor, rays=301).valid_points
    ).max()
    PRECISION[name, offset] = (refined, float(float32), float(naive))
    print(
        f"{name:9s} offset {offset:8.0e} mm: refined {refined:.1e}, float32 local frame "
        f"{float32:.1e}, float32 world frame {naive:.1e} mm"
    )
    assert refined <= 1e-6
    if offset >= 1e5:
        assert float32 > refined
        assert naive > float32


def test_first_hit_returns_points_normals_and_misses() -> None:
    box = trimesh.creation.box(extents=(10.0, 10.0, 10.0))
    box.apply_translation([1e5, -2e4, 3e3])
    caster = RayCaster.from_mesh(box)
    origin = np.array([1e5 + 1.2345678, -2e4 + 0.5, 3e3 + 100.0])
    hits = caster.first_hit(origin, [[0, 0, -1.0], [0, 0, 1.0], [0.01, 0.0, -1.0]])
    assert hits.hit.tolist() == [True, False, True]
    np.testing.assert_allclose(hits.points[0], origin - [0, 0, 95.0], atol=1e-9)
    np.testing.assert_allclose(hits.normals[0], [0, 0, 1.0])
    assert hits.distance_mm[0] == pytest.approx(95.0, abs=1e-9)
    assert np.isnan(hits.points[1]).all() and hits.face[1] == -1 and not hits.refined[1]
    blocked = caster.line_of_sight_blocked(
        np.array([[1e5, -2e4, 3e3 + 5.0], [1e5, -2e4, 3e3 - 5.0]]), origin
    )
    assert blocked.tolist() == [False, True]


def test_rays_through_shared_edges_and_vertices_hit_in_float64() -> None:
    """A 1 mm grid plate: rays aimed exactly at its vertices and edge midpoints."""
    xs = np.arange(-5.0, 6.0)
    grid = np.stack(np.meshgrid(xs, xs, indexing="ij"), -1).reshape(-1, 2)
    vertices = np.column_stack([grid, np.zeros(len(grid))]) + np.array([1e4, 1e4, 0.0])
    idx = np.arange(len(grid)).reshape(11, 11)
    a, b, c, d = (
        idx[:-1, :-1].ravel(),
        idx[1:, :-1].ravel(),
        idx[1:, 1:].ravel(),
        idx[:-1, 1:].ravel(),
    )
    caster = RayCaster(
        vertices, np.concatenate([np.column_stack([a, b, c]), np.column_stack([a, c, d])])
    )
    targets = np.concatenate(
        [
            vertices[idx[1:-1, 1:-1].ravel()],
            0.5 * (vertices[a] + vertices[c]),
            0.5 * (vertices[a] + vertices[b]),
        ]
    )
    origin = np.array([1e4 + 0.3, 1e4 - 0.2, 50.0])
    hits = caster.first_hit(origin, targets - origin)
    assert hits.hit.all() and hits.refined.all()
    np.testing.assert_allclose(hits.points, targets, atol=1e-9)


def test_refinement_moves_a_hit_across_a_crease_to_the_right_face() -> None:
    """Embree's face replaced by its neighbour: the float64 test finds the true face."""
    mesh = extruded_mesh(SECTIONS["v_groove"], np.eye(4))
    caster = RayCaster.from_mesh(mesh)
    origin = np.array([[0.3, -1.0, 50.0]]) - caster.local_origin
    direction = np.array([[0.0, 0.0, -1.0]])
    prim, tfar = caster.cast_local(origin.astype(np.float32), direction.astype(np.float32))
    true_face = int(prim[0])
    wrong = [
        g
        for g in range(caster.n_faces)
        if g != true_face and set(caster.faces[g]) & set(caster.faces[true_face])
    ]
    t, face, refined = caster.refine_local(
        origin, direction, np.array(wrong[:1], dtype=np.int32), tfar
    )
    assert face[0] == true_face and refined[0]
    assert 50.0 - t[0] == pytest.approx(-8.0 * (1.0 - 1.0 / 5.0), abs=1e-12)


@pytest.mark.parametrize("grazing_rad", [1e-3, 1e-4, 1e-5, 1e-6, 1e-7])
def test_grazing_rays_give_no_nan_and_the_right_reason(grazing_rad: float) -> None:
    """A plate whose plane the central ray meets at ``grazing_rad``, 1e4 mm from the origin."""
    T_world_sensor = frames.make(translation=[1e4, 0.0, 0.0])
    center = np.array([1e4, 0.0, STANDOFF])
    normal = np.array([0.0, np.cos(grazing_rad), np.sin(grazing_rad)])
    u = np.array([1.0, 0.0, 0.0])
    v = np.cross(normal, u)
    corners = center + 60.0 * np.array([-u - v, u - v, u + v, -u + v])
    plate = trimesh.Trimesh(corners, [[0, 1, 2], [0, 2, 3]], process=False)
    for sensor in (SENSOR, dataclasses.replace(IDEAL, max_incidence_rad=np.pi / 2)):
        profile = scan_mesh(sensor, plate, T_world_sensor, rays=101)
        assert profile.valid is not None and profile.reason is not None
        assert np.isfinite(profile.valid_points).all()
        central = profile.reason[50]
        if sensor is SENSOR:
            assert central in (Reason.INCIDENCE, Reason.MISS)
        elif central == Reason.VALID:
            world = profile.points_world[50]
            assert abs((world - center) @ normal) <= 1e-6


def test_caster_is_built_once_per_mesh_and_released_with_it() -> None:
    mesh = extruded_mesh(SECTIONS["flat"], np.eye(4))
    caster = RayCaster.for_mesh(mesh)
    assert RayCaster.for_mesh(mesh) is caster
    from seamtrack.sensing import raycast

    key = id(mesh)
    del mesh
    gc.collect()
    assert key not in raycast._CACHE


def test_fused_kernels_match_the_sensor_methods() -> None:
    from seamtrack.sensing.kernels import _chip, _pixel_center

    sp = laser_fan(SENSOR, 3).sensor_params
    rng = np.random.default_rng(3)
    y = rng.uniform(-20, 20, 400)
    z = rng.uniform(60, 140, 400)
    x_c, z_c = SENSOR.project(y, z)
    inside = SENSOR.in_field_of_view(y, z)
    y_q, z_q = SENSOR.measure(y, z)
    for i in range(len(y)):
        xk, zk, ok = _chip(y[i], z[i], sp)
        assert ok == inside[i]
        assert xk == pytest.approx(x_c[i], abs=1e-12) and zk == pytest.approx(z_c[i], abs=1e-12)
        if ok:
            yq, zq = _pixel_center(xk, zk, sp)
            assert yq == pytest.approx(y_q[i], abs=1e-12)
            assert zq == pytest.approx(z_q[i], abs=1e-12)
