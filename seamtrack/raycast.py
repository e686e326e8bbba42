"""Ray casting on triangle meshes: Embree (through embreex) in float32, refined in float64.

Embree takes float32 only, and float32 error grows with the distance from the origin (about
1e-4 mm at 0, 3e-3 mm at 1e5 mm; DESIGN.md). So a :class:`RayCaster` builds its Embree scene once,
in a *local* frame: the vertices are shifted by a local origin (the bounding-box centre) in float64
before the cast to float32, and so are the ray origins. Every hit is then recomputed in float64
from the triangle Embree returned: the exact intersection of the ray with the float64 triangle's
plane, and a barycentric inside test; a point that falls outside (a ray that Embree assigned
across a crease, or a hit at a shared edge) is re-tested against the faces that share a vertex
with that triangle, and the nearest face that contains it wins. When no face contains it (rays
grazing a face at ~1e-7 rad), Embree's own hit is kept: refinement never makes a hit worse.

Vertices that coincide exactly are welded for that neighbour search (a CAD mesh duplicates
vertices along every B-rep edge, which is where the creases are); Embree sees the mesh as given.

Embree is called in packets of 8 rays from numba (:mod:`seamtrack.embree`, on the library inside
the embreex wheel), faster than embreex's one-ray-at-a-time ``scene.run`` (``seamtrack bench
raycast`` times both), which remains the fallback (``backend="embreex"``). Occlusion (shadow) rays
start a small offset (:data:`seamtrack.constants.SHADOW_RAY_OFFSET_MM`) from the surface point
towards their target, as embreex's fixed ``tnear = 0`` requires; both backends cast the same rays.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any

import numba
import numpy as np
from embreex import mesh_construction, rtcore_scene
from numpy.typing import ArrayLike, NDArray

from . import constants, embree

FloatArray = NDArray[np.float64]
BoolArray = NDArray[np.bool_]


@dataclass(frozen=True, eq=False)
class Hits:
    """First hits of a batch of rays, in the world frame.

    Attributes
    ----------
    hit : (n,) bool
        The ray hit the mesh.
    distance_mm : (n,) float
        Distance from the ray origin along the unit direction; NaN where missed.
    points : (n, 3) float
        Hit points; NaN where missed.
    face : (n,) int64
        Index of the triangle hit; -1 where missed.
    normals : (n, 3) float
        Unit normal of that triangle, turned to face the ray origin; NaN where missed.
    refined : (n,) bool
        The point was recomputed in float64 (False where refinement was off, where the ray
        missed, or where no nearby triangle contained the float64 point and Embree's hit was kept).
    """

    hit: BoolArray
    distance_mm: FloatArray
    points: FloatArray
    face: NDArray[np.int64]
    normals: FloatArray
    refined: BoolArray

    def __len__(self) -> int:
        return len(self.hit)


# --------------------------------------------------------------------------- float64 kernels
@numba.njit(cache=True, nogil=True, inline="always")
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


@numba.njit(cache=True, nogil=True, inline="always")
def _refine_one(
    ox: float, oy: float, oz: float, dx: float, dy: float, dz: float, f: int, tf: float,
    vertices: NDArray[np.float64], faces: NDArray[np.int64], weld: NDArray[np.int64],
    ring_ptr: NDArray[np.int64], ring_faces: NDArray[np.int64], tol: float,
) -> tuple[float, int, bool]:  # fmt: skip
    """(t, face, refined) of one ray that Embree says hits face ``f`` at ``tf``."""
    t, inside = _intersect_face(ox, oy, oz, dx, dy, dz, vertices, faces, f, tol)
    if inside and t > 0.0:
        return t, f, True
    # Outside its triangle: the ray crossed a crease or an edge. The nearest face around the
    # triangle's vertices that contains the float64 point is the true first hit.
    best_t = np.inf
    best_f = -1
    for k in range(3):
        vid = weld[faces[f, k]]
        for m in range(ring_ptr[vid], ring_ptr[vid + 1]):
            g = ring_faces[m]
            if g == f:
                continue
            t, inside = _intersect_face(ox, oy, oz, dx, dy, dz, vertices, faces, g, tol)
            if inside and 0.0 < t < best_t:
                best_t = t
                best_f = g
    if best_f >= 0:
        return best_t, best_f, True
    return tf, f, False


@numba.njit(cache=True, nogil=True)
def refine_hits(
    origins: NDArray[np.float64],
    directions: NDArray[np.float64],
    prim: NDArray[np.int32],
    tfar: NDArray[np.float32],
    vertices: NDArray[np.float64],
    faces: NDArray[np.int64],
    weld: NDArray[np.int64],
    ring_ptr: NDArray[np.int64],
    ring_faces: NDArray[np.int64],
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
    vertices, faces, weld, ring_ptr, ring_faces
        The local float64 mesh, the welded vertex id of each vertex and, per welded vertex, the
        faces around it (CSR).
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
                directions[i, 0], directions[i, 1], directions[i, 2], f, tfar[i],
                vertices, faces, weld, ring_ptr, ring_faces, tol,
            )  # fmt: skip


# --------------------------------------------------------------------------- laser-fan kernels
# The mesh-mode stripe (seamtrack.scan) runs through these two kernels so that a 1024-ray profile
# costs little more than its Embree calls. The sensor enters as a parameter vector (indices below,
# built by ``seamtrack.scan``); _chip and _pixel_center compute LaserLineSensor.project,
# in_field_of_view and measure with fewer divisions (tests pin them equal to 1e-12).
SP_B, SP_LAM, SP_SIN, SP_COS, SP_H, SP_V, SP_NH, SP_NV, SP_SLACK, SP_COS_MAX_INC = range(10)

MISS, OCCLUDED, OUT_OF_RANGE, INCIDENCE = 1, 2, 3, 4  # = seamtrack.profiles.Reason


@numba.njit(cache=True, nogil=True, inline="always")
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


@numba.njit(cache=True, nogil=True, inline="always")
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


@numba.njit(cache=True, nogil=True)
def fan_stripe_hits(
    origin: NDArray[np.float64],
    rotation: NDArray[np.float64],
    fan: NDArray[np.float64],
    directions: NDArray[np.float64],
    prim: NDArray[np.int32],
    tfar: NDArray[np.float32],
    vertices: NDArray[np.float64],
    faces: NDArray[np.int64],
    weld: NDArray[np.int64],
    ring_ptr: NDArray[np.int64],
    ring_faces: NDArray[np.int64],
    face_normals: NDArray[np.float64],
    refine: bool,
    tol: float,
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
    in the local frame. Returns ``points`` (n, 2) = (y_L, z_L) (NaN on a miss), ``reason``
    (0 for the points still to test for occlusion), ``t``, ``face``, ``cos_incidence``,
    ``chip`` (n, 2) = (x_c, z_c), and the k shadow rays: origins offset towards the camera,
    unit directions, lengths, ray indices (k,).
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
    k = 0
    for i in range(directions.shape[0]):
        f = prim[i]
        if f < 0:
            points[i, 0] = np.nan
            points[i, 1] = np.nan
            chip[i, 0] = np.nan
            chip[i, 1] = np.nan
            reason[i] = MISS
            t_out[i] = np.nan
            face_out[i] = -1
            cos_incidence[i] = np.nan
            continue
        dx, dy, dz = directions[i, 0], directions[i, 1], directions[i, 2]
        t = float(tfar[i])
        if refine:
            t, f, _ = _refine_one(origin[0], origin[1], origin[2], dx, dy, dz, f, t,
                                  vertices, faces, weld, ring_ptr, ring_faces, tol)  # fmt: skip
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
        shadow_origins[k, 0] = px + offset * vx
        shadow_origins[k, 1] = py + offset * vy
        shadow_origins[k, 2] = pz + offset * vz
        shadow_directions[k, 0] = vx
        shadow_directions[k, 1] = vy
        shadow_directions[k, 2] = vz
        shadow_far[k] = max(length - offset, 0.0)
        shadow_index[k] = i
        k += 1
    return (points, reason, t_out, face_out, cos_incidence, chip, shadow_origins[:k],
            shadow_directions[:k], shadow_far[:k], shadow_index[:k])  # fmt: skip


@numba.njit(cache=True, nogil=True)
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


@numba.njit(cache=True, nogil=True)
def fan_stripe_packets(
    intersect8: Any, occluded8: Any, scene: int,
    origin: NDArray[np.float64], rotation: NDArray[np.float64], fan: NDArray[np.float64],
    vertices: NDArray[np.float64], faces: NDArray[np.int64], weld: NDArray[np.int64],
    ring_ptr: NDArray[np.int64], ring_faces: NDArray[np.int64],
    face_normals: NDArray[np.float64], refine: bool, tol: float, sp: NDArray[np.float64],
    offset: float, quantize: bool,
) -> tuple[NDArray[np.float64], NDArray[np.uint8], NDArray[np.float64], NDArray[np.int64],
           NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
    """The whole noiseless stripe in one call on the packet backend (:mod:`seamtrack.embree`).

    The fan turned into the local frame, first hits, :func:`fan_stripe_hits`, shadow rays,
    :func:`fan_stripe_finish`. Returns (points, reason, t, face, cos_incidence, directions).
    """
    n = fan.shape[0]
    directions = np.empty((n, 3))
    for i in range(n):
        for a in range(3):
            directions[i, a] = (rotation[a, 0] * fan[i, 0] + rotation[a, 1] * fan[i, 1]
                                + rotation[a, 2] * fan[i, 2])  # fmt: skip
    origins = origin.reshape((1, 3))
    prim = np.empty(n, dtype=np.int32)
    tfar = np.empty(n, dtype=np.float32)
    embree.intersect(intersect8, scene, origins, directions, prim, tfar)
    points, reason, t, face, cos_incidence, chip, shadow_o, shadow_d, shadow_far, shadow_index = (
        fan_stripe_hits(origin, rotation, fan, directions, prim, tfar, vertices, faces, weld,
                        ring_ptr, ring_faces, face_normals, refine, tol, sp, offset)
    )  # fmt: skip
    blocked = np.empty(shadow_index.shape[0], dtype=np.bool_)
    embree.occluded(occluded8, scene, shadow_o, shadow_d, shadow_far, 0.0, blocked)
    fan_stripe_finish(points, reason, chip, blocked, shadow_index, sp, quantize)
    return points, reason, t, face, cos_incidence, directions


# --------------------------------------------------------------------------- the caster
class RayCaster:
    """An Embree scene of one triangle mesh, with first-hit and occlusion queries.

    Parameters
    ----------
    vertices : (v, 3) float
        Vertex positions in the world (part) frame, mm.
    faces : (f, 3) int
        Triangles as vertex indices.
    local_origin : (3,) float, optional
        Origin of the float32 frame; default the bounding-box centre. ``np.zeros(3)`` gives the
        naive world-frame float32 scene (useful only to measure what the shift buys).
    backend : {"auto", "packets", "embreex"}
        How Embree is called: ray packets from numba (:mod:`seamtrack.embree`, the default when
        the embreex wheel's Embree 4 library is found) or embreex's ``scene.run``. Both cast
        the same float32 rays on a robust scene and give the same hits (tests/test_embree.py).

    Attributes
    ----------
    backend : str
        ``"packets"`` or ``"embreex"``, as chosen.
    packets : seamtrack.embree.Scene or None
        The packet backend's scene (None on the fallback, which uses ``scene``).

    Notes
    -----
    Build it once per mesh (:meth:`for_mesh` caches one per live mesh object). Queries are
    single-threaded and allocate only their outputs.
    """

    def __init__(
        self,
        vertices: ArrayLike,
        faces: ArrayLike,
        *,
        local_origin: ArrayLike | None = None,
        backend: str = "auto",
    ) -> None:
        v = np.asarray(vertices, dtype=np.float64)
        f = np.asarray(faces, dtype=np.int64)
        if v.ndim != 2 or v.shape[1] != 3 or f.ndim != 2 or f.shape[1] != 3:
            raise ValueError(f"need (v, 3) vertices and (f, 3) faces, got {v.shape}, {f.shape}")
        if len(f) == 0:
            raise ValueError("the mesh has no faces")
        if f.min() < 0 or f.max() >= len(v):
            raise ValueError("faces index vertices that do not exist")
        if not np.isfinite(v).all():
            raise ValueError("vertices must be finite")
        if local_origin is None:
            origin = 0.5 * (v.min(axis=0) + v.max(axis=0))
        else:
            origin = np.asarray(local_origin, dtype=np.float64).reshape(3).copy()
        self.local_origin: FloatArray = origin
        self.vertices_local: FloatArray = np.ascontiguousarray(v - origin)
        self.faces: NDArray[np.int64] = np.ascontiguousarray(f)
        if backend not in ("auto", "packets", "embreex"):
            raise ValueError(f"backend must be 'auto', 'packets' or 'embreex', got {backend!r}")
        lib = embree.library() if backend != "embreex" else None
        if backend == "packets" and lib is None:
            raise RuntimeError("no Embree 4 library found in the embreex wheel")
        self.backend: str = "packets" if lib is not None else "embreex"
        self.packets: embree.Scene | None = None
        self.scene: Any = None  # embreex's EmbreeScene, on the fallback backend
        if lib is not None:
            self.packets = embree.Scene(lib, self.vertices_local, self.faces)
        else:
            self.scene = rtcore_scene.EmbreeScene()
            # The TriangleMesh object must outlive the scene's use of its buffers: keep it.
            self._embree_mesh = mesh_construction.TriangleMesh(
                self.scene, self.vertices_local.astype(np.float32), f.astype(np.int32)
            )
        self.weld, self.ring_ptr, self.ring_faces = _vertex_rings(v, f)
        unit = np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]])
        norm = np.linalg.norm(unit, axis=1, keepdims=True)
        with np.errstate(invalid="ignore", divide="ignore"):
            self.face_normals: FloatArray = np.where(norm > 0, unit / norm, 0.0)

    # ------------------------------------------------------------------ construction
    @classmethod
    def from_mesh(
        cls, mesh: Any, *, local_origin: ArrayLike | None = None, backend: str = "auto"
    ) -> RayCaster:
        """A caster of a ``trimesh.Trimesh`` (or anything with ``vertices`` and ``faces``)."""
        return cls(mesh.vertices, mesh.faces, local_origin=local_origin, backend=backend)

    @classmethod
    def for_mesh(cls, mesh: Any) -> RayCaster:
        """The cached caster of this mesh object, built on first use.

        The cache holds one caster per live mesh object (by identity, released with the mesh);
        a mesh whose vertices change in place needs a fresh ``RayCaster.from_mesh(mesh)``.
        """
        key = id(mesh)
        entry = _CACHE.get(key)
        if entry is not None and entry[0]() is mesh:
            return entry[1]
        caster = cls.from_mesh(mesh)
        _CACHE[key] = (weakref.ref(mesh), caster)
        weakref.finalize(mesh, _CACHE.pop, key, None)
        return caster

    @property
    def n_faces(self) -> int:
        """Number of triangles."""
        return len(self.faces)

    # ------------------------------------------------------------------ queries
    def cast_local(
        self, origins: NDArray[Any], directions: NDArray[Any]
    ) -> tuple[NDArray[np.int32], NDArray[np.float32]]:
        """Bare Embree first hits in the local frame: (primID (n,), tfar (n,)); -1 is a miss.

        ``origins`` is (1, 3) (shared by all rays) or (n, 3), ``directions`` (n, 3); Embree
        sees both rounded to float32.
        """
        if self.packets is not None:
            return self.packets.intersect(origins, directions)
        d32 = np.ascontiguousarray(directions, dtype=np.float32)
        o32 = np.ascontiguousarray(np.broadcast_to(origins, d32.shape), dtype=np.float32)
        out = self.scene.run(o32, d32, output=1)
        return out["primID"], out["tfar"]

    def occluded_local(
        self, origins: NDArray[Any], directions: NDArray[Any], far: NDArray[Any]
    ) -> BoolArray:
        """Bare Embree occlusion in the local frame: True where ray i meets the mesh in
        (0, far[i]]; arguments as :meth:`cast_local`, ``far`` (n,)."""
        if self.packets is not None:
            return self.packets.occluded(origins, directions, far)
        d32 = np.ascontiguousarray(directions, dtype=np.float32)
        o32 = np.ascontiguousarray(np.broadcast_to(origins, d32.shape), dtype=np.float32)
        far32 = np.array(far, dtype=np.float32)  # a copy: embreex writes into it
        return np.asarray(self.scene.run(o32, d32, dists=far32, query="OCCLUDED") >= 0)

    def refine_local(
        self,
        origins_local: FloatArray,
        directions: FloatArray,
        prim: NDArray[np.int32],
        tfar: NDArray[np.float32],
        *,
        refine: bool = True,
    ) -> tuple[FloatArray, NDArray[np.int64], BoolArray]:
        """Float64 distances of Embree's hits: (t (n,), face (n,), refined (n,)).

        ``origins_local`` is (1, 3) (shared) or (n, 3); ``directions`` (n, 3) unit, float64.
        """
        n = len(directions)
        t = np.empty(n)
        face = np.empty(n, dtype=np.int64)
        refined = np.empty(n, dtype=np.bool_)
        refine_hits(
            np.ascontiguousarray(origins_local, dtype=np.float64),
            np.ascontiguousarray(directions, dtype=np.float64),
            prim, tfar, self.vertices_local, self.faces, self.weld, self.ring_ptr,
            self.ring_faces, bool(refine), constants.BARYCENTRIC_TOL, t, face, refined,
        )  # fmt: skip
        return t, face, refined

    def first_hit(self, origins: ArrayLike, directions: ArrayLike, *, refine: bool = True) -> Hits:
        """First hit of each ray.

        Parameters
        ----------
        origins : (n, 3) or (3,) float
            Ray origins, world frame (one origin: shared by all rays).
        directions : (n, 3) float
            Directions (normalized here).
        refine : bool
            Recompute each hit in float64 from its triangle (default); False keeps Embree's
            float32 distance.

        Returns
        -------
        Hits
        """
        d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
        o_local = np.asarray(origins, dtype=np.float64).reshape(-1, 3) - self.local_origin
        if len(o_local) not in (1, len(d)):
            raise ValueError(f"{len(o_local)} origins for {len(d)} directions")
        prim, tfar = self.cast_local(o_local, d)
        t, face, refined = self.refine_local(o_local, d, prim, tfar, refine=refine)
        hit = face >= 0
        points = o_local + t[:, None] * d + self.local_origin
        normals = np.full_like(d, np.nan)
        n_hit = self.face_normals[face[hit]]
        flip = np.einsum("ij,ij->i", n_hit, d[hit]) > 0
        n_hit[flip] *= -1.0
        normals[hit] = n_hit
        return Hits(hit=hit, distance_mm=t, points=points, face=face, normals=normals,
                    refined=refined)  # fmt: skip

    def occluded(
        self, origins: ArrayLike, directions: ArrayLike, distances_mm: ArrayLike
    ) -> BoolArray:
        """True where a ray meets the mesh before ``distances_mm`` (world frame, (n,) each).

        The rays start exactly at ``origins`` (Embree's tnear is 0): offset them off the
        surface yourself, or use :meth:`line_of_sight_blocked`.
        """
        d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
        o_local = np.asarray(origins, dtype=np.float64).reshape(-1, 3) - self.local_origin
        if len(o_local) not in (1, len(d)):
            raise ValueError(f"{len(o_local)} origins for {len(d)} directions")
        far = np.ascontiguousarray(np.broadcast_to(distances_mm, len(d)), dtype=np.float64)
        return self.occluded_local(o_local, d, far)

    def line_of_sight_blocked(
        self,
        points: ArrayLike,
        target: ArrayLike,
        *,
        offset_mm: float = constants.SHADOW_RAY_OFFSET_MM,
    ) -> BoolArray:
        """True where the segment from a surface point to ``target`` (3,) meets the mesh.

        Each shadow ray starts ``offset_mm`` from its point towards the target, so that the
        point's own triangle does not block it.
        """
        p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        to_target = np.asarray(target, dtype=np.float64).reshape(3) - p
        length = np.linalg.norm(to_target, axis=1)
        d = to_target / length[:, None]
        return self.occluded(p + offset_mm * d, d, np.maximum(length - offset_mm, 0.0))


_CACHE: dict[int, tuple[weakref.ref[Any], RayCaster]] = {}


def _vertex_rings(
    vertices: FloatArray, faces: NDArray[np.int64]
) -> tuple[NDArray[np.int64], NDArray[np.int64], NDArray[np.int64]]:
    """Welded vertex ids (exactly equal coordinates) and the faces around each, as CSR."""
    _, weld = np.unique(vertices, axis=0, return_inverse=True)
    weld = np.ascontiguousarray(weld.reshape(-1), dtype=np.int64)
    owner = weld[faces].reshape(-1)
    face_of = np.repeat(np.arange(len(faces), dtype=np.int64), 3)
    order = np.argsort(owner, kind="stable")
    counts = np.bincount(owner, minlength=int(weld.max()) + 1)
    ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    return weld, ptr, np.ascontiguousarray(face_of[order])
