"""The laser fan as one plane section of the mesh: exact float64 first hits, no Embree.

Every ray of the fan starts at the emitter and lies in the laser plane x_L = 0, so the stripe is
the visible part of one plane section of the part. A :class:`SectionIndex` (a bounding-volume
hierarchy over the triangles, built once per mesh in numba) finds the triangles the plane
crosses inside the fan's wedge; each is cut to a 2-D segment (y_L, z_L) in float64 straight
from the float64 vertices; and the fan's rays are cast against the segments in 2-D: each
segment covers a run of consecutive rays (the fan is sorted by tan(phi) = y_L / z_L), found by
binary search on its end points' angles, and each of those rays keeps its nearest crossing.

The hit is the exact intersection of the float64 ray with the float64 triangle's plane (to a few
ulp), the same point that :mod:`seamtrack.sensing.raycast` refines Embree's float32 hit to; what
follows (field of view, incidence, the camera on the lit side, the shadow rays and the pixels)
is the mesh-mode stripe's own kernels (:mod:`seamtrack.sensing.kernels`), so the reasons are the
same. The shadow rays from the lit points to the camera do not lie in the laser plane: they stay
on Embree (occlusion queries; ``RayCaster.occluded_local``).

Rays through a segment's end (a triangle edge crossing the plane) hit the segment whose
parameter is within :data:`END_SLACK` of [0, 1]: never neither. A triangle lying in the laser
plane is grazed, not hit (as the float64 refinement treats it), and a triangle that touches the
plane at one vertex only is skipped.
"""

from __future__ import annotations

from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from seamtrack.jit import KERNEL
from seamtrack.sensing._section_tree import LEAF_SIZE, SectionIndex, build
from seamtrack.sensing.kernels import (
    HitMesh,
    fan_directions,
    fan_stripe_hits,
    packet_shadows_finish,
)

__all__ = ["LEAF_SIZE", "SectionIndex", "build", "fan_stripe_section",
           "fan_stripe_section_packets", "fan_tans", "hit_faces", "section_hits",
           "section_segments"]  # fmt: skip


#: A crossing at a segment's end counts for the segment within this fraction of its length.
END_SLACK = 1e-12
#: Boxes within this distance (mm) of the plane or of the fan's wedge are opened (conservative).
BOX_SLACK_MM = 1e-6
#: The ray parameter of "no crossing".
NO_HIT = np.inf
#: A vertex closer to the laser plane than this (mm) lies on it (rounding of the frame change
#: is ~1e-13 mm at the parts' sizes).
ON_PLANE_MM = 1e-9
#: Rays per block of the running maxima of the hits (:func:`section_hits` culls against them).
BLOCK = 32
#: :func:`section_hits` starts culling nodes behind the hits found after cutting this many
#: triangles, seeds included (on a small section the tests cost more than they save; on a
#: large one the seeds, the last frame's hit triangles, make the culling's bounds tight early).
CULL_AFTER = 96
#: A stripe that lights more triangles than this seeds nothing (a fine mesh: each seed would
#: be cut twice, for culling that on its small triangles gains less: +13 us a profile on the
#: raycast bench's 101k-triangle plate); pipe-saddle's stripe lights 10-17.
MAX_SEEDS = 64
#: No seeds (:func:`_section_hits`).
NO_SEEDS = np.empty(0, dtype=np.int64)


# --------------------------------------------------------------------------- the section
@numba.njit(**KERNEL, inline="always")
def _box_outside(
    lo: NDArray[np.float64], hi: NDArray[np.float64], node: int, o: NDArray[np.float64],
    m0: float, m1: float, m2: float,
) -> float:  # fmt: skip
    """min over the box of m . (p - o): > 0 means the whole box is on the positive side."""
    c0 = 0.5 * (lo[node, 0] + hi[node, 0]) - o[0]
    c1 = 0.5 * (lo[node, 1] + hi[node, 1]) - o[1]
    c2 = 0.5 * (lo[node, 2] + hi[node, 2]) - o[2]
    h0 = 0.5 * (hi[node, 0] - lo[node, 0])
    h1 = 0.5 * (hi[node, 1] - lo[node, 1])
    h2 = 0.5 * (hi[node, 2] - lo[node, 2])
    return m0 * c0 + m1 * c1 + m2 * c2 - (abs(m0) * h0 + abs(m1) * h1 + abs(m2) * h2)


