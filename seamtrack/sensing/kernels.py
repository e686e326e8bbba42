"""The numba kernels of the mesh-mode stripe: float64 refinement of Embree's float32 hits, and
one fused kernel per profile (fan, refinement, field-of-view and depth clips, shadow rays, pixel
quantization) that calls Embree in packets of 8 (:mod:`seamtrack.sensing.embree`).

:class:`seamtrack.sensing.raycast.RayCaster` owns the scene these kernels run on.
"""

from __future__ import annotations

from typing import Any, NamedTuple, cast

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.jit import KERNEL
from seamtrack.sensing import embree

#: An int64 0: numba types a literal 0 as ``Literal[int](0)`` and compiles the kernel it
#: reaches once more for it, a loop counter's start too.
_ZERO = cast(int, np.int64(0))


class VertexRings(NamedTuple):
    """The faces around each vertex, as the float64 refinement of Embree's hits walks them:
    the welded id of each vertex (exactly equal coordinates share one) and, per welded vertex,
    its faces (CSR: ``faces[ptr[w]:ptr[w + 1]]``). All three empty where nothing is refined.

    Attributes
    ----------
    weld : (v,) int64
    ptr : (w + 1,) int64
    faces : (r,) int64
    """

    weld: NDArray[np.int64]
    ptr: NDArray[np.int64]
    faces: NDArray[np.int64]


class HitMesh(NamedTuple):
    """The mesh the fan's kernels cast, refine and clip on (these and the plane section's of
    :mod:`seamtrack.sensing.section`), one record: float64, in the caster's local frame
    (:class:`seamtrack.sensing.raycast.RayCaster`).

    Attributes
    ----------
    vertices : (v, 3) float
    faces : (f, 3) int64
    face_normals : (f, 3) float
        Unit normals.
    rings : VertexRings
        Empty where nothing is refined.
    """

    vertices: NDArray[np.float64]
    faces: NDArray[np.int64]
    face_normals: NDArray[np.float64]
    rings: VertexRings


@numba.njit(**KERNEL)
def _intersect_face(
    ox: float, oy: float, oz: float, dx: float, dy: float, dz: float,
    vertices: NDArray[np.float64], faces: NDArray[np.int64], f: int, tol: float,
) -> tuple[float, bool]:  # fmt: skip
    """Ray / triangle plane intersection in float64: (t, inside the triangle)."""
    a, b, c = faces[f, 0], faces[f, 1], faces[f, 2]
    ax, ay, az = vertices[a, 0], vertices[a, 1], vertices[a, 2]
    e1x, e1y, e1z = vertices[b, 0] - ax, vertices[b, 1] - ay, vertices[b, 2] - az
    e2x, e2y, e2z = vertices[c, 0] - ax, vertices[c, 1] - ay, vertices[c, 2] - az
    nx = e1y * e2z - e1z * e2y
    ny = e1z * e2x - e1x * e2z
    nz = e1x * e2y - e1y * e2x
    den = nx * dx + ny * dy + nz * dz
    if den == 0.0:
        return np.nan, False
    t = (nx * (ax - ox) + ny * (ay - oy) + nz * (az - oz)) / den
    wx, wy, wz = ox + t * dx - ax, oy + t * dy - ay, oz + t * dz - az
    d00 = e1x * e1x + e1y * e1y + e1z * e1z
    d01 = e1x * e2x + e1y * e2y + e1z * e2z
    d11 = e2x * e2x + e2y * e2y + e2z * e2z
    d20 = wx * e1x + wy * e1y + wz * e1z
    d21 = wx * e2x + wy * e2y + wz * e2z
    det = d00 * d11 - d01 * d01
    if not det > 0.0:
        return t, False
    # Barycentrics times det (> 0): no divisions on the hot path.
    v = d11 * d20 - d01 * d21
    w = d00 * d21 - d01 * d20
    slack = -tol * det
    return t, v >= slack and w >= slack and det - v - w >= slack


