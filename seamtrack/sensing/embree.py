"""Embree 4 driven from numba: ray packets through the library that embreex ships.

embreex's ``scene.run`` casts one ray at a time (``rtcIntersect1``) from Cython, allocates five
output arrays per call and cannot start a shadow ray off the surface (``tnear`` is fixed at 0).
Embree itself offers packets of 4, 8 or 16 rays, which trace a coherent bundle (a laser fan, the
shadow rays of one stripe, all aimed at the same camera) together. This module calls
``rtcIntersect8`` / ``rtcOccluded8`` (``rtcOccluded16`` where the CPU traces packets of 16
natively: the shadow rays) from numba kernels through their addresses, on
Embree's own scene objects, built from the shared library inside the embreex wheel: no compiler,
no second copy of Embree. :func:`library` returns ``None`` when that library cannot be found or is
not Embree 4 (the ABI below); :class:`seamtrack.sensing.raycast.RayCaster` then falls back to
embreex's
``scene.run``.

Embree 4 ABI used here (``rtcore_ray.h``; every field 4 bytes, packets are structs of arrays):
``RTCRay8`` = org_x, org_y, org_z, tnear, dir_x, dir_y, dir_z, time, tfar, mask, id, flags (12 x 8);
``RTCHit8`` = Ng_x, Ng_y, Ng_z, u, v, primID, geomID, instID[L] (+ instPrimID[L] when built with
instance arrays; L = RTC_MAX_INSTANCE_LEVEL_COUNT, 1 in the wheel); ``RTCRayHit8`` is the two,
aligned to 32 bytes. Only the fields up to geomID are read, and room is left for L up to 8.
A query with ``args = NULL`` uses the default arguments (a full traversal, no filters).
"""

from __future__ import annotations

import ctypes
import glob
import os
import weakref
from functools import cache
from typing import Any

import numba
import numpy as np
from llvmlite import ir
from numba.core import types
from numba.extending import intrinsic
from numpy.typing import NDArray

from seamtrack.jit import KERNEL

W = 8  # rays per packet of the first-hit queries
WIDE = 16  # the widest packet (of the occlusion queries, where the CPU traces it natively)
_INVALID = 0xFFFFFFFF
# Field offsets, in 4-byte words from the packet start, times W lanes.
_ORG, _TNEAR, _DIR, _TIME, _TFAR, _MASK, _ID, _FLAGS = 0, 3, 4, 7, 8, 9, 10, 11
_HIT = 12  # RTCHit8 follows the ray
_PRIM, _GEOM, _INST = _HIT + 5, _HIT + 6, _HIT + 7
_WORDS = (_HIT + 7 + 2 * 8) * WIDE  # ray + hit with up to 8 instance levels, in words
_ALIGN = 64  # bytes (32 is required)

_VERTEX_BUFFER, _INDEX_BUFFER = 1, 0  # RTCBufferType
_FORMAT_FLOAT3, _FORMAT_UINT3 = 0x9003, 0x5003  # RTCFormat
_GEOMETRY_TRIANGLE = 0  # RTCGeometryType
_PROPERTY_VERSION_MAJOR = 1  # RTCDeviceProperty
_PROPERTY_NATIVE_RAY16 = 34  # RTCDeviceProperty: packets of 16 traced natively (AVX-512)
_SCENE_FLAG_ROBUST = 1 << 2  # RTCSceneFlags: without it, rays through shared edges miss

_u64 = ctypes.c_uint64  # handles and pointers travel as integers (the x86-64/arm64 ABI)


