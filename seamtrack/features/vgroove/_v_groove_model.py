"""The V-groove extractor's model, compiled: the V (:mod:`seamtrack.features.vgroove._v_search`),
its root ends and top edges, the plates beside the bevels, what lies between the root ends
(:mod:`seamtrack.features.vgroove._v_root`), the seam point, its confidence and the share of the
profile the model explains, in one call (:func:`v_groove`, for
:meth:`seamtrack.features.vgroove.extractor.VGrooveExtractor._extract`).

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import math
from typing import NamedTuple, cast

import numba
import numpy as np

from seamtrack.features.counts import (
    LINE_CY,
    LINE_CZ,
    LINE_NY,
    LINE_NZ,
    ZONE_HI,
    ZONE_LINES,
    ZONE_LO,
    explained_share,
)
from seamtrack.features.vgroove._v_root import (
    Bevels,
    KeptPoints,
    Root,
    RootEnds,
    at_depth,
    bridged,
    continued,
    covered_end,
    gap_seen,
    plate_depth,
)
from seamtrack.features.vgroove._v_search import (
    COUNT,
    CY,
    CZ,
    FIRST_END,
    LAST_END,
    NONE,
    RMS,
    UY,
    UZ,
    SearchParams,
    contains,
    corner_with,
    dot_dir,
    first,
    last,
    pmax,
    pmin,
    point,
    search,
)
from seamtrack.jit import KERNEL

#: A bevel within this angle of a plate runs along it (deg): a quarter of the flattest V's
#: opening off the straight (150 deg included: bevels 15 deg off the plates).
ALONG_DEG = 7.5
COS_ALONG = math.cos(math.radians(ALONG_DEG))
#: A plate beside a bevel starts within this distance of the bevel's top edge (mm).
PLATE_REACH_MM = 1.5
#: At most this share of the kept points lies between the bevels' lower ends (the root).
MAX_ROOT_SHARE = 0.35
#: The zones of the share explained, in column order.
_PLATE_L, _BEVEL_L, _ROOT, _BEVEL_R, _PLATE_R = range(5)

#: What the model found (:attr:`VGrooveResult.code`): a groove; no V; no plate beside the
#: bevels; a side of the V along a plate; a root wider than :data:`MAX_ROOT_SHARE`.
#: (int64, not literals: numba compiles a kernel called with a literal once for each value)
GROOVE, NO_V, NO_PLATE, SIDE_ALONG_PLATE, WIDE_ROOT = (cast(int, np.int64(c)) for c in range(5))
#: An int64 0 (a literal 0 would compile ``plates_beside`` twice).
_ZERO = cast(int, np.int64(0))


class GrooveParams(NamedTuple):
    """The V-groove extractor's parameters as the model reads them: the V search's for the
    bevels (a V opening towards the sensor, ``max_reach`` the widest root gap, the tracker's
    hint when there is one), the narrowest root gap (mm) and whether no gap is expected."""

    search: SearchParams
    min_gap: float
    gapless: bool


class VGrooveResult(NamedTuple):
    """What the model found: ``code`` (:data:`GROOVE` or why not), the seam point (y, z),
    its confidence, the root gap (mm; 0: the bevels meet, NaN: no gap shows), the top edges
    (left y, z; right y, z), the share of the profile the model explains, the included angle
    (rad), the seam's mean depth below the plates (mm) and, for :data:`WIDE_ROOT`, the
    share (%) of the profile between the bevels' lower ends. NaN where not reached."""

    code: int
    seam_y: float
    seam_z: float
    confidence: float
    gap: float
    top_left_y: float
    top_left_z: float
    top_right_y: float
    top_right_z: float
    explained: float
    angle: float
    depth: float
    root_share: float


class SidePlates(NamedTuple):
    """The plates beside a bevel (records; :data:`NONE`: none): the one met at its top
    edge, else the largest, and a second one beyond it."""

    near: int
    far: int


@numba.njit(**KERNEL)
def group_of(tb, piece, groups):
    """The group (collinear pieces joined) that holds record ``piece``, else the piece."""
    if piece == NONE:
        return NONE
    i = first(tb, piece)
    for g in groups:
        if contains(tb, g, i):
            return g
    return piece


