"""The V-groove extractor: two bevels opening towards the sensor, and what lies between their
lower ends (a root gap, a stray line over a root corner, or no gap at all).

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from seamtrack.features.base import Zone, _Base, _confidence, explained, included, largest_in
from seamtrack.features.expect import Expect
from seamtrack.features.lines import (
    _WALL_DEG,
    Line,
    Segments,
    _ray_t,
    _towards_sensor,
    corner_or_end,
    corner_with,
    intersect,
)
from seamtrack.features.robust import _median
from seamtrack.sensing.profiles import Feature, Profile

FloatArray = NDArray[np.float64]
#: A bevel within this angle of a plate runs along it (deg): a quarter of the flattest V's
#: opening off the straight (150 deg included: bevels 15 deg off the plates).
_ALONG_DEG = 7.5
#: A plate beside a bevel starts within this distance of the bevel's top edge (mm).
_PLATE_REACH_MM = 1.5
#: At most this share of the kept points lies between the bevels' lower ends (the root).
_MAX_ROOT_SHARE = 0.35


def _covered_end(
    seg: Segments, line: Line, at_end: bool, other: Line, plate: Line | None
) -> tuple[float, float] | None:
    """Where along ``line`` (a bevel) its root end may lie when a stray line covers the
    columns beyond its last seen point (``at_end``: its last inlier, else its first), or
    None when the end is seen.

    The end is covered when the first piece beyond it lies in the next columns (at most
    two columns lost, at most two points off the line in between), is no wall (steep on
    ``plate``: a root face) and no part of ``other`` (the other bevel), and does not run
    on into ``other`` without a jump: a false reflection, in front of or behind the
    surface, which hides where the bevel really ends. Lost columns (the gap, a shadow)
    hide nothing. Returns (t0, t1), coordinates along the line, from the end outwards:
    from the last point seen to where the ray of the stray piece's last point crosses the
    line; or, when at least three points beyond the piece lie on the line again (the bevel
    shows beyond the reflection), from there to the last of them (which may already lie on
    a root face that leaves the line at a small angle). Ends are half a spacing out.
    """
    pts = seg.points
    s = 1 if at_end else -1
    i = int(line.index[-1] if at_end else line.index[0])
    beyond = [ln for ln in seg.lines if (int(ln.index[0]) > i if at_end else int(ln.index[-1]) < i)]
    if not beyond:
        return None
    piece = beyond[0] if at_end else beyond[-1]
    near = int(piece.index[0] if at_end else piece.index[-1])
    far = int(piece.index[-1] if at_end else piece.index[0])
    k = int(np.searchsorted(other.index, near))
    if k < len(other.index) and int(other.index[k]) == near:
        return None  # the other bevel (no gap) or a piece of it
    own = line.index[-11:] if at_end else line.index[:11]
    dphi = _median(np.abs(np.diff(_ray_angle(pts[own]))))
    phi_i, phi_near, phi_far = _ray_angle(pts[[i, near, far]])
    between = pts[min(i, near) + 1 : max(i, near)]
    lost = abs(float(phi_near - phi_i)) / dphi - len(between) - 1 if dphi > 0 else math.inf
    if lost > 2.5 or int((np.abs(_towards_sensor(line, between)) > 2.0 * seg.tol).sum()) > 2:
        return None  # lost columns (the gap, a shadow) or another surface first
    flat = plate.direction if plate is not None else np.array([1.0, 0.0])
    if abs(float(piece.direction @ flat)) <= math.cos(math.radians(_WALL_DEG)):
        return None  # a wall: a root face
    nxt = far + s
    if 0 <= nxt < len(pts):
        held = max(6.0 * seg.spacing, 4.0 * seg.sigma, 0.1)
        on_other = abs(float((pts[nxt] - other.centroid) @ other.normal)) <= 2.0 * seg.tol
        if (
            on_other
            and abs(float(_ray_angle(pts[nxt : nxt + 1])[0] - phi_far)) <= 3.5 * dphi
            and float(np.hypot(*(pts[nxt] - pts[far]))) <= held
        ):
            return None  # runs on into the other bevel: part of the part
    half = s * 0.5 * max(line.step(at_end), seg.spacing)
    t_far = float(_ray_t(line, pts[far].reshape(1, 2))[0]) + half
    # Beyond the stray piece the bevel may show again.
    ahead = pts[far + s :: s][:400] if s > 0 or far > 0 else pts[:0]
    on = np.abs(_towards_sensor(line, ahead)) <= seg.tol
    again = int(np.argmin(on)) if not on.all() else len(on)
    if again >= 3:
        return t_far, float((ahead[again - 1] - line.centroid) @ line.direction) + half
    return float(line.t[-1] if at_end else line.t[0]) + half, t_far


def _ray_angle(q: FloatArray) -> FloatArray:
    """Angles of the emitter's rays (from the origin) through points ``q`` (rad)."""
    return np.arctan2(q[:, 0], q[:, 1])