@numba.njit(**KERNEL, inline="always")
def _edge_point(
    xa: float, ya: float, za: float, xb: float, yb: float, zb: float
) -> tuple[float, float]:  # fmt: skip
    """Where the edge a-b (x of opposite signs) crosses x_L = 0."""
    s = xa / (xa - xb)
    return ya + s * (yb - ya), za + s * (zb - za)


@numba.njit(**KERNEL, inline="always")
def _cut(
    vertices: NDArray[np.float64], faces: NDArray[np.int64], k: int, o: NDArray[np.float64],
    r: NDArray[np.float64],
) -> tuple[bool, float, float, float, float]:  # fmt: skip
    """Triangle k cut by the plane x_L = 0: (crossed, y0, z0, y1, z1) in the laser frame."""
    a, b, c = faces[k, 0], faces[k, 1], faces[k, 2]
    ax, ay, az = vertices[a, 0] - o[0], vertices[a, 1] - o[1], vertices[a, 2] - o[2]
    bx, by, bz = vertices[b, 0] - o[0], vertices[b, 1] - o[1], vertices[b, 2] - o[2]
    cx, cy, cz = vertices[c, 0] - o[0], vertices[c, 1] - o[1], vertices[c, 2] - o[2]
    xa = r[0, 0] * ax + r[1, 0] * ay + r[2, 0] * az
    xb = r[0, 0] * bx + r[1, 0] * by + r[2, 0] * bz
    xc = r[0, 0] * cx + r[1, 0] * cy + r[2, 0] * cz
    # A vertex within rounding of the plane lies on it, and counts as in front of it (a
    # symbolic perturbation, x -> x + eps): a face in the plane, or one touching it along an
    # edge or at a vertex from the front, is grazed; a surface that continues across the
    # plane along an edge is cut by exactly one of the edge's two triangles.
    if abs(xa) <= ON_PLANE_MM:
        xa = 0.0
    if abs(xb) <= ON_PLANE_MM:
        xb = 0.0
    if abs(xc) <= ON_PLANE_MM:
        xc = 0.0
    behind = (xa < 0.0) + (xb < 0.0) + (xc < 0.0)
    if behind == 0 or behind == 3:
        return False, 0.0, 0.0, 0.0, 0.0
    ya = r[0, 1] * ax + r[1, 1] * ay + r[2, 1] * az
    yb = r[0, 1] * bx + r[1, 1] * by + r[2, 1] * bz
    yc = r[0, 1] * cx + r[1, 1] * cy + r[2, 1] * cz
    za = r[0, 2] * ax + r[1, 2] * ay + r[2, 2] * az
    zb = r[0, 2] * bx + r[1, 2] * by + r[2, 2] * bz
    zc = r[0, 2] * cx + r[1, 2] * cy + r[2, 2] * cz
    # The two edges from behind to in front: their crossings (a vertex on the plane itself).
    found = 0
    p0y = p0z = p1y = p1z = 0.0
    for j in range(3):
        if j == 0:
            x0, y0, z0, x1, y1, z1 = xa, ya, za, xb, yb, zb
        elif j == 1:
            x0, y0, z0, x1, y1, z1 = xb, yb, zb, xc, yc, zc
        else:
            x0, y0, z0, x1, y1, z1 = xc, yc, zc, xa, ya, za
        if (x0 < 0.0) == (x1 < 0.0):
            continue
        if x0 == 0.0:
            py, pz = y0, z0
        elif x1 == 0.0:
            py, pz = y1, z1
        else:
            py, pz = _edge_point(x0, y0, z0, x1, y1, z1)
        if found == 0:
            p0y, p0z = py, pz
        else:
            p1y, p1z = py, pz
        found += 1
    if found != 2 or (p0y == p1y and p0z == p1z):  # a vertex touched from behind: a point
        return False, 0.0, 0.0, 0.0, 0.0
    return True, p0y, p0z, p1y, p1z


