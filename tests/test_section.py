"""The laser fan as a plane section (seamtrack.sensing.section): exact hits, the same reasons.

Oracles: analytic geometry (extruded planes and V-grooves, whose planes give each ray's exact
hit), a brute-force cut of every triangle (the hierarchy finds them all), and the independent
Embree fan refined in float64 (the same reasons, hits within 1e-9 mm off the edges).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
import trimesh
from scipy.spatial.transform import Rotation
from test_raycast import SECTIONS, extruded_mesh, posed

from seamtrack.bench.raycast import AGREE_MM, fan_agreement, v_groove_plate_mesh
from seamtrack.bench.raycast_precision import analytic_first_hit
from seamtrack.errors import SceneError
from seamtrack.geometry import frames
from seamtrack.sensing import section
from seamtrack.sensing.raycast import RayCaster
from seamtrack.sensing.scan import auto_fan, laser_fan, scan_mesh, stripe_hits
from seamtrack.sensing.sensor import preset
from seamtrack.simulation.scene import load_scene

pytestmark = pytest.mark.embree

SENSOR = preset("paper")
IDEAL = dataclasses.replace(SENSOR, quantize=False)
LOOK_DOWN = frames.look_rotation([0.0, 0.0, -1.0], [1.0, 0.0, 0.0])


# ----------------------------------------------------------------------------- exact hits
@pytest.mark.parametrize("name", sorted(SECTIONS))
@pytest.mark.parametrize("offset", [0.0, 1e3, 1e5])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_section_hits_are_the_exact_intersections(name: str, offset: float, seed: int) -> None:
    """Every ray's hit on a plane, a V-groove and a fillet joint, posed anywhere, is the exact
    intersection with the section's planes, to 1e-9 mm (1e-13 relative at 1e5 mm)."""
    T_world_part, T_world_sensor = posed(offset, seed)
    mesh = extruded_mesh(SECTIONS[name], T_world_part)
    caster = RayCaster.from_mesh(mesh)
    rays = 301
    hits = stripe_hits(IDEAL, caster, T_world_sensor, rays, fan="section")
    fan = frames.apply_vectors(T_world_sensor, laser_fan(IDEAL, rays).directions)
    exact = analytic_first_hit(SECTIONS[name], T_world_part, T_world_sensor[:3, 3], fan)
    t_exact = np.linalg.norm(exact - T_world_sensor[:3, 3], axis=1)
    hit = np.isfinite(t_exact)
    assert hit.sum() > rays // 2
    np.testing.assert_array_equal(hits.face >= 0, hit)
    tolerance = 1e-9 * max(1.0, offset / 1e3)  # the pose itself is float64 at |offset|
    assert np.abs(hits.distance_mm[hit] - t_exact[hit]).max() <= tolerance


def test_a_plane_seen_straight_down_is_hit_at_its_height_exactly() -> None:
    """One flat plate of two triangles, the fan straight down from 91 mm: z_L = 91 exactly."""
    mesh = extruded_mesh(SECTIONS["flat"], np.eye(4), n_along=2, n_per_segment=1)
    T = frames.make(LOOK_DOWN, [0.3, 0.2, 91.0])
    hits = stripe_hits(IDEAL, RayCaster.from_mesh(mesh), T, 257, fan="section")
    assert (hits.face >= 0).all()
    assert np.abs(hits.points_laser[:, 1] - 91.0).max() <= 1e-12
    profile = scan_mesh(IDEAL, mesh, T, rays=257, fan="section")
    assert profile.valid is not None and profile.valid.sum() > 200


