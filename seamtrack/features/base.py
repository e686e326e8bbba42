"""The built-in family extractors' base class: shared parameters, the never-raise wrapper,
line groups and the V (or ridge) search.

Laser frame: points are (y_L, z_L); z_L grows away from the sensor (into a groove).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from seamtrack.features.counts import explained_share, support
from seamtrack.features.expect import Expect, parse_expect
from seamtrack.features.lines import (
    DATA_ERRORS,
    Line,
    Segments,
    _fit,
    collinear_groups,
    intersect,
    segment_profile,
)
from seamtrack.sensing.profiles import Feature, Profile

FloatArray = NDArray[np.float64]
#: A stretch of kept points ``points[lo:hi]`` and the line(s) a joint's model puts there
#: (None: left out of the count, such as a gap).
Zone = tuple[int, int, Line | tuple[Line, ...] | None]


@dataclass(frozen=True)
class _Base:
    """Shared parameters and the never-raise wrapper of the built-in extractors."""

    name: str = "base"
    min_tol_mm: float | None = None
    resolution_mm: float | None = None
    min_points: int = 8
    min_arm_mm: float = 0.5
    min_explained: float = 0.8
    #: Also try single pieces of a collinear group as arms (a weldment's web seen on both sides
    #: of a gusset standing on it); off by default: a raised block's base would read as a joint.
    arms_from_pieces: bool = False
    expect: Mapping[str, float] | Expect | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "expect", parse_expect(self.expect, self.name))

    def _angles(self, min_deg: float, max_deg: float) -> tuple[float, float]:
        """The family's included-angle range (deg), narrowed to the expected angle."""
        if not isinstance(self.expect, Expect):
            return min_deg, max_deg
        lo, hi = self.expect.angle_range(math.radians(min_deg), math.radians(max_deg))
        return math.degrees(lo), math.degrees(hi)

    def _implausible(self, **measured: float | None) -> Feature | None:
        """A failure when measured values break the expectation (``angle`` in rad,
        ``depth`` and ``gap`` in mm), else None."""
        if not isinstance(self.expect, Expect):
            return None
        why = self.expect.check(**measured)
        return Feature.failed(f"{self.name}: {why}", joint=self.name) if why else None

    def __call__(self, profile: Profile) -> Feature:
        return self.scored(profile)[0]

    def segments(self, profile: Profile) -> Segments | str:
        """The profile's straight pieces with this extractor's front-end parameters."""
        return segment_profile(
            profile,
            min_tol_mm=self.min_tol_mm,
            resolution_mm=self.resolution_mm,
            min_points=self.min_points,
        )

    def scored(self, profile: Profile, seg: Segments | str | None = None) -> tuple[Feature, float]:
        """The feature and the share of the profile's surface points its joint model explains
        (0 when not found); ``seg``: the profile's pieces when already segmented. Never
        raises on data."""
        try:
            with np.errstate(all="ignore"):
                if seg is None:
                    seg = self.segments(profile)
                if isinstance(seg, str):
                    return Feature.failed(seg, joint=self.name), 0.0
                found = self._extract(profile, seg)
                if isinstance(found, Feature):
                    return found, 0.0
                feature, share = found
                if share < self.min_explained:
                    return Feature.failed(
                        f"not a {self.name}: its model explains {100 * share:.0f} % of the "
                        f"profile (at least {100 * self.min_explained:.0f} % needed)",
                        joint=self.name,
                    ), share
                return feature, share
        except DATA_ERRORS as exc:  # never raise on data
            return Feature.failed(f"{self.name}: unusable profile ({exc})", joint=self.name), 0.0

    def _extract(self, profile: Profile, seg: Segments) -> Feature | tuple[Feature, float]:
        """A failure, or the feature and the share of the profile its model explains."""
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
        if self.arms_from_pieces:
            # A plane seen on both sides of something standing on it (a web either side of a
            # gusset) is one collinear group running through the corner: its pieces are arms.
            grouped = {id(g) for g in groups}
            groups = groups + [
                ln
                for ln in seg.lines
                if id(ln) not in grouped
                and ln.count >= self.min_points
                and ln.extent >= self.min_arm_mm
            ]
        sign = 1.0 if opening_down else -1.0
        best: tuple[Line, Line, FloatArray, float] | None = None
        m = len(seg.points)
        surface = ~seg.stray if seg.stray.shape == (m,) else np.ones(m, dtype=np.bool_)
        band = 2.0 * seg.tol
        owner = np.full(len(seg.points), -1, dtype=np.intp)  # each point's piece
        for k, ln in enumerate(seg.lines):
            owner[ln.index] = k

        def supported(g: Line, x: FloatArray, v: FloatArray) -> int:
            # The surface points on the line (within the band), on the arm's side of x.
            s = 1.0 if float(v @ g.direction) > 0 else -1.0
            (cy, cz), (uy, uz) = g.centroid.tolist(), g.direction.tolist()
            x_u = float(x @ g.direction)
            return int(support(seg.points, surface, cy, cz, uy, uz, band, x_u, s, seg.tol))

        def reach(g: Line, x: FloatArray, v: FloatArray) -> float:
            # How near the arm comes to the apex. A tenth of a group may lie past it (trimmed
            # below): fragments of the root collinear with a bevel, or a bevel's own piece
            # rounding into the root, but none by more than three tolerances (a piece that
            # runs on through the apex crosses the other arm: no V there).
            t = (seg.points[g.index] - x) @ v
            ahead = t >= -seg.tol
            over = g.count - int(np.count_nonzero(ahead))
            if over == 0:
                return float(t.min())
            if 10 * over > g.count:
                return -np.inf
            through = np.isin(owner[g.index], owner[g.index[ahead]]) & (t < -3.0 * seg.tol)
            return -np.inf if through.any() else float(t[ahead].min())

        # The groups' lines as floats: most pairs fail the V's shape, which scalar arithmetic
        # rules out at a fraction of numpy's cost on 2-vectors; the pairs left (within a
        # hair of passing) are then tested exactly as before.
        flat = [(*g.centroid.tolist(), *g.direction.tolist()) for g in groups]
        lo_deg, hi_deg = min_deg - 1e-6, max_deg + 1e-6
        for i, a in enumerate(groups):
            ay, az, ady, adz = flat[i]
            for j in range(i + 1, len(groups)):
                by, bz, bdy, bdz = flat[j]
                d = ady * bdz - adz * bdy
                if abs(d) < 1e-9:
                    continue  # parallel: no apex
                s_ = ((by - ay) * bdz - (bz - az) * bdy) / d
                xy, xz = ay + s_ * ady, az + s_ * adz
                uy, uz, wy, wz = ay - xy, az - xz, by - xy, bz - xz
                nu, nw = max(math.hypot(uy, uz), 1e-300), max(math.hypot(wy, wz), 1e-300)
                uy, uz, wy, wz = uy / nu, uz / nu, wy / nw, wz / nw
                if wy < uy:
                    uy, uz, wy, wz = wy, wz, uy, uz
                c = min(max(uy * wy + uz * wz, -1.0), 1.0)
                eps = 1e-9
                if not (
                    uy < eps
                    and wy > -eps
                    and sign * uz > -eps
                    and sign * wz > -eps
                    and lo_deg <= math.degrees(math.acos(c)) <= hi_deg
                    and sign * (uz + wz) > 0.7 * math.hypot(uy + wy, uz + wz) - eps
                ):
                    continue
                b = groups[j]
                x = intersect(a, b)
                if x is None:
                    continue
                va, vb = a.centroid - x, b.centroid - x
                va, vb = (
                    va / max(float(np.hypot(*va)), 1e-300),
                    vb / max(float(np.hypot(*vb)), 1e-300),
                )
                ga, gb = a, b
                if vb[0] < va[0]:
                    va, vb, ga, gb = vb, va, b, a
                included = math.degrees(math.acos(min(max(float(va @ vb), -1.0), 1.0)))
                bis = va + vb
                if not (
                    va[0] < 0 < vb[0]
                    and sign * va[1] > 0
                    and sign * vb[1] > 0
                    and min_deg <= included <= max_deg
                    and sign * bis[1] > 0.7 * float(np.hypot(*bis))  # bisector within 45 deg
                ):
                    continue
                na, nb = reach(ga, x, va), reach(gb, x, vb)
                if not (-seg.tol <= min(na, nb) and max(na, nb) <= max_reach_mm):
                    continue
                # Support: the surface points on either arm's line, on its side of the apex
                # (fragments of a bevel cut up by spikes count, whatever piece they are in).
                score = float(supported(ga, x, va) + supported(gb, x, vb))
                if best is None or score > best[3]:
                    best = (ga, gb, x, score)
        if best is None:
            return "no pair of lines forms the joint"
        ga, gb, x, score = best
        return _short_of(ga, x, seg), _short_of(gb, x, seg), x, score