def _group_of(piece: Line | None, groups: list[Line]) -> Line | None:
    """The group (collinear pieces joined) that holds ``piece``, else the piece itself."""
    if piece is None:
        return None
    first = int(piece.index[0])
    for g in groups:
        k = int(np.searchsorted(g.index, first))
        if k < len(g.index) and int(g.index[k]) == first:
            return g
    return piece


def _plate_depth(plate: Line, q: FloatArray) -> float:
    """Depth of ``q`` behind ``plate``'s line (away from the sensor, at the origin)."""
    (cy, cz), (dy, dz), (qy, qz) = plate.centroid.tolist(), plate.direction.tolist(), q.tolist()
    ny, nz = -dz, dy  # the normal, turned away from the sensor
    if not cy * ny + cz * nz > 0:
        ny, nz = -ny, -nz
    return (qy - cy) * ny + (qz - cz) * nz


@dataclass(frozen=True)
class VGrooveExtractor(_Base):
    """V-groove: two bevels opening towards the sensor, a plate beside at least one of them.
    Seam: the root centre, midpoint of the bevels' lower ends, when a root gap shows between
    them (the ends level, the V's tip below them empty, the columns between them open);
    else the bevels' intersection (confidence halved unless they meet: the bottom is cut up
    by spikes and dropouts, or filled). Edges: the top edges.

    Where a stray line (a false reflection) covers a bevel's root end, the end is hidden:
    it is put at the depth of the other root end below the plates (both root corners lie
    at one depth under their plate: thickness minus root face), within the covered
    stretch (confidence halved). Confidence is halved too when a surface that is no wall
    joins the two root ends: there is no gap between them (a false V where the laser plane
    crosses a mitred corner, a tack weld over the root).

    Refused with a reason when the profile shows no groove (:func:`_groove_zones`: two
    faces alone, a side along the other's plate, a wide root, or less than
    ``min_explained`` of the profile on the model's lines) or when ``expect`` says the
    included angle, the depth below the plates or the gap is implausible.
    """

    name: str = "v-groove"
    min_angle_deg: float = 20.0
    max_angle_deg: float = 150.0
    max_gap_mm: float = 6.0
    min_gap_mm: float = 0.05

    def _extract(self, profile: Profile, seg: Segments) -> Feature | tuple[Feature, float]:
        groups = self._groups(seg)
        lo, hi = self._angles(self.min_angle_deg, self.max_angle_deg)
        found = self._arms(seg, False, lo, hi, self.max_gap_mm, groups)
        if isinstance(found, str):
            return Feature.failed(found, joint=self.name)
        left, right, apex, _ = found
        others = [g for g in seg.lines if g.count >= self.min_points] + [left, right]
        # Column order runs left to right: the left bevel's root end is its last point.
        root_l = _continued(seg, left, True, apex, corner_or_end(left, True, others, seg))
        root_r = _continued(seg, right, False, apex, corner_or_end(right, False, others, seg))
        top_l, plate_l = corner_with(left, False, others, seg)
        top_r, plate_r = corner_with(right, True, others, seg)
        # The plates: the pieces met at the top edges, as whole lines (their groups).
        plate_l, plate_r = _group_of(plate_l, groups), _group_of(plate_r, groups)
        model = _groove_zones(seg, groups, left, right, plate_l, plate_r)
        if isinstance(model, str):
            return Feature.failed(model, joint=self.name)
        zones, plates = model
        sure = True
        ref_l, ref_r = plate_l or plate_r, plate_r or plate_l
        cover_l = _covered_end(seg, left, True, right, ref_l)
        cover_r = _covered_end(seg, right, False, left, ref_r)
        if cover_l is not None or cover_r is not None:
            # A covered end is at least where the bevel is last seen; the shallower root end
            # goes down to the other's depth, within the stretch where it may lie.
            if cover_l is not None:
                root_l = left.point(cover_l[0])
            if cover_r is not None:
                root_r = right.point(cover_r[0])
            if ref_l is not None and ref_r is not None:
                d_l, d_r = _plate_depth(ref_l, root_l), _plate_depth(ref_r, root_r)
                if cover_l is not None and d_l < d_r:
                    root_l, sure = _at_depth(left, ref_l, d_r, cover_l), False
                elif cover_r is not None and d_r < d_l:
                    root_r, sure = _at_depth(right, ref_r, d_l, cover_r), False
            else:  # no plate to measure depth on: the middle of the stretch
                for line, cover in ((left, cover_l), (right, cover_r)):
                    if cover is not None:
                        mid = line.point(0.5 * (cover[0] + cover[1]))
                        root_l, root_r = (mid, root_r) if line is left else (root_l, mid)
                        sure = False
        covered = cover_l is not None or cover_r is not None
        gap = float(np.hypot(*(root_r - root_l)))
        expect = self.expect if isinstance(self.expect, Expect) else None
        if gap <= max(self.min_gap_mm, 2.0 * seg.spacing + seg.tol) or (
            expect is not None and expect.gapless
        ):
            seam, gap = apex, 0.0
        elif not _gap_seen(
            seg, left, right, root_l, root_r, apex, ref_l, ref_r, gap, covered, self.min_points
        ):
            # No gap shows between the bevels' lower ends: they end where spikes, dropouts or
            # a fill take over, not at the root. Their intersection is the best estimate.
            seam, gap, sure = apex, math.nan, False
        else:
            seam = 0.5 * (root_l + root_r)
            # A surface joining both root ends (no wall) means no gap lies between them: a
            # false V where the laser plane crosses a mitred corner, a tack over the root.
            if _bridged(seg, left, right, root_l, root_r, ref_l, self.min_points):
                sure = False
        wrong = self._implausible(
            angle=included(left, right, apex),
            depth=float(np.mean([_plate_depth(p, seam) for p in plates])),
            gap=gap,
        )
        if wrong is not None:
            return wrong
        conf = _confidence([left, right], seg) * (1.0 if sure else 0.5)
        feature = self._found(
            profile, seam, confidence=conf, edges_laser=np.array([top_l, top_r]), gap_mm=gap
        )
        return feature, explained(seg, zones)