def test_the_rays_of_a_v_groove_land_on_its_flanks() -> None:
    """A V-groove (root 8 mm deep, sides at +-5 mm) seen across: each point lies on the flank
    or the top its lateral position says, in closed form, to 1e-12 mm."""
    mesh = extruded_mesh(SECTIONS["v_groove"], np.eye(4))
    T = frames.make(LOOK_DOWN, [0.0, 0.0, 91.0])
    hits = stripe_hits(IDEAL, RayCaster.from_mesh(mesh), T, 513, fan="section")
    y, z = hits.points_laser[:, 0], 91.0 - hits.points_laser[:, 1]  # world y (flipped), z
    y = -y
    expected = np.where(np.abs(y) >= 5.0, 0.0, -8.0 + 8.0 * np.abs(y) / 5.0)
    assert np.abs(z - expected).max() <= 1e-12


# ----------------------------------------------------------------------------- the hierarchy
def _brute_force_segments(caster: RayCaster, T: np.ndarray, tan_max: float) -> set[int]:
    """The triangles that the plane x_L = 0 cuts with a segment inside the wedge, by testing
    every triangle (numpy)."""
    origin = T[:3, 3] - caster.local_origin
    v = (caster.vertices_local - origin) @ T[:3, :3]  # laser frame
    tri = v[caster.faces]  # (f, 3, 3)
    x = tri[:, :, 0]
    crossed = (x.max(axis=1) > 0) & (x.min(axis=1) < 0)
    found = set()
    for k in np.flatnonzero(crossed):
        pts = []
        for a, b in ((0, 1), (1, 2), (2, 0)):
            xa, xb = x[k, a], x[k, b]
            if (xa > 0) != (xb > 0) and xa != 0 and xb != 0:
                s = xa / (xa - xb)
                pts.append(tri[k, a, 1:] + s * (tri[k, b, 1:] - tri[k, a, 1:]))
        if len(pts) != 2:
            continue
        (y0, z0), (y1, z1) = pts
        # Inside the wedge |y| <= tan_max z somewhere along the segment.
        s = np.linspace(0.0, 1.0, 201)
        y, z = y0 + s * (y1 - y0), z0 + s * (z1 - z0)
        if np.any(np.abs(y) <= tan_max * z):
            found.add(int(k))
    return found


@pytest.mark.parametrize("seed", range(4))
def test_the_hierarchy_finds_every_triangle_the_plane_cuts_in_the_wedge(seed: int) -> None:
    mesh = v_groove_plate_mesh(triangles=4_000, seed=seed)
    caster = RayCaster.from_mesh(mesh)
    rng = np.random.default_rng(seed)
    rotation = Rotation.from_rotvec(rng.normal(0.0, 0.12, 3)).as_matrix() @ LOOK_DOWN
    T = frames.make(rotation, [rng.uniform(-10, 10), rng.uniform(-10, 10), 91.0])
    tan_max = 0.2
    index = caster.section
    _, tri = section.section_segments(index, caster.section_mesh, T[:3, 3] - caster.local_origin,
                                      np.ascontiguousarray(T[:3, :3]), tan_max)  # fmt: skip
    expected = _brute_force_segments(caster, T, tan_max)
    assert len(expected) > 20
    assert expected <= set(tri.tolist())
    # Every triangle of the mesh sits in exactly one leaf.
    leaves = index.leaf_count > 0
    assert sorted(index.order.tolist()) == list(range(len(mesh.faces)))
    assert index.leaf_count[leaves].sum() == len(mesh.faces)


# ----------------------------------------------------------------------------- agreement
def _plate_poses() -> list[np.ndarray]:
    """Straight down and tilted, on and off the plate's grid lines."""
    poses = []
    for x, tilt in ((0.37, 0.0), (-12.3, 0.2), (7.1, -0.35), (0.0, 0.0)):
        rotation = Rotation.from_rotvec([tilt, 0.5 * tilt, 0.3 * tilt]).as_matrix() @ LOOK_DOWN
        poses.append(frames.make(rotation, [x, 1.3 * tilt, 91.0]))
    return poses