def _confidence(arms: list[Line], seg: Segments) -> float:
    """Share of the kept points explained by the feature's lines, scaled by their fit."""
    explained = sum(a.count for a in arms) / max(len(seg.points), 1)
    fit = max(0.0, 1.0 - max(a.rms for a in arms) / seg.tol)
    return min(max(float(0.5 * explained + 0.5 * fit), 0.0), 1.0)  # NaN stays NaN


def explained(seg: Segments, zones: list[tuple[int, int, Line | tuple[Line, ...] | None]]) -> float:
    """Share of the profile's surface points (detours left out) that lie within three
    tolerances of a line of their zone: ``(lo, hi, lines)`` spans of kept points
    (``seg.points[lo:hi]``) in column order, each with the line (or lines) the joint's model
    puts there; a zone without a line (a gap, a corner) is left out of the count. Points in
    no zone count as unexplained."""
    m = len(seg.points)
    surface = ~seg.stray if seg.stray.shape == (m,) else np.ones(m, dtype=bool)
    if not zones:
        return 0.0
    groups = [() if z is None else z if isinstance(z, tuple) else (z,) for _, _, z in zones]
    spans = np.array(
        [(lo, hi, len(g)) for (lo, hi, _), g in zip(zones, groups, strict=True)], dtype=np.int64
    )
    fits = np.zeros((len(zones), max((len(g) for g in groups), default=1), 4))
    for k, group in enumerate(groups):
        for j, line in enumerate(group):
            fits[k, j, :2] = line.centroid
            fits[k, j, 2:] = line.normal
    return float(explained_share(seg.points, surface, spans, fits, 3.0 * seg.tol))


