"""Split-and-merge line segmentation of stripe profiles: the front end of the extractors.

:func:`segment_profile` drops isolated outliers against a 5-point running median, estimates the
noise from second differences, cuts the profile at jumps, splits each run by Douglas-Peucker at a
noise-scaled tolerance, merges neighbours that fit one line, and refits each piece by total
least squares on its inliers. :func:`collinear_groups`, :func:`intersect` and
:func:`corner_or_end` are the geometry the family extractors build on, and ``_Base`` their
shared parameters and never-raise wrapper (the extractors themselves live in
:mod:`seamtrack.features.extractors` and :mod:`seamtrack.features.plates`).

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.sensing.profiles import Feature, Profile

FloatArray = NDArray[np.float64]
#: Coordinates beyond this (mm) are not measurements: treated as invalid.
_MAX_ABS_MM = 1e6


def _median5(z: FloatArray) -> FloatArray:
    """Running median of 5 (edges: the nearest full window), by a min/max network."""
    if len(z) < 5:
        return np.full_like(z, np.median(z))
    a, b, c, d, e = z[:-4], z[1:-3], z[2:-2], z[3:-1], z[4:]
    f = np.maximum(np.minimum(a, b), np.minimum(c, d))
    g = np.minimum(np.maximum(a, b), np.maximum(c, d))
    med = np.maximum(np.minimum(e, f), np.minimum(np.maximum(e, f), g))
    return np.concatenate([np.full(2, med[0]), med, np.full(2, med[-1])])


@dataclass
class Line:
    """A straight piece of a profile (internal to the extractors; mutable while built).

    ``index`` are the inliers' positions in the kept points (column order); ``direction``
    points along increasing column; ``t`` are the inliers' coordinates along it.
    """

    index: NDArray[np.intp]
    centroid: FloatArray
    direction: FloatArray
    t: FloatArray
    rms: float

    @property
    def normal(self) -> FloatArray:
        return np.array([-self.direction[1], self.direction[0]])

    @property
    def count(self) -> int:
        return len(self.index)

    @property
    def extent(self) -> float:
        return float(self.t[-1] - self.t[0]) if len(self.t) else 0.0

    def point(self, t: float) -> FloatArray:
        return self.centroid + t * self.direction

    def step(self, at_end: bool) -> float:
        """Mean spacing of the last (``at_end``) or first ten inliers along the line."""
        k = min(10, len(self.t) - 1)
        if k < 1:
            return 0.0
        t = self.t
        return float(abs(t[-1] - t[-1 - k]) if at_end else abs(t[k] - t[0])) / k

    def end(self, at_end: bool) -> FloatArray:
        """The line's end half a spacing beyond its last (first) inlier."""
        half = 0.5 * self.step(at_end)
        return self.point(float(self.t[-1] + half if at_end else self.t[0] - half))


def _fit(points: FloatArray, index: NDArray[np.intp]) -> Line:
    """Total-least-squares line through ``points[index]`` (column order kept)."""
    p = points[index]
    c = p.sum(axis=0) / len(p)  # (sum / n: np.mean's overhead is most of the cost here)
    q = p - c
    syy, szz, syz = float(q[:, 0] @ q[:, 0]), float(q[:, 1] @ q[:, 1]), float(q[:, 0] @ q[:, 1])
    theta = 0.5 * math.atan2(2.0 * syz, syy - szz)
    u = np.array([math.cos(theta), math.sin(theta)])
    if u @ (p[-1] - p[0]) < 0:
        u = -u
    t = q @ u
    r = q @ np.array([-u[1], u[0]])
    return Line(index, c, u, t, math.sqrt(float(r @ r) / len(r)))


@dataclass
class Segments:
    """What :func:`segment_profile` found: kept points, noise and straight pieces."""

    points: FloatArray  # (m, 2) kept points, column order
    sigma: float  # noise estimate (mm)
    tol: float  # split / inlier tolerance (mm)
    spacing: float  # median distance between neighbouring points (mm)
    lines: list[Line]