def test_the_section_agrees_with_refined_embree_on_the_rough_plate() -> None:
    """The raycast bench's plate (20k triangles here, with 5 um roughness): the same hit or
    miss, the same reason, and the hit within 1e-9 mm on every ray off the edges; the pose on
    a grid line (its every ray on an edge lying in the plane) agrees in reason too."""
    caster = RayCaster.from_mesh(v_groove_plate_mesh(triangles=20_000))
    result = fan_agreement(SENSOR, caster, _plate_poses())
    assert result["rays"] == 4 * 1024
    assert result["disagree"] == 0, result
    assert result["max_dt_mm"] <= AGREE_MM
    assert result["edge_rays"] >= 1024  # the grid-line pose
    assert result["disagree_edge"] == 0, result


def test_the_section_agrees_with_refined_embree_on_the_paper_part() -> None:
    """The paper's CAD V-groove (mesh scene ``paper-v-groove``), at poses along its seam."""
    from seamtrack.simulation.assemble import build_parts

    parts = build_parts(load_scene("paper-v-groove", {"workpiece.params.seam_length_mm": 60.0}))
    assert parts.mesh is not None
    robot = parts.robot
    arc = np.linspace(0.0, 0.95 * parts.seam.length_mm, 8)
    poses = [robot.T_world_sensor(robot.q_from_world(p)) for p in parts.seam.interpolate(arc)]
    result = fan_agreement(SENSOR, RayCaster.from_mesh(parts.mesh), poses)
    assert result["disagree"] == 0, result
    assert result["max_dt_mm"] <= AGREE_MM


def test_the_embreex_fallback_casts_the_same_section_stripe() -> None:
    mesh = v_groove_plate_mesh(triangles=8_000)
    T = _plate_poses()[1]
    a = stripe_hits(SENSOR, RayCaster.from_mesh(mesh), T, 512, fan="section")
    b = stripe_hits(SENSOR, RayCaster.from_mesh(mesh, backend="embreex"), T, 512, fan="section")
    np.testing.assert_array_equal(a.reason, b.reason)
    np.testing.assert_array_equal(a.points_laser, b.points_laser)


def test_auto_is_the_section_when_refining_with_enough_rays_and_embree_otherwise() -> None:
    mesh = v_groove_plate_mesh(triangles=8_000)
    caster = RayCaster.from_mesh(mesh)
    T = _plate_poses()[2]
    # 8k triangles: the section from 90 rays up (sqrt(8000) = 89.4).
    for rays, refine, fan in ((256, True, "section"), (256, False, "embree"),
                              (64, True, "embree")):  # fmt: skip
        assert auto_fan(rays, caster.n_faces, refine) == fan
        auto = stripe_hits(SENSOR, caster, T, rays, refine=refine)
        chosen = stripe_hits(SENSOR, caster, T, rays, refine=refine, fan=fan)
        exact = stripe_hits(SENSOR, caster, T, rays, fan="section")
        np.testing.assert_array_equal(auto.distance_mm, chosen.distance_mm)
        # Float32 Embree hits differ from the section's exact ones; refined ones agree.
        assert (np.nanmax(np.abs(auto.distance_mm - exact.distance_mm)) <= AGREE_MM) == refine
    with pytest.raises(ValueError, match="fan must be one of"):
        stripe_hits(SENSOR, caster, T, 256, fan="optix")


# ----------------------------------------------------------------------------- scene key
def test_the_scene_key_is_validated() -> None:
    assert load_scene("paper-v-groove").config.sensor.fan == "auto"
    assert load_scene("paper-v-groove", {"sensor.fan": "embree"}).config.sensor.fan == "embree"
    with pytest.raises(SceneError) as error:
        load_scene("paper-v-groove", {"sensor.fan": "optix"})
    assert error.value.field == "sensor.fan"
    with pytest.raises(SceneError) as error:
        load_scene("paper-v-groove", {"sensor.fan": "section", "sensor.refine_float64": False})
    assert error.value.field == "sensor.fan"