@numba.njit(**KERNEL)
def _refine_one(
    ox: float, oy: float, oz: float, dx: float, dy: float, dz: float, f: int, tf: float,
    mesh: HitMesh, tol: float,
) -> tuple[float, int, bool]:  # fmt: skip
    """(t, face, refined) of one ray that Embree says hits face ``f`` at ``tf``."""
    vertices, faces, rings = mesh.vertices, mesh.faces, mesh.rings
    t, inside = _intersect_face(ox, oy, oz, dx, dy, dz, vertices, faces, f, tol)
    if inside and t > 0.0:
        return t, f, True
    # Outside its triangle: the ray crossed a crease or an edge. The nearest face around the
    # triangle's vertices that contains the float64 point is the true first hit.
    best_t = np.inf
    best_f = -1
    for k in range(3):
        vid = rings.weld[faces[f, k]]
        for m in range(rings.ptr[vid], rings.ptr[vid + 1]):
            g = rings.faces[m]
            if g == f:
                continue
            t, inside = _intersect_face(ox, oy, oz, dx, dy, dz, vertices, faces, g, tol)
            if inside and 0.0 < t < best_t:
                best_t = t
                best_f = g
    if best_f >= 0:
        return best_t, best_f, True
    return tf, f, False


@numba.njit(**KERNEL)
def refine_hits(
    origins: NDArray[np.float64],
    directions: NDArray[np.float64],
    prim: NDArray[np.int32],
    tfar: NDArray[np.float32],
    mesh: HitMesh,
    refine: bool,
    tol: float,
    t_out: NDArray[np.float64],
    face_out: NDArray[np.int64],
    refined_out: NDArray[np.bool_],
) -> None:
    """Float64 distance along each ray from Embree's first hit (in place into the outputs).

    Parameters
    ----------
    origins : (1, 3) or (n, 3) float
        Ray origins in the local frame (one row: shared by all rays).
    directions : (n, 3) float
        Unit directions.
    prim, tfar : (n,) int32, (n,) float32
        Embree's primitive id (-1: miss) and parametric distance.
    mesh : HitMesh
        The local float64 mesh (its rings empty when ``refine`` is False).
    refine : bool
        False: return Embree's distance.
    tol : float
        Barycentric slack of the inside test.
    t_out, face_out, refined_out : (n,) outputs
        Distance (NaN: miss), face (-1: miss), refined in float64.
    """
    single = origins.shape[0] == 1
    for i in range(directions.shape[0]):
        f = prim[i]
        if f < 0:
            t_out[i] = np.nan
            face_out[i] = -1
            refined_out[i] = False
        elif not refine:
            t_out[i] = tfar[i]
            face_out[i] = f
            refined_out[i] = False
        else:
            j = 0 if single else i
            t_out[i], face_out[i], refined_out[i] = _refine_one(
                origins[j, 0], origins[j, 1], origins[j, 2],
                directions[i, 0], directions[i, 1], directions[i, 2], f, tfar[i], mesh, tol,
            )  # fmt: skip


# --------------------------------------------------------------------------- laser-fan kernels
# The mesh-mode stripe (seamtrack.sensing.scan) runs through these two kernels so that a 1024-ray
# profile
# costs little more than its Embree calls. The sensor enters as a parameter vector (indices below,
# built by ``seamtrack.sensing.scan``); _chip and _pixel_center compute LaserLineSensor.project,
# in_field_of_view and measure with fewer divisions (tests pin them equal to 1e-12).
SP_B, SP_LAM, SP_SIN, SP_COS, SP_H, SP_V, SP_NH, SP_NV, SP_SLACK, SP_COS_MAX_INC = range(10)

MISS, OCCLUDED, OUT_OF_RANGE, INCIDENCE = 1, 2, 3, 4  # = seamtrack.sensing.profiles.Reason


