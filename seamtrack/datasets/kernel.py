"""The stripe of an extruded cross-section, exactly, in one numba call per profile.

Why not Embree: a dataset draws a new joint for every sample, and building an Embree scene per
sample costs more than the whole profile may (the target is 4,000 labelled profiles a second
per core). The joint is an extrusion along the seam (x_S), so the first hit of a 3D ray
``o + t d`` is the first crossing of its (y, z) projection with the section's segments, at the
same parameter t: a 2D ray / segment test, exact in float64, with no mesh and no float32 stage.
Everything after the hit is the mesh-mode stripe itself: these exact hits go through the kernels
of :mod:`seamtrack.sensing.kernels` (``fan_stripe_hits``: field of view and depth of field,
incidence, the camera on the lit side, the shadow rays from ``SHADOW_RAY_OFFSET_MM`` off the
point to the camera centre; ``fan_stripe_finish``: occlusion and pixel quantization), with the
shadow rays cast by the same 2D test. A test holds the result equal to
:func:`seamtrack.sensing.scan.scan_mesh` on the extruded mesh of the same section.
"""

from __future__ import annotations

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.jit import KERNEL
from seamtrack.sensing.kernels import fan_directions, fan_stripe_finish, fan_stripe_hits

#: A crossing at a segment's end counts for the segment within this fraction of its length
#: (rays through a shared vertex hit one of the two segments, never neither).
END_SLACK = 1e-12
#: Hits closer to the ray origin than this (mm) are the origin's own surface.
T_MIN_MM = 1e-9
#: The ray parameter of "no crossing" (finite, so that comparisons stay plain arithmetic).
NO_HIT = 1e300


@numba.njit(**KERNEL)
def ray_segment_crossings(
    oy: NDArray[np.float64], oz: NDArray[np.float64], dy: NDArray[np.float64],
    dz: NDArray[np.float64], segs: NDArray[np.float64], t_min: float, t_max: NDArray[np.float64],
    best_t: NDArray[np.float64], best: NDArray[np.int64],
) -> None:  # fmt: skip
    """First crossings of m 2D rays ``o + t d``, t in (t_min, t_max], with the segments, into
    ``best_t`` (:data:`NO_HIT` where none) and ``best`` (-1).

    Segments outside, rays inside: the inner loop has no branch the compiler cannot turn into
    a select, so it runs on SIMD lanes (5x faster than ray by ray over the segments).
    """
    m = oy.shape[0]
    for i in range(m):
        best_t[i] = NO_HIT
        best[i] = -1
    for k in range(segs.shape[0]):
        ay, az = segs[k, 0], segs[k, 1]
        ey, ez = segs[k, 2] - ay, segs[k, 3] - az
        for i in range(m):
            det = ey * dz[i] - dy[i] * ez
            wy, wz = ay - oy[i], az - oz[i]
            sign = 1.0 if det > 0.0 else -1.0
            a_det = det * sign
            t_det = (ey * wz - wy * ez) * sign
            s_det = (dy[i] * wz - dz[i] * wy) * sign
            t = t_det / a_det if a_det > 0.0 else NO_HIT
            inside = (s_det >= -END_SLACK * a_det) & (s_det <= (1.0 + END_SLACK) * a_det)
            take = (a_det > 0.0) & (t > t_min) & (t <= t_max[i]) & (t < best_t[i]) & inside
            best_t[i] = t if take else best_t[i]
            best[i] = k if take else best[i]