class Library:
    """The Embree 4 entry points seamtrack calls (ctypes functions; numba calls two of them,
    ``intersect8`` and ``occluded8``, by address)."""

    def __init__(self, path: str) -> None:
        lib = ctypes.CDLL(path)
        self.path = path

        def bind(name: str, restype: Any, *argtypes: Any) -> Any:
            fn = getattr(lib, name)
            fn.restype, fn.argtypes = restype, list(argtypes)
            return fn

        self.new_device = bind("rtcNewDevice", _u64, ctypes.c_char_p)
        self.device_property = bind("rtcGetDeviceProperty", ctypes.c_ssize_t, _u64, ctypes.c_int)
        self.device_error = bind("rtcGetDeviceError", ctypes.c_int, _u64)
        self.new_scene = bind("rtcNewScene", _u64, _u64)
        self.commit_scene = bind("rtcCommitScene", None, _u64)
        self.release_scene = bind("rtcReleaseScene", None, _u64)
        self.scene_flags = bind("rtcSetSceneFlags", None, _u64, ctypes.c_int)
        self.new_geometry = bind("rtcNewGeometry", _u64, _u64, ctypes.c_int)
        size = ctypes.c_size_t
        self.new_buffer = bind("rtcSetNewGeometryBuffer", _u64, _u64, ctypes.c_int, ctypes.c_uint,
                               ctypes.c_int, size, size)  # fmt: skip
        self.commit_geometry = bind("rtcCommitGeometry", None, _u64)
        self.attach_geometry = bind("rtcAttachGeometry", ctypes.c_uint, _u64, _u64)
        self.release_geometry = bind("rtcReleaseGeometry", None, _u64)
        # (valid*, scene, rayhit*, args*): called from numba, so plain integer arguments.
        # The two queries numba calls, as addresses (:func:`_call_query`): a ctypes function
        # passed to a compiled function costs ~3 us of typing per call, an integer nothing.
        self.intersect8_fn = bind("rtcIntersect8", None, _u64, _u64, _u64, _u64)
        self.occluded8_fn = bind("rtcOccluded8", None, _u64, _u64, _u64, _u64)
        self.occluded16_fn = bind("rtcOccluded16", None, _u64, _u64, _u64, _u64)
        self.intersect8 = _address(self.intersect8_fn)
        self.occluded8 = _address(self.occluded8_fn)
        self.occluded16 = _address(self.occluded16_fn)
        # One build thread: a scene builds in the calling thread, so Embree's TBB never starts
        # workers. Sweeps and datasets fork worker processes; a child forked while TBB workers
        # of the parent were about (busy or spinning after a build) inherits a scheduler whose
        # threads do not exist, and its next scene commit waits for them forever (a dataset
        # test's worker hung so in rtcCommitScene). seamtrack runs one process a core anyway.
        self.device = self.new_device(b"threads=1")
        if not self.device:
            raise OSError(f"rtcNewDevice failed in {path}")
        self.version_major = int(self.device_property(self.device, _PROPERTY_VERSION_MAJOR))
        # The shadow rays go in packets of 16 where the CPU traces them natively (~15-35 %
        # faster than 8 on AVX-512; the same answers), else of 8.
        wide = self.device_property(self.device, _PROPERTY_NATIVE_RAY16) == 1
        self.occluded_width = WIDE if wide else W
        self.occluded_query = self.occluded16 if wide else self.occluded8


def _address(fn: Any) -> int:
    """The address of a ctypes function."""
    return int(ctypes.cast(fn, ctypes.c_void_p).value or 0)


def _query_typer(
    typingctx: Any, fn: Any, valid: Any, scene: Any, packet: Any, args: Any
) -> tuple[Any, Any]:  # fmt: skip
    """``fn(valid, scene, packet, args)`` for ``fn`` the address of ``rtcIntersect8`` or
    ``rtcOccluded8`` (``void (const int*, RTCScene, RTCRayHit8* / RTCRay8*, args*)``), every
    argument an integer passed as a 64-bit word."""
    sig = types.void(fn, valid, scene, packet, args)

    def codegen(context: Any, builder: Any, signature: Any, values: Any) -> Any:
        word = ir.IntType(64)
        words = [
            context.cast(builder, v, t, types.uint64)
            for v, t in zip(values, signature.args, strict=True)
        ]
        query = builder.inttoptr(words[0], ir.FunctionType(ir.VoidType(), [word] * 4).as_pointer())
        builder.call(query, words[1:])
        return context.get_dummy_value()

    return sig, codegen


_call_query: Any = intrinsic(_query_typer)


