"""The pieces of a profile that lie on plates, compiled (:func:`plate_pieces`): the first step
of the two-plate search (:mod:`seamtrack.features.plates._two_plate_search`).

Flat pieces are grouped by the line they lie on as
:func:`seamtrack.features.lines.collinear_members` groups them (best supported first, each
joining the earliest group whose anchor holds both its ends); a line spanning
``min_plate_mm`` is a plate line. The pieces are passed as
:class:`~seamtrack.features.plates._two_lines.PieceLines` and per-piece arrays.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numba
import numpy as np

from seamtrack.features.arrays import FloatArray, IntArray
from seamtrack.features.line_geometry import holds
from seamtrack.features.plates._two_lines import PieceLines, median, piece_line
from seamtrack.jit import KERNEL


class PlateLimits(NamedTuple):
    """What the search asks of plates and pairs (the extractor's parameters): pieces of
    ``min_points`` within ``max_tilt_deg`` of the y axis, plates spanning
    ``min_plate_mm``, facing ends within ``max_gap_mm``; a square butt (``butt``) wants an
    opening of ``min_opening`` and an open gap of ``min_open_mm`` (a bottom
    ``min_bottom_mm`` behind the plates is open), a lap a step of ``min_step_mm``."""

    min_points: int
    min_plate_mm: float
    max_tilt_deg: float
    max_gap_mm: float
    butt: bool
    min_opening: float
    min_open_mm: float
    min_bottom_mm: float
    min_step_mm: float


class PlatePieces(NamedTuple):
    """The pieces on plates in column order (:func:`plate_pieces`): each one's plate line
    (``plate``) and the piece (``piece``), and each plate line's anchor piece
    (``anchor``)."""

    plate: IntArray
    piece: IntArray
    anchor: IntArray


@numba.njit(**KERNEL, error_model="numpy")
def _order(keys: IntArray) -> IntArray:
    """Stable ascending order of a few keys (an insertion sort: small code, where numba's
    sorts made the kernel slow to compile)."""
    n = keys.shape[0]
    o = np.arange(n)
    for i in range(1, n):
        x = o[i]
        j = i
        while j > 0 and keys[o[j - 1]] > keys[x]:
            o[j] = o[j - 1]
            j -= 1
        o[j] = x
    return o


@numba.njit(**KERNEL, error_model="numpy")
def span(
    lines: PieceLines, t_first: FloatArray, t_last: FloatArray, on: int, members: IntArray
) -> float:
    """Extent along piece ``on``'s line of the pieces ``members`` (from their ends)."""
    ly, lz, ldy, ldz = piece_line(lines, on)
    lo = math.inf
    hi = -math.inf
    for p in members:
        c = (lines.cy[p] - ly) * ldy + (lines.cz[p] - lz) * ldz
        d = lines.dy[p] * ldy + lines.dz[p] * ldz
        for x in (c + d * t_first[p], c + d * t_last[p]):
            lo = min(lo, x)
            hi = max(hi, x)
    return hi - lo


class FlatGroups(NamedTuple):
    """The flat pieces (positions among the pieces, best supported first), each one's group
    of pieces on one line (a position in ``anchors``) and each group's anchor piece."""

    flat: IntArray
    group: IntArray
    anchors: IntArray


@numba.njit(**KERNEL, error_model="numpy")
def _flat_groups(
    lines: PieceLines,
    count: IntArray,
    t_first: FloatArray,
    t_last: FloatArray,
    limits: PlateLimits,
    tol: float,
) -> FlatGroups:
    """Flat pieces (``limits.min_points``, within ``limits.max_tilt_deg`` of the y axis),
    grouped by the line they lie on (collinear_members: best supported first, each joins the
    earliest group whose anchor holds both its ends)."""
    nl = lines.cy.shape[0]
    tilt = math.radians(limits.max_tilt_deg)
    flat = np.empty(nl, dtype=np.int64)
    nf = 0
    for j in range(nl):
        if count[j] >= limits.min_points and abs(math.atan2(lines.dz[j], lines.dy[j])) <= tilt:
            flat[nf] = j
            nf += 1
    flat = flat[:nf]
    minus = np.empty(nf, dtype=np.int64)
    for o in range(nf):
        minus[o] = -count[flat[o]]
    order = _order(minus)
    cos_max = math.cos(math.radians(30.0))
    group = np.empty(nf, dtype=np.int64)  # each flat piece's group (position in flat)
    anchors = np.empty(nf, dtype=np.int64)  # each group's anchor (a piece)
    ng = 0
    for o in order:
        i = flat[o]
        line = piece_line(lines, i)
        joined = -1
        for k in range(ng):
            if holds(piece_line(lines, anchors[k]), line, t_first[i], t_last[i], cos_max, tol):
                joined = k
                break
        if joined < 0:
            anchors[ng] = i
            joined = ng
            ng += 1
        group[o] = joined
    return FlatGroups(flat, group, anchors[:ng])


class Block(NamedTuple):
    """A block of plate pieces ``[start, end)`` (-1, -1: none)."""

    start: int
    end: int


@numba.njit(**KERNEL, error_model="numpy")
def _weakest_brief_block(
    lines: PieceLines,
    count: IntArray,
    t_first: FloatArray,
    t_last: FloatArray,
    pg: IntArray,
    pl: IntArray,
    plate_anchor: IntArray,
    limits: PlateLimits,
) -> Block:
    """Of the blocks of one plate line showing between two stretches of another and tilted
    to it, far behind it (square butt) or too short, the one with the fewest inliers."""
    ten = math.radians(10.0)
    n = pg.shape[0]
    best_c, bi, bj = 0, -1, -1
    i = 1
    while i < n - 1:
        j = i
        while j < n and pg[j] == pg[i]:
            j += 1
        if j < n and pg[i - 1] == pg[j]:
            host = plate_anchor[pg[j]]
            b0 = pl[i]
            c = abs(lines.dy[b0] * lines.dy[host] + lines.dz[b0] * lines.dz[host])
            tilted = math.acos(min(1.0, c)) > ten
            hy, hz, hdy, hdz = piece_line(lines, host)
            flip = not hy * -hdz + hz * hdy < 0
            heights = np.empty(j - i)
            for r in range(i, j):
                h = (lines.cy[pl[r]] - hy) * -hdz + (lines.cz[pl[r]] - hz) * hdy
                heights[r - i] = -h if flip else h
            behind = -median(heights) >= limits.min_bottom_mm if limits.butt else False
            short = span(lines, t_first, t_last, plate_anchor[pg[i]], pl[i:j]) < limits.min_plate_mm
            if tilted or behind or short:
                cnt = 0
                for r in range(i, j):
                    cnt += count[pl[r]]
                if bi < 0 or cnt < best_c:
                    best_c, bi, bj = cnt, i, j
        i = j
    return Block(bi, bj)


@numba.njit(**KERNEL, error_model="numpy")
def plate_pieces(
    lines: PieceLines,
    count: IntArray,
    t_first: FloatArray,
    t_last: FloatArray,
    first: IntArray,
    limits: PlateLimits,
    tol: float,
) -> PlatePieces:
    """The pieces that lie on plates, in column order (``first``: each piece's first
    inlier): flat pieces (``limits.min_points``, within ``limits.max_tilt_deg`` of the y
    axis) grouped by the line they lie on, the lines spanning ``limits.min_plate_mm``
    plates; a plate line showing only briefly between two stretches of another is no plate
    there."""
    flat, group, anchors = _flat_groups(lines, count, t_first, t_last, limits, tol)
    # Plate lines span min_plate_mm; their pieces in column order.
    ng = anchors.shape[0]
    plate_of = np.full(ng, -1, dtype=np.int64)  # collinear group -> plate line
    plate_anchor = np.empty(ng, dtype=np.int64)
    npl = 0
    for k in range(ng):
        members = flat[group == k]
        if span(lines, t_first, t_last, anchors[k], members) >= limits.min_plate_mm:
            plate_of[k] = npl
            plate_anchor[npl] = anchors[k]
            npl += 1
    on_plate = plate_of[group] >= 0
    pg = plate_of[group][on_plate]  # each plate piece's plate line
    pl = flat[on_plate]  # and the piece
    srt = _order(first[pl])  # in column order
    pg, pl = pg[srt], pl[srt]
    n = pg.shape[0]
    # A plate line showing briefly between two stretches of another, tilted to it, far
    # behind it or too short, is no plate there; of competing blocks the smallest goes.
    while True:
        bi, bj = _weakest_brief_block(lines, count, t_first, t_last, pg[:n], pl[:n],
                                      plate_anchor, limits)  # fmt: skip
        if bi < 0:
            break
        for o in range(bj, n):
            pg[o - (bj - bi)], pl[o - (bj - bi)] = pg[o], pl[o]
        n -= bj - bi
    return PlatePieces(pg[:n], pl[:n], plate_anchor)