@numba.njit(**KERNEL, inline="always")
def _ray_range(
    tans: NDArray[np.float64], step: float, y0: float, z0: float, y1: float, z1: float
) -> tuple[int, int]:  # fmt: skip
    """The rays [first, last) whose angle lies within the segment's (with a margin);
    ``step`` the rays' even spacing in tan (:func:`_even_step`), 0 if uneven."""
    if z0 <= 0.0 and z1 <= 0.0:
        return 0, 0
    if z0 > 0.0 and z1 > 0.0:
        ta, tb = y0 / z0, y1 / z1
        t_lo, t_hi = min(ta, tb), max(ta, tb)
    else:  # one end behind the emitter's line z_L = 0: the rest spans to one side's infinity
        if z0 > 0.0:
            t_pos = y0 / z0
        else:
            t_pos = y1 / z1
        y_cross = y0 + (0.0 - z0) / (z1 - z0) * (y1 - y0)
        if y_cross > 0.0:
            t_lo, t_hi = t_pos, np.inf
        elif y_cross < 0.0:
            t_lo, t_hi = -np.inf, t_pos
        else:
            t_lo, t_hi = -np.inf, np.inf
    return _tan_range(tans, step, t_lo, t_hi)


@numba.njit(**KERNEL, inline="always")
def _tan_range(
    tans: NDArray[np.float64], step: float, t_lo: float, t_hi: float
) -> tuple[int, int]:  # fmt: skip
    """The rays [first, last) whose tan(phi) lies within [t_lo, t_hi] (with a margin)."""
    n = tans.shape[0]
    margin_lo = 1e-9 * (1.0 + abs(t_lo)) if np.isfinite(t_lo) else 0.0
    margin_hi = 1e-9 * (1.0 + abs(t_hi)) if np.isfinite(t_hi) else 0.0
    if step > 0.0:
        # Evenly spaced: the index from the angle, a ray wider on each side than the binary
        # search's (its result +- 1 ray of rounding), so never fewer rays.
        first = 0
        if t_lo > -np.inf:
            u = (t_lo - margin_lo - tans[0]) / step
            first = int(max(min(np.floor(u), n), 0.0))
        last = n
        if t_hi < np.inf:
            u = (t_hi + margin_hi - tans[0]) / step
            last = int(max(min(np.floor(u) + 1.0, n), 0.0))
        return max(first - 2, 0), min(last + 2, n)
    first = int(np.searchsorted(tans, t_lo - margin_lo))
    last = int(np.searchsorted(tans, t_hi + margin_hi, side="right"))
    return max(first - 1, 0), min(last + 1, n)


#: A fan whose rays' tan(phi) lie within this fraction of their spacing of an even grid is
#: evenly spaced (:func:`_even_step`): the rays a segment covers are then found by arithmetic.
EVEN_RTOL = 1e-6


@numba.njit(**KERNEL)
def _even_step(tans: NDArray[np.float64]) -> float:
    """The spacing of ``tans`` (sorted) when evenly spaced (within :data:`EVEN_RTOL` of it),
    else 0: the laser fan (:func:`seamtrack.sensing.scan.laser_fan`, a ``linspace`` in tan)."""
    n = tans.shape[0]
    if n < 2:
        return 0.0
    step = (tans[n - 1] - tans[0]) / (n - 1)
    if not step > 0.0:
        return 0.0
    for i in range(n):
        if abs(tans[i] - (tans[0] + i * step)) > EVEN_RTOL * step:
            return 0.0
    return step


@numba.njit(**KERNEL, inline="always")
def _sweep(
    fan: NDArray[np.float64], first: int, last: int, y0: float, z0: float, y1: float,
    z1: float, k: int, best_t: NDArray[np.float64], best_f: NDArray[np.int64],
) -> None:  # fmt: skip
    """Rays first..last-1 from the emitter against the segment: keep each ray's nearest (of
    two at the same distance, the lower triangle index: the order segments come in does not
    matter)."""
    ey, ez = y1 - y0, z1 - z0
    for i in range(first, last):
        dy, dz = fan[i, 1], fan[i, 2]
        det = ey * dz - dy * ez
        if det == 0.0:
            continue  # the ray runs along the segment: grazing
        sign = 1.0 if det > 0.0 else -1.0
        a_det = det * sign
        t_det = (ey * z0 - y0 * ez) * sign
        s_det = (dy * z0 - dz * y0) * sign
        if s_det < -END_SLACK * a_det or s_det > (1.0 + END_SLACK) * a_det:
            continue
        t = t_det / a_det
        if t > 0.0 and (t < best_t[i] or (t == best_t[i] and k < best_f[i])):
            best_t[i] = t
            best_f[i] = k