def _candidates() -> list[str]:
    """Where a wheel of embreex keeps its Embree library (auditwheel, delocate, delvewheel)."""
    import embreex

    here = os.path.dirname(os.path.abspath(embreex.__file__))
    folders = [os.path.join(here, "..", "embreex.libs"), os.path.join(here, ".dylibs"), here]
    patterns = [os.path.join(folder, "*embree4*") for folder in folders]
    return sorted(p for pattern in patterns for p in glob.glob(pattern))


@cache
def library() -> Library | None:
    """The Embree 4 library inside the embreex wheel, or None (then embreex's API is used).

    ``SEAMTRACK_EMBREE=embreex`` in the environment forces the fallback.
    """
    if os.environ.get("SEAMTRACK_EMBREE", "").lower() == "embreex":
        return None
    for path in _candidates():
        try:
            lib = Library(path)
        except (OSError, AttributeError):
            continue
        if lib.version_major == 4:
            return lib
    return None


class Scene:
    """A committed Embree scene of one triangle mesh (float32 vertices, as given).

    Embree owns copies of the buffers; the scene is released with this object.
    """

    def __init__(self, lib: Library, vertices: NDArray[Any], faces: NDArray[Any]) -> None:
        v = np.ascontiguousarray(vertices, dtype=np.float32)
        f = np.ascontiguousarray(faces, dtype=np.uint32)
        scene = lib.new_scene(lib.device)
        lib.scene_flags(scene, _SCENE_FLAG_ROBUST)
        geometry = lib.new_geometry(lib.device, _GEOMETRY_TRIANGLE)
        vbuf = lib.new_buffer(geometry, _VERTEX_BUFFER, 0, _FORMAT_FLOAT3, 12, len(v))
        ibuf = lib.new_buffer(geometry, _INDEX_BUFFER, 0, _FORMAT_UINT3, 12, len(f))
        if not (scene and geometry and vbuf and ibuf):
            raise MemoryError(f"Embree could not allocate a scene of {len(f)} triangles")
        ctypes.memmove(vbuf, v.ctypes.data, v.nbytes)
        ctypes.memmove(ibuf, f.ctypes.data, f.nbytes)
        lib.commit_geometry(geometry)
        lib.attach_geometry(scene, geometry)
        lib.release_geometry(geometry)  # the scene holds it now
        lib.commit_scene(scene)
        error = lib.device_error(lib.device)
        if error:
            lib.release_scene(scene)
            raise RuntimeError(f"Embree error {error} while building a scene")
        self.handle = int(scene)
        self.lib = lib
        weakref.finalize(self, lib.release_scene, scene)

    def intersect(
        self, origins: NDArray[Any], directions: NDArray[Any]
    ) -> tuple[NDArray[np.int32], NDArray[np.float32]]:
        """First hits: (primID (n,), tfar (n,)); primID -1 on a miss.

        ``origins`` (1, 3) shared or (n, 3); ``directions`` (n, 3); any float dtype, rounded to
        float32 as Embree takes them.
        """
        n = len(directions)
        prim = np.empty(n, dtype=np.int32)
        tfar = np.empty(n, dtype=np.float32)
        intersect(self.lib.intersect8, self.handle, origins, directions, prim, tfar)
        return prim, tfar

    def occluded(
        self, origins: NDArray[Any], directions: NDArray[Any], far: NDArray[Any]
    ) -> NDArray[np.bool_]:
        """True where a ray meets the mesh within (0, far]."""
        blocked = np.empty(len(directions), dtype=np.bool_)
        occluded(self.lib.occluded_query, self.lib.occluded_width, self.handle, origins,
                 directions, far, 0.0, blocked)  # fmt: skip
        return blocked