@numba.njit(**KERNEL)
def plates_beside(points, tb, groups, arm, met, lo, hi, left, right, lo_l):
    """The plates beside bevel ``arm`` among kept points ``lo:hi``, as two records
    (:class:`SidePlates`; -1: none). A plate turns away from its bevel (pieces along the
    bevel are more bevel) and starts at the top edge: the piece ``met`` there (when it is a
    group) and the largest group beyond it whose nearest point lies within
    :data:`PLATE_REACH_MM` of where its line crosses the bevel's (a plate bent at the edge
    shows both; a plate beyond a raised block is not beside the block's wall)."""
    if met != NONE:
        grouped = False
        for g in groups:
            grouped = grouped or g == met
        if not grouped or met == left or met == right or abs(dot_dir(tb, met, arm)) > COS_ALONG:
            met = NONE
    largest, count = NONE, 0
    span, pool = tb.span, tb.index
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
        geo = tb.geo
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
        return SidePlates(met, NONE)
    return SidePlates(largest, NONE) if met == NONE else SidePlates(met, largest)


@numba.njit(**KERNEL)
def _steep_beside(tb, own, other, arm):
    """A side with no plate of its own (``own``) running along the other side's plate."""
    if own.near != NONE:
        return False
    for p in (other.near, other.far):
        if p != NONE and abs(dot_dir(tb, p, arm)) > COS_ALONG:
            return True
    return False


@numba.njit(**KERNEL)
def _refused(code, root_share=math.nan):
    """A :class:`VGrooveResult` that says why there is no groove (called with an int64
    ``code`` and a float: one compiled signature, where a literal code compiles one a code)."""
    nan = math.nan
    return VGrooveResult(code, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, root_share)


@numba.njit(**KERNEL)
def _others(tb, n, min_points, left, right):
    """The lines a bevel may meet at a corner: the pieces with ``min_points`` inliers, and
    the two bevels."""
    others = np.empty(n + 2, dtype=np.int64)
    k_others = 0
    for k in range(n):
        if tb.span[k, COUNT] >= min_points:
            others[k_others] = k
            k_others += 1
    others[k_others], others[k_others + 1] = left, right
    return others[: k_others + 2]


@numba.njit(**KERNEL)
def _covered_root(points, tb, n, bevels, ends, ref_l, ref_r, tol, spacing, sigma):
    """The root ends where a stray line covers one (:func:`~._v_root.covered_end`): a
    covered end is at least where the bevel is last seen; the shallower root end goes down
    to the other's depth below the plates, within the stretch where it may lie (the middle
    of the stretch with no plate to measure depth on); a :class:`Root`."""
    left, right = bevels.left, bevels.right
    lx, lz, rx, rz = ends
    cov_l = covered_end(points, tb, n, left, LAST_END, right, ref_l, tol, spacing, sigma)
    cov_r = covered_end(points, tb, n, right, FIRST_END, left, ref_r, tol, spacing, sigma)
    sure = True
    if cov_l.covered or cov_r.covered:
        if cov_l.covered:
            lx, lz = point(tb, left, cov_l.t0)
        if cov_r.covered:
            rx, rz = point(tb, right, cov_r.t0)
        if ref_l != NONE and ref_r != NONE:
            d_l, d_r = plate_depth(tb, ref_l, lx, lz), plate_depth(tb, ref_r, rx, rz)
            if cov_l.covered and d_l < d_r:
                (lx, lz), sure = at_depth(tb, left, ref_l, d_r, cov_l.t0, cov_l.t1), False
            elif cov_r.covered and d_r < d_l:
                (rx, rz), sure = at_depth(tb, right, ref_r, d_l, cov_r.t0, cov_r.t1), False
        else:  # no plate to measure depth on: the middle of the stretch
            if cov_l.covered:
                (lx, lz), sure = point(tb, left, 0.5 * (cov_l.t0 + cov_l.t1)), False
            if cov_r.covered:
                (rx, rz), sure = point(tb, right, 0.5 * (cov_r.t0 + cov_r.t1)), False
    return Root(RootEnds(lx, lz, rx, rz), cov_l.covered or cov_r.covered, sure)