def test_a_mesh_scene_run_both_ways_has_the_same_error() -> None:
    """The loop on a short paper-v-groove, with each fan: the same status and a max error that
    moves by far less than one depth resolution (identical hits off the edges)."""
    import seamtrack as st

    short = {"workpiece.params.seam_length_mm": 60.0}
    runs = {
        fan: st.simulate(load_scene("paper-v-groove", {**short, "sensor.fan": fan})).summary
        for fan in ("embree", "section")
    }
    assert runs["embree"]["status"] == runs["section"]["status"] == "completed"
    delta = abs(runs["embree"]["max_error_mm"] - runs["section"]["max_error_mm"])
    assert delta < 0.1 * SENSOR.depth_resolution_mm


def test_a_closed_box_agrees_with_refined_embree() -> None:
    """A closed solid (front and back faces, the plane through its diagonals' crossings): the
    section lights the near faces only, as Embree does."""
    import trimesh

    box = trimesh.creation.box(extents=[40.0, 30.0, 12.0])
    box.apply_translation([0.0, 0.0, -6.0])
    result = fan_agreement(SENSOR, RayCaster.from_mesh(box), _plate_poses())
    assert result["rays"] == 4 * 1024
    assert result["disagree"] == 0, result
    assert result["max_dt_mm"] <= AGREE_MM


def test_a_triangle_lying_in_the_laser_plane_is_grazed_not_hit() -> None:
    """A wall lying exactly in the laser plane, standing on a plate: the fan runs along it and
    lights the plate, as if the wall were not there (no ray crosses it)."""
    import trimesh

    plate = extruded_mesh(SECTIONS["flat"], np.eye(4), n_along=2, n_per_segment=1)
    wall = trimesh.Trimesh([[0.0, -20.0, 0.0], [0.0, 20.0, 0.0], [0.0, 0.0, 30.0]], [[0, 1, 2]])
    both = trimesh.util.concatenate([plate, wall])
    T = frames.make(LOOK_DOWN, [0.0, 0.0, 91.0])
    with_wall = stripe_hits(IDEAL, RayCaster.from_mesh(both), T, 257, fan="section")
    without = stripe_hits(IDEAL, RayCaster.from_mesh(plate), T, 257, fan="section")
    np.testing.assert_array_equal(with_wall.distance_mm, without.distance_mm)
    np.testing.assert_array_equal(with_wall.reason, without.reason)


# ----------------------------------------------------------------------------- ray ranges
def _all_rays_hits(caster: RayCaster, T: np.ndarray, fan: np.ndarray) -> tuple[np.ndarray, ...]:
    """Each ray's nearest crossing, every segment tested against every ray (no ray range)."""
    index = caster.section
    tans = fan[:, 1] / fan[:, 2]
    segs, tri = section.section_segments(
        index, caster.section_mesh, T[:3, 3] - caster.local_origin,
        np.ascontiguousarray(T[:3, :3]), float(np.abs(tans).max()) * (1 + 1e-9) + 1e-9,
    )  # fmt: skip
    best_t = np.full(len(fan), np.inf)
    best_f = np.full(len(fan), -1, dtype=np.int64)
    for (y0, z0, y1, z1), k in zip(segs, tri, strict=True):
        section._sweep(fan, 0, len(fan), y0, z0, y1, z1, int(k), best_t, best_f)
    return best_t, best_f


def _pipe_mesh() -> trimesh.Trimesh:
    """A thick-walled pipe across the fan (axis along x), finely faceted: the laser plane cuts
    its outer and inner walls, near and far, so most of the section lies behind the hits."""
    pipe = trimesh.creation.annulus(r_min=44.0, r_max=50.0, height=400.0, sections=900)
    pipe.apply_transform(frames.make(Rotation.from_rotvec([0.0, np.pi / 2, 0.0]).as_matrix(),
                                     [0.0, 0.0, -50.0]))  # fmt: skip
    return pipe