# --------------------------------------------------------------------------- numba kernels
@numba.njit(**KERNEL, inline="always")
def _packet_buffer() -> tuple[NDArray[np.float32], NDArray[np.uint32], NDArray[np.int32], int,
                              int]:  # fmt: skip
    """A 64-byte aligned RTCRayHit8 or RTCRayHit16 and its valid mask: float and uint views,
    addresses."""
    raw = np.empty(_WORDS + WIDE + _ALIGN // 4, dtype=np.uint32)
    skip = ((_ALIGN - raw.ctypes.data % _ALIGN) % _ALIGN) // 4
    words = raw[skip : skip + _WORDS + WIDE]
    return (words[:_WORDS].view(np.float32), words[:_WORDS], words[_WORDS:].view(np.int32),
            words.ctypes.data, words.ctypes.data + 4 * _WORDS)  # fmt: skip


@numba.njit(**KERNEL, inline="always")
def _load_ray(
    f: NDArray[np.float32], u: NDArray[np.uint32], j: int, origins: NDArray[Any],
    directions: NDArray[Any], i: int, tnear: float, tfar: float, width: int,
) -> None:  # fmt: skip
    """Write ray i into lane j of a packet of width (float32 rounding, as numpy's astype)."""
    io = i if origins.shape[0] > 1 else 0
    for a in range(3):
        f[(_ORG + a) * width + j] = np.float32(origins[io, a])
        f[(_DIR + a) * width + j] = np.float32(directions[i, a])
    f[_TNEAR * width + j] = np.float32(tnear)
    f[_TIME * width + j] = np.float32(0.0)
    f[_TFAR * width + j] = np.float32(tfar)
    u[_MASK * width + j] = _INVALID
    u[_ID * width + j] = 0
    u[_FLAGS * width + j] = 0
    u[_GEOM * width + j] = _INVALID
    u[_INST * width + j] = _INVALID


@numba.njit(**KERNEL)
def _trace(
    query: int, width: int, scene: int, origins: NDArray[Any], directions: NDArray[Any],
    tnear: float, far: NDArray[Any], prim: NDArray[np.int32], tfar: NDArray[np.float32],
) -> None:  # fmt: skip
    """Rays i over [tnear, far[i]] (``far`` (n,) or (1,)), width (8 or 16) per call of ``query``
    (the address of the query of packets of width); fills primID (-1: no hit) and tfar (the hit
    distance; -inf after an occlusion query that met the mesh)."""
    f, u, valid, packet, mask = _packet_buffer()
    n = directions.shape[0]
    for start in range(0, n, width):
        lanes = min(width, n - start)
        for j in range(width):
            valid[j] = -1 if j < lanes else 0
            if j < lanes:
                i = start + j
                length = far[i] if far.shape[0] > 1 else far[0]
                _load_ray(f, u, j, origins, directions, i, tnear, length, width)
        _call_query(query, mask, scene, packet, 0)
        for j in range(lanes):
            hit = u[_GEOM * width + j] != _INVALID
            prim[start + j] = np.int32(u[_PRIM * width + j]) if hit else -1
            tfar[start + j] = f[_TFAR * width + j]


@numba.njit(**KERNEL)
def intersect(
    intersect8: Any, scene: int, origins: NDArray[Any], directions: NDArray[Any],
    prim: NDArray[np.int32], tfar: NDArray[np.float32],
) -> None:  # fmt: skip
    """First hit of each ray (``rtcIntersect8``): primID (-1 on a miss) and distance."""
    _trace(intersect8, W, scene, origins, directions, 0.0, np.full(1, np.inf), prim, tfar)


@numba.njit(**KERNEL)
def occluded(
    query: int, width: int, scene: int, origins: NDArray[Any], directions: NDArray[Any],
    far: NDArray[Any], tnear: float, blocked: NDArray[np.bool_],
) -> None:  # fmt: skip
    """``blocked[i]``: ray i meets the mesh within [tnear, far[i]] (``query`` the address of
    ``rtcOccluded8`` or ``rtcOccluded16``, ``width`` its packet: ``Library.occluded_query``
    and ``Library.occluded_width``)."""
    n = directions.shape[0]
    prim = np.empty(n, dtype=np.int32)
    tfar = np.empty(n, dtype=np.float32)
    _trace(query, width, scene, origins, directions, tnear, far, prim, tfar)
    for i in range(n):
        blocked[i] = tfar[i] == -np.inf