def _groove_zones(
    seg: Segments,
    groups: list[Line],
    left: Line,
    right: Line,
    plate_l: Line | None,
    plate_r: Line | None,
) -> tuple[list[Zone], list[Line]] | str:
    """The model of a groove, or why the V is none: plates (the piece met at each top edge
    and the largest group beyond it) outside the bevels, the bevels, and the root between
    them (left out). At least one plate must show, a bevel without a plate of its own may not
    lie along the other's (within :data:`_ALONG_DEG`), and the root may hold at most
    :data:`_MAX_ROOT_SHARE` of the points: two faces alone are a fillet or a corner, a face
    along the plate is plate (a step, a raised block's foot), and a groove's root is
    narrow."""
    m = len(seg.points)
    lo_l, hi_l = int(left.index[0]), int(left.index[-1]) + 1
    lo_r, hi_r = int(right.index[0]), int(right.index[-1]) + 1
    arms = (left, right)
    flat = math.cos(math.radians(_ALONG_DEG))

    def plates_beside(arm: Line, met: Line | None, lo: int, hi: int) -> tuple[Line, ...]:
        # A plate turns away from its bevel (pieces along the bevel are more bevel) and
        # starts at the top edge: the piece met there and the largest group beyond it whose
        # nearest point lies within PLATE_REACH_MM of where its line crosses the bevel's (a
        # plate bent at the edge shows both; a plate beyond a raised block is not beside
        # the block's wall).
        along = [g for g in groups if abs(float(g.direction @ arm.direction)) > flat]
        if met is not None and (
            all(met is not g for g in groups)  # a stub, no plate
            or any(met is a for a in arms)
            or abs(float(met.direction @ arm.direction)) > flat
        ):
            met = None
        largest = largest_in(groups, lo, hi, (*arms, *along))
        if largest is not None:
            inside = largest.index[(largest.index >= lo) & (largest.index < hi)]
            nearest = seg.points[inside[-1] if hi <= lo_l else inside[0]]
            edge = intersect(largest, arm)
            if edge is None or float(np.hypot(*(nearest - edge))) > _PLATE_REACH_MM:
                largest = None
        if largest is None or largest is met:
            return () if met is None else (met,)
        return (largest,) if met is None else (met, largest)

    outer = (plates_beside(left, plate_l, 0, lo_l), plates_beside(right, plate_r, hi_r, m))
    plates = [*outer[0], *outer[1]]
    if not plates:
        return "not a v-groove: no plate beside the bevels (two faces alone: a fillet?)"
    # A side with no plate of its own that runs along the other side's plate is plate
    # itself: the lower sheet of a lap, the plate at a raised block's foot.
    for arm, own, other in ((left, outer[0], outer[1]), (right, outer[1], outer[0])):
        if not own and any(abs(float(p.direction @ arm.direction)) > flat for p in other):
            return "not a v-groove: a side of the V runs along a plate (a step or a block's foot)"
    if hi_l < lo_r and lo_r - hi_l > _MAX_ROOT_SHARE * m:
        return (
            f"not a v-groove: {100 * (lo_r - hi_l) / m:.0f} % of the profile lies between the "
            "bevels' lower ends (a raised block between two plates?)"
        )
    # Beyond a top edge: the plate, or the bevel going on (when no plate turns off it).
    zones: list[Zone] = [
        (0, lo_l, (*outer[0], left)),
        (lo_l, hi_l, left),
        (hi_l, lo_r, None),
        (lo_r, hi_r, right),
        (hi_r, m, (*outer[1], right)),
    ]
    return zones, plates