@pytest.mark.parametrize(("part", "even"), [("plate", True), ("plate", False), ("pipe", True)])
def test_the_rays_a_segment_covers_miss_no_hit(part: str, even: bool) -> None:
    """The rays each segment is tested against (found by arithmetic on an evenly spaced fan,
    by binary search otherwise) and the nodes left closed behind the hits found (the pipe's
    far and inner walls) lose no hit: the hits equal those of every segment tested against
    every ray, bit for bit; and so with seeds (cut first, each skipped where the walk meets
    it again): this pose's hit triangles, the last pose's, and any 50 of the mesh's."""
    mesh = v_groove_plate_mesh(triangles=4_000, seed=3) if part == "plate" else _pipe_mesh()
    caster = RayCaster.from_mesh(mesh)
    rng = np.random.default_rng(5)
    fan = np.array(laser_fan(IDEAL, 777).directions)
    if not even:  # the same span, uneven
        tans = np.sort(rng.uniform(-1.0, 1.0, len(fan))) * np.abs(fan[:, 1] / fan[:, 2]).max()
        fan = np.column_stack([np.zeros(len(fan)), tans, np.ones(len(fan))])
        fan /= np.linalg.norm(fan, axis=1, keepdims=True)
    tans = fan[:, 1] / fan[:, 2]
    assert (section._even_step(tans) > 0.0) == even
    index = caster.section
    mesh = caster.section_mesh
    last = section.NO_SEEDS
    for _ in range(6):
        rotation = Rotation.from_rotvec(rng.normal(0.0, 0.15, 3)).as_matrix() @ LOOK_DOWN
        T = frames.make(rotation, [rng.uniform(-10, 10), rng.uniform(-10, 10), 91.0])
        t, face = section.section_hits(index, mesh, T[:3, 3] - caster.local_origin,
                                       np.ascontiguousarray(T[:3, :3]), fan)  # fmt: skip
        t_all, face_all = _all_rays_hits(caster, T, fan)
        assert (face >= 0).sum() > len(fan) // 2
        if part == "pipe":  # the culling runs: more crossings than it waits for
            assert len(_brute_force_segments(caster, T, 0.3)) > 2 * section.CULL_AFTER
        np.testing.assert_array_equal(face, face_all)
        np.testing.assert_array_equal(t, t_all)
        seen = section.hit_faces(face_all)
        assert set(seen.tolist()) == set(face_all[face_all >= 0].tolist())
        o, r = T[:3, 3] - caster.local_origin, np.ascontiguousarray(T[:3, :3])
        for seeds in (seen, last, rng.choice(len(caster.faces), 50)):
            t_s, face_s, _ = section._section_hits(index, mesh, o, r, fan, *section.fan_tans(fan),
                                                   seeds.astype(np.int64))  # fmt: skip
            np.testing.assert_array_equal(face_s, face_all)
            np.testing.assert_array_equal(t_s, t_all)
        last = seen


def test_an_evenly_spaced_fan_covers_at_least_the_binary_searched_rays() -> None:
    """On the laser fan (a linspace in tan), each segment's arithmetic ray range contains the
    binary-searched one, and is at most two rays wider on each side."""
    tans = np.array(laser_fan(IDEAL, 1024).directions)
    tans = tans[:, 1] / tans[:, 2]
    step = section._even_step(tans)
    assert step == pytest.approx((tans[-1] - tans[0]) / 1023, rel=1e-12)
    rng = np.random.default_rng(7)
    for _ in range(2000):
        y0, y1 = rng.uniform(-40.0, 40.0, 2)
        z0, z1 = rng.uniform(-5.0, 120.0, 2)
        a, b = section._ray_range(tans, step, y0, z0, y1, z1)
        c, d = section._ray_range(tans, 0.0, y0, z0, y1, z1)
        if c < d:
            assert a <= c and b >= d
            assert c - a <= 2 and b - d <= 2
