"""Embree ray packets from numba (seamtrack.sensing.embree) against embreex's own ``scene.run``.

The packet backend must be a drop-in for embreex: the same first hits and the same occlusion
answers on the same float32 rays, for any number of rays (packets of 8, a partial last one),
and the same stripe after float64 refinement. The fallback must be reachable and equivalent.
"""

from __future__ import annotations

import numpy as np
import pytest

from seamtrack.bench import raycast as bench
from seamtrack.geometry import frames
from seamtrack.sensing import embree, raycast
from seamtrack.sensing.raycast import RayCaster
from seamtrack.sensing.scan import stripe_hits
from seamtrack.sensing.sensor import preset

pytestmark = pytest.mark.embree

needs_packets = pytest.mark.skipif(
    embree.library() is None, reason="no Embree 4 library in this embreex wheel"
)


@pytest.fixture(scope="module")
def plate():
    """A rough 20k-triangle V-groove plate and one caster per backend."""
    mesh = bench.v_groove_plate_mesh(triangles=20_000, roughness_mm=0.02, seed=4)
    return mesh, RayCaster.from_mesh(mesh), RayCaster.from_mesh(mesh, backend="embreex")


def random_rays(n: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Rays from above the plate towards random points on it, some aimed off the part."""
    rng = np.random.default_rng(seed)
    origins = np.column_stack([rng.uniform(-40, 40, n), rng.uniform(-40, 40, n),
                               rng.uniform(20, 120, n)])  # fmt: skip
    targets = np.column_stack([rng.uniform(-70, 70, n), rng.uniform(-70, 70, n),
                               rng.uniform(-12, 1, n)])  # fmt: skip
    d = targets - origins
    return origins, d / np.linalg.norm(d, axis=1, keepdims=True)


@needs_packets
@pytest.mark.parametrize("n", [0, 1, 7, 8, 9, 1037])
def test_packets_give_embreex_first_hits_for_any_ray_count(plate, n: int) -> None:
    _, packets, fallback = plate
    assert (packets.backend, fallback.backend) == ("packets", "embreex")
    origins, directions = random_rays(n, seed=n)
    o_local = origins - packets.local_origin
    prim, tfar = packets.cast_local(o_local, directions)
    prim_x, tfar_x = fallback.cast_local(o_local, directions)
    assert prim.shape == tfar.shape == (n,)
    np.testing.assert_array_equal(prim, prim_x)
    np.testing.assert_array_equal(tfar[prim >= 0], tfar_x[prim_x >= 0])
    if n > 100:  # the batch exercises both outcomes
        assert 0.2 < np.mean(prim >= 0) < 0.95


@needs_packets
def test_packets_give_embreex_occlusion(plate) -> None:
    _, packets, fallback = plate
    origins, directions = random_rays(2000, seed=11)
    hits = packets.first_hit(origins, directions)
    camera = np.array([10.0, 60.0, 15.0])  # low, across the groove
    points = hits.points[hits.hit]
    blocked = packets.line_of_sight_blocked(points, camera)
    np.testing.assert_array_equal(blocked, fallback.line_of_sight_blocked(points, camera))
    assert 0.02 < blocked.mean() < 0.98  # the groove walls hide part of it
    # A ray that ends short of the plate top (z = 0 +- 0.1 roughness) is free; through it, blocked.
    down = np.array([[0.0, 0.0, -1.0]])
    above = np.array([[30.0, 30.0, 10.0]])
    for caster in (packets, fallback):
        assert not caster.occluded(above, down, [9.9])[0]
        assert caster.occluded(above, down, [10.1])[0]


@needs_packets
@pytest.mark.parametrize("n", [0, 1, 15, 16, 17, 2003])
def test_occlusion_packets_of_16_and_of_8_agree(plate, n: int) -> None:
    """The shadow rays give the same answers in packets of 16 (where the CPU traces them
    natively, the default there) as in packets of 8, ray for ray, for any ray count."""
    _, packets, _ = plate
    lib = packets.packets.lib
    rng = np.random.default_rng(n)
    origins, directions = random_rays(n, seed=n + 1)
    far = rng.uniform(5.0, 150.0, n)
    o_local = origins - packets.local_origin
    by_width = {}
    for query, width in ((lib.occluded8, 8), (lib.occluded16, 16)):
        blocked = np.empty(n, dtype=np.bool_)
        embree.occluded(query, width, packets.packets.handle, o_local, directions, far, 0.0,
                        blocked)  # fmt: skip
        by_width[width] = blocked
    np.testing.assert_array_equal(by_width[16], by_width[8])
    if n > 100:
        assert 0.05 < by_width[8].mean() < 0.95
    native = lib.device_property(lib.device, embree._PROPERTY_NATIVE_RAY16) == 1
    assert lib.occluded_width == (16 if native else 8)
    assert lib.occluded_query == (lib.occluded16 if native else lib.occluded8)


@needs_packets
@pytest.mark.parametrize("refine", [True, False])
def test_the_stripe_is_the_same_on_both_backends(plate, refine: bool) -> None:
    _, packets, fallback = plate
    sensor = preset("paper")
    for tilt in (0.0, 0.3):
        R = frames.look_rotation([np.sin(tilt), 0.0, -np.cos(tilt)], [1.0, 0.0, 0.0])
        T = frames.make(R, [1.0, 2.0, 91.0])
        a = stripe_hits(sensor, packets, T, 1024, refine=refine)
        b = stripe_hits(sensor, fallback, T, 1024, refine=refine)
        np.testing.assert_array_equal(a.reason, b.reason)
        np.testing.assert_array_equal(a.points_laser, b.points_laser)
        np.testing.assert_array_equal(a.face, b.face)
        assert (a.reason == 0).sum() > 500


def test_the_fallback_is_chosen_when_the_library_is_missing(monkeypatch) -> None:
    monkeypatch.setenv("SEAMTRACK_EMBREE", "embreex")
    assert embree.library.__wrapped__() is None
    monkeypatch.setattr(raycast.embree, "library", lambda: None)
    vertices = np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    caster = RayCaster(vertices, [[0, 1, 2]])
    assert caster.backend == "embreex"
    hits = caster.first_hit([0.2, 0.2, 1.0], [[0.0, 0.0, -1.0]])
    np.testing.assert_allclose(hits.points, [[0.2, 0.2, 0.0]], atol=1e-12)
    with pytest.raises(RuntimeError, match="Embree 4"):
        RayCaster(vertices, [[0, 1, 2]], backend="packets")
    with pytest.raises(ValueError, match="backend"):
        RayCaster(vertices, [[0, 1, 2]], backend="optix")