def _gap_seen(
    seg: Segments,
    left: Line,
    right: Line,
    root_l: FloatArray,
    root_r: FloatArray,
    apex: FloatArray,
    plate_l: Line | None,
    plate_r: Line | None,
    gap: float,
    covered: bool,
    min_points: int,
) -> bool:
    """Whether the stretch between the bevels' lower ends is a root gap: the ends lie at one
    depth (not read where a stray line hides an end: its depth is then taken from the other),
    no detour lies between them (a surface continuing across spikes), the V's tip below them
    is empty and the columns between them are open (the laser falls through the gap).
    Otherwise the bevels end where spikes, dropouts or a fill take over."""
    if not covered and not _level(seg, left, right, root_l, root_r, plate_l, plate_r, gap):
        return False
    lo, hi = int(left.index[-1]), int(right.index[0])
    if seg.stray.shape == (len(seg.points),) and int(seg.stray[lo + 1 : hi].sum()) >= 3:
        return False  # a detour between them: a surface goes on across it, no gap
    if _tip_filled(seg, left, right, root_l, root_r, apex, plate_l, min_points):
        return False
    return _covered_between(seg, left, right, plate_l, min_points) < 0.5


def _continued(
    seg: Segments, arm: Line, at_end: bool, apex: FloatArray, end: FloatArray
) -> FloatArray:
    """Where a bevel ends when pieces beyond its last inlier, towards the apex, lie on its
    line (within 15 deg and two tolerances: the bevel goes on past spikes or a dropout): the
    farthest such point; else ``end``."""
    t_apex = float((apex - arm.centroid) @ arm.direction)
    t_end = float(arm.t[-1] if at_end else arm.t[0])
    best = t_end
    cos_max = math.cos(math.radians(15.0))
    for ln in seg.lines:
        if abs(float(ln.direction @ arm.direction)) < cos_max:
            continue
        if abs(float((ln.centroid - arm.centroid) @ arm.normal)) > 2.0 * seg.tol:
            continue
        t = (seg.points[ln.index] - arm.centroid) @ arm.direction
        if at_end and float(t.min()) > t_end and float(t.max()) <= t_apex + seg.tol:
            best = max(best, float(t.max()))
        elif not at_end and float(t.max()) < t_end and float(t.min()) >= t_apex - seg.tol:
            best = min(best, float(t.min()))
    return end if best == t_end else arm.point(best)