def largest_in(groups: list[Line], lo: int, hi: int, skip: tuple[Line, ...] = ()) -> Line | None:
    """The group with the most inliers among kept points ``lo:hi``, ``skip`` left out; None
    when there is none."""
    best, count = None, 0
    for g in groups:
        if any(g is s for s in skip):
            continue
        n = int(np.count_nonzero((g.index >= lo) & (g.index < hi)))
        if n > count:
            best, count = g, n
    return best


def _short_of(arm: Line, apex: FloatArray, seg: Segments) -> Line:
    """``arm`` without the inliers that lie past ``apex`` (more than a tolerance): the arm of
    a V ends at its apex."""
    v = arm.centroid - apex
    t = (seg.points[arm.index] - apex) @ v
    keep = t >= -seg.tol * float(np.hypot(*v))
    if keep.all() or np.count_nonzero(keep) < 2:
        return arm
    return _fit(seg.points, arm.index[keep])


def included(left: Line, right: Line, apex: FloatArray) -> float:
    """Included angle (rad) of the V or ridge whose arms run from ``apex`` to the lines'
    centroids."""
    va, vb = left.centroid - apex, right.centroid - apex
    c = float(va @ vb) / max(float(np.hypot(*va) * np.hypot(*vb)), 1e-300)
    return math.acos(min(1.0, max(-1.0, c)))