@numba.njit(**KERNEL)
def _explained(points, surface, tb, bevels, outer_l, outer_r, tol):
    """``explained()``: the share of the surface points on the plates and bevels beside the
    root, the root left out."""
    geo = tb.geo
    left, right = bevels.left, bevels.right
    m = points.shape[0]
    lo_l, hi_l = first(tb, left), last(tb, left) + 1
    lo_r, hi_r = first(tb, right), last(tb, right) + 1
    # Zones: the left plate(s), the left bevel, the root (no line), the right bevel, the
    # right plate(s); a plate's zone holds its bevel's line too.
    zones = np.zeros((5, 3), dtype=np.int64)
    bounds = (0, lo_l, hi_l, lo_r, hi_r, m)
    for k in range(5):
        zones[k, ZONE_LO], zones[k, ZONE_HI] = bounds[k], bounds[k + 1]
        zones[k, ZONE_LINES] = k != _ROOT
    fits = np.zeros((5, 3, 4))
    for k, side, arm in ((_PLATE_L, outer_l, left), (_PLATE_R, outer_r, right)):
        for p in (side.near, side.far, arm):
            if p != NONE:
                line = fits[k, zones[k, ZONE_LINES] - 1]
                line[LINE_CY], line[LINE_CZ] = geo[p, CY], geo[p, CZ]
                line[LINE_NY], line[LINE_NZ] = -geo[p, UZ], geo[p, UY]
                zones[k, ZONE_LINES] += 1
        zones[k, ZONE_LINES] -= 1
    for k, arm in ((_BEVEL_L, left), (_BEVEL_R, right)):
        line = fits[k, 0]
        line[LINE_CY], line[LINE_CZ] = geo[arm, CY], geo[arm, CZ]
        line[LINE_NY], line[LINE_NZ] = -geo[arm, UZ], geo[arm, UY]
    return explained_share(points, surface, zones, fits, 3.0 * tol)


