"""The V-groove extractor's model, compiled: the V (:mod:`seamtrack.features.vkernels`), its
root ends and top edges, the plates beside the bevels, what lies between the root ends
(:mod:`seamtrack.features.vroot`), the seam point, its confidence and the share of the profile
the model explains, in one call (:meth:`seamtrack.features.vgroove.VGrooveExtractor._extract`).

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import math

import numba
import numpy as np

from seamtrack.features.counts import explained_share
from seamtrack.features.vkernels import (
    NONE,
    arms,
    contains,
    corner_with,
    dot_dir,
    first,
    groups_of,
    last,
    new_table,
    owners,
    pmax,
    pmin,
    point,
    surface_of,
)
from seamtrack.features.vroot import (
    at_depth,
    bridged,
    continued,
    covered_end,
    gap_seen,
    plate_depth,
)

#: A bevel within this angle of a plate runs along it (deg): a quarter of the flattest V's
#: opening off the straight (150 deg included: bevels 15 deg off the plates).
ALONG_DEG = 7.5
COS_ALONG = math.cos(math.radians(ALONG_DEG))
#: A plate beside a bevel starts within this distance of the bevel's top edge (mm).
PLATE_REACH_MM = 1.5
#: At most this share of the kept points lies between the bevels' lower ends (the root).
MAX_ROOT_SHARE = 0.35


@numba.njit(cache=True, nogil=True)
def group_of(tb, piece, groups):
    """The group (collinear pieces joined) that holds record ``piece``, else the piece."""
    if piece == NONE:
        return NONE
    i = first(tb, piece)
    for g in groups:
        if contains(tb, g, i):
            return g
    return piece


@numba.njit(cache=True, nogil=True)
def plates_beside(points, tb, groups, arm, met, lo, hi, left, right, lo_l):
    """The plates beside bevel ``arm`` among kept points ``lo:hi``, as two records (-1:
    none). A plate turns away from its bevel (pieces along the bevel are more bevel) and
    starts at the top edge: the piece ``met`` there (when it is a group) and the largest
    group beyond it whose nearest point lies within :data:`PLATE_REACH_MM` of where its line
    crosses the bevel's (a plate bent at the edge shows both; a plate beyond a raised block
    is not beside the block's wall)."""
    if met != NONE:
        grouped = False
        for g in groups:
            grouped = grouped or g == met
        if not grouped or met == left or met == right or abs(dot_dir(tb, met, arm)) > COS_ALONG:
            met = NONE
    largest, count = NONE, 0
    span, pool = tb[1], tb[2]
    for g in groups:
        if g == left or g == right or abs(dot_dir(tb, g, arm)) > COS_ALONG:
            continue
        c = 0
        for q in range(span[g, 0], span[g, 0] + span[g, 1]):
            c += lo <= pool[q] < hi
        if c > count:
            largest, count = g, c
    if largest != NONE:
        inside_first, inside_last = -1, -1
        for q in range(span[largest, 0], span[largest, 0] + span[largest, 1]):
            if lo <= pool[q] < hi:
                if inside_first < 0:
                    inside_first = pool[q]
                inside_last = pool[q]
        near = inside_last if hi <= lo_l else inside_first
        geo = tb[0]
        ay, az, ady, adz = geo[largest, 0], geo[largest, 1], geo[largest, 2], geo[largest, 3]
        by, bz, bdy, bdz = geo[arm, 0], geo[arm, 1], geo[arm, 2], geo[arm, 3]
        d = ady * bdz - adz * bdy
        if abs(d) < 1e-9:
            largest = NONE
        else:
            s = ((by - ay) * bdz - (bz - az) * bdy) / d
            ey, ez = ay + s * ady, az + s * adz
            if math.hypot(points[near, 0] - ey, points[near, 1] - ez) > PLATE_REACH_MM:
                largest = NONE
    if largest == NONE or largest == met:
        return met, NONE
    return (largest, NONE) if met == NONE else (met, largest)


@numba.njit(cache=True, nogil=True)
def _steep_beside(tb, own, other, arm):
    """A side with no plate of its own (``own``) running along the other side's plate."""
    if own[0] != NONE:
        return False
    for p in other:
        if p != NONE and abs(dot_dir(tb, p, arm)) > COS_ALONG:
            return True
    return False


