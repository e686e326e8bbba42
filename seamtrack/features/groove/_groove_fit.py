"""Fits the groove extractor's corners rest on (:mod:`seamtrack.features.groove.extractor`).

* :func:`trim_wall`: a wall's line refitted on the points that lie on it (a root radius's
  round at the wall's foot, and the odd spike, left out);
* :func:`ray_reach`: with no wall seen, how far the fill surface reaches towards the side:
  a spike moves a point along its ray, so the ray still says where the surface is across the
  groove.
* :func:`short_walls`, :func:`mirrored_walls`: a wall seen as a scrap or not at all, stood
  in for by the other one mirrored; :func:`cross_uv`: a wall's line crossed with the
  surface's;
* :func:`bottom_points`: the three bottom points on the fill surface.

Points are (u, v): u across the groove (the plates' line, left to right), v into it.
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numpy.typing import NDArray

from seamtrack.features.arrays import FloatArray, IndexArray
from seamtrack.features.groove import _groove_kernels as kern
from seamtrack.features.groove._groove_kernels import local_v, robust_uv_line
from seamtrack.features.line_geometry import Line, fit_line
from seamtrack.features.lines import Segments
from seamtrack.geometry.groove_points import LEFT_FOOT, LEFT_TOP, RIGHT_FOOT, RIGHT_TOP

#: A groove's bottom spread over at most this angle of the fan (rad) ...
RAY_SPREAD_RAD = math.radians(0.2)
#: ... and over more than this range (mm) lies along one ray: spikes, not a surface.
RAY_DEPTH_MM = 1.0


def angle_deg(a: FloatArray, b: FloatArray) -> float:
    return math.degrees(math.acos(min(1.0, abs(float(a @ b)))))


def trim_wall(points: FloatArray, line: Line, tol: float, rounds: int = 3) -> Line:
    """``line`` refitted (total least squares) on its points within two tolerances of it, a
    few times over: a round at the wall's foot that leaves the line slowly, and points
    of a spike that the pieces took in, stop pulling it. Unchanged when fewer than half its
    points would stay."""
    index = np.asarray(line.index)
    keep = index
    cur = line
    for _ in range(rounds):
        off = np.abs((points[index] - cur.centroid) @ cur.normal)
        new = index[off <= 2.0 * tol]
        if len(new) < max(3, len(index) // 2) or np.array_equal(new, keep):
            break
        keep = new
        cur = Line.from_fit(keep, fit_line(points, np.asarray(keep, dtype=np.int64)))
    if cur.direction[0] * line.direction[0] + cur.direction[1] * line.direction[1] < 0:
        cur = cur.flipped()
    return cur


def running_median(v: FloatArray, k: int) -> FloatArray:
    """The median over ``k`` points about each point; at the ends over those there are (a
    window cut short: the end's own level, not its whole window's)."""
    if len(v) < k:
        return np.full(len(v), float(np.median(v)))
    return kern.running_median_cut(np.ascontiguousarray(v, dtype=np.float64), k)


#: Two walls more than MIRROR_DEG off each other's mirror: the one seen over less than
#: MIRROR_SHARE of the other's length is no wall (:func:`short_walls`).
MIRROR_DEG = 2.0
MIRROR_SHARE = 0.75


#: A point within RAY_BAND_MM of the fill surface's line whose ray meets the line at most
#: RAY_REACH_MM beyond the surface's outermost point stands for a column that lit the surface
#: there (:func:`ray_reach`; mm).
RAY_BAND_MM = 6.0
RAY_REACH_MM = 1.0


def ray_reach(
    points: FloatArray, u: FloatArray, v: FloatArray, surface: tuple[float, float], out_u: float,
    left: bool,
) -> float:  # fmt: skip
    """How far (u) the ``surface`` v = a + b u (``(a, b)``) reaches towards a side with no
    wall seen (``left``, else right): each point (spikes too) within :data:`RAY_BAND_MM` of the
    line whose ray (from the sensor's origin, the laser frame's (0, 0)) meets the line at most
    :data:`RAY_REACH_MM` beyond ``out_u`` (the surface's outermost point on its line) stands
    for a column that lit the surface there; the outermost of those crossings, or ``out_u``."""
    a, b = surface
    reach, band = RAY_REACH_MM, RAY_BAND_MM
    sign = 1.0 if left else -1.0
    pu, pv = points @ u, points @ v
    near = np.abs(pv - (a + b * pu)) <= band
    beyond = sign * (pu - out_u) < -reach - 2.0  # far out: not this surface's columns
    sel = near & ~beyond
    pu, pv = pu[sel], pv[sel]
    if not len(pu):
        return out_u
    # The ray through (pu, pv) from the origin: (t pu, t pv); on the line: t pv = a + b t pu.
    ou, ov = 0.0, 0.0  # the origin in (u, v): u, v are a rotation of the laser frame
    den = pv - ov - b * (pu - ou)
    ok = np.abs(den) > 1e-9
    t = np.where(ok, (a + b * ou - ov) / np.where(ok, den, 1.0), np.nan)
    xu = ou + t * (pu - ou)
    xu = xu[ok & (t > 0)]
    cand = xu[(sign * (out_u - xu) > 0) & (sign * (out_u - xu) <= reach)]
    if not len(cand):
        return out_u
    return float(cand.min() if left else cand.max())


def _stretches(qu: FloatArray, runs: NDArray[np.intp]) -> tuple[list[IndexArray], FloatArray]:
    """The fill surface's stretches: each run's points (in u order), the stretches ordered by
    the u of their middle points, and those u."""
    labels, inv = np.unique(runs, return_inverse=True)
    m = len(labels)
    by = np.argsort(inv, kind="stable")  # each run's points, in u order
    members = np.split(by, np.cumsum(np.bincount(inv, minlength=m))[:-1])
    mid_u = np.array([float(qu[k[len(k) // 2]]) for k in members])
    order = np.argsort(mid_u, kind="stable")
    return [members[c] for c in order], mid_u[order]


def _stretch_end(
    qu: FloatArray, qv: FloatArray, k: IndexArray, w: int, tail: bool
) -> tuple[float, float, float]:
    """(u, v) of the end of the stretch of points ``k`` (its last point by u, or first) and
    its slope dv/du over its last (first) ``w`` points."""
    k = k[-w:] if tail else k[:w]
    uu, vv = qu[k], qv[k]
    slope = 0.0
    du = uu - uu.mean()
    if len(uu) >= 3 and float(du @ du) > 1e-12:
        slope = float(du @ (vv - vv.mean()) / (du @ du))
    e = k[-1] if tail else k[0]
    return float(qu[e]), float(qv[e]), slope


def _neighbours(pieces: IndexArray, c: int) -> tuple[int | None, int | None]:
    """The nearest pieces before and after stretch ``c`` (None: none on that side)."""
    before = pieces[pieces < c]
    after = pieces[pieces > c]
    return (
        int(before[-1]) if len(before) else None,
        int(after[0]) if len(after) else None,
    )


def _may_be_island(
    c: int, a: int | None, b: int | None, big: NDArray[np.bool_], size: IndexArray, width: float
) -> bool:
    """Whether stretch ``c`` (``width`` wide in u) is small enough to be an island: no
    piece, or a piece with fewer points than the pieces ``a`` and ``b`` around it (at an
    end, than its one neighbour, and under half a millimetre wide)."""
    if not big[c]:
        return True
    if a is not None and b is not None:
        return bool(size[c] < min(size[a], size[b]))
    nb = a if a is not None else b
    assert nb is not None
    return not (size[c] >= size[nb] or width > 0.5)


def _surface_across(
    qu: FloatArray,
    qv: FloatArray,
    k: IndexArray,
    u: float,
    ends: tuple[tuple[float, float, float] | None, tuple[float, float, float] | None],
    off_max: float,
) -> float | None:
    """The surface's v carried across the stretch of points ``k`` at its middle's ``u``,
    from the ``ends`` (u, v, slope) of the pieces before and after it (None where there is
    none): the line joining them, or the one end carried on at its slope (within +-1: a steep
    end carried far is a wall's). None when the stretch carries on the piece before it (a
    flank, the piece after a spike) or the pieces do not face each other."""
    before, after = ends
    if before is not None and after is not None:
        au, av, sa = before
        bu, bv, _ = after
        if bu - au < 1e-9:
            return None
        lo = int(k[np.argmin(qu[k])])
        if abs(float(qv[lo]) - (av + sa * (float(qu[lo]) - au))) <= off_max:
            return None
        return av + (u - au) * (bv - av) / (bu - au)
    one = before if before is not None else after
    assert one is not None
    eu, ev, slope = one
    return ev + min(max(slope, -1.0), 1.0) * (u - eu)


def drop_islands(
    qu: FloatArray, qv: FloatArray, runs: NDArray[np.intp], spacing: float, tol: float
) -> NDArray[np.bool_]:
    """Which of the fill surface's points (sorted by u) to keep: all but its islands. The
    points' ``runs`` (the front end's runs between jumps, in column order) are its stretches;
    a stretch of at least 0.2 mm worth of points is a piece of surface. A stretch is an
    island (a spike run, a streak standing where a dropout took the surface) when its middle
    lies more than ``max(0.3, 6 tol)`` off the surface carried across it: the line joining
    the facing ends of the pieces on both sides (by their middles' u), or at an end of the
    surface the last piece's end carried on (its slope over 0.3 mm) - and it is no piece, or
    a piece with fewer points than those around it (at an end: under half a millimetre
    wide). A curved surface broken by a dropout stays: its pieces join across the gap."""
    n = len(qu)
    keep = np.ones(n, dtype=bool)
    if n < 6 or len(np.unique(runs)) < 2:
        return keep
    members, mid_u = _stretches(qu, runs)
    size = np.array([len(k) for k in members])
    off_max = max(0.3, 6.0 * tol)
    w = max(3, int(round(0.3 / max(spacing, 1e-9))))
    big = size >= max(5, int(round(0.2 / max(spacing, 1e-9))))
    alive = np.ones(len(members), dtype=bool)
    for _ in range(3):  # again without the islands found: an island beside an island
        pieces = np.flatnonzero(big & alive)
        dropped = False
        for c in np.flatnonzero(alive).tolist():
            k = members[c]
            a, b = _neighbours(pieces, c)
            if a is None and b is None:
                continue
            if not _may_be_island(c, a, b, big, size, float(np.ptp(qu[k]))):
                continue
            ends = (
                None if a is None else _stretch_end(qu, qv, members[a], w, True),
                None if b is None else _stretch_end(qu, qv, members[b], w, False),
            )
            line_v = _surface_across(qu, qv, k, float(mid_u[c]), ends, off_max)
            if line_v is not None and abs(float(np.median(qv[k])) - line_v) > off_max:
                keep[k] = False
                alive[c] = False
                dropped = True
        if not dropped:
            break
    return keep


def mirrored_walls(
    walls: tuple[Line | None, Line | None],
    tops: tuple[FloatArray, FloatArray],
    fu: FloatArray,
    fv: FloatArray,
    u: FloatArray,
    v: FloatArray,
) -> tuple[Line | None, Line | None]:
    """The walls, a hidden one (no points: in the shadow of its plate's edge) stood in for by
    the seen one mirrored across the groove (a groove's bevels are cut alike) through its
    own top corner, when the fill surface there lies at least a millimetre below that corner
    (the wall is not buried) and nowhere more than 0.3 mm outside the mirrored line (the
    groove is not one-sided). Otherwise as they were."""
    out = list(walls)
    for side in (0, 1):
        seen = walls[1 - side]
        if walls[side] is not None or seen is None or len(fu) < 3:
            continue
        d = seen.direction - 2.0 * float(seen.direction @ u) * u
        top = tops[side]
        outer_v = float(fv[0] if side == 0 else fv[-1])
        if outer_v - float(top @ v) < 1.0:
            continue
        n = np.array([-d[1], d[0]])
        if (n @ u < 0) != (side == 0):
            n = -n  # outwards, away from the groove
        q = fu[:, None] * u + fv[:, None] * v
        if np.count_nonzero((q - top) @ n > 0.3) > 2:
            continue
        out[side] = Line(np.zeros(0, dtype=np.intp), top.copy(), d, np.zeros(0), 0.0)
    return out[0], out[1]


def short_walls(
    walls: tuple[Line | None, Line | None],
    fv: FloatArray,
    v: FloatArray,
    max_mm: float = 3.0,
    share: float = 0.25,
    below_mm: float = 3.0,
) -> tuple[Line | None, Line | None]:
    """The walls, one that says little of its direction taken for hidden (None; the mirror of
    the other stands in for it, :func:`mirrored_walls`):

    * one seen over less than ``max_mm`` and less than ``share`` of the other's seen length,
      ending more than ``below_mm`` above the fill surface's outer end on its side (``fv``:
      the surface's v, sorted by u): a scrap at its top edge, the rest in the shadow of its
      plate (a degree over 0.7 mm moves its foot 0.3 mm 15 mm down);
    * of two walls more than :data:`MIRROR_DEG` off each other's mirror (a groove's bevels
      are cut alike), the one seen over less than :data:`MIRROR_SHARE` of the other's length:
      a spike streak along the rays beside a wall in shadow (13 points over 5.3 mm, 4.9 deg
      off), or a round's upper part taken for its wall. Of two walls seen alike, neither.
    """
    a, b = walls
    if a is None or b is None or not len(a.t) or not len(b.t) or not len(fv):
        return walls
    la, lb = float(np.ptp(a.t)), float(np.ptp(b.t))
    out: list[Line | None] = [a, b]
    for side, (w, mine, other) in enumerate(((a, la, lb), (b, lb, la))):
        low = max(float(w.point(float(w.t[0])) @ v), float(w.point(float(w.t[-1])) @ v))
        edge = float(fv[0] if side == 0 else fv[-1])
        if mine < min(max_mm, share * other) and edge - low > below_mm:
            out[side] = None
    if out[0] is not None and out[1] is not None:
        u = np.array([v[1], -v[0]])
        mirror = b.direction - 2.0 * float(b.direction @ u) * u
        apart = math.degrees(math.acos(min(1.0, abs(float(mirror @ a.direction)))))
        if apart > MIRROR_DEG:
            if la < MIRROR_SHARE * lb:
                out[0] = None
            elif lb < MIRROR_SHARE * la:
                out[1] = None
    return out[0], out[1]


def cross_uv(wall: Line, a: float, b: float, u: FloatArray, v: FloatArray) -> FloatArray | None:
    """(u, v) where ``wall``'s line crosses the line v = a + b u (None: parallel)."""
    cu, cv = float(wall.centroid @ u), float(wall.centroid @ v)
    du, dv = float(wall.direction @ u), float(wall.direction @ v)
    den = dv - b * du
    if abs(den) <= 1e-9:
        return None
    t = (a + b * cu - cv) / den
    return np.array([cu + t * du, cv + t * dv])


def median_of(x: FloatArray) -> float:
    """``np.median`` of a 1-d array, the same number without its per-call overhead (the
    extractor takes thousands of small medians a second)."""
    n = len(x)
    if n == 0:
        return math.nan
    s = np.sort(x)
    if math.isnan(s[-1]):  # NaN sorts last; np.median's answer then is NaN
        return math.nan
    h = n // 2
    return float(s[h]) if n % 2 else float((s[h - 1] + s[h]) / 2)


def on_line(seg: Segments, ref: Line, ln: Line, max_deg: float = 5.0) -> bool:
    """Whether piece ``ln`` lies on the line of ``ref`` (within ``max_deg`` and two
    tolerances)."""
    if angle_deg(ln.direction, ref.direction) > max_deg:
        return False
    off = np.abs((seg.points[ln.index] - ref.centroid) @ ref.normal)
    return bool(median_of(off) <= 2.0 * seg.tol)


def count_outwards(
    q: FloatArray, ln: Line, v: FloatArray, left: bool, tol: float, upper: float | None = None
) -> int:
    """How many of the points ``q`` lie outwards of a wall piece ``ln`` (on the plate's side,
    more than 3 tolerances off its line) and deeper than its upper end (or ``upper``)."""
    n = ln.normal if (ln.normal @ np.array([v[1], -v[0]]) < 0) == left else -ln.normal
    if upper is None:
        upper = float(min(ln.point(float(ln.t[0])) @ v, ln.point(float(ln.t[-1])) @ v))
    out = ((q - ln.centroid) @ n > 3.0 * tol) & (q @ v > upper)
    return int(np.count_nonzero(out))


def robust_uv_fit(qu: FloatArray, qv: FloatArray, tol: float) -> tuple[float, float] | None:
    """v = a + b u through the most points within two tolerances, of the lines through pairs
    of (at most 40, evenly picked) points at least a third of the stretch apart; refitted on
    those points. Spike runs less than half the points do not move it (compiled:
    :func:`seamtrack.features.groove._groove_kernels.robust_uv_line`)."""
    n = len(qu)
    if n < 3:
        return None
    i, j = _pairs(n)
    a, b, found = robust_uv_line(contiguous(qu), contiguous(qv), float(tol), i, j)
    return (a, b) if found else None


@functools.lru_cache(maxsize=256)
def _pairs(n: int) -> tuple[IndexArray, IndexArray]:
    """The pairs of :func:`robust_uv_fit` among ``n`` points, in order (read-only)."""
    pick = np.unique(np.linspace(0, n - 1, min(n, 40)).round().astype(np.intp))
    i, j = np.triu_indices(len(pick), k=max(1, len(pick) // 3))
    i, j = pick[i], pick[j]
    i.setflags(write=False)
    j.setflags(write=False)
    return i, j


def contiguous(x: FloatArray) -> FloatArray:
    return np.ascontiguousarray(x, dtype=np.float64)


def polygon_area(pts: FloatArray, P: FloatArray, inner: IndexArray, u: FloatArray) -> float:
    """The polygon of the top corners, the bottom corners and the surface between them, below
    the line joining the top corners (mm^2), signed: a crowned fill's metal above that line
    counts against it (a nearly full groove's area is about 0, a capped one's negative)."""
    qu = P[inner] @ u
    zone = inner[(qu > pts[LEFT_FOOT] @ u) & (qu < pts[RIGHT_FOOT] @ u)]
    ring = np.vstack([pts[LEFT_TOP], pts[LEFT_FOOT], P[zone], pts[RIGHT_FOOT], pts[RIGHT_TOP]])
    v = np.array([-u[1], u[0]])
    a, b = ring @ u, ring @ v  # along the plates, into the groove
    a_next, b_next = np.concatenate((a[1:], a[:1])), np.concatenate((b[1:], b[:1]))  # np.roll
    return float(-0.5 * (np.dot(a, b_next) - np.dot(b, a_next)))


def stretched(seg: Segments, plate: Line, stop: int, step: int) -> Line:
    """``plate`` carried on over the points after its last piece (``step`` +1: rightwards) that
    no piece took and that lie within two tolerances of its line, up to point ``stop`` (the
    next piece's first): a quantized plate's last step, which split-and-merge leaves between
    the plate and the wall, is plate; its end is the plate's inner end."""
    P = seg.points
    k = int(plate.index[-1] if step > 0 else plate.index[0])
    n = plate.normal
    add = []
    while k + step != stop and 0 <= k + step < len(P):
        k += step
        if seg.stray[k]:
            continue
        if abs(float((P[k] - plate.centroid) @ n)) > 2.0 * seg.tol:
            break
        add.append(k)
    if not add:
        return plate
    index = np.sort(np.concatenate([plate.index, np.asarray(add, dtype=np.intp)]))
    line = Line.from_fit(index, fit_line(P, np.asarray(index, dtype=np.int64)))
    if line.direction[0] < 0:
        line = line.flipped()
    return line


def along_a_ray(bottom: FloatArray) -> bool:
    """Whether the bottom corners and points lie along one ray of the fan (from the laser
    frame's origin, within :data:`RAY_SPREAD_RAD`) over more than :data:`RAY_DEPTH_MM` of
    depth: a streak of spikes (a reflection) does; a fill surface, which crosses the rays, and
    an empty V's root, a point, do not."""
    angle = np.arctan2(bottom[:, 0], bottom[:, 1])
    rng = np.hypot(bottom[:, 0], bottom[:, 1])
    spread, depth = float(np.ptp(angle)), float(np.ptp(rng))
    return spread <= RAY_SPREAD_RAD and depth > RAY_DEPTH_MM


def explained_share(
    seg: Segments,
    plates: tuple[Line, Line],
    walls: tuple[Line | None, Line | None],
    inner: IndexArray,
    bl: FloatArray,
    br: FloatArray,
    u: FloatArray,
) -> float:
    """The share of the profile's kept points the model explains: on a plate's line (outside
    the groove), on a wall's line, or inside the groove between the bottom corners."""
    P = seg.points
    kept = np.flatnonzero(~seg.stray)
    if not len(kept):
        return 0.0
    band = 3.0 * seg.tol
    ok = np.zeros(len(P), dtype=bool)
    left, right = plates
    lo, hi = int(left.index[-1]), int(right.index[0])
    for line, sel in ((left, slice(0, lo + 1)), (right, slice(hi, len(P)))):
        ok[sel] = np.abs((P[sel] - line.centroid) @ line.normal) <= band
    for w in walls:
        if w is not None:
            ok[inner] |= np.abs((P[inner] - w.centroid) @ w.normal) <= band
    qu = P[inner] @ u
    ok[inner[(qu >= bl @ u - band) & (qu <= br @ u + band)]] = True
    return float(np.count_nonzero(ok[kept]) / len(kept))


def surface_v_at(qu: FloatArray, qv: FloatArray, ut: float, h: float, tol: float) -> float | None:
    """v of the surface at u = ut: a robust line fit of the points within h of it (None: fewer
    than 3 there, or none on one side; compiled:
    :func:`seamtrack.features.groove._groove_kernels.local_v`)."""
    val = local_v(contiguous(qu), contiguous(qv), float(ut), float(h), float(tol))
    return None if math.isnan(val) else float(val)


def bottom_points(
    seg: Segments,
    qu: FloatArray,
    qv: FloatArray,
    bl: FloatArray,
    br: FloatArray,
    u: FloatArray,
    v: FloatArray,
) -> FloatArray:
    """The three bottom points (3, 2): the fill surface (``qu``, ``qv``) at a quarter, half
    and three quarters of the way from the bottom corner ``bl`` to ``br`` along u, each a
    local robust line fit there (:func:`surface_v_at`, over 4 times the width where too few
    points show); on the line joining the corners where none do (an open root)."""
    ul, ur = float(bl @ u), float(br @ u)
    out = []
    h = max(0.25, 5.0 * seg.spacing)
    for t in (0.25, 0.5, 0.75):
        chord = bl + t * (br - bl)
        ut = float(chord @ u)
        val = None
        if ur - ul > 2 * h:
            val = surface_v_at(qu, qv, ut, h, seg.tol)
            if val is None:
                val = surface_v_at(qu, qv, ut, 4 * h, seg.tol)
        if val is None:
            out.append(chord)
        else:
            out.append(ut * u + val * v)
    return np.array(out)