@numba.njit(**KERNEL, inline="always")
def _chip(y: float, z: float, sp: NDArray[np.float64]) -> tuple[float, float, bool]:
    """Laser-plane point to chip coordinates and the field-of-view test."""
    b, lam, s, c = sp[SP_B], sp[SP_LAM], sp[SP_SIN], sp[SP_COS]
    depth = z * c + b * s
    if not depth > 0:
        return np.nan, np.nan, False
    lam_over_depth = lam / depth
    x_c = (b * c - z * s) * lam_over_depth
    z_c = y * lam_over_depth
    # A NaN or infinite input gives a NaN chip coordinate, which fails both comparisons.
    inside = abs(x_c) <= 0.5 * sp[SP_H] * sp[SP_SLACK] and abs(z_c) <= 0.5 * sp[SP_V] * sp[SP_SLACK]
    return x_c, z_c, inside


@numba.njit(**KERNEL, inline="always")
def _pixel_center(x_c: float, z_c: float, sp: NDArray[np.float64]) -> tuple[float, float]:
    """The laser-plane point the sensor reports for chip coordinates: snap, triangulate."""
    b, lam, s, c, H, V = sp[SP_B], sp[SP_LAM], sp[SP_SIN], sp[SP_COS], sp[SP_H], sp[SP_V]
    pitch_h, pitch_v = H / sp[SP_NH], V / sp[SP_NV]
    ih = min(max(np.floor((x_c + 0.5 * H) * sp[SP_NH] / H), 0.0), sp[SP_NH] - 1)
    iv = min(max(np.floor((z_c + 0.5 * V) * sp[SP_NV] / V), 0.0), sp[SP_NV] - 1)
    xq = (ih + 0.5) * pitch_h - 0.5 * H
    zq = (iv + 0.5) * pitch_v - 0.5 * V
    b_over_den = b / (xq * c + lam * s)
    return zq * b_over_den, (lam * c - xq * s) * b_over_den


@numba.njit(**KERNEL, inline="always")
def _mark_miss(
    i: int, points: NDArray[np.float64], reason: NDArray[np.uint8], t_out: NDArray[np.float64],
    face_out: NDArray[np.int64], cos_incidence: NDArray[np.float64], chip: NDArray[np.float64],
) -> None:  # fmt: skip
    """Ray ``i`` hits nothing: no point, no chip coordinates, no face, reason MISS."""
    points[i, 0] = np.nan
    points[i, 1] = np.nan
    chip[i, 0] = np.nan
    chip[i, 1] = np.nan
    reason[i] = MISS
    t_out[i] = np.nan
    face_out[i] = -1
    cos_incidence[i] = np.nan


@numba.njit(**KERNEL, inline="always")
def _set_shadow_ray(
    k: int, i: int, px: float, py: float, pz: float, vx: float, vy: float, vz: float,
    length: float, offset: float, shadow_origins: NDArray[np.float64],
    shadow_directions: NDArray[np.float64], shadow_far: NDArray[np.float64],
    shadow_index: NDArray[np.int64],
) -> None:  # fmt: skip
    """Shadow ray ``k`` of ray ``i``: from the hit ``p`` (moved ``offset`` off the surface)
    along the unit ``v`` towards the camera, ``length`` away."""
    shadow_origins[k, 0] = px + offset * vx
    shadow_origins[k, 1] = py + offset * vy
    shadow_origins[k, 2] = pz + offset * vz
    shadow_directions[k, 0] = vx
    shadow_directions[k, 1] = vy
    shadow_directions[k, 2] = vz
    shadow_far[k] = max(length - offset, 0.0)
    shadow_index[k] = i