@numba.njit(**KERNEL)
def _visit(
    lo: NDArray[np.float64], hi: NDArray[np.float64], child: NDArray[np.int64],
    count: NDArray[np.int64], order: NDArray[np.int64], o: NDArray[np.float64],
    rotation: NDArray[np.float64], tan_max: float,
) -> tuple[NDArray[np.int64], int]:  # fmt: skip
    """The leaves whose box meets the laser plane inside the fan's wedge: (leaves, how many)."""
    n0, n1, n2 = rotation[0, 0], rotation[1, 0], rotation[2, 0]
    # The wedge |y_L| <= tan_max z_L as two half-spaces m . (p - o) <= 0.
    a0 = rotation[0, 1] - tan_max * rotation[0, 2]
    a1 = rotation[1, 1] - tan_max * rotation[1, 2]
    a2 = rotation[2, 1] - tan_max * rotation[2, 2]
    b0 = -rotation[0, 1] - tan_max * rotation[0, 2]
    b1 = -rotation[1, 1] - tan_max * rotation[1, 2]
    b2 = -rotation[2, 1] - tan_max * rotation[2, 2]
    leaves = np.empty(1024, dtype=np.int64)
    stack = np.empty(128, dtype=np.int64)
    stack[0] = 0
    top = 1
    found = 0
    while top > 0:
        top -= 1
        node = stack[top]
        if _box_outside(lo, hi, node, o, n0, n1, n2) > BOX_SLACK_MM:
            continue
        if _box_outside(lo, hi, node, o, -n0, -n1, -n2) > BOX_SLACK_MM:
            continue
        if _box_outside(lo, hi, node, o, a0, a1, a2) > BOX_SLACK_MM:
            continue
        if _box_outside(lo, hi, node, o, b0, b1, b2) > BOX_SLACK_MM:
            continue
        if count[node] > 0:
            if found == leaves.shape[0]:
                grown = np.empty(2 * leaves.shape[0], dtype=np.int64)
                grown[:found] = leaves[:found]
                leaves = grown
            leaves[found] = node
            found += 1
        else:
            stack[top] = child[node]
            stack[top + 1] = child[node] + 1
            top += 2
    return leaves, found


@numba.njit(**KERNEL, inline="always")
def _box_distance2(
    lo: NDArray[np.float64], hi: NDArray[np.float64], node: int, o: NDArray[np.float64]
) -> float:  # fmt: skip
    """The squared distance from ``o`` to the node's box (0 inside)."""
    d2 = 0.0
    for a in range(3):
        d = max(lo[node, a] - o[a], 0.0, o[a] - hi[node, a])
        d2 += d * d
    return d2


@numba.njit(**KERNEL, inline="always")
def _box_rays(
    lo: NDArray[np.float64], hi: NDArray[np.float64], node: int, o: NDArray[np.float64],
    rotation: NDArray[np.float64], tans: NDArray[np.float64], step: float,
) -> tuple[int, int]:  # fmt: skip
    """The rays [first, last) that may meet the node's box: the box's (y_L, z_L) as intervals,
    their angles' range (a superset)."""
    cy = cz = hy = hz = 0.0
    for a in range(3):
        c = 0.5 * (lo[node, a] + hi[node, a]) - o[a]
        h = 0.5 * (hi[node, a] - lo[node, a])
        cy += rotation[a, 1] * c
        cz += rotation[a, 2] * c
        hy += abs(rotation[a, 1]) * h
        hz += abs(rotation[a, 2]) * h
    y_lo, y_hi, z_lo, z_hi = cy - hy, cy + hy, cz - hz, cz + hz
    if not z_lo > 0.0:  # the box reaches the emitter's line z_L = 0: every ray may
        return 0, tans.shape[0]
    t_lo = min(y_lo / z_lo, y_lo / z_hi)
    t_hi = max(y_hi / z_lo, y_hi / z_hi)
    return _tan_range(tans, step, t_lo, t_hi)