def kept_points(profile: Profile) -> FloatArray:
    """(m, 2) valid, finite, bounded points of a profile, in column order."""
    pts = np.asarray(profile.points_laser, dtype=np.float64).reshape(-1, 2)
    valid = np.asarray(profile.valid, dtype=bool).reshape(-1)
    if valid.shape != (len(pts),):
        return np.empty((0, 2))
    a = np.abs(pts)
    return pts[valid & (a[:, 0] < _MAX_ABS_MM) & (a[:, 1] < _MAX_ABS_MM)]  # NaN fails too


def _median(x: FloatArray) -> float:
    """Upper median, without ``np.median``'s overhead (0 for an empty array).

    A full sort, not ``np.partition``: on quantized profiles most values repeat (second
    differences are mostly 0 or one pixel step), and introselect then takes ~70 us for 1000
    values where the sort takes 7 us.
    """
    n = len(x)
    return float(np.sort(x)[n // 2]) if n else 0.0


def _spacing(points: FloatArray) -> float:
    """Typical distance between neighbouring columns (mm): the median lateral step, which
    range noise does not inflate (the median absolute step when the profile is vertical)."""
    d = np.abs(np.diff(points, axis=0))
    lateral = _median(d[:, 0])
    return lateral if lateral > 0 else _median(np.hypot(d[:, 0], d[:, 1]))


def noise_sigma(points: FloatArray) -> float:
    """Robust noise estimate (mm) in range z_L, where a triangulation sensor's noise lies:
    1.4826 median |second difference of z_L| / sqrt(6). On lines sampled at even spacing the
    second differences are noise only; corners and jumps are few."""
    if len(points) < 3:
        return 0.0
    z = points[:, 1]
    return 1.4826 / math.sqrt(6.0) * _median(np.abs(z[2:] - 2.0 * z[1:-1] + z[:-2]))


def segment_profile(
    profile: Profile,
    *,
    min_tol_mm: float = 0.03,
    sigma_factor: float = 5.0,
    min_points: int = 8,
    max_lines: int = 64,
) -> Segments | str:
    """Split-and-merge a profile into straight pieces, or say why not (a ``str``).

    Parameters
    ----------
    profile : Profile
    min_tol_mm : float
        Floor of the split tolerance (covers pixel quantization).
    sigma_factor : float
        Split tolerance = max(min_tol_mm, sigma_factor * estimated noise).
    min_points : int
        Pieces with fewer inliers are dropped.
    max_lines : int
        More pieces than this means there is no line structure: give up.
    """
    p = kept_points(profile)
    if len(p) < 2 * min_points:
        return f"too few valid points ({len(p)})"
    # Isolated outliers first: they would split lines and bias the noise estimate.
    sigma = noise_sigma(p)
    spacing = _spacing(p)
    if not spacing > 0:
        return "the valid points do not spread out (constant profile)"
    dev = np.abs(p[:, 1] - _median5(p[:, 1]))
    p = p[dev <= max(6.0 * sigma, 4.0 * min_tol_mm, 4.0 * spacing)]
    sigma = noise_sigma(p)
    tol = max(min_tol_mm, sigma_factor * sigma)
    gaps = np.hypot(*np.diff(p, axis=0).T)
    cuts = np.flatnonzero(gaps > max(6.0 * spacing, 2.0 * tol, 0.1)) + 1
    bounds = np.concatenate([[0], cuts, [len(p)]])
    pieces: list[tuple[int, int]] = []
    for lo, hi in itertools.pairwise(bounds):
        if hi - lo >= min_points:
            run = _split(p, int(lo), int(hi) - 1, tol, max_lines)
            if run is None:
                return "no straight pieces (too noisy or curved)"
            pieces.extend(_refine(p, _merge(p, run, tol), sigma, min_tol_mm, min_points))
        if len(pieces) > max_lines:
            return "no straight pieces (too noisy or curved)"
    lines = []
    trim = max(3.0 * sigma, 0.5 * min_tol_mm)
    for lo, hi in pieces:
        idx = np.arange(lo, hi + 1)
        line = _fit(p, idx)
        resid = np.abs((p[idx] - line.centroid) @ line.normal)
        idx = idx[resid <= trim]
        if len(idx) >= min_points:
            lines.append(_fit(p, idx))
    if not lines:
        return "no straight pieces with enough points"
    return Segments(p, sigma, tol, spacing, lines)


def _best_split(q: FloatArray, min_size: int) -> tuple[int, float, float]:
    """Best split of ordered points into two lines: (b, cost of q[:b] + q[b:], cost of q).

    Costs are total-least-squares sums of squared residuals, for every b at once from
    prefix sums (O(n)).
    """
    k = len(q)
    q = q - q.mean(axis=0)
    cols = np.column_stack(
        [np.ones(k), q[:, 0], q[:, 1], q[:, 0] ** 2, q[:, 1] ** 2, q[:, 0] * q[:, 1]]
    )
    pre = np.cumsum(cols, axis=0)
    total = pre[-1]

    def cost(s: FloatArray) -> FloatArray:
        n = np.maximum(s[..., 0], 1.0)
        cyy = s[..., 3] - s[..., 1] ** 2 / n
        czz = s[..., 4] - s[..., 2] ** 2 / n
        cyz = s[..., 5] - s[..., 1] * s[..., 2] / n
        return np.maximum(0.5 * (cyy + czz) - np.hypot(0.5 * (cyy - czz), cyz), 0.0)

    b = np.arange(min_size, k - min_size + 1)
    if b.size == 0:
        c = float(cost(total))
        return k, c, c
    left = pre[b - 1]
    both = cost(left) + cost(total - left)
    i = int(np.argmin(both))
    return int(b[i]), float(both[i]), float(cost(total))


def _refine(
    p: FloatArray,
    pieces: list[tuple[int, int]],
    sigma: float,
    min_tol_mm: float,
    min_points: int,
    min_kink_deg: float = 5.0,
) -> list[tuple[int, int]]:
    """Place each corner between neighbouring pieces at the best two-line split (DP's split
    point strays under noise), and split a run's end pieces at a kink too small for DP's
    tolerance (a root face seen at a slant) when that explains the points much better."""
    out = [list(piece) for piece in pieces]
    for left, right in itertools.pairwise(out):
        lo, hi = left[0], right[1] + 1
        if hi - lo >= 6:
            cut = lo + _best_split(p[lo:hi], 3)[0]
            left[1], right[0] = cut - 1, cut
    significant = 30.0 * max(sigma, min_tol_mm / 5.0) ** 2
    result: list[tuple[int, int]] = []
    for i, (lo, hi) in enumerate(out):
        cuts = []
        if hi - lo + 1 >= 4 * min_points:
            mid = (lo + hi) // 2
            halves = ([(lo, mid + 1)] if i == 0 else []) + (
                [(mid, hi + 1)] if i == len(out) - 1 else []
            )
            for h_lo, h_hi in halves:
                b, split, single = _best_split(p[h_lo:h_hi], min_points)
                if single - split > significant:
                    cut = h_lo + b
                    kink = _angle(_fit(p, np.arange(lo, cut)), _fit(p, np.arange(cut, hi + 1)))
                    if kink > math.radians(min_kink_deg):
                        cuts.append(cut)
        bounds = [lo, *sorted(cuts), hi + 1]
        result += [(a, b - 1) for a, b in itertools.pairwise(bounds) if b > a]
    return result


def _chord_distance(p: FloatArray, a: int, b: int) -> FloatArray:
    chord = p[b] - p[a]
    norm = math.hypot(chord[0], chord[1])
    q = p[a + 1 : b] - p[a]
    if norm == 0.0:
        return np.hypot(q[:, 0], q[:, 1])
    return np.abs(q[:, 0] * chord[1] - q[:, 1] * chord[0]) / norm


def _split(p: FloatArray, lo: int, hi: int, tol: float, limit: int) -> list[tuple[int, int]] | None:
    """Douglas-Peucker: inclusive index ranges whose points lie within ``tol`` of the chord."""
    out, stack = [], [(lo, hi)]
    while stack:
        a, b = stack.pop()
        if b - a < 2:
            out.append((a, b))
            continue
        d = _chord_distance(p, a, b)
        k = int(np.argmax(d))
        if d[k] > tol:
            stack += [(a + 1 + k, b), (a, a + 1 + k)]
        else:
            out.append((a, b))
        if len(out) + len(stack) > limit:
            return None
    return out


def _merge(p: FloatArray, pieces: list[tuple[int, int]], tol: float) -> list[tuple[int, int]]:
    """Join neighbouring pieces whose union still fits one line within ``tol``."""
    merged = [pieces[0]]
    for lo, hi in pieces[1:]:
        a = merged[-1][0]
        line = _fit(p, np.arange(a, hi + 1))
        if np.max(np.abs((p[a : hi + 1] - line.centroid) @ line.normal)) <= tol:
            merged[-1] = (a, hi)
        else:
            merged.append((lo, hi))
    return merged


def collinear_members(
    seg: Segments, lines: list[Line], max_angle_deg: float = 30.0
) -> list[list[int]]:
    """Positions in ``lines`` grouped by the straight line they lie on, largest group first.

    Pieces are taken from the best supported down; each joins the largest earlier group
    whose anchor (its best supported piece) holds both the piece's ends within the
    tolerance (directions within ``max_angle_deg``), so a short piece at a corner cannot
    bridge two lines, and a short stub cut off a plate by an interruption joins the plate.
    """
    order = sorted(range(len(lines)), key=lambda i: -lines[i].count)
    # (centroid, direction, normal) of each group's anchor, as floats: these are a handful
    # of tests on scalars, where numpy's per-call overhead would dominate.
    anchors: list[tuple[float, float, float, float]] = []
    members: list[list[int]] = []
    cos_max = math.cos(math.radians(max_angle_deg))
    tol = seg.tol
    for i in order:
        ln = lines[i]
        cy, cz = float(ln.centroid[0]), float(ln.centroid[1])
        dy, dz = float(ln.direction[0]), float(ln.direction[1])
        t0, t1 = float(ln.t[0]), float(ln.t[-1])
        ends = ((cy + t0 * dy, cz + t0 * dz), (cy + t1 * dy, cz + t1 * dz))
        for k, (ay, az, ady, adz) in enumerate(anchors):
            if abs(ady * dy + adz * dz) >= cos_max and all(
                abs((ey - ay) * -adz + (ez - az) * ady) <= tol for ey, ez in ends
            ):
                members[k].append(i)
                break
        else:
            anchors.append((cy, cz, dy, dz))
            members.append([i])
    return members


def collinear_groups(seg: Segments, max_angle_deg: float = 30.0) -> list[Line]:
    """Join pieces that lie on one line, across gaps and interruptions (refit on the union);
    see :func:`collinear_members`."""
    return [
        seg.lines[m[0]]
        if len(m) == 1
        else _fit(seg.points, np.sort(np.concatenate([seg.lines[i].index for i in m])))
        for m in collinear_members(seg, seg.lines, max_angle_deg)
    ]


def intersect(a: Line, b: Line) -> FloatArray | None:
    """(2,) crossing of two lines, or None when (nearly) parallel."""
    d = a.direction[0] * b.direction[1] - a.direction[1] * b.direction[0]
    if abs(d) < 1e-9:
        return None
    w = b.centroid - a.centroid
    s = (w[0] * b.direction[1] - w[1] * b.direction[0]) / d
    return a.point(s)


def _angle(a: Line, b: Line) -> float:
    """Unsigned angle between two lines (rad, in [0, pi/2])."""
    return math.acos(min(1.0, abs(float(a.direction @ b.direction))))


def corner_with(
    line: Line, at_end: bool, others: list[Line], seg: Segments
) -> tuple[FloatArray, Line | None]:
    """Where ``line`` ends and the neighbour it meets there: its crossing with a line of
    ``others`` that meets it at that end (a visible corner, exact), else half a spacing
    beyond its last inlier (the edge lies between rays) and None."""
    # Scalars, not numpy: a handful of tests per neighbour, where numpy's per-call overhead
    # would dominate (the extractors call this four times per profile).
    cy, cz = float(line.centroid[0]), float(line.centroid[1])
    dy, dz = float(line.direction[0]), float(line.direction[1])
    t_tip = float(line.t[-1] if at_end else line.t[0])
    tip_y, tip_z = cy + t_tip * dy, cz + t_tip * dz
    reach = 3.0 * max(line.step(at_end), seg.spacing) + seg.tol
    cos_min = math.cos(math.radians(20))
    best, best_d, best_line = None, math.inf, None
    for other in others:
        if other is line:
            continue
        ody, odz = float(other.direction[0]), float(other.direction[1])
        if abs(dy * ody + dz * odz) > cos_min:
            continue  # within 20 deg: no corner
        det = dy * odz - dz * ody
        if abs(det) < 1e-9:
            continue
        ocy, ocz = float(other.centroid[0]), float(other.centroid[1])
        s = ((ocy - cy) * odz - (ocz - cz) * ody) / det
        xy, xz = cy + s * dy, cz + s * dz
        d = math.hypot(xy - tip_y, xz - tip_z)
        if d > reach or d >= best_d:
            continue
        near_other = min(
            math.hypot(ocy + t * ody - xy, ocz + t * odz - xz)
            for t in (float(other.t[0]), float(other.t[-1]))
        )
        reach_other = 3.0 * max(other.step(True), other.step(False), seg.spacing) + seg.tol
        if near_other <= reach_other:
            best, best_d, best_line = (xy, xz), d, other
    if best is None:
        return line.end(at_end), None
    return np.array(best), best_line


def corner_or_end(line: Line, at_end: bool, others: list[Line], seg: Segments) -> FloatArray:
    """Where ``line`` ends: its crossing with a neighbour that meets it there (a visible
    corner, exact), else half a spacing beyond its last inlier (the edge lies between rays)."""
    return corner_with(line, at_end, others, seg)[0]


# ----------------------------------------------------------------- the extractors' base
#: What bad data (NaN, degenerate fits, empty selections) can raise inside an extractor: caught
#: and turned into a falsy ``Feature.failed``.
DATA_ERRORS = (
    ValueError,
    IndexError,
    ZeroDivisionError,
    FloatingPointError,
    np.linalg.LinAlgError,
    AttributeError,
    TypeError,
)


@dataclass(frozen=True)
class _Base:
    """Shared parameters and the never-raise wrapper of the built-in extractors."""

    name: str = "base"
    min_tol_mm: float = 0.03
    min_points: int = 8
    min_arm_mm: float = 0.5

    def __call__(self, profile: Profile) -> Feature:
        try:
            with np.errstate(all="ignore"):
                seg = segment_profile(
                    profile, min_tol_mm=self.min_tol_mm, min_points=self.min_points
                )
                if isinstance(seg, str):
                    return Feature.failed(seg, joint=self.name)
                return self._extract(profile, seg)
        except DATA_ERRORS as exc:  # never raise on data
            return Feature.failed(f"{self.name}: unusable profile ({exc})", joint=self.name)

    def _extract(self, profile: Profile, seg: Segments) -> Feature:
        raise NotImplementedError

    def _found(self, profile: Profile, point: FloatArray, **kw: Any) -> Feature:
        return Feature.found(point, profile.T_world_sensor, joint=self.name, **kw)

    def _groups(self, seg: Segments) -> list[Line]:
        """Collinear groups supported enough to be an arm or a plate."""
        return [
            g
            for g in collinear_groups(seg)
            if g.count >= self.min_points and g.extent >= self.min_arm_mm
        ]

    def _arms(
        self,
        seg: Segments,
        opening_down: bool,
        min_deg: float,
        max_deg: float,
        max_reach_mm: float,
        groups: list[Line] | None = None,
    ) -> tuple[Line, Line, FloatArray, float] | str:
        """The best pair of lines forming a V (opening towards the sensor, -z) or a ridge
        (``opening_down``: the arms fall away from the sensor): (left, right, apex, score)."""
        if groups is None:
            groups = self._groups(seg)
        sign = 1.0 if opening_down else -1.0
        best: tuple[Line, Line, FloatArray, float] | None = None
        for i, a in enumerate(groups):
            for b in groups[i + 1 :]:
                x = intersect(a, b)
                if x is None:
                    continue
                arms = []
                for g in (a, b):
                    v = g.centroid - x
                    v = v / max(float(np.hypot(*v)), 1e-300)
                    near = float(np.min((seg.points[g.index] - x) @ v))
                    arms.append((v, near, g))
                (va, na, ga), (vb, nb, gb) = sorted(arms, key=lambda arm: float(arm[0][0]))
                included = math.degrees(math.acos(float(np.clip(va @ vb, -1, 1))))
                bis = va + vb
                ok = (
                    va[0] < 0 < vb[0]
                    and sign * va[1] > 0
                    and sign * vb[1] > 0
                    and min_deg <= included <= max_deg
                    and sign * bis[1] > 0.7 * float(np.hypot(*bis))  # bisector within 45 deg
                    and -seg.tol <= min(na, nb)
                    and max(na, nb) <= max_reach_mm
                )
                score = float(ga.count + gb.count)
                if ok and (best is None or score > best[3]):
                    best = (ga, gb, x, score)
        return best if best is not None else "no pair of lines forms the joint"


def _confidence(arms: list[Line], seg: Segments) -> float:
    """Share of the kept points explained by the feature's lines, scaled by their fit."""
    explained = sum(a.count for a in arms) / max(len(seg.points), 1)
    fit = max(0.0, 1.0 - max(a.rms for a in arms) / seg.tol)
    return float(np.clip(0.5 * explained + 0.5 * fit, 0.0, 1.0))


#: A gap's wall or a lap's edge face stands at least this steep on the plates (deg). A false
#: reflection is a stray line tilted by at most 45 deg in the laser plane: up to 60 deg on a
#: plate rolled by 15 deg, so it is never taken for a wall.
_WALL_DEG = 65.0
#: A gap's bottom (a backing seen through the gap) lies within this angle of the plates (deg).
_BOTTOM_DEG = 10.0
#: A piece within this angle of a plate (deg) is plate where it lies on the plate's line.
_PLATE_DEG = 20.0


def _on(line: Line, index: NDArray[np.intp], points: FloatArray) -> Line:
    """``line`` carrying other inliers (their coordinates along it): a stub's edge measured
    on the line of the whole plate."""
    t = (points[index] - line.centroid) @ line.direction
    return Line(index, line.centroid, line.direction, t, line.rms)


def _towards_sensor(line: Line, q: FloatArray) -> FloatArray:
    """Signed distance of points from ``line``, positive on the sensor's side (the origin)."""
    h = (q - line.centroid) @ line.normal
    return h if float(line.centroid @ line.normal) < 0 else -h


def _ray_t(line: Line, q: FloatArray) -> FloatArray:
    """Where the rays from the emitter (the origin) through points ``q`` cross ``line``, as
    coordinates along it: which stretch of the plate those columns would have shown."""
    n = line.normal
    s = float(line.centroid @ n) / (q @ n)
    return (q * s[:, None] - line.centroid) @ line.direction