@numba.njit(**KERNEL)
def fan_stripe_hits(
    origin: NDArray[np.float64],
    rotation: NDArray[np.float64],
    fan: NDArray[np.float64],
    directions: NDArray[np.float64],
    t_hit: NDArray[np.float64],
    face_hit: NDArray[np.int64],
    face_normals: NDArray[np.float64],
    sp: NDArray[np.float64],
    offset: float,
) -> tuple[
    NDArray[np.float64], NDArray[np.uint8], NDArray[np.float64], NDArray[np.int64],
    NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64],
    NDArray[np.float64], NDArray[np.int64],
]:  # fmt: skip
    """Laser fan hits -> laser-plane points, clip reasons and the batch of shadow rays.

    ``origin`` (3,) is the emitter in the local frame, ``rotation`` (3, 3) the laser frame's
    axes, ``fan`` (n, 3) the unit ray directions in the laser frame and ``directions`` the same
    in the local frame; ``t_hit``, ``face_hit`` (n,) each ray's first hit in float64 (face -1:
    a miss; :func:`refine_hits` of Embree's, or exact from a plane section) and
    ``face_normals`` (f, 3) the faces' unit normals. Returns
    ``points`` (n, 2) = (y_L, z_L) (NaN on a miss), ``reason`` (0 for the points still to test
    for occlusion), ``t``, ``face``, ``cos_incidence``, ``chip`` (n, 2) = (x_c, z_c), and the k
    shadow rays: origins offset towards the camera, unit directions, lengths, ray indices (k,).
    """
    n = directions.shape[0]
    points = np.empty((n, 2))
    reason = np.empty(n, dtype=np.uint8)
    t_out = np.empty(n)
    face_out = np.empty(n, dtype=np.int64)
    cos_incidence = np.empty(n)
    chip = np.empty((n, 2))
    shadow_origins = np.empty((n, 3))
    shadow_directions = np.empty((n, 3))
    shadow_far = np.empty(n)
    shadow_index = np.empty(n, dtype=np.int64)
    cx = origin[0] + sp[SP_B] * rotation[0, 0]
    cy = origin[1] + sp[SP_B] * rotation[1, 0]
    cz = origin[2] + sp[SP_B] * rotation[2, 0]
    k = _ZERO
    for i in range(directions.shape[0]):
        f = face_hit[i]
        if f < 0:
            _mark_miss(i, points, reason, t_out, face_out, cos_incidence, chip)
            continue
        dx, dy, dz = directions[i, 0], directions[i, 1], directions[i, 2]
        t = t_hit[i]
        t_out[i] = t
        face_out[i] = f
        # The ray lies in the laser plane, so the laser-frame point is exact: x_L = 0.
        y = t * fan[i, 1]
        z = t * fan[i, 2]
        points[i, 0] = y
        points[i, 1] = z
        nx, ny, nz = face_normals[f, 0], face_normals[f, 1], face_normals[f, 2]
        n_dot_d = nx * dx + ny * dy + nz * dz
        cos_incidence[i] = abs(n_dot_d)
        x_c, z_c, inside = _chip(y, z, sp)
        chip[i, 0] = x_c
        chip[i, 1] = z_c
        if not inside:
            reason[i] = OUT_OF_RANGE
            continue
        if abs(n_dot_d) < sp[SP_COS_MAX_INC]:
            reason[i] = INCIDENCE
            continue
        px, py, pz = origin[0] + t * dx, origin[1] + t * dy, origin[2] + t * dz
        vx, vy, vz = cx - px, cy - py, cz - pz
        length = np.sqrt(vx * vx + vy * vy + vz * vz)
        inv_length = 1.0 / length
        vx, vy, vz = vx * inv_length, vy * inv_length, vz * inv_length
        # The camera must be on the lit side of the face (thin sheets, back faces).
        if (nx * vx + ny * vy + nz * vz) * n_dot_d >= 0.0:
            reason[i] = OCCLUDED
            continue
        reason[i] = 0
        _set_shadow_ray(k, i, px, py, pz, vx, vy, vz, length, offset,
                        shadow_origins, shadow_directions, shadow_far, shadow_index)  # fmt: skip
        k += 1
    return (points, reason, t_out, face_out, cos_incidence, chip, shadow_origins[:k],
            shadow_directions[:k], shadow_far[:k], shadow_index[:k])  # fmt: skip


@numba.njit(**KERNEL)
def fan_stripe_finish(
    points: NDArray[np.float64],
    reason: NDArray[np.uint8],
    chip: NDArray[np.float64],
    blocked: NDArray[np.bool_],
    shadow_index: NDArray[np.int64],
    sp: NDArray[np.float64],
    quantize: bool,
) -> None:
    """Mark the occluded points (``blocked`` shadow rays) and pixel-quantize the valid ones."""
    for j in range(blocked.shape[0]):
        if blocked[j]:
            reason[shadow_index[j]] = OCCLUDED
    if not quantize:
        return
    for i in range(points.shape[0]):
        if reason[i] == 0:
            points[i, 0], points[i, 1] = _pixel_center(chip[i, 0], chip[i, 1], sp)