@numba.njit(**KERNEL, inline="always")
def _farthest(
    best_t: NDArray[np.float64], block_max: NDArray[np.float64], stale: NDArray[np.bool_],
    first: int, last: int,
) -> float:  # fmt: skip
    """An upper bound of the nearest hits of rays [first, last): the maxima of their blocks
    (a stale block's recomputed)."""
    far = -np.inf
    n = best_t.shape[0]
    for b in range(first // BLOCK, (last - 1) // BLOCK + 1):
        if stale[b]:
            m = -np.inf
            for i in range(b * BLOCK, min((b + 1) * BLOCK, n)):
                m = max(m, best_t[i])
            block_max[b] = m
            stale[b] = False
        far = max(far, block_max[b])
    return far


@numba.njit(**KERNEL)
def fan_tans(fan: NDArray[np.float64]) -> tuple[NDArray[np.float64], float, float]:
    """What :func:`section_hits` needs of a fan besides its directions, once per fan: each
    ray's tan(phi) = y_L / z_L, the wedge's half-opening in tan (a margin added) and the rays'
    even spacing in tan (:func:`_even_step`; 0: uneven)."""
    n = fan.shape[0]
    tans = np.empty(n)
    tan_max = 0.0
    for i in range(n):
        tans[i] = fan[i, 1] / fan[i, 2]
        tan_max = max(tan_max, abs(tans[i]))
    return tans, tan_max * (1.0 + 1e-9) + 1e-9, _even_step(tans)


@numba.njit(**KERNEL)
def section_hits(
    tree: SectionIndex, mesh: HitMesh, origin: NDArray[np.float64],
    rotation: NDArray[np.float64], fan: NDArray[np.float64],
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:  # fmt: skip
    """First hit of each fan ray: (t (n,), triangle (n,)); (inf, -1) where none.

    ``origin`` (3,) is the emitter and ``vertices`` the mesh in the same (local) frame;
    ``rotation`` (3, 3) the laser frame's axes; ``fan`` (n, 3) unit directions in the laser
    frame, x_L = 0, sorted by y_L / z_L, all with z_L > 0.

    The hierarchy is walked nearer child first, and a node farther from the emitter than the
    hits already found on every ray that may meet it is not opened (a crossing in it could
    only be farther): behind the visible surface (a pipe's far wall, its inside) nothing is
    cut. Which crossings win does not depend on the order (:func:`_sweep`).
    """
    tans, tan_max, step = fan_tans(fan)
    t, face, _ = _section_hits(tree, mesh, origin, rotation, fan, tans, tan_max, step, NO_SEEDS)
    return t, face


@numba.njit(**KERNEL)
def hit_faces(face: NDArray[np.int64]) -> NDArray[np.int64]:
    """The triangles a stripe's rays hit (``face``, -1: none), each run of rays on one
    triangle once: the seeds of the next frame's :func:`_section_hits`."""
    out = np.empty(face.shape[0], dtype=np.int64)
    k = 0
    last = -1
    for f in face:
        if f >= 0 and f != last:
            out[k] = f
            k += 1
        last = f
    return out[:k].copy()


@numba.njit(**KERNEL, inline="always")
def _cut_and_sweep(
    vertices: NDArray[np.float64], faces: NDArray[np.int64], k: int, o: NDArray[np.float64],
    rotation: NDArray[np.float64], fan: NDArray[np.float64], tans: NDArray[np.float64],
    step: float, best_t: NDArray[np.float64], best_f: NDArray[np.int64],
) -> tuple[int, int]:  # fmt: skip
    """Triangle k cut and its segment swept by the rays it may meet: the rays [first, last)
    (first >= last: none)."""
    crossed, y0, z0, y1, z1 = _cut(vertices, faces, k, o, rotation)
    if not crossed:
        return 0, 0
    first, last = _ray_range(tans, step, y0, z0, y1, z1)
    if first < last:
        _sweep(fan, first, last, y0, z0, y1, z1, k, best_t, best_f)
    return first, last


@numba.njit(**KERNEL)
def _section_hits(
    tree: SectionIndex, mesh: HitMesh, origin: NDArray[np.float64],
    rotation: NDArray[np.float64], fan: NDArray[np.float64], tans: NDArray[np.float64],
    tan_max: float, step: float, seeds: NDArray[np.int64],
) -> tuple[NDArray[np.float64], NDArray[np.int64], int]:  # fmt: skip
    """:func:`section_hits` with the fan's :func:`fan_tans` given, and how many triangles it
    cut; ``seeds``: triangles (of this mesh) cut first, before the hierarchy is walked (the
    last frame's :func:`hit_faces`: at 100 Hz most of this frame's visible surface). They
    count towards :data:`CULL_AFTER`, and their crossings are true crossings, so once the walk
    culls, it culls behind them; which crossings win does not depend on the seeds (each is
    cut once: met again in the walk it is skipped), only how much is cut."""
    lo, hi, child, count, order = tree
    vertices, faces = mesh.vertices, mesh.faces
    n = fan.shape[0]
    best_t = np.full(n, NO_HIT)
    best_f = np.full(n, -1, dtype=np.int64)
    blocks = (n + BLOCK - 1) // BLOCK
    block_max = np.full(blocks, NO_HIT)
    stale = np.ones(blocks, dtype=np.bool_)
    seeded = np.sort(seeds)  # met again in the walk, a seed is skipped (binary search)
    for k in seeded:
        _cut_and_sweep(vertices, faces, k, origin, rotation, fan, tans, step, best_t, best_f)
    r = rotation
    n0, n1, n2 = r[0, 0], r[1, 0], r[2, 0]
    # The wedge |y_L| <= tan_max z_L as two half-spaces m . (p - o) <= 0.
    a0, a1, a2 = (
        r[0, 1] - tan_max * r[0, 2],
        r[1, 1] - tan_max * r[1, 2],
        r[2, 1] - tan_max * r[2, 2],
    )
    b0, b1, b2 = (
        -r[0, 1] - tan_max * r[0, 2],
        -r[1, 1] - tan_max * r[1, 2],
        -r[2, 1] - tan_max * r[2, 2],
    )
    stack = np.empty(128, dtype=np.int64)
    stack[0] = 0
    top = 1
    cuts = seeds.shape[0]  # the seeds count towards CULL_AFTER: their hits bound the culling
    culling = cuts >= CULL_AFTER
    while top > 0:
        top -= 1
        node = stack[top]
        if (
            _box_outside(lo, hi, node, origin, n0, n1, n2) > BOX_SLACK_MM
            or _box_outside(lo, hi, node, origin, -n0, -n1, -n2) > BOX_SLACK_MM
            or _box_outside(lo, hi, node, origin, a0, a1, a2) > BOX_SLACK_MM
            or _box_outside(lo, hi, node, origin, b0, b1, b2) > BOX_SLACK_MM
        ):
            continue
        if count[node] == 0:
            if culling:
                first, last = _box_rays(lo, hi, node, origin, rotation, tans, step)
                if first >= last:
                    continue
                # A crossing in the box is at least its distance from the emitter (rounding of the
                # hits' distances allowed for); the leaves are cut without this test.
                far = _farthest(best_t, block_max, stale, first, last)
                near2 = _box_distance2(lo, hi, node, origin)
                if far < NO_HIT and near2 * (1.0 - 1e-9) > (far + 1e-9) * (far + 1e-9):
                    continue
            c = child[node]
            if _box_distance2(lo, hi, c, origin) <= _box_distance2(lo, hi, c + 1, origin):
                stack[top], stack[top + 1] = c + 1, c
            else:
                stack[top], stack[top + 1] = c, c + 1
            top += 2
            continue
        cuts += count[node]
        if not culling and cuts >= CULL_AFTER:
            culling = True
            stale[:] = True
        for m in range(child[node], child[node] + count[node]):
            k = order[m]
            if seeded.shape[0]:
                j = np.searchsorted(seeded, k)
                if j < seeded.shape[0] and seeded[j] == k:
                    continue
            first, last = _cut_and_sweep(vertices, faces, k, origin, rotation, fan, tans, step,
                                         best_t, best_f)  # fmt: skip
            if culling and first < last:
                for b in range(first // BLOCK, (last - 1) // BLOCK + 1):
                    stale[b] = True
    return best_t, best_f, cuts


@numba.njit(**KERNEL)
def section_segments(
    tree: SectionIndex, mesh: HitMesh, origin: NDArray[np.float64],
    rotation: NDArray[np.float64], tan_max: float,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:  # fmt: skip
    """The plane section inside the wedge |y_L| <= tan_max z_L (and maybe a little more):
    segments (k, 4) = (y0, z0, y1, z1) in the laser frame and their triangles (k,)."""
    lo, hi, child, count, order = tree
    vertices, faces = mesh.vertices, mesh.faces
    leaves, found = _visit(lo, hi, child, count, order, origin, rotation, tan_max)
    segs = np.empty((found * 4, 4))
    tri = np.empty(found * 4, dtype=np.int64)
    k_out = 0
    for j in range(found):
        node = leaves[j]
        for m in range(child[node], child[node] + count[node]):
            k = order[m]
            crossed, y0, z0, y1, z1 = _cut(vertices, faces, k, origin, rotation)
            if crossed:
                segs[k_out, 0], segs[k_out, 1], segs[k_out, 2], segs[k_out, 3] = y0, z0, y1, z1
                tri[k_out] = k
                k_out += 1
    return segs[:k_out].copy(), tri[:k_out].copy()


# --------------------------------------------------------------------------- the stripe
@numba.njit(**KERNEL)
def fan_stripe_section(
    tree: SectionIndex, mesh: HitMesh, origin: NDArray[np.float64],
    rotation: NDArray[np.float64], fan: NDArray[np.float64], tans: NDArray[np.float64],
    tan_max: float, step: float, sp: NDArray[np.float64], offset: float,
    seeds: NDArray[np.int64],
) -> tuple[NDArray[np.float64], NDArray[np.uint8], NDArray[np.float64], NDArray[np.int64],
           NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64],
           NDArray[np.float64], NDArray[np.int64], NDArray[np.float64],
           NDArray[np.int64]]:  # fmt: skip
    """The section's hits through the stripe's clips (``fan_stripe_hits``); returns its ten
    arrays, the rays' directions in the local frame and the next frame's seeds (the
    triangles hit, :func:`hit_faces`, where the walk cut at least :data:`CULL_AFTER`: on a
    smaller section culling never starts, and seeds would only be cut twice; and at most
    :data:`MAX_SEEDS`). The shadow rays
    are the caller's. ``tans, tan_max, step``: the fan's :func:`fan_tans`; ``seeds``:
    :func:`_section_hits`'."""
    directions = fan_directions(rotation, fan)
    t, face, cuts = _section_hits(tree, mesh, origin, rotation, fan, tans, tan_max, step, seeds)
    none = np.empty(0, dtype=np.int64)
    next_seeds = hit_faces(face) if cuts >= CULL_AFTER else none
    if next_seeds.shape[0] > MAX_SEEDS:
        next_seeds = none
    points, reason, t, face, cos_incidence, chip, s_o, s_d, s_far, s_index = fan_stripe_hits(
        origin, rotation, fan, directions, t, face, mesh.face_normals, sp, offset,
    )  # fmt: skip
    return (points, reason, t, face, cos_incidence, chip, s_o, s_d, s_far, s_index, directions,
            next_seeds)  # fmt: skip


@numba.njit(**KERNEL)
def fan_stripe_section_packets(
    occluded: Any, width: int, scene: int, tree: SectionIndex, mesh: HitMesh,
    origin: NDArray[np.float64], rotation: NDArray[np.float64], fan: NDArray[np.float64],
    tans: NDArray[np.float64], tan_max: float, step: float, sp: NDArray[np.float64],
    offset: float, quantize: bool, seeds: NDArray[np.int64],
) -> tuple[NDArray[np.float64], NDArray[np.uint8], NDArray[np.float64], NDArray[np.int64],
           NDArray[np.float64], NDArray[np.float64], NDArray[np.int64]]:  # fmt: skip
    """The whole noiseless stripe in one call: the section's hits, the clips, the shadow rays
    on Embree packets (``occluded``, the address of the query of packets of ``width``:
    ``Library.occluded_query``, ``Library.occluded_width``) and the pixels. Returns (points,
    reason, t, face, cos_incidence, directions), as ``kernels.fan_stripe_packets``, and the
    next frame's seeds (:func:`fan_stripe_section`'s). ``tans, tan_max, step``: the fan's
    :func:`fan_tans`; ``seeds``: :func:`_section_hits`'."""
    points, reason, t, face, cos_incidence, chip, s_o, s_d, s_far, s_index, directions, nxt = (
        fan_stripe_section(tree, mesh, origin, rotation, fan, tans, tan_max, step, sp, offset,
                           seeds)
    )  # fmt: skip
    packet_shadows_finish(occluded, width, scene, s_o, s_d, s_far, s_index, points, reason, chip,
                          sp, quantize)  # fmt: skip
    return points, reason, t, face, cos_incidence, directions, nxt