def _covered_between(
    seg: Segments, left: Line, right: Line, plate: Line | None, min_points: int
) -> float:
    """Share of the columns between the bevels' lower ends that show a surface: points in no
    wall (steep on ``plate``: a root face), no long straight piece off both bevels and no
    piece cut off by jumps at both ends (a reflection, a backing), or, when more, the share
    not in the longest run of open columns. Over a gap the laser falls through (no points)."""
    lo, hi = int(left.index[-1]), int(right.index[0])
    if hi - lo < 2 or seg.columns.shape != (len(seg.points),):
        return 0.0
    columns = int(seg.columns[hi] - seg.columns[lo]) - 1
    if columns <= 0:
        return 0.0
    keep = np.ones(hi - lo - 1, dtype=bool)
    flat = plate.direction if plate is not None else np.array([1.0, 0.0])
    cos_wall = math.cos(math.radians(_WALL_DEG))
    cos_arm = math.cos(math.radians(15.0))
    starts, ends = seg.runs[:-1], seg.runs[1:]
    for ln in seg.lines:
        first, last = int(ln.index[0]), int(ln.index[-1])
        if last <= lo or first >= hi:
            continue
        wall = abs(float(ln.direction @ flat)) <= cos_wall
        stray = ln.count >= 2 * min_points and all(
            abs(float(ln.direction @ arm.direction)) < cos_arm for arm in (left, right)
        )
        # A line cut off at both ends by jumps: a reflection over the root.
        k = int(np.searchsorted(starts, first, side="right")) - 1
        cut_off = 0 <= k < len(starts) and first - starts[k] <= 3 and ends[k] - 1 - last <= 3
        if wall or stray or cut_off:
            inner = ln.index[(ln.index > lo) & (ln.index < hi)]
            keep[inner - lo - 1] = False
    # The open columns: no counted point in them. Over a gap they form one run.
    hit = np.zeros(columns, dtype=bool)
    hit[seg.columns[lo + 1 : hi][keep] - seg.columns[lo] - 1] = True
    edges = np.flatnonzero(np.diff(np.concatenate([[1], hit.astype(np.int8), [1]])))
    longest = int(np.max(edges[1::2] - edges[::2])) if edges.size else 0
    return max(float(np.count_nonzero(keep)) / columns, 1.0 - longest / columns)


def _tip_filled(
    seg: Segments,
    left: Line,
    right: Line,
    root_l: FloatArray,
    root_r: FloatArray,
    apex: FloatArray,
    plate: Line | None,
    min_points: int,
) -> bool:
    """Whether surface points fill the V's tip below the bevels' lower ends: the triangle of
    the two lower ends and the apex (grown by a tolerance), away from the lower ends (root
    faces start there). Under a gap the tip is open air; there the bevels go on (cut up by
    spikes and dropouts) or a fill lies. Walls (root faces: steep on ``plate``) and straight
    pieces that are no part of a bevel (a reflection, a backing) do not count. Only read
    when the apex lies more than three tolerances below the lower ends (else noise fills
    any tip)."""
    chord = root_r - root_l
    length = float(np.hypot(*chord))
    if length <= 0:
        return False
    n = np.array([-chord[1], chord[0]]) / length
    if abs(float((apex - root_l) @ n)) <= 3.0 * seg.tol:
        return False
    keep = ~seg.stray if seg.stray.shape == (len(seg.points),) else np.ones(len(seg.points), bool)
    cos_arm = math.cos(math.radians(15.0))
    cos_wall = math.cos(math.radians(_WALL_DEG))
    flat = plate.direction if plate is not None else np.array([1.0, 0.0])
    for ln in seg.lines:
        wall = abs(float(ln.direction @ flat)) <= cos_wall
        if wall or (
            ln.count >= 2 * min_points
            and all(abs(float(ln.direction @ arm.direction)) < cos_arm for arm in (left, right))
        ):
            keep[ln.index] = False
    keep[left.index] = False  # the bevels themselves (above their lower ends)
    keep[right.index] = False
    q = seg.points[keep]
    tri = (root_l, root_r, apex)
    centre = (root_l + root_r + apex) / 3.0
    inside = np.ones(len(q), dtype=bool)
    for a, b in ((0, 1), (1, 2), (2, 0)):
        e = tri[b] - tri[a]
        m = np.array([-e[1], e[0]]) / max(float(np.hypot(*e)), 1e-300)
        if float((centre - tri[a]) @ m) < 0:
            m = -m
        inside &= (q - tri[a]) @ m >= -seg.tol
    r0 = 2.0 * seg.tol + 3.0 * seg.spacing
    away = (np.hypot(*(q - root_l).T) > r0) & (np.hypot(*(q - root_r).T) > r0)
    return int(np.count_nonzero(inside & away)) > min_points