@numba.njit(cache=True, nogil=True)
def vgroove(
    points,
    stray,
    columns,
    runs,
    tol,
    sigma,
    spacing,
    index,
    along,
    centroids,
    directions,
    fits,
    params,
):
    """:meth:`VGrooveExtractor._extract` after segmentation, on the profile's pieces
    (:func:`~seamtrack.features.vkernels.flat_lines`: ``index`` .. ``fits``; separate
    arguments, as a tuple costs microseconds to dispatch). ``params``: min points,
    min arm (mm), min and max included angle (deg), max gap (mm), min gap (mm), pieces as
    arms (0/1), gapless (0/1).

    The model of a groove: plates (the piece met at each top edge and the largest group
    beyond it, :func:`plates_beside`) outside the bevels, the bevels, and the root between
    them (left out of the share explained). At least one plate must show, a bevel without a
    plate of its own may not lie along the other's (within :data:`ALONG_DEG`), and the root
    may hold at most :data:`MAX_ROOT_SHARE` of the points: two faces alone are a fillet or a
    corner, a face along the plate is plate (a step, a raised block's foot), and a groove's
    root is narrow. The root ends, the covered ends and the gap are read by
    :mod:`seamtrack.features.vroot`.

    Returns (13,): code (0 found; 1 no V; 2 no plate; 3 a side along a plate; 4 a wide
    root, its share in [12]), seam y, z, confidence, gap, top edges (y, z) left and right,
    the share explained, the included angle (rad), the seam's mean depth below the plates.
    """
    tb = new_table(index, along, centroids, directions, fits)
    n = fits.shape[0]
    out = np.empty(13)
    for k in range(13):
        out[k] = np.nan
    min_points, min_arm = int(params[0]), params[1]
    m = points.shape[0]
    surface = surface_of(stray, m)
    owner = np.empty(m, dtype=np.int64)  # each point's piece
    span, pool, geo = tb[1], tb[2], tb[0]
    owners(owner, span, pool, n)
    groups = groups_of(points, tb, n, tol, min_points, min_arm)
    left, right, ax, az, _ = arms(
        points,
        surface,
        owner,
        tb,
        groups,
        n,
        -1.0,
        params[2],
        params[3],
        params[4],
        tol,
        params[6] != 0,
        min_points,
        min_arm,
    )
    if left == NONE:
        out[0] = 1
        return out
    others = np.empty(n + 2, dtype=np.int64)
    k_others = 0
    for k in range(n):
        if span[k, 1] >= min_points:
            others[k_others] = k
            k_others += 1
    others[k_others], others[k_others + 1] = left, right
    others = others[: k_others + 2]
    # Column order runs left to right: the left bevel's root end is its last point.
    ey, ez, _ = corner_with(tb, left, True, others, spacing, tol)
    lx, lz = continued(points, tb, n, left, True, ax, az, ey, ez, tol)
    ey, ez, _ = corner_with(tb, right, False, others, spacing, tol)
    rx, rz = continued(points, tb, n, right, False, ax, az, ey, ez, tol)
    top_ly, top_lz, plate_l = corner_with(tb, left, False, others, spacing, tol)
    top_ry, top_rz, plate_r = corner_with(tb, right, True, others, spacing, tol)
    out[5], out[6], out[7], out[8] = top_ly, top_lz, top_ry, top_rz
    plate_l, plate_r = group_of(tb, plate_l, groups), group_of(tb, plate_r, groups)
    # The model: plates outside the bevels, the bevels, the root between them left out.
    lo_l, hi_l = first(tb, left), last(tb, left) + 1
    lo_r, hi_r = first(tb, right), last(tb, right) + 1
    outer_l = plates_beside(points, tb, groups, left, plate_l, 0, lo_l, left, right, lo_l)
    outer_r = plates_beside(points, tb, groups, right, plate_r, hi_r, m, left, right, lo_l)
    if outer_l[0] == NONE and outer_r[0] == NONE:
        out[0] = 2
        return out
    if _steep_beside(tb, outer_l, outer_r, left) or _steep_beside(tb, outer_r, outer_l, right):
        out[0] = 3
        return out
    if hi_l < lo_r and lo_r - hi_l > MAX_ROOT_SHARE * m:
        out[0], out[12] = 4, 100 * (lo_r - hi_l) / m
        return out
    ref_l = plate_l if plate_l != NONE else plate_r
    ref_r = plate_r if plate_r != NONE else plate_l
    cov_l, l0, l1 = covered_end(points, tb, n, left, True, right, ref_l, tol, spacing, sigma)
    cov_r, r0, r1 = covered_end(points, tb, n, right, False, left, ref_r, tol, spacing, sigma)
    sure = True
    if cov_l or cov_r:
        # A covered end is at least where the bevel is last seen; the shallower root end goes
        # down to the other's depth, within the stretch where it may lie.
        if cov_l:
            lx, lz = point(tb, left, l0)
        if cov_r:
            rx, rz = point(tb, right, r0)
        if ref_l != NONE and ref_r != NONE:
            d_l, d_r = plate_depth(tb, ref_l, lx, lz), plate_depth(tb, ref_r, rx, rz)
            if cov_l and d_l < d_r:
                (lx, lz), sure = at_depth(tb, left, ref_l, d_r, l0, l1), False
            elif cov_r and d_r < d_l:
                (rx, rz), sure = at_depth(tb, right, ref_r, d_l, r0, r1), False
        else:  # no plate to measure depth on: the middle of the stretch
            if cov_l:
                (lx, lz), sure = point(tb, left, 0.5 * (l0 + l1)), False
            if cov_r:
                (rx, rz), sure = point(tb, right, 0.5 * (r0 + r1)), False
    gap = math.hypot(rx - lx, rz - lz)
    if gap <= pmax(params[5], 2.0 * spacing + tol) or params[7] != 0:
        sy, sz, gap = ax, az, 0.0
    elif not gap_seen(
        points,
        stray,
        surface,
        columns,
        runs,
        tb,
        n,
        left,
        right,
        lx,
        lz,
        rx,
        rz,
        ax,
        az,
        ref_l,
        ref_r,
        gap,
        cov_l or cov_r,
        min_points,
        tol,
        spacing,
    ):
        # No gap shows between the bevels' lower ends: they end where spikes, dropouts or a
        # fill take over, not at the root. Their intersection is the best estimate.
        sy, sz, gap, sure = ax, az, np.nan, False
    else:
        sy, sz = 0.5 * (lx + rx), 0.5 * (lz + rz)
        if bridged(tb, n, left, right, lx, lz, rx, rz, ref_l, min_points, tol, spacing):
            sure = False
    # Confidence (_confidence): the bevels' share of the points, scaled by their fit.
    share = (span[left, 1] + span[right, 1]) / max(m, 1)
    fit = pmax(0.0, 1.0 - pmax(geo[left, 4], geo[right, 4]) / tol)
    conf = pmin(pmax(0.5 * share + 0.5 * fit, 0.0), 1.0)
    out[0], out[1], out[2], out[3], out[4] = 0, sy, sz, conf * (1.0 if sure else 0.5), gap
    # included(): the angle between the arms from the apex to their centroids.
    vay, vaz = geo[left, 0] - ax, geo[left, 1] - az
    vby, vbz = geo[right, 0] - ax, geo[right, 1] - az
    c = (vay * vby + vaz * vbz) / max(math.hypot(vay, vaz) * math.hypot(vby, vbz), 1e-300)
    out[10] = math.acos(pmin(1.0, pmax(-1.0, c)))
    depth, plates = 0.0, 0
    for p in (outer_l[0], outer_l[1], outer_r[0], outer_r[1]):
        if p != NONE:
            depth += plate_depth(tb, p, sy, sz)
            plates += 1
    out[11] = depth / plates
    # explained(): the plates and bevels beside the root, the root left out.
    zones = np.zeros((5, 3), dtype=np.int64)
    bounds = (0, lo_l, hi_l, lo_r, hi_r, m)
    for k in range(5):
        zones[k, 0], zones[k, 1], zones[k, 2] = bounds[k], bounds[k + 1], k != 2
    fits = np.zeros((5, 3, 4))
    for k, side, arm in ((0, outer_l, left), (4, outer_r, right)):
        for p in (side[0], side[1], arm):
            if p != NONE:
                j = zones[k, 2] - 1
                fits[k, j, 0], fits[k, j, 1] = geo[p, 0], geo[p, 1]
                fits[k, j, 2], fits[k, j, 3] = -geo[p, 3], geo[p, 2]
                zones[k, 2] += 1
        zones[k, 2] -= 1
    for k, arm in ((1, left), (3, right)):
        fits[k, 0, 0], fits[k, 0, 1] = geo[arm, 0], geo[arm, 1]
        fits[k, 0, 2], fits[k, 0, 3] = -geo[arm, 3], geo[arm, 2]
    out[9] = explained_share(points, surface, zones, fits, 3.0 * tol)
    return out
