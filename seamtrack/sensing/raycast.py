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

Embree is called in packets of 8 rays from numba (:mod:`seamtrack.sensing.embree`, on the library
inside
the embreex wheel), faster than embreex's one-ray-at-a-time ``scene.run`` (``seamtrack bench
raycast`` times both), which remains the fallback (``backend="embreex"``). Occlusion (shadow) rays
start a small offset (:data:`seamtrack.constants.SHADOW_RAY_OFFSET_MM`) from the surface point
towards their target, as embreex's fixed ``tnear = 0`` requires; both backends cast the same rays.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np
from embreex import mesh_construction, rtcore_scene
from numpy.typing import ArrayLike, NDArray

from seamtrack import constants
from seamtrack.sensing import embree, section
from seamtrack.sensing.kernels import HitMesh, VertexRings, refine_hits

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
        How Embree is called: ray packets from numba (:mod:`seamtrack.sensing.embree`, the default
        when
        the embreex wheel's Embree 4 library is found) or embreex's ``scene.run``. Both cast
        the same float32 rays on a robust scene and give the same hits (tests/test_embree.py).

    Attributes
    ----------
    backend : str
        ``"packets"`` or ``"embreex"``, as chosen.
    packets : seamtrack.sensing.embree.Scene or None
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
        # the rings, built when first asked for
        self._rings: VertexRings | None = None
        self._vertices_world = v  # welded as given (exactly equal world coordinates)
        self._section: section.SectionIndex | None = None
        # The triangles the last plane-section stripe hit (section.hit_faces): the next one's
        # seeds. Only how much the next section cuts depends on them, not its hits.
        self.section_seeds: NDArray[np.int64] = section.NO_SEEDS
        # What the section's kernels take of this mesh and a fan, per fan (scan._section_args).
        self.section_args: dict[Any, tuple[tuple[Any, ...], ...]] = {}
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
    def section(self) -> section.SectionIndex:
        """The bounding-volume hierarchy of the plane-section fan
        (:mod:`seamtrack.sensing.section`), built on first use (about 0.1 s per 100k triangles,
        56 bytes a triangle)."""
        if self._section is None:
            self._section = section.build(self.vertices_local, self.faces)
        return self._section

    @property
    def section_mesh(self) -> HitMesh:
        """The mesh as the section's kernels take it (local frame, one record, no rings)."""
        return self.hit_mesh(refine=False)

    @property
    def rings(self) -> VertexRings:
        """Each vertex's welded id (exactly equal coordinates share one) and the faces around
        each welded vertex (CSR), which the float64 refinement of Embree's hits walks. Built on
        first use (a sort of the vertices: 0.3 s for 566k triangles), which the plane-section
        fan never needs."""
        if self._rings is None:
            self._rings = _vertex_rings(self._vertices_world, self.faces)
        return self._rings

    def hit_mesh(self, refine: bool = True) -> HitMesh:
        """The mesh as the fan's kernels take it (local frame, one record); its vertex rings
        are built (on first use) only to ``refine``, and are empty otherwise."""
        rings = self.rings if refine else _NO_RINGS
        return HitMesh(self.vertices_local, self.faces, self.face_normals, rings)

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
            prim, tfar, self.hit_mesh(refine), bool(refine), constants.BARYCENTRIC_TOL, t, face,
            refined,
        )  # fmt: skip
        return t, face, refined

    def _local_rays(
        self, origins: ArrayLike, directions: ArrayLike
    ) -> tuple[FloatArray, FloatArray]:
        """World rays in the caster's frame: the origins less :attr:`local_origin` ((1, 3): one
        shared by all, or (n, 3)) and the unit directions (n, 3)."""
        d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
        d = d / np.linalg.norm(d, axis=1, keepdims=True)
        o_local = np.asarray(origins, dtype=np.float64).reshape(-1, 3) - self.local_origin
        if len(o_local) not in (1, len(d)):
            raise ValueError(f"{len(o_local)} origins for {len(d)} directions")
        return o_local, d

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
        o_local, d = self._local_rays(origins, directions)
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
        o_local, d = self._local_rays(origins, directions)
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


_NO_RING = np.empty(0, dtype=np.int64)
_NO_RINGS = VertexRings(_NO_RING, _NO_RING, _NO_RING)


def _vertex_rings(vertices: FloatArray, faces: NDArray[np.int64]) -> VertexRings:
    """Welded vertex ids (exactly equal coordinates) and the faces around each, as CSR."""
    _, weld = np.unique(vertices, axis=0, return_inverse=True)
    weld = np.ascontiguousarray(weld.reshape(-1), dtype=np.int64)
    owner = weld[faces].reshape(-1)
    face_of = np.repeat(np.arange(len(faces), dtype=np.int64), 3)
    order = np.argsort(owner, kind="stable")
    counts = np.bincount(owner, minlength=int(weld.max()) + 1)
    ptr = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    return VertexRings(weld, ptr, np.ascontiguousarray(face_of[order]))