def _level(
    seg: Segments,
    left: Line,
    right: Line,
    root_l: FloatArray,
    root_r: FloatArray,
    plate_l: Line | None,
    plate_r: Line | None,
    gap: float,
) -> bool:
    """Whether the bevels' lower ends lie at one depth (below their own plates, else along
    the V's bisector): within 3 tolerances or a quarter of the gap between them."""
    cos_min = math.cos(math.radians(20.0))
    if plate_l is not None and abs(float(plate_l.direction @ left.direction)) > cos_min:
        plate_l = None  # a piece of the bevel, no plate
    if plate_r is not None and abs(float(plate_r.direction @ right.direction)) > cos_min:
        plate_r = None
    plate_l, plate_r = plate_l or plate_r, plate_r or plate_l
    if plate_l is not None and plate_r is not None:
        d_l, d_r = _plate_depth(plate_l, root_l), _plate_depth(plate_r, root_r)
    else:
        up = -(left.direction + right.direction)  # left runs down, right up: the opening
        if up[1] > 0:
            up = -up
        up = up / max(float(np.hypot(*up)), 1e-300)
        d_l, d_r = -float(root_l @ up), -float(root_r @ up)
    return abs(d_l - d_r) <= max(3.0 * seg.tol, 0.25 * gap)


def _bridged(
    seg: Segments,
    left: Line,
    right: Line,
    root_l: FloatArray,
    root_r: FloatArray,
    plate: Line | None,
    min_points: int,
) -> bool:
    """Whether a piece between the bevels that is no wall (steep on ``plate``) runs from one
    root end to the other: the "gap" between them is a surface."""
    lo, hi = int(left.index[-1]), int(right.index[0])
    flat = plate.direction if plate is not None else np.array([1.0, 0.0])
    for ln in seg.lines:
        if ln.count < min_points or int(ln.index[0]) <= lo or int(ln.index[-1]) >= hi:
            continue
        if abs(float(ln.direction @ flat)) <= math.cos(math.radians(_WALL_DEG)):
            continue
        reach = 3.0 * max(seg.spacing, ln.step(True), ln.step(False)) + seg.tol
        if (
            float(np.hypot(*(ln.end(False) - root_l))) <= reach
            and float(np.hypot(*(ln.end(True) - root_r))) <= reach
        ):
            return True
    return False


def _at_depth(line: Line, plate: Line, depth: float, stretch: tuple[float, float]) -> FloatArray:
    """The point of ``line`` at ``depth`` behind ``plate``, kept within ``stretch`` (two
    coordinates along the line)."""
    n = plate.normal if float(plate.centroid @ plate.normal) > 0 else -plate.normal
    rate = float(line.direction @ n)
    lo, hi = min(stretch), max(stretch)
    if abs(rate) < 1e-6:
        return line.point(stretch[0])
    t = float((depth - _plate_depth(plate, line.centroid)) / rate)
    return line.point(min(max(t, lo), hi))  # as np.clip (NaN stays NaN)