@numba.njit(**KERNEL)
def packet_shadows_finish(
    occluded: Any, width: int, scene: int, shadow_origins: NDArray[np.float64],
    shadow_directions: NDArray[np.float64], shadow_far: NDArray[np.float64],
    shadow_index: NDArray[np.int64], points: NDArray[np.float64], reason: NDArray[np.uint8],
    chip: NDArray[np.float64], sp: NDArray[np.float64], quantize: bool,
) -> None:  # fmt: skip
    """The shadow rays (:func:`fan_stripe_hits`') cast on Embree packets (``occluded``, the
    address of the query of packets of ``width``), then :func:`fan_stripe_finish`."""
    blocked = np.empty(shadow_index.shape[0], dtype=np.bool_)
    embree.occluded(occluded, width, scene, shadow_origins, shadow_directions, shadow_far, 0.0,
                    blocked)  # fmt: skip
    fan_stripe_finish(points, reason, chip, blocked, shadow_index, sp, quantize)


@numba.njit(**KERNEL)
def fan_directions(rotation: NDArray[np.float64], fan: NDArray[np.float64]) -> NDArray[np.float64]:
    """The fan's unit rays (n, 3), given in the laser frame, turned by ``rotation`` (3, 3)
    (the laser frame's axes as columns) into the frame the rays are cast in."""
    n = fan.shape[0]
    directions = np.empty((n, 3))
    for i in range(n):
        for a in range(3):
            directions[i, a] = (rotation[a, 0] * fan[i, 0] + rotation[a, 1] * fan[i, 1]
                                + rotation[a, 2] * fan[i, 2])  # fmt: skip
    return directions


@numba.njit(**KERNEL)
def fan_stripe_packets(
    intersect8: Any, occluded: Any, width: int, scene: int,
    origin: NDArray[np.float64], rotation: NDArray[np.float64], fan: NDArray[np.float64],
    mesh: HitMesh, refine: bool, tol: float, sp: NDArray[np.float64], offset: float,
    quantize: bool,
) -> tuple[NDArray[np.float64], NDArray[np.uint8], NDArray[np.float64], NDArray[np.int64],
           NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
    """The whole noiseless stripe in one call on the packet backend
    (:mod:`seamtrack.sensing.embree`): ``intersect8`` the address of ``rtcIntersect8``,
    ``occluded`` and ``width`` the occlusion query's and its packet's
    (``Library.occluded_query``, ``Library.occluded_width``).

    The fan turned into the local frame, first hits, :func:`refine_hits`,
    :func:`fan_stripe_hits`, shadow rays, :func:`fan_stripe_finish`. Returns (points, reason,
    t, face, cos_incidence, directions).
    """
    n = fan.shape[0]
    directions = fan_directions(rotation, fan)
    origins = origin.reshape((1, 3))
    prim = np.empty(n, dtype=np.int32)
    tfar = np.empty(n, dtype=np.float32)
    embree.intersect(intersect8, scene, origins, directions, prim, tfar)
    t_hit = np.empty(n)
    face_hit = np.empty(n, dtype=np.int64)
    refined = np.empty(n, dtype=np.bool_)
    refine_hits(origins, directions, prim, tfar, mesh, refine, tol, t_hit, face_hit, refined)
    points, reason, t, face, cos_incidence, chip, shadow_o, shadow_d, shadow_far, shadow_index = (
        fan_stripe_hits(origin, rotation, fan, directions, t_hit, face_hit, mesh.face_normals, sp,
                        offset)
    )  # fmt: skip
    packet_shadows_finish(occluded, width, scene, shadow_o, shadow_d, shadow_far, shadow_index,
                          points, reason, chip, sp, quantize)  # fmt: skip
    return points, reason, t, face, cos_incidence, directions


# --------------------------------------------------------------------------- the caster