@numba.njit(**KERNEL)
def stripe(
    origin: NDArray[np.float64], rotation: NDArray[np.float64], fan: NDArray[np.float64],
    segs: NDArray[np.float64], sp: NDArray[np.float64], offset: float, quantize: bool,
) -> tuple[NDArray[np.float64], NDArray[np.uint8], NDArray[np.float64], NDArray[np.int64],
           NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
    """The noiseless stripe of the laser fan on an extruded section.

    Parameters
    ----------
    origin : (3,) float
        The emitter in the seam frame.
    rotation : (3, 3) float
        The laser frame's axes in the seam frame (``T_seam_sensor[:3, :3]``).
    fan : (n, 3) float
        Unit ray directions in the laser frame (:func:`seamtrack.sensing.scan.laser_fan`).
    segs : (k, 4) float
        The section's segments ``(y0, z0, y1, z1)`` in the seam frame.
    sp : (10,) float
        The sensor as the stripe kernels take it (``laser_fan(...).sensor_params``).
    offset : float
        Shadow rays start this far (mm) from the lit point towards the camera.
    quantize : bool
        Snap the valid points to pixel centres.

    Returns
    -------
    points : (n, 2) float
        (y_L, z_L); the lit point (quantized where valid and ``quantize``), NaN on a miss.
    reason : (n,) uint8
        :class:`~seamtrack.sensing.profiles.Reason` codes.
    t : (n,) float
        Emitter to lit point, mm (NaN on a miss).
    face : (n,) int64
        Segment lit by each ray (-1 on a miss).
    cos_incidence : (n,) float
        |cos| of the angle between the ray and the surface normal (NaN on a miss).
    directions : (n, 3) float
        The rays in the seam frame.
    """
    n = fan.shape[0]
    directions = fan_directions(rotation, fan)
    t_hit = np.empty(n)
    face = np.empty(n, dtype=np.int64)
    ray_segment_crossings(np.full(n, origin[1]), np.full(n, origin[2]),
               np.ascontiguousarray(directions[:, 1]), np.ascontiguousarray(directions[:, 2]),
               segs, T_MIN_MM, np.full(n, NO_HIT), t_hit, face)  # fmt: skip
    # The segments' normals (x component 0: an extrusion), then the mesh-mode stripe's clips
    # on these exact hits.
    normals = np.zeros((segs.shape[0], 3))
    for k in range(segs.shape[0]):
        ey, ez = segs[k, 2] - segs[k, 0], segs[k, 3] - segs[k, 1]
        inv = 1.0 / np.sqrt(ey * ey + ez * ez)
        normals[k, 1], normals[k, 2] = -ez * inv, ey * inv
    points, reason, t, face, cos_incidence, chip, s_origins, s_directions, s_far, s_index = (
        fan_stripe_hits(origin, rotation, fan, directions, t_hit, face, normals, sp, offset)
    )  # fmt: skip
    m = s_index.shape[0]
    blocked_t = np.empty(m)
    blocker = np.empty(m, dtype=np.int64)
    ray_segment_crossings(
        np.ascontiguousarray(s_origins[:, 1]), np.ascontiguousarray(s_origins[:, 2]),
        np.ascontiguousarray(s_directions[:, 1]), np.ascontiguousarray(s_directions[:, 2]),
        segs, 0.0, s_far, blocked_t, blocker,
    )  # fmt: skip
    fan_stripe_finish(points, reason, chip, blocker >= 0, s_index, sp, quantize)
    return points, reason, t, face, cos_incidence, directions


@numba.njit(**KERNEL)
def first_hits(
    origins: NDArray[np.float64], directions: NDArray[np.float64], segs: NDArray[np.float64],
    far: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:  # fmt: skip
    """(t, segment) of the first crossing of each 3D ray (m, 3) with the extruded segments,
    within ``far`` (m,); (:data:`NO_HIT`, -1) where none."""
    m = origins.shape[0]
    t = np.empty(m)
    seg = np.empty(m, dtype=np.int64)
    ray_segment_crossings(np.ascontiguousarray(origins[:, 1]), np.ascontiguousarray(origins[:, 2]),
               np.ascontiguousarray(directions[:, 1]), np.ascontiguousarray(directions[:, 2]),
               segs, T_MIN_MM, far, t, seg)  # fmt: skip
    return t, seg