@numba.njit(**KERNEL)
def v_groove(points, stray, columns, runs, tol, sigma, spacing, pieces, params):
    """:meth:`VGrooveExtractor._extract` after segmentation, on the profile's kept points
    (the fields of a :class:`~._v_root.KeptPoints`, loose: numba reads a named tuple from
    Python in about a microsecond, its arrays in a tenth of that) and pieces
    (:class:`~seamtrack.features._segmentation.PieceTable`), with the extractor's
    :class:`GrooveParams`; a :class:`VGrooveResult`.

    The model of a groove, in its steps: the V (:func:`~._v_search.search`); its root ends
    (where each bevel's corner lies towards the apex, or the bevel goes on past spikes:
    :func:`~._v_root.continued`) and top edges (the corners at its other ends, the plates
    met there); the plates beside the bevels (the piece met at each top edge and the largest
    group beyond it, :func:`plates_beside`). At least one plate must show, a bevel without
    a plate of its own may not lie along the other's (within :data:`ALONG_DEG`), and the root
    may hold at most :data:`MAX_ROOT_SHARE` of the points: two faces alone are a fillet or a
    corner, a face along the plate is plate (a step, a raised block's foot), and a groove's
    root is narrow. Then the root ends a stray line covers (:func:`_covered_root`), the gap
    between the ends (:func:`~._v_root.gap_seen`: else the bevels' intersection is the seam),
    the confidence, the included angle, the depth below the plates and the share of the
    profile the model explains (the root left out).
    """
    kept = KeptPoints(points, stray, columns, runs)
    found = search(points, stray, tol, pieces, params.search)
    tb, groups, surface, pair = found.table, found.groups, found.surface, found.pair
    n = pieces.fits.shape[0]
    m = points.shape[0]
    geo, min_points = tb.geo, params.search.min_points
    if pair.left == NONE:
        return _refused(NO_V, math.nan)
    bevels = Bevels(pair.left, pair.right, pair.apex_y, pair.apex_z)
    left, right, ax, az = bevels
    others = _others(tb, n, min_points, left, right)
    # Column order runs left to right: the left bevel's root end is its last point.
    root_l = corner_with(tb, left, LAST_END, others, spacing, tol)
    lx, lz = continued(points, tb, n, left, LAST_END, ax, az, root_l.y, root_l.z, tol)
    root_r = corner_with(tb, right, FIRST_END, others, spacing, tol)
    rx, rz = continued(points, tb, n, right, FIRST_END, ax, az, root_r.y, root_r.z, tol)
    top_l = corner_with(tb, left, FIRST_END, others, spacing, tol)
    top_r = corner_with(tb, right, LAST_END, others, spacing, tol)
    plate_l, plate_r = group_of(tb, top_l.line, groups), group_of(tb, top_r.line, groups)
    # The model: plates outside the bevels, the bevels, the root between them left out.
    lo_l, hi_l = first(tb, left), last(tb, left) + 1
    lo_r, hi_r = first(tb, right), last(tb, right) + 1
    outer_l = plates_beside(points, tb, groups, left, plate_l, _ZERO, lo_l, left, right, lo_l)
    outer_r = plates_beside(points, tb, groups, right, plate_r, hi_r, m, left, right, lo_l)
    if outer_l.near == NONE and outer_r.near == NONE:
        return _refused(NO_PLATE, math.nan)
    if _steep_beside(tb, outer_l, outer_r, left) or _steep_beside(tb, outer_r, outer_l, right):
        return _refused(SIDE_ALONG_PLATE, math.nan)
    if hi_l < lo_r and lo_r - hi_l > MAX_ROOT_SHARE * m:
        return _refused(WIDE_ROOT, 100 * (lo_r - hi_l) / m)
    ref_l = plate_l if plate_l != NONE else plate_r
    ref_r = plate_r if plate_r != NONE else plate_l
    root = _covered_root(
        points, tb, n, bevels, RootEnds(lx, lz, rx, rz), ref_l, ref_r, tol, spacing, sigma
    )
    ends, sure = root.ends, root.sure
    lx, lz, rx, rz = ends
    gap = math.hypot(rx - lx, rz - lz)
    if gap <= pmax(params.min_gap, 2.0 * spacing + tol) or params.gapless:
        sy, sz, gap = ax, az, 0.0
    elif not gap_seen(
        kept, surface, tb, n, bevels, root, ref_l, ref_r, gap, min_points, tol, spacing
    ):
        # No gap shows between the bevels' lower ends: they end where spikes, dropouts or a
        # fill take over, not at the root. Their intersection is the best estimate.
        sy, sz, gap, sure = ax, az, np.nan, False
    else:
        sy, sz = 0.5 * (lx + rx), 0.5 * (lz + rz)
        if bridged(tb, n, bevels, ends, ref_l, min_points, tol, spacing):
            sure = False
    # Confidence (line_confidence): the bevels' share of the points, scaled by their fit.
    share = (tb.span[left, COUNT] + tb.span[right, COUNT]) / max(m, 1)
    fit = pmax(0.0, 1.0 - pmax(geo[left, RMS], geo[right, RMS]) / tol)
    conf = pmin(pmax(0.5 * share + 0.5 * fit, 0.0), 1.0)
    # included(): the angle between the arms from the apex to their centroids.
    vay, vaz = geo[left, CY] - ax, geo[left, CZ] - az
    vby, vbz = geo[right, CY] - ax, geo[right, CZ] - az
    c = (vay * vby + vaz * vbz) / max(math.hypot(vay, vaz) * math.hypot(vby, vbz), 1e-300)
    angle = math.acos(pmin(1.0, pmax(-1.0, c)))
    depth, plates = 0.0, 0
    for p in (outer_l.near, outer_l.far, outer_r.near, outer_r.far):
        if p != NONE:
            depth += plate_depth(tb, p, sy, sz)
            plates += 1
    return VGrooveResult(
        GROOVE,
        sy,
        sz,
        conf * (1.0 if sure else 0.5),
        gap,
        top_l.y,
        top_l.z,
        top_r.y,
        top_r.z,
        _explained(points, surface, tb, bevels, outer_l, outer_r, tol),
        angle,
        depth / plates,
        math.nan,
    )
